//! `evorec timing --out DIR`: worst-case instructions, stack and memory of one GA generation on
//! the Cortex-M4, measured under QEMU, and a cycle estimate for a 168 MHz Cortex-M4F.
//!
//! What it does (it builds nothing; a missing image or tool is reported with the command that
//! provides it):
//! 1. runs the timing firmware (`evorec-timing`, see `hil-stubs/src/bin/evorec-timing.rs`)
//!    under `qemu-system-arm -machine mps2-an386 -icount shift=10`. The firmware makes its
//!    frames on the board (the core's `synth` rasterizer plus a xorshift noise generator: blank,
//!    target absent, target filling the image, noise, target under noise, target tracked, at
//!    random poses, fast arm motion), runs one generation per frame with feedforward on, and
//!    reads TIMER0 (25 MHz, counting on QEMU's instruction clock) around `step_probed` and at
//!    each phase boundary (`evorec_firmware::timing::PhaseTimer`). Instructions are
//!    `ticks · 40 / 2¹⁰`, the same run after run;
//! 2. runs the normal firmware (`evorec-firmware`) in its demo mode for its painted stack
//!    high-water mark, and reads flash and static RAM from the section headers of both ELFs;
//! 3. computes the worst-case stack of one generation statically: frame sizes from the
//!    `.stack_sizes` section of the images built by `hil-stubs/scripts/build-stack-sizes.sh`
//!    (`-Z emit-stack-sizes`) if they exist, else from the function prologues, plus the call
//!    graph from `llvm-objdump -d`;
//! 4. classifies the instructions of the hot loop and of the rest of the generation's code
//!    (`llvm-objdump`) to turn the measured counts into a cycle ESTIMATE (never a
//!    measurement) for a 168 MHz Cortex-M4F with per-class worst-case cycle costs;
//! 5. writes `DIR/timing.json`, `DIR/timing.md` and the raw QEMU logs.

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::fmt::Write as _;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, anyhow, bail};
use evorec_firmware::timing::{BANNER, CaseKind, GenLine, ICOUNT_SHIFT, NS_PER_TICK, ticks_to_instructions};
use serde_json::{Value, json};

/// How to build both firmware images.
pub const BUILD_HINT: &str = "cd hil-stubs && cargo build --release";
/// How to build the images with `.stack_sizes` (optional, for the static stack analysis).
pub const STACK_SIZES_HINT: &str = "hil-stubs/scripts/build-stack-sizes.sh";
/// How to install QEMU.
pub const QEMU_HINT: &str = evorec_firmware::host::QEMU_INSTALL_HINT;
/// How to get `llvm-objdump`.
pub const LLVM_HINT: &str = "rustup component add llvm-tools (or apt-get install -y llvm)";
/// Environment variable naming the timing ELF (overrides the search).
pub const TIMING_ELF_ENV: &str = "EVOREC_TIMING_ELF";
/// The timing firmware's file name.
pub const TIMING_IMAGE: &str = "evorec-timing";
/// The firmware's file name.
pub const FIRMWARE_IMAGE: &str = "evorec-firmware";
/// Budget of one generation of the default configuration (instructions).
pub const GENERATION_BUDGET: f64 = 1.0e6;
/// Target for one sample-point evaluation on the M4 (instructions).
pub const POINT_TARGET: f64 = 25.0;
/// Target for max/min instructions over the frames.
pub const RATIO_TARGET: f64 = 1.05;
/// RAM of the budgeted part (memory.x).
pub const RAM_BYTES: u64 = 128 * 1024;
/// Clock of the cycle estimate.
pub const ESTIMATE_CLOCK_HZ: f64 = 168.0e6;
/// Longest a QEMU run may take.
pub const QEMU_TIMEOUT: Duration = Duration::from_secs(600);
/// The target triple of the firmware.
const TARGET: &str = "thumbv7em-none-eabihf";
/// Start of RAM on mps2-an386 / STM32F4 (`memory.x`).
const RAM_ORIGIN: u64 = 0x2000_0000;

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Target directories searched for the firmware: `$CARGO_TARGET_DIR` (relative to the
/// workspace root), then the workspace's `target/`.
fn target_dirs() -> Vec<PathBuf> {
    let ws = workspace();
    let mut dirs = Vec::new();
    if let Some(dir) = std::env::var_os("CARGO_TARGET_DIR") {
        dirs.push(ws.join(dir));
    }
    let default = ws.join("target");
    if !dirs.contains(&default) {
        dirs.push(default);
    }
    dirs
}

/// The release image `name` built in `hil-stubs/` (`$EVOREC_TIMING_ELF` for the timing image,
/// `$EVOREC_FIRMWARE_ELF` for the firmware, if set).
///
/// # Errors
/// The image does not exist; the message says how to build it.
pub fn find_image(name: &str) -> Result<PathBuf> {
    let env = if name == TIMING_IMAGE { TIMING_ELF_ENV } else { evorec_firmware::host::FIRMWARE_ENV };
    if let Some(p) = std::env::var_os(env) {
        let p = PathBuf::from(p);
        if p.is_file() {
            return Ok(p);
        }
        bail!("{env}={} does not exist: build the firmware with `{BUILD_HINT}`", p.display());
    }
    let candidates: Vec<PathBuf> =
        target_dirs().into_iter().map(|d| d.join(TARGET).join("release").join(name)).collect();
    if let Some(p) = candidates.iter().find(|p| p.is_file()) {
        return Ok(p.clone());
    }
    let list: Vec<String> = candidates.iter().map(|p| p.display().to_string()).collect();
    bail!(
        "firmware image `{name}` not found (looked at {}): build it with `{BUILD_HINT}` \
         (needs `rustup target add {TARGET}`), or point {env} at it",
        list.join(", ")
    )
}

/// The `.stack_sizes` build of image `name` by [`STACK_SIZES_HINT`], if it exists.
pub fn find_stack_sizes_image(name: &str) -> Option<PathBuf> {
    target_dirs()
        .into_iter()
        .map(|d| d.join("stack-sizes").join(TARGET).join("release").join(name))
        .find(|p| p.is_file())
}

/// `qemu-system-arm` (or `$EVOREC_QEMU`), checked by running `--version`.
///
/// # Errors
/// QEMU is not installed; the message says how to install it.
pub fn find_qemu() -> Result<PathBuf> {
    let qemu = std::env::var_os("EVOREC_QEMU").map_or_else(|| PathBuf::from("qemu-system-arm"), PathBuf::from);
    match Command::new(&qemu).arg("--version").stdout(Stdio::null()).stderr(Stdio::null()).status() {
        Ok(_) => Ok(qemu),
        Err(e) => bail!("{} not usable ({e}): install it with `{QEMU_HINT}`", qemu.display()),
    }
}

/// An LLVM tool (`llvm-objdump`): the Rust toolchain's llvm-tools first, else `PATH`.
///
/// # Errors
/// Not found; the message says how to get it.
pub fn find_llvm_tool(tool: &str) -> Result<PathBuf> {
    let rustc = std::env::var_os("RUSTC").unwrap_or_else(|| "rustc".into());
    let sysroot = Command::new(&rustc).args(["--print", "sysroot"]).output().ok();
    let host = Command::new(&rustc).arg("-vV").output().ok().and_then(|o| {
        String::from_utf8_lossy(&o.stdout).lines().find_map(|l| l.strip_prefix("host: ").map(str::to_owned))
    });
    if let (Some(s), Some(host)) = (sysroot, host) {
        let p = PathBuf::from(String::from_utf8_lossy(&s.stdout).trim())
            .join("lib/rustlib")
            .join(host)
            .join("bin")
            .join(tool);
        if p.is_file() {
            return Ok(p);
        }
    }
    match Command::new(tool).arg("--version").stdout(Stdio::null()).stderr(Stdio::null()).status() {
        Ok(_) => Ok(PathBuf::from(tool)),
        Err(_) => bail!("{tool} not found: {LLVM_HINT}"),
    }
}

/// Runs `elf` on QEMU mps2-an386 (with `-icount shift=`[`ICOUNT_SHIFT`] if `icount`) in
/// `workdir`, its output to `workdir/log_name`, and returns that output.
///
/// # Errors
/// QEMU could not start, timed out or exited with failure (the log's end is in the message).
pub fn run_qemu(qemu: &Path, elf: &Path, workdir: &Path, log_name: &str, icount: bool) -> Result<String> {
    fs::create_dir_all(workdir).with_context(|| format!("creating {}", workdir.display()))?;
    let log_path = workdir.join(log_name);
    let log = fs::File::create(&log_path).with_context(|| format!("creating {}", log_path.display()))?;
    let mut cmd = Command::new(qemu);
    cmd.args(["-cpu", "cortex-m4", "-machine", "mps2-an386", "-nographic", "-monitor", "none"])
        .args(["-semihosting-config", "enable=on,target=native"]);
    if icount {
        cmd.args(["-icount", &format!("shift={ICOUNT_SHIFT}")]);
    }
    let elf_abs = elf.canonicalize().with_context(|| format!("{}", elf.display()))?;
    cmd.arg("-kernel").arg(&elf_abs).current_dir(workdir).stdin(Stdio::null()).stdout(log.try_clone()?).stderr(log);
    let mut child =
        cmd.spawn().with_context(|| format!("starting {} (install it with `{QEMU_HINT}`)", qemu.display()))?;
    let start = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait()? {
            break s;
        }
        if start.elapsed() > QEMU_TIMEOUT {
            let _ = child.kill();
            let _ = child.wait();
            bail!("QEMU timed out after {:?} running {}; log: {}", QEMU_TIMEOUT, elf.display(), log_path.display());
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let text = fs::read_to_string(&log_path).with_context(|| format!("reading {}", log_path.display()))?;
    if !status.success() {
        let tail: Vec<&str> = text.lines().rev().take(15).collect::<Vec<_>>().into_iter().rev().collect();
        bail!("QEMU running {} exited with {status}; its log ends:\n{}", elf.display(), tail.join("\n"));
    }
    Ok(text)
}

/// The generations of one configuration.
#[derive(Debug, Clone)]
pub struct Run {
    /// `full` (the default configuration's long run) or `sweep`.
    pub name: String,
    /// Population size.
    pub population: u32,
    /// Points per row.
    pub grid: u32,
    /// Sample points per camera and pose (`SurfaceStrips::POINTS_PER_CAMERA`).
    pub points_per_camera: u32,
    /// Every measured generation.
    pub generations: Vec<GenLine>,
}

/// Everything the timing firmware printed.
#[derive(Debug, Clone)]
pub struct Measurement {
    /// Ticks between two back-to-back TIMER0 reads (one read's cost).
    pub read_pair_ticks: u32,
    /// The runs in order.
    pub runs: Vec<Run>,
}

/// Parses the timing firmware's output.
///
/// # Errors
/// The banner or the final `END ok` is missing, or a `GEN` line comes before any `RUN`.
pub fn parse_output(text: &str) -> Result<Measurement> {
    if !text.lines().any(|l| l.trim() == BANNER) {
        bail!("not the output of the timing firmware (no `{BANNER}` line)");
    }
    let mut m = Measurement { read_pair_ticks: 0, runs: Vec::new() };
    let mut ended = false;
    for line in text.lines() {
        let line = line.trim();
        let field = |key: &str| -> Option<&str> {
            line.split_whitespace().find_map(|w| w.strip_prefix(key).and_then(|r| r.strip_prefix('=')))
        };
        let num = |key: &str| -> Result<u32> {
            field(key).and_then(|v| v.parse().ok()).ok_or_else(|| anyhow!("no {key}= in `{line}`"))
        };
        if line.starts_with("CALIBRATION") {
            m.read_pair_ticks = num("read_pair")?;
        } else if line.starts_with("RUN ") {
            m.runs.push(Run {
                name: field("name").unwrap_or("?").to_owned(),
                population: num("p")?,
                grid: num("g")?,
                points_per_camera: num("points_per_camera")?,
                generations: Vec::new(),
            });
        } else if line.starts_with("GEN ") {
            let g = GenLine::parse(line).ok_or_else(|| anyhow!("malformed line `{line}`"))?;
            m.runs.last_mut().ok_or_else(|| anyhow!("GEN before RUN"))?.generations.push(g);
        } else if line.starts_with("END ") {
            if line != "END ok" {
                bail!("the timing firmware failed: `{line}`");
            }
            ended = true;
        } else if line.starts_with("ERROR") || line.starts_with("PANIC") {
            bail!("the timing firmware failed: `{line}`");
        }
    }
    if !ended {
        bail!("the timing firmware's output has no `END ok` line");
    }
    Ok(m)
}

/// Runs the timing image `elf` under QEMU (log in `workdir/timing-firmware.log`) and parses it.
///
/// # Errors
/// As [`run_qemu`] and [`parse_output`].
pub fn measure(qemu: &Path, elf: &Path, workdir: &Path) -> Result<Measurement> {
    parse_output(&run_qemu(qemu, elf, workdir, "timing-firmware.log", true)?)
}

/// Min, max and mean of a series.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Range {
    /// Smallest value.
    pub min: f64,
    /// Largest value.
    pub max: f64,
    /// Mean.
    pub mean: f64,
}

impl Range {
    fn of(values: impl IntoIterator<Item = f64>) -> Self {
        let (mut min, mut max, mut sum, mut n) = (f64::INFINITY, f64::NEG_INFINITY, 0.0, 0u32);
        for v in values {
            min = min.min(v);
            max = max.max(v);
            sum += v;
            n += 1;
        }
        Self { min, max, mean: if n == 0 { 0.0 } else { sum / f64::from(n) } }
    }

    /// `max / min`.
    pub fn ratio(&self) -> f64 {
        self.max / self.min
    }

    fn json(&self) -> Value {
        json!({ "min": self.min.round(), "max": self.max.round(), "mean": self.mean.round() })
    }
}

/// Instruction counts of one run.
#[derive(Debug, Clone)]
pub struct RunStats {
    /// Population size.
    pub population: u32,
    /// Points per row.
    pub grid: u32,
    /// Sample points per individual (both cameras).
    pub points_per_individual: u32,
    /// Generations measured.
    pub generations: usize,
    /// The whole `step_probed` call.
    pub call: Range,
    /// Feedforward phase.
    pub feedforward: Range,
    /// Projection + fitness.
    pub evaluate: Range,
    /// Selection, crossover, mutation.
    pub breed: Range,
    /// Evaluate phase / (population · points per individual).
    pub per_point: Range,
    /// Largest painted stack high-water mark of a generation (bytes from the top of RAM).
    pub stack: u32,
    /// Whole call per kind of frame.
    pub by_kind: Vec<(CaseKind, usize, Range)>,
}

impl Run {
    /// The run's statistics in instructions.
    pub fn stats(&self) -> RunStats {
        let g = &self.generations;
        let ins = |f: fn(&GenLine) -> u32| Range::of(g.iter().map(|x| ticks_to_instructions(u64::from(f(x)))));
        let points = 2 * self.points_per_camera;
        let evals = f64::from(self.population) * f64::from(points);
        let by_kind = CaseKind::ALL
            .into_iter()
            .filter_map(|k| {
                let v: Vec<f64> =
                    g.iter().filter(|x| x.kind == k).map(|x| ticks_to_instructions(u64::from(x.call))).collect();
                (!v.is_empty()).then(|| (k, v.len(), Range::of(v)))
            })
            .collect();
        let evaluate = ins(|x| x.phases.evaluate);
        RunStats {
            population: self.population,
            grid: self.grid,
            points_per_individual: points,
            generations: g.len(),
            call: ins(|x| x.call),
            feedforward: ins(|x| x.phases.feedforward),
            evaluate,
            breed: ins(|x| x.phases.breed),
            per_point: Range { min: evaluate.min / evals, max: evaluate.max / evals, mean: evaluate.mean / evals },
            stack: g.iter().map(|x| x.stack).max().unwrap_or(0),
            by_kind,
        }
    }
}

/// A section header.
#[derive(Debug, Clone)]
struct Section {
    name: String,
    kind: u32,
    flags: u32,
    addr: u64,
    offset: u64,
    size: u64,
}

const SHT_NOBITS: u32 = 8;
const SHF_ALLOC: u32 = 2;

fn le32(b: &[u8], at: usize) -> Result<u32> {
    let s = b.get(at..at + 4).ok_or_else(|| anyhow!("ELF truncated"))?;
    Ok(u32::from_le_bytes([s[0], s[1], s[2], s[3]]))
}

fn le16(b: &[u8], at: usize) -> Result<u16> {
    let s = b.get(at..at + 2).ok_or_else(|| anyhow!("ELF truncated"))?;
    Ok(u16::from_le_bytes([s[0], s[1]]))
}

/// The section headers of a 32-bit little-endian ELF.
fn sections(elf: &[u8]) -> Result<Vec<Section>> {
    if elf.get(..6) != Some(&[0x7f, b'E', b'L', b'F', 1, 1][..]) {
        bail!("not a 32-bit little-endian ELF");
    }
    let shoff = le32(elf, 0x20)? as usize;
    let shentsize = usize::from(le16(elf, 0x2e)?);
    let shnum = usize::from(le16(elf, 0x30)?);
    let shstrndx = usize::from(le16(elf, 0x32)?);
    let mut raw = Vec::with_capacity(shnum);
    for i in 0..shnum {
        let h = shoff + i * shentsize;
        raw.push((
            le32(elf, h)?,
            le32(elf, h + 4)?,
            le32(elf, h + 8)?,
            le32(elf, h + 12)?,
            le32(elf, h + 16)?,
            le32(elf, h + 20)?,
        ));
    }
    let strtab = raw.get(shstrndx).map_or(0, |s| s.4 as usize);
    raw.into_iter()
        .map(|(name, kind, flags, addr, offset, size)| {
            let start = strtab + name as usize;
            let bytes = elf.get(start..).unwrap_or_default();
            let end = bytes.iter().position(|&c| c == 0).unwrap_or(0);
            Ok(Section {
                name: String::from_utf8_lossy(bytes.get(..end).unwrap_or_default()).into_owned(),
                kind,
                flags,
                addr: u64::from(addr),
                offset: u64::from(offset),
                size: u64::from(size),
            })
        })
        .collect()
}

/// Flash and static RAM of an image.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MemoryUse {
    /// Bytes stored in flash: every allocated section with contents (`.vector_table`,
    /// `.text`, `.rodata`, and `.data`'s initial values).
    pub flash_bytes: u64,
    /// Bytes of RAM taken by statics (`.data`, `.bss`, `.uninit`).
    pub static_ram_bytes: u64,
}

fn memory_use(secs: &[Section]) -> MemoryUse {
    let alloc = secs.iter().filter(|s| s.flags & SHF_ALLOC != 0);
    MemoryUse {
        flash_bytes: alloc.clone().filter(|s| s.kind != SHT_NOBITS).map(|s| s.size).sum(),
        static_ram_bytes: alloc.filter(|s| s.addr >= RAM_ORIGIN).map(|s| s.size).sum(),
    }
}

/// The `.stack_sizes` section (`-Z emit-stack-sizes`): function address (Thumb bit cleared) →
/// frame bytes. `None` if the image has no such section.
fn stack_sizes(elf: &[u8], secs: &[Section]) -> Option<HashMap<u32, u32>> {
    let s = secs.iter().find(|s| s.name == ".stack_sizes")?;
    let data = elf.get(s.offset as usize..(s.offset + s.size) as usize)?;
    let mut out = HashMap::new();
    let mut i = 0;
    while i + 4 <= data.len() {
        let addr = le32(data, i).ok()? & !1;
        i += 4;
        let (mut size, mut shift) = (0u32, 0);
        loop {
            let b = *data.get(i)?;
            i += 1;
            size |= u32::from(b & 0x7f) << shift;
            shift += 7;
            if b & 0x80 == 0 {
                break;
            }
        }
        out.insert(addr, size);
    }
    Some(out)
}

/// One disassembled instruction.
#[derive(Debug, Clone)]
struct Insn {
    mnemonic: String,
    operands: String,
}

/// One function of the disassembly.
#[derive(Debug, Clone)]
struct Function {
    name: String,
    addr: u32,
    end: u32,
    insns: Vec<(u32, Insn)>,
}

/// Parses `llvm-objdump -d --no-show-raw-insn` output into functions (ARM mapping symbols
/// `$t`, `$d` do not start a function; data words are dropped).
fn parse_disassembly(text: &str) -> Vec<Function> {
    let mut funcs: Vec<Function> = Vec::new();
    for line in text.lines() {
        if let Some((addr, rest)) = line.split_once(" <")
            && let Some(name) = rest.strip_suffix(">:")
            && let Ok(addr) = u32::from_str_radix(addr.trim(), 16)
        {
            if !name.starts_with('$') {
                funcs.push(Function { name: name.to_owned(), addr, end: addr, insns: Vec::new() });
            }
            continue;
        }
        let Some((addr, rest)) = line.split_once(':') else { continue };
        let Ok(addr) = u32::from_str_radix(addr.trim(), 16) else { continue };
        let rest = rest.split(" @ ").next().unwrap_or("").trim();
        // Literal pools (`$d`) show as raw bytes and `.word`/`.short`/`.byte`.
        if [".word", ".short", ".byte", ".long"].iter().any(|d| rest.contains(d)) {
            continue;
        }
        let mut parts = rest.splitn(2, char::is_whitespace);
        let mnemonic = parts.next().unwrap_or("").trim();
        if mnemonic.is_empty() || mnemonic.starts_with('.') || mnemonic.starts_with('<') {
            continue;
        }
        let operands = parts.next().unwrap_or("").trim();
        if let Some(f) = funcs.last_mut() {
            f.insns.push((addr, Insn { mnemonic: mnemonic.to_owned(), operands: operands.to_owned() }));
            f.end = addr;
        }
    }
    funcs
}

/// Disassembles `elf` with demangled names.
fn disassemble(objdump: &Path, elf: &Path) -> Result<Vec<Function>> {
    let out = Command::new(objdump)
        .args(["-d", "-C", "--no-show-raw-insn"])
        .arg(elf)
        .output()
        .with_context(|| format!("running {} ({LLVM_HINT})", objdump.display()))?;
    if !out.status.success() {
        bail!("{} failed on {}: {}", objdump.display(), elf.display(), String::from_utf8_lossy(&out.stderr));
    }
    Ok(parse_disassembly(&String::from_utf8_lossy(&out.stdout)))
}

fn reg_count(list: &str) -> u32 {
    let inner = list.split('{').nth(1).and_then(|s| s.split('}').next()).unwrap_or("");
    inner
        .split(',')
        .map(str::trim)
        .filter(|r| !r.is_empty())
        .map(|r| match r.split_once('-') {
            Some((a, b)) => {
                let n = |s: &str| s.trim_start_matches(|c: char| c.is_ascii_alphabetic()).parse::<u32>().unwrap_or(0);
                n(b).saturating_sub(n(a)) + 1
            }
            None => 1,
        })
        .sum()
}

fn imm(s: &str) -> Option<u32> {
    let v = s.trim().trim_start_matches('#');
    match v.strip_prefix("0x") {
        Some(h) => u32::from_str_radix(h, 16).ok(),
        None => v.parse().ok(),
    }
}

/// Frame bytes from a function's prologue: `push`/`stmdb sp!` (4 per register), `vpush` (4 per
/// s, 8 per d register) and `sub sp` (immediate, or a register set by `movw`/`movt`), up to
/// the first branch.
fn prologue_frame(f: &Function) -> u32 {
    let mut frame = 0u32;
    let mut regs: HashMap<String, u32> = HashMap::new();
    for (_, i) in f.insns.iter().take(24) {
        let m = i.mnemonic.trim_end_matches(".w");
        let ops: Vec<&str> = i.operands.split(',').map(str::trim).collect();
        match m {
            "push" => frame += 4 * reg_count(&i.operands),
            "stmdb" if i.operands.starts_with("sp!") => frame += 4 * reg_count(&i.operands),
            "vpush" => {
                let per = if i.operands.contains("{d") { 8 } else { 4 };
                frame += per * reg_count(&i.operands);
            }
            "movw" | "mov" if ops.len() == 2 => {
                if let (Some(r), Some(v)) = (ops.first(), ops.get(1).and_then(|v| imm(v))) {
                    regs.insert((*r).to_owned(), v);
                }
            }
            "movt" if ops.len() == 2 => {
                if let (Some(r), Some(v)) = (ops.first(), ops.get(1).and_then(|v| imm(v))) {
                    let lo = regs.get(*r).copied().unwrap_or(0) & 0xffff;
                    regs.insert((*r).to_owned(), lo | (v << 16));
                }
            }
            "sub" | "subw" if ops.first() == Some(&"sp") => {
                if let Some(last) = ops.last() {
                    frame += imm(last).or_else(|| regs.get(*last).copied()).unwrap_or(0);
                }
            }
            _ if m.starts_with('b') || m.starts_with("cb") => break,
            _ => {}
        }
    }
    frame
}

fn is_branch(m: &str) -> bool {
    let m = m.trim_end_matches(".w").trim_end_matches(".n");
    const CONDS: [&str; 14] = ["eq", "ne", "cs", "hs", "cc", "lo", "mi", "pl", "vs", "vc", "hi", "ls", "ge", "lt"];
    m == "b"
        || m == "bl"
        || m == "blx"
        || m == "bx"
        || m == "cbz"
        || m == "cbnz"
        || m == "tbb"
        || m == "tbh"
        || m.strip_prefix('b').is_some_and(|c| CONDS.contains(&c) || c == "gt" || c == "le" || c == "al")
}

fn target_addr(operands: &str) -> Option<u32> {
    operands.split([' ', ',']).find_map(|w| w.strip_prefix("0x").and_then(|h| u32::from_str_radix(h, 16).ok()))
}

/// Calls out of each function: direct callees (`bl`, `blx #imm`, branches to another
/// function = tail calls) and the number of indirect calls (`blx rN`, `bx rN` other than `lr`).
#[derive(Debug, Clone, Default)]
struct Calls {
    direct: BTreeSet<usize>,
    indirect: u32,
}

fn call_graph(funcs: &[Function]) -> Vec<Calls> {
    let mut starts: Vec<(u32, usize)> = funcs.iter().enumerate().map(|(i, f)| (f.addr, i)).collect();
    starts.sort_unstable();
    let owner = |a: u32| -> Option<usize> {
        let k = starts.partition_point(|(s, _)| *s <= a);
        let (_, i) = *starts.get(k.checked_sub(1)?)?;
        funcs.get(i).filter(|f| a <= f.end).map(|_| i)
    };
    funcs
        .iter()
        .enumerate()
        .map(|(me, f)| {
            let mut c = Calls::default();
            for (_, i) in &f.insns {
                let m = i.mnemonic.as_str();
                if !is_branch(m) || m.starts_with("tb") {
                    continue;
                }
                let reg_target = !i.operands.contains("0x");
                if reg_target {
                    if (m == "blx" || m == "bx") && i.operands.trim() != "lr" {
                        c.indirect += 1;
                    }
                    continue;
                }
                if let Some(t) = target_addr(&i.operands).and_then(owner)
                    && t != me
                {
                    c.direct.insert(t);
                }
            }
            c
        })
        .collect()
}

/// A worst-case stack path.
#[derive(Debug, Clone, Default)]
pub struct StackPath {
    /// Total bytes.
    pub bytes: u32,
    /// The functions on the path with their frames, outermost first.
    pub frames: Vec<(String, u32)>,
}

/// The static worst-case stack of one generation.
#[derive(Debug, Clone)]
pub struct StackAnalysis {
    /// Where the frame sizes come from.
    pub method: String,
    /// The image analysed.
    pub image: PathBuf,
    /// Deepest path below the generation function (itself included).
    pub generation: StackPath,
    /// Deepest path from `Reset` to the generation function (itself excluded).
    pub callers: StackPath,
    /// Indirect calls reachable from the generation function (not followed).
    pub indirect_calls: u32,
    /// Whether recursion was found below the generation function (then the bound is void).
    pub recursion: bool,
    /// Functions whose `.stack_sizes` frame differs from their prologue's (if both known).
    pub prologue_mismatches: Vec<(String, u32, u32)>,
}

impl StackAnalysis {
    /// Worst case from `Reset` through one generation.
    pub fn total(&self) -> u32 {
        self.callers.bytes + self.generation.bytes
    }
}

struct Graph<'a> {
    funcs: &'a [Function],
    calls: Vec<Calls>,
    frame: Vec<u32>,
}

impl Graph<'_> {
    fn find(&self, pred: impl Fn(&str) -> bool) -> Option<usize> {
        self.funcs.iter().position(|f| pred(&f.name))
    }

    /// Deepest path below `f` (memoised; `on_path` detects recursion).
    fn deepest(
        &self,
        f: usize,
        memo: &mut HashMap<usize, StackPath>,
        on_path: &mut Vec<usize>,
        rec: &mut bool,
    ) -> StackPath {
        if let Some(p) = memo.get(&f) {
            return p.clone();
        }
        if on_path.contains(&f) {
            *rec = true;
            return StackPath::default();
        }
        on_path.push(f);
        let mut best = StackPath::default();
        for &c in self.calls.get(f).map(|c| &c.direct).into_iter().flatten() {
            let p = self.deepest(c, memo, on_path, rec);
            if p.bytes > best.bytes || best.frames.is_empty() {
                best = p;
            }
        }
        on_path.pop();
        let own = self.frame.get(f).copied().unwrap_or(0);
        let name = self.funcs.get(f).map(|x| x.name.clone()).unwrap_or_default();
        let mut path = StackPath { bytes: own + best.bytes, frames: vec![(name, own)] };
        path.frames.extend(best.frames);
        memo.insert(f, path.clone());
        path
    }

    /// Deepest path from `f` to `target` (frames of `f` .. excluding `target`).
    fn to_target(
        &self,
        f: usize,
        target: usize,
        memo: &mut HashMap<usize, Option<StackPath>>,
        seen: &mut Vec<usize>,
    ) -> Option<StackPath> {
        if f == target {
            return Some(StackPath::default());
        }
        if let Some(p) = memo.get(&f) {
            return p.clone();
        }
        if seen.contains(&f) {
            return None;
        }
        seen.push(f);
        let mut best: Option<StackPath> = None;
        for &c in self.calls.get(f).map(|c| &c.direct).into_iter().flatten() {
            if let Some(p) = self.to_target(c, target, memo, seen)
                && best.as_ref().is_none_or(|b| p.bytes > b.bytes)
            {
                best = Some(p);
            }
        }
        seen.pop();
        let result = best.map(|b| {
            let own = self.frame.get(f).copied().unwrap_or(0);
            let mut frames = vec![(self.funcs.get(f).map(|x| x.name.clone()).unwrap_or_default(), own)];
            frames.extend(b.frames);
            StackPath { bytes: own + b.bytes, frames }
        });
        memo.insert(f, result.clone());
        result
    }

    fn reachable(&self, root: usize) -> BTreeSet<usize> {
        let mut seen = BTreeSet::new();
        let mut todo = vec![root];
        while let Some(f) = todo.pop() {
            if seen.insert(f) {
                todo.extend(self.calls.get(f).map(|c| c.direct.iter().copied()).into_iter().flatten());
            }
        }
        seen
    }
}

/// Name test of the default configuration's generation function.
fn is_default_generation(name: &str) -> bool {
    name.contains("P40G5") && name.contains("generation")
}

/// Static worst-case stack of the default configuration's generation in `elf`.
fn analyse_stack(objdump: &Path, elf: &Path) -> Result<StackAnalysis> {
    let bytes = fs::read(elf).with_context(|| format!("reading {}", elf.display()))?;
    let secs = sections(&bytes)?;
    let sizes = stack_sizes(&bytes, &secs);
    let funcs = disassemble(objdump, elf)?;
    let prologue: Vec<u32> = funcs.iter().map(prologue_frame).collect();
    let (frame, method, mismatches) = match &sizes {
        Some(s) => {
            let frame: Vec<u32> =
                funcs.iter().zip(&prologue).map(|(f, p)| s.get(&f.addr).copied().unwrap_or(*p)).collect();
            let mism = funcs
                .iter()
                .zip(&prologue)
                .filter_map(|(f, p)| s.get(&f.addr).filter(|v| *v != p).map(|v| (f.name.clone(), *v, *p)))
                .collect();
            (frame, "`.stack_sizes` (-Z emit-stack-sizes; prologue where a function has no entry) + call graph from llvm-objdump".to_owned(), mism)
        }
        None => {
            (prologue, "function prologues (push/vpush/sub sp) + call graph from llvm-objdump".to_owned(), Vec::new())
        }
    };
    let g = Graph { funcs: &funcs, calls: call_graph(&funcs), frame };
    let root =
        g.find(is_default_generation).ok_or_else(|| anyhow!("no P40G5 generation function in {}", elf.display()))?;
    let mut rec = false;
    let generation = g.deepest(root, &mut HashMap::new(), &mut Vec::new(), &mut rec);
    // cortex-m-rt's `Reset` (its `__stext` alias is the name llvm-objdump shows).
    let reset = g.find(|n| n == "Reset" || n == "__stext").or_else(|| g.find(|n| n == "main"));
    let callers = reset.and_then(|r| g.to_target(r, root, &mut HashMap::new(), &mut Vec::new())).unwrap_or_default();
    let indirect = g.reachable(root).iter().map(|&f| g.calls.get(f).map_or(0, |c| c.indirect)).sum();
    Ok(StackAnalysis {
        method,
        image: elf.to_path_buf(),
        generation,
        callers,
        indirect_calls: indirect,
        recursion: rec,
        prologue_mismatches: mismatches,
    })
}

/// Instruction classes with their worst-case Cortex-M4 cycle costs (Cortex-M4 TRM r0p1,
/// §3.3 "Processor instruction timings" and the FPU chapter's instruction timings), for
/// zero-wait-state memory; a taken branch refills the pipeline (1 + P, P ≤ 3).
fn classify(i: &Insn) -> (&'static str, u32) {
    let m = i.mnemonic.trim_end_matches(".w").trim_end_matches(".n");
    let ops = i.operands.as_str();
    let base = m.trim_end_matches(".f32").trim_end_matches(".f64");
    if m.starts_with("vdiv") || m.starts_with("vsqrt") {
        return ("fp divide/sqrt (14)", 14);
    }
    if ["vmla", "vmls", "vnmla", "vnmls", "vfma", "vfms", "vfnma", "vfnms"].contains(&base) {
        return ("fp multiply-accumulate (3)", 3);
    }
    if base == "vldr" || base == "vstr" {
        return ("fp load/store (2)", 2);
    }
    if ["vpush", "vpop", "vldmia", "vstmia", "vldmdb", "vstmdb", "vldm", "vstm"].contains(&base) {
        let per = if ops.contains("{d") { 2 } else { 1 };
        return ("fp load/store multiple (1+N)", 1 + per * reg_count(ops));
    }
    if m.starts_with('v') {
        let words = ops.split(',').count();
        return ("fp arithmetic/convert/move (1)", if base == "vmov" && words == 4 { 2 } else { 1 });
    }
    if is_branch(m) {
        return ("branch (1+P, P=3)", if m == "tbb" || m == "tbh" { 2 + 3 } else { 1 + 3 });
    }
    if m == "pop" || m == "ldm" || m == "ldmia" || m == "ldmdb" {
        let pc = if ops.contains("pc") { 3 } else { 0 };
        return ("load/store multiple (1+N)", 1 + reg_count(ops) + pc);
    }
    if m == "push" || m.starts_with("stm") {
        return ("load/store multiple (1+N)", 1 + reg_count(ops));
    }
    if m == "ldrd" || m == "strd" {
        return ("load/store (2; LDRD/STRD 3)", 3);
    }
    if m.starts_with("ldr") || m.starts_with("str") {
        let pc = if m.starts_with("ldr") && ops.starts_with("pc") { 3 } else { 0 };
        return ("load/store (2; LDRD/STRD 3)", 2 + pc);
    }
    if m == "sdiv" || m == "udiv" {
        return ("integer divide (2-12)", 12);
    }
    if ["mla", "mls"].contains(&m) {
        return ("multiply (1; MLA/MLS 2)", 2);
    }
    if ["mul", "muls", "umull", "smull", "umlal", "smlal"].contains(&m) {
        return ("multiply (1; MLA/MLS 2)", 1);
    }
    ("integer ALU, IT (1)", 1)
}

/// Cycles of a class mix if every branch cost `branch` cycles instead of 4.
fn cycles_with_branch_cost(mix: &Mix, branch: f64) -> f64 {
    let n = mix.classes.get("branch (1+P, P=3)").copied().unwrap_or(0.0);
    mix.cycles - n * (4.0 - branch)
}

/// Class counts and cycles of a set of instructions.
#[derive(Debug, Clone, Default)]
pub struct Mix {
    /// Instructions per class.
    pub classes: BTreeMap<&'static str, f64>,
    /// Instructions.
    pub instructions: f64,
    /// Worst-case cycles.
    pub cycles: f64,
}

impl Mix {
    fn add(&mut self, i: &Insn, weight: f64) {
        let (class, cyc) = classify(i);
        *self.classes.entry(class).or_default() += weight;
        self.instructions += weight;
        self.cycles += weight * f64::from(cyc);
    }

    /// Cycles per instruction.
    pub fn cpi(&self) -> f64 {
        if self.instructions > 0.0 { self.cycles / self.instructions } else { 0.0 }
    }
}

/// The cycle estimate's inputs from the disassembly of the measured image.
#[derive(Debug, Clone)]
pub struct MixAnalysis {
    /// The mix of one sample point: the instructions between consecutive `vdiv.f32` of the
    /// fitness kernel (`camera_counts`, inlined rows), averaged over those windows.
    pub point: Mix,
    /// Number of point windows found.
    pub windows: usize,
    /// Static mix of every other instruction reachable from the generation function.
    pub rest: Mix,
}

fn analyse_mix(objdump: &Path, elf: &Path) -> Result<MixAnalysis> {
    let funcs = disassemble(objdump, elf)?;
    let g = Graph { funcs: &funcs, calls: call_graph(&funcs), frame: Vec::new() };
    let root =
        g.find(is_default_generation).ok_or_else(|| anyhow!("no P40G5 generation function in {}", elf.display()))?;
    let reach = g.reachable(root);
    let kernel = reach
        .iter()
        .copied()
        .find(|&f| funcs.get(f).is_some_and(|x| x.name.contains("camera_counts")))
        .ok_or_else(|| anyhow!("no camera_counts reachable from the generation in {}", elf.display()))?;
    // Windows from one vdiv to the next (a point each), where the row is unrolled.
    let kf = funcs.get(kernel).ok_or_else(|| anyhow!("kernel index"))?;
    let divs: Vec<usize> =
        kf.insns.iter().enumerate().filter(|(_, (_, i))| i.mnemonic.starts_with("vdiv")).map(|(k, _)| k).collect();
    let mut gaps: Vec<usize> = divs.windows(2).map(|w| w[1] - w[0]).collect();
    gaps.sort_unstable();
    let median = gaps.get(gaps.len() / 2).copied().unwrap_or(0);
    let mut in_window = vec![false; kf.insns.len()];
    let mut point = Mix::default();
    let mut windows = 0usize;
    for w in divs.windows(2) {
        let (a, b) = (w[0], w[1]);
        if b - a <= median + median / 4 {
            windows += 1;
            for k in a..b {
                if let Some((_, i)) = kf.insns.get(k) {
                    point.add(i, 1.0);
                }
                if let Some(x) = in_window.get_mut(k) {
                    *x = true;
                }
            }
        }
    }
    if windows > 0 {
        let n = windows as f64;
        point.instructions /= n;
        point.cycles /= n;
        point.classes.values_mut().for_each(|v| *v /= n);
    }
    let mut rest = Mix::default();
    for &f in &reach {
        for (k, (_, i)) in funcs.get(f).map(|x| x.insns.iter().enumerate()).into_iter().flatten() {
            if !(f == kernel && in_window.get(k).copied().unwrap_or(false)) {
                rest.add(i, 1.0);
            }
        }
    }
    Ok(MixAnalysis { point, windows, rest })
}

/// Cycle ESTIMATE of one worst-case generation.
#[derive(Debug, Clone)]
pub struct CycleEstimate {
    /// Cycles attributed to the sample points (`points · point.cycles`).
    pub point_cycles: f64,
    /// Cycles of all other instructions (measured remainder × rest CPI).
    pub rest_cycles: f64,
    /// Total.
    pub cycles: f64,
    /// At [`ESTIMATE_CLOCK_HZ`].
    pub microseconds: f64,
}

fn estimate(mix: &MixAnalysis, worst_instructions: f64, points: f64, branch: f64) -> CycleEstimate {
    let cpi = |m: &Mix| if m.instructions > 0.0 { cycles_with_branch_cost(m, branch) / m.instructions } else { 0.0 };
    let point_ins = (points * mix.point.instructions).min(worst_instructions);
    let point_cycles = point_ins * cpi(&mix.point);
    let rest_cycles = (worst_instructions - point_ins) * cpi(&mix.rest);
    let cycles = point_cycles + rest_cycles;
    CycleEstimate { point_cycles, rest_cycles, cycles, microseconds: cycles / ESTIMATE_CLOCK_HZ * 1e6 }
}

/// Parses `stack high-water mark: N of M bytes` from the firmware's log.
fn painted_stack(log: &str) -> Option<(u32, u32)> {
    let line = log.lines().rev().find(|l| l.contains("stack high-water mark:"))?;
    let rest = line.split("stack high-water mark:").nth(1)?;
    let mut words = rest.split_whitespace();
    let used = words.next()?.parse().ok()?;
    let size = words.nth(1)?.parse().ok()?;
    Some((used, size))
}

fn round1(v: f64) -> f64 {
    (v * 10.0).round() / 10.0
}

fn round2(v: f64) -> f64 {
    (v * 100.0).round() / 100.0
}

/// `evorec timing --out DIR`: see the module docs.
///
/// # Errors
/// A missing image, QEMU or llvm-objdump (the message says how to get it), a failed QEMU
/// run, or an output file that cannot be written.
pub fn run(out: &Path) -> Result<()> {
    let timing_elf = find_image(TIMING_IMAGE)?;
    let firmware_elf = find_image(FIRMWARE_IMAGE)?;
    let qemu = find_qemu()?;
    let objdump = find_llvm_tool("llvm-objdump")?;
    fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;

    eprintln!("timing: running {} under QEMU -icount shift={ICOUNT_SHIFT}", timing_elf.display());
    let started = Instant::now();
    let m = measure(&qemu, &timing_elf, out)?;
    eprintln!("timing: {} runs measured in {:.1} s", m.runs.len(), started.elapsed().as_secs_f64());
    let full = m.runs.iter().find(|r| r.name == "full").ok_or_else(|| anyhow!("no full run in the output"))?;
    let fs_ = full.stats();
    let sweep: Vec<RunStats> = m.runs.iter().filter(|r| r.name == "sweep").map(Run::stats).collect();

    // The normal firmware's demo (no FIFOs in its working directory): painted stack of 30
    // frames including the tracker's construction.
    let demo_dir = out.join("firmware-demo");
    let _ = fs::remove_dir_all(&demo_dir);
    let demo_log = run_qemu(&qemu, &firmware_elf, &demo_dir, "firmware.log", false)?;
    let demo_stack = painted_stack(&demo_log);

    let fw_mem = memory_use(&sections(&fs::read(&firmware_elf)?)?);
    let timing_mem = memory_use(&sections(&fs::read(&timing_elf)?)?);

    // The `.stack_sizes` build is used only if it is not older than the measured image.
    let modified = |p: &Path| fs::metadata(p).and_then(|m| m.modified()).ok();
    let stack_image = find_stack_sizes_image(TIMING_IMAGE).filter(|p| {
        let fresh = modified(p) >= modified(&timing_elf);
        if !fresh {
            eprintln!(
                "timing: {} is older than {}; not used (rebuild it with {STACK_SIZES_HINT})",
                p.display(),
                timing_elf.display()
            );
        }
        fresh
    });
    if stack_image.is_none() {
        eprintln!("timing: static stack from function prologues; for `.stack_sizes` frames run {STACK_SIZES_HINT}");
    }
    let stack = analyse_stack(&objdump, stack_image.as_deref().unwrap_or(&timing_elf))?;
    let stack_prologue = match &stack_image {
        Some(_) => Some(analyse_stack(&objdump, &timing_elf)?),
        None => None,
    };
    let mix = analyse_mix(&objdump, &timing_elf)?;
    let points = f64::from(fs_.population) * f64::from(fs_.points_per_individual);
    let cyc = estimate(&mix, fs_.call.max, points, 4.0);
    let cyc_eval = estimate(&mix, fs_.evaluate.max, points, 4.0);
    // Sensitivity: every branch at 2 cycles (taken with a 1-cycle refill; not-taken ones cost 1).
    let cyc_b2 = estimate(&mix, fs_.call.max, points, 2.0);

    // Marginal cost of a point: Evaluate at 8 vs 4 points per row, population 40.
    let eval_at = |p: u32, g: u32| sweep.iter().find(|s| s.population == p && s.grid == g).map(|s| s.evaluate.mean);
    let marginal = match (eval_at(40, 4), eval_at(40, 8)) {
        (Some(a), Some(b)) => Some((b - a) / (40.0 * 2.0 * 60.0 * 4.0)),
        _ => None,
    };

    let stack_bytes = stack.total().max(fs_.stack);
    let instr_per_point = fs_.per_point.max;
    let ram_check_fw = demo_stack.map(|(u, _)| fw_mem.static_ram_bytes + u64::from(u));
    let ram_check_timing = timing_mem.static_ram_bytes + u64::from(stack_bytes);
    let read_ins = ticks_to_instructions(u64::from(m.read_pair_ticks));

    let json = json!({
        "population": fs_.population,
        "points_per_individual": fs_.points_per_individual,
        "points_per_row": fs_.grid,
        "frames": fs_.generations,
        "frame_source": "generated on the board before each generation (core synth rasterizer + xorshift32 noise); not in the measured window",
        "instructions_per_generation": {
            "min": fs_.call.min.round(), "max": fs_.call.max.round(), "mean": fs_.call.mean.round(),
            "ratio_max_min": (fs_.call.ratio() * 1e4).round() / 1e4,
            "budget": GENERATION_BUDGET, "within_budget": fs_.call.max <= GENERATION_BUDGET,
            "over_budget_percent": round1((fs_.call.max / GENERATION_BUDGET - 1.0) * 100.0),
        },
        "phases": {
            "feedforward": fs_.feedforward.json(),
            "evaluate": fs_.evaluate.json(),
            "breed": fs_.breed.json(),
        },
        "frame_kinds": fs_.by_kind.iter().map(|(k, n, r)| (k.name().to_owned(), json!({"frames": n, "min": r.min.round(), "max": r.max.round()}))).collect::<serde_json::Map<_, _>>(),
        "instructions_per_point_eval": round2(instr_per_point),
        "instructions_per_point_eval_range": { "min": round2(fs_.per_point.min), "max": round2(fs_.per_point.max) },
        "instructions_per_point_eval_marginal": marginal.map(round2),
        "point_eval_target": POINT_TARGET,
        "stack_bytes": stack_bytes,
        "stack": {
            "static_generation_bytes": stack.generation.bytes,
            "static_callers_bytes": stack.callers.bytes,
            "static_total_bytes": stack.total(),
            "static_method": stack.method,
            "static_image": stack.image.display().to_string(),
            "static_prologue_total_bytes": stack_prologue.as_ref().map(StackAnalysis::total),
            "indirect_calls_in_generation": stack.indirect_calls,
            "recursion": stack.recursion,
            "stack_sizes_vs_prologue_mismatches": stack.prologue_mismatches.len(),
            "painted_generation_bytes": fs_.stack,
            "firmware_painted_bytes": demo_stack.map(|(u, _)| u),
            "firmware_stack_region_bytes": demo_stack.map(|(_, s)| s),
        },
        "static_ram_bytes": fw_mem.static_ram_bytes,
        "flash_bytes": fw_mem.flash_bytes,
        "ram_bytes": RAM_BYTES,
        "ram_check": {
            "firmware_static_plus_painted_bytes": ram_check_fw,
            "timing_static_plus_stack_bytes": ram_check_timing,
            "fits": ram_check_fw.is_none_or(|v| v <= RAM_BYTES) && ram_check_timing <= RAM_BYTES,
        },
        "timing_firmware": { "flash_bytes": timing_mem.flash_bytes, "static_ram_bytes": timing_mem.static_ram_bytes },
        "sweep": sweep.iter().map(|s| json!({
            "population": s.population, "points_per_row": s.grid, "points_per_individual": s.points_per_individual,
            "frames": s.generations,
            "min": s.call.min.round(), "max": s.call.max.round(), "ratio_max_min": (s.call.ratio() * 1e4).round() / 1e4,
            "evaluate_max": s.evaluate.max.round(), "feedforward_max": s.feedforward.max.round(), "breed_max": s.breed.max.round(),
            "instructions_per_point_eval": round2(s.per_point.max),
        })).collect::<Vec<_>>(),
        "cycle_estimate_168mhz": {
            "label": "ESTIMATE (not a measurement): measured worst-case instruction count x per-class worst-case Cortex-M4 cycle costs",
            "cycles_per_generation": cyc.cycles.round(),
            "microseconds_per_generation": round1(cyc.microseconds),
            "evaluate_cycles": cyc_eval.cycles.round(),
            "cycles_per_generation_if_branches_cost_2": cyc_b2.cycles.round(),
            "microseconds_per_generation_if_branches_cost_2": round1(cyc_b2.microseconds),
            "point_cycles_per_point": round2(mix.point.cycles),
            "point_instructions_static": round2(mix.point.instructions),
            "point_windows": mix.windows,
            "rest_cycles_per_instruction": round2(mix.rest.cpi()),
            "point_mix": mix.point.classes.iter().map(|(k, v)| ((*k).to_owned(), json!(round2(*v)))).collect::<serde_json::Map<_, _>>(),
            "rest_mix": mix.rest.classes.iter().map(|(k, v)| ((*k).to_owned(), json!(v.round()))).collect::<serde_json::Map<_, _>>(),
            "assumptions": assumptions(),
        },
        "measurement": {
            "qemu": "qemu-system-arm -cpu cortex-m4 -machine mps2-an386 -icount shift=10 (1 instruction = 1024 ns virtual)",
            "timer": format!("CMSDK APB TIMER0 @ 0x40000000, SYSCLK 25 MHz ({NS_PER_TICK} ns/tick): instructions = ticks * 40 / 1024"),
            "timer_read_pair_ticks": m.read_pair_ticks,
            "timer_read_instructions": round2(read_ins),
            "window": "instructions_per_generation = the whole Tracker::step_probed call (input checks, 4 probe marks of ~4 instructions each included); phases between probe marks",
            "timing_image": timing_elf.display().to_string(),
            "firmware_image": firmware_elf.display().to_string(),
        },
    });
    let json_path = out.join("timing.json");
    crate::io::write_json(&json_path, &json)?;

    let md = markdown(
        &fs_,
        &sweep,
        &stack,
        stack_prologue.as_ref(),
        &mix,
        [&cyc, &cyc_b2],
        marginal,
        fw_mem,
        timing_mem,
        demo_stack,
        read_ins,
    );
    let md_path = out.join("timing.md");
    crate::io::write_bytes(&md_path, md.as_bytes())?;
    println!(
        "instructions per generation (P = {}, G = {}): min {:.0}, max {:.0} (max/min {:.4}); {:.2} per point; stack {} B; \
         flash {} B; static RAM {} B; ESTIMATE {:.0} cycles = {:.0} µs at 168 MHz",
        fs_.population,
        fs_.grid,
        fs_.call.min,
        fs_.call.max,
        fs_.call.ratio(),
        instr_per_point,
        stack_bytes,
        fw_mem.flash_bytes,
        fw_mem.static_ram_bytes,
        cyc.cycles,
        cyc.microseconds
    );
    println!("wrote {} and {}", json_path.display(), md_path.display());
    Ok(())
}

fn assumptions() -> Vec<&'static str> {
    vec![
        "Cortex-M4F at 168 MHz, zero-wait-state memory for code and data (an STM32F4 needs its ART accelerator hits and SRAM; flash wait states are not modelled)",
        "per-class worst-case costs from the Cortex-M4 TRM: ALU/IT 1, MUL/UMULL/UMLAL 1, MLA/MLS 2, SDIV/UDIV 12, LDR/STR 2, LDRD/STRD 3, LDM/STM/PUSH/POP 1+N (+3 if PC is loaded), every branch 1+P with P = 3 (pipeline refill, conditional branches counted as taken), VADD/VSUB/VMUL/VCVT/VMOV/VCMP 1, VMLA/VMLS 3, VDIV.F32/VSQRT.F32 14, VLDR/VSTR 2, VLDM/VSTM/VPUSH/VPOP 1+N words",
        "instruction mix: sample points = measured points x the mean static mix of one point (the instructions between consecutive vdiv.f32 in the unrolled fitness kernel camera_counts, both arms of the bounds test included); every other measured instruction x the cycles per instruction of the static mix of all other code reachable from the generation function (llvm-objdump)",
        "no interrupts, no DMA contention, FPU lazy stacking not triggered",
    ]
}

#[allow(clippy::too_many_arguments)]
fn markdown(
    full: &RunStats,
    sweep: &[RunStats],
    stack: &StackAnalysis,
    stack_prologue: Option<&StackAnalysis>,
    mix: &MixAnalysis,
    [cyc, cyc_b2]: [&CycleEstimate; 2],
    marginal: Option<f64>,
    fw: MemoryUse,
    timing: MemoryUse,
    demo_stack: Option<(u32, u32)>,
    read_ins: f64,
) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# Worst-case timing and memory of one GA generation (Cortex-M4, QEMU `-icount shift=10`)\n");
    let _ = writeln!(
        s,
        "Default configuration: population {}, {} points per row ({} sample points per individual, both cameras), \
         160×120 frames, feedforward on. {} generations on frames made on the board: every kind below, one tracker \
         running through all of them. Instructions are counted with TIMER0 on QEMU's instruction clock \
         (`ticks · 40 / 1024`, deterministic); a generation is the whole `Tracker::step_probed` call.\n",
        full.population, full.grid, full.points_per_individual, full.generations
    );
    let _ = writeln!(s, "| quantity | min | max | mean | target |\n|---|---:|---:|---:|---|");
    let row = |s: &mut String, name: &str, r: &Range, target: &str| {
        let _ = writeln!(s, "| {name} | {:.0} | {:.0} | {:.0} | {target} |", r.min, r.max, r.mean);
    };
    row(&mut s, "instructions per generation", &full.call, &format!("≤ {GENERATION_BUDGET:.0}"));
    row(&mut s, "— feedforward", &full.feedforward, "");
    row(&mut s, "— projection + fitness (Evaluate)", &full.evaluate, "");
    row(&mut s, "— selection/crossover/mutation (Breed)", &full.breed, "");
    let _ = writeln!(
        s,
        "| instructions per point evaluation (Evaluate / ({} · {})) | {:.2} | {:.2} | {:.2} | ≤ {POINT_TARGET} |",
        full.population, full.points_per_individual, full.per_point.min, full.per_point.max, full.per_point.mean
    );
    let _ = writeln!(s);
    let verdict = if full.call.max <= GENERATION_BUDGET {
        "within budget".to_owned()
    } else {
        format!("**over budget by {:.1} %**", (full.call.max / GENERATION_BUDGET - 1.0) * 100.0)
    };
    let _ = writeln!(
        s,
        "- max/min over the frames: **{:.4}** (target ≤ {RATIO_TARGET}); worst case {:.0} instructions: {verdict}.",
        full.call.ratio(),
        full.call.max
    );
    let _ = writeln!(
        s,
        "- per point: the Evaluate phase divided by the points; it includes the per-pose overhead (ψ → rotation, two \
         projectors, face choice and visibility, row starts, the GA's best-of bookkeeping). Marginal cost of a point \
         (Evaluate at 8 minus 4 points per row, population 40): {}.",
        marginal.map_or("n/a".to_owned(), |v| format!("{v:.2} instructions"))
    );
    let _ = writeln!(
        s,
        "- one TIMER0 read costs {read_ins:.2} instructions; the 4 probe marks add ≈ 16 to a generation.\n"
    );
    let _ = writeln!(
        s,
        "## By kind of frame (whole call, instructions)\n\n| frames | n | min | max |\n|---|---:|---:|---:|"
    );
    for (k, n, r) in &full.by_kind {
        let _ = writeln!(s, "| {} | {n} | {:.0} | {:.0} |", k.name(), r.min, r.max);
    }
    let _ = writeln!(
        s,
        "\n## Sweep: population × points per row ({} frames each, every kind)\n\n\
         | population | points/row | points/individual | min | max | max/min | Evaluate max | per point (max) |\n\
         |---:|---:|---:|---:|---:|---:|---:|---:|",
        sweep.first().map_or(0, |r| r.generations)
    );
    for r in sweep {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.0} | {:.0} | {:.4} | {:.0} | {:.2} |",
            r.population,
            r.grid,
            r.points_per_individual,
            r.call.min,
            r.call.max,
            r.call.ratio(),
            r.evaluate.max,
            r.per_point.max
        );
    }
    let _ = writeln!(
        s,
        "\n## Cycle ESTIMATE for a 168 MHz Cortex-M4F (not a measurement)\n\n\
         **≈ {:.0} cycles = {:.0} µs per worst-case generation** ({:.0} cycles in the {} sample points at {:.1} cycles \
         each, {:.0} in the rest at {:.2} cycles per instruction).\n",
        cyc.cycles,
        cyc.microseconds,
        cyc.point_cycles,
        full.population * full.points_per_individual,
        mix.point.cycles,
        cyc.rest_cycles,
        mix.rest.cpi()
    );
    let _ = writeln!(
        s,
        "Sensitivity: with every branch at 2 cycles instead of 4 (a 1-cycle refill), {:.0} cycles = {:.0} µs.\n",
        cyc_b2.cycles, cyc_b2.microseconds
    );
    let _ = writeln!(
        s,
        "One sample point ({} windows between `vdiv.f32` in the fitness kernel; {:.1} static instructions per point):\n",
        mix.windows, mix.point.instructions
    );
    let _ = writeln!(s, "| class (worst-case cycles) | instructions per point |\n|---|---:|");
    for (k, v) in &mix.point.classes {
        let _ = writeln!(s, "| {k} | {v:.2} |");
    }
    let _ = writeln!(s, "\nAssumptions:\n");
    for a in assumptions() {
        let _ = writeln!(s, "- {a}");
    }
    let _ = writeln!(s, "\n## Stack and memory\n");
    let _ = writeln!(s, "| quantity | bytes | how |\n|---|---:|---|");
    let _ = writeln!(
        s,
        "| static worst case, one generation (below the generation function) | {} | {} |",
        stack.generation.bytes, stack.method
    );
    let _ = writeln!(s, "| static worst case, `Reset` → generation | {} | same, deepest caller path |", stack.total());
    if let Some(p) = stack_prologue {
        let _ = writeln!(s, "| same from the prologues of the measured image | {} | cross-check |", p.total());
    }
    let _ = writeln!(
        s,
        "| painted high-water mark, one generation (max over the run) | {} | stack re-painted before each generation |",
        full.stack
    );
    if let Some((u, sz)) = demo_stack {
        let _ = writeln!(
            s,
            "| firmware painted high-water mark (demo, 30 frames, incl. tracker construction) | {u} | of a {sz}-byte stack region |"
        );
    }
    let _ = writeln!(
        s,
        "| firmware flash (`.vector_table + .text + .rodata + .data`) | {} | ELF section headers |",
        fw.flash_bytes
    );
    let _ = writeln!(
        s,
        "| firmware static RAM (`.data + .bss + .uninit`) | {} | ELF section headers |",
        fw.static_ram_bytes
    );
    if let Some((u, _)) = demo_stack {
        let total = fw.static_ram_bytes + u64::from(u);
        let _ = writeln!(s, "| firmware static RAM + painted stack | {total} | of {RAM_BYTES} (memory.x) |");
    }
    let _ = writeln!(
        s,
        "| timing firmware flash / static RAM (9 trackers) | {} / {} | ELF section headers |",
        timing.flash_bytes, timing.static_ram_bytes
    );
    let _ = writeln!(
        s,
        "\nIndirect calls reachable from the generation: {}; recursion: {}.\n\nDeepest static path:\n",
        stack.indirect_calls,
        if stack.recursion { "yes (bound void)" } else { "none" }
    );
    for (name, frame) in stack.callers.frames.iter().chain(stack.generation.frames.iter()) {
        let _ = writeln!(s, "- {frame:>6} B  `{name}`");
    }
    let _ = writeln!(
        s,
        "\nReproduce: `{BUILD_HINT}` (and optionally `{STACK_SIZES_HINT}`), then \
         `cargo run --release -p evorec-sim -- timing --out DIR`."
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn disassembly_parses_functions_calls_and_prologues() {
        let text = "\n00001000 <foo>:\n    1000:      \tpush\t{r4, r5, r7, lr}\n    1002:      \tvpush\t{d8, d9}\n    \
                    1006:      \tsub\tsp, #0x20\n    1008:      \tbl\t0x2000 <bar> @ imm = #4084\n    100c:      \tblx\tr3\n\
                    00001010 <$d>:\n    1010: 00 00 00 00  \t.word\t0x00000000\n\
                    00002000 <bar>:\n    2000:      \tmovw\tr12, #4200\n    2004:      \tsub.w\tsp, sp, r12\n    2008:      \tb.w\t0x1000 <foo>\n";
        let f = parse_disassembly(text);
        assert_eq!(f.len(), 2);
        assert_eq!(prologue_frame(&f[0]), 16 + 16 + 32);
        assert_eq!(prologue_frame(&f[1]), 4200);
        let c = call_graph(&f);
        assert!(c[0].direct.contains(&1) && c[0].indirect == 1);
        assert!(c[1].direct.contains(&0));
        let g = Graph { funcs: &f, calls: c, frame: vec![64, 4200] };
        let mut rec = false;
        let p = g.deepest(0, &mut HashMap::new(), &mut Vec::new(), &mut rec);
        assert!(rec);
        assert_eq!(p.bytes, 4264);
    }

    #[test]
    fn classes_and_costs() {
        let i = |m: &str, o: &str| Insn { mnemonic: m.to_owned(), operands: o.to_owned() };
        assert_eq!(classify(&i("vdiv.f32", "s0, s1, s2")).1, 14);
        assert_eq!(classify(&i("vmla.f32", "s0, s1, s2")).1, 3);
        assert_eq!(classify(&i("ldrb.w", "r1, [r11, r2]")).1, 2);
        assert_eq!(classify(&i("bhs", "0x67cc <$t+0x1d4>")).1, 4);
        assert_eq!(classify(&i("pop", "{r4, r5, pc}")).1, 7);
        assert_eq!(classify(&i("umlal", "r2, r4, r3, r6")).1, 1);
        assert_eq!(classify(&i("adds", "r2, r1, r0")).1, 1);
    }

    #[test]
    fn output_is_parsed() {
        let text = "EVOREC-TIMING v1\nCALIBRATION read_pair=25\nRUN name=full p=40 g=8 frames=1 points_per_camera=480 width=160 height=120\n\
                    GEN p=40 g=8 k=0 kind=blank call=2048 ff=1024 eval=512 breed=256 stack=4000 fitness=0\nEND ok\n";
        let m = parse_output(text).unwrap();
        assert_eq!(m.read_pair_ticks, 25);
        let s = m.runs[0].stats();
        assert_eq!(s.call.max, 80.0);
        assert_eq!(s.points_per_individual, 960);
        assert!(parse_output("EVOREC-TIMING v1\nEND failed\n").is_err());
        assert!(parse_output("hello\n").is_err());
        assert_eq!(painted_stack("[INFO ] stack high-water mark: 13892 of 90000 bytes"), Some((13892, 90000)));
    }
}
