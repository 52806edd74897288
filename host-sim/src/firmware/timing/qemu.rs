//! Finding the images and tools, running QEMU, and parsing the timing firmware's output.

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, anyhow, bail};
use evorec_firmware::timing::{BANNER, DEADLINE_TICKS, DeadlineReport, GenLine, ICOUNT_SHIFT, ticks_to_instructions};

use super::profile::Board;
use super::{LLVM_HINT, QEMU_HINT, QEMU_TIMEOUT, TARGET, TIMING_ELF_ENV, TIMING_IMAGE};

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Target directories searched for the firmware of `board`: `$CARGO_TARGET_DIR` (relative to
/// the workspace root), then the workspace's `target/`; each with the board's subdirectory
/// (`m7/` for the M7).
fn target_dirs(board: &Board) -> Vec<PathBuf> {
    let ws = workspace();
    let mut dirs = Vec::new();
    if let Some(dir) = std::env::var_os("CARGO_TARGET_DIR") {
        dirs.push(ws.join(dir));
    }
    let default = ws.join("target");
    if !dirs.contains(&default) {
        dirs.push(default);
    }
    match board.target_subdir {
        Some(sub) => dirs.into_iter().map(|d| d.join(sub)).collect(),
        None => dirs,
    }
}

/// The release image `name` of `board` built in `hil-stubs/` (on the M4, `$EVOREC_TIMING_ELF`
/// for the timing image and `$EVOREC_FIRMWARE_ELF` for the firmware, if set).
///
/// # Errors
/// The image does not exist; the message says how to build it.
pub fn find_image(board: &Board, name: &str) -> Result<PathBuf> {
    let env = if name == TIMING_IMAGE { TIMING_ELF_ENV } else { evorec_firmware::host::FIRMWARE_ENV };
    let build_hint = board.build_hint;
    if let Some(p) = std::env::var_os(env).filter(|_| *board == Board::M4) {
        let p = PathBuf::from(p);
        if p.is_file() {
            return Ok(p);
        }
        bail!("{env}={} does not exist: build the firmware with `{build_hint}`", p.display());
    }
    let candidates: Vec<PathBuf> =
        target_dirs(board).into_iter().map(|d| d.join(TARGET).join("release").join(name)).collect();
    if let Some(p) = candidates.iter().find(|p| p.is_file()) {
        return Ok(p.clone());
    }
    let list: Vec<String> = candidates.iter().map(|p| p.display().to_string()).collect();
    bail!(
        "firmware image `{name}` not found (looked at {}): build it with `{build_hint}` \
         (needs `rustup target add {TARGET}`), or point {env} at it",
        list.join(", ")
    )
}

/// The sources an image is built from: `core/` and `hil-stubs/` (their `src/` and manifests),
/// the firmware's build script, the memory map (`memory.x`, both profiles), and the lock file.
fn image_sources() -> Vec<PathBuf> {
    let ws = workspace();
    let mut roots = vec![ws.join("Cargo.lock"), ws.join("memory.x")];
    for krate in ["core", "hil-stubs"] {
        roots.push(ws.join(krate).join("src"));
        roots.push(ws.join(krate).join("Cargo.toml"));
    }
    roots.push(ws.join("hil-stubs").join("build.rs"));
    roots
}

/// The newest file under `roots` (files or directories, walked recursively) modified after
/// `image` was written, if any: a sign that `image` was built from older sources.
pub fn newer_source(image: &Path, roots: &[PathBuf]) -> Option<PathBuf> {
    let built = fs::metadata(image).and_then(|m| m.modified()).ok()?;
    let mut newest: Option<(std::time::SystemTime, PathBuf)> = None;
    let mut stack: Vec<PathBuf> = roots.to_vec();
    while let Some(path) = stack.pop() {
        let Ok(meta) = fs::metadata(&path) else { continue };
        if meta.is_dir() {
            if let Ok(entries) = fs::read_dir(&path) {
                stack.extend(entries.flatten().map(|e| e.path()));
            }
        } else if let Ok(t) = meta.modified()
            && t > built
            && newest.as_ref().is_none_or(|(n, _)| t > *n)
        {
            newest = Some((t, path));
        }
    }
    newest.map(|(_, p)| p)
}

/// Warns (on stderr) when `image` is older than a source it is built from: `evorec timing`
/// builds nothing, so a stale image would be measured without a word.
pub fn warn_if_stale(board: &Board, image: &Path) {
    if let Some(src) = newer_source(image, &image_sources()) {
        eprintln!(
            "timing: warning: {} is older than {} (changed after the build): the numbers are the old \
             code's; rebuild with `{}`",
            image.display(),
            src.display(),
            board.build_hint
        );
    }
}

/// The `.stack_sizes` build of image `name` by [`STACK_SIZES_HINT`](super::STACK_SIZES_HINT), if it exists.
pub fn find_stack_sizes_image(board: &Board, name: &str) -> Option<PathBuf> {
    target_dirs(board)
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

/// Runs `elf` on QEMU as `board`'s machine (mps2-an386 or mps2-an500; with `-icount
/// shift=`[`ICOUNT_SHIFT`] if `icount`) in `workdir`, its output to `workdir/log_name`, and
/// returns that output.
///
/// # Errors
/// QEMU could not start, timed out or exited with failure (the log's end is in the message).
pub fn run_qemu(
    qemu: &Path,
    board: &Board,
    elf: &Path,
    workdir: &Path,
    log_name: &str,
    icount: bool,
) -> Result<String> {
    fs::create_dir_all(workdir).with_context(|| format!("creating {}", workdir.display()))?;
    let log_path = workdir.join(log_name);
    let log = fs::File::create(&log_path).with_context(|| format!("creating {}", log_path.display()))?;
    let mut cmd = Command::new(qemu);
    cmd.args(board.qemu_machine())
        .args(["-nographic", "-monitor", "none"])
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
    /// Population size in use.
    pub population: u32,
    /// Population capacity of the tracker type (`cap=`; the population when absent).
    pub capacity: u32,
    /// Points per row.
    pub grid: u32,
    /// Sample points per camera and pose in the model (`SurfaceStrips::POINTS_PER_CAMERA`,
    /// 60 · G: the convention of the per-point targets).
    pub points_per_camera: u32,
    /// Sample points the kernel walks per camera and pose (`SurfaceStrips::WALKED_PER_CAMERA`,
    /// 48 · G: outer rows only on the silhouette edges; `points_per_camera` when the line has
    /// no `walked_per_camera=`).
    pub walked_per_camera: u32,
    /// Frame size the firmware ran at (`width=`, `height=`; 0 when absent).
    pub frame: (u32, u32),
    /// Every measured generation.
    pub generations: Vec<GenLine>,
    /// The firmware's deadline check of this run (its `DEADLINE` line).
    pub deadline: DeadlineReport,
}

/// Everything the timing firmware printed.
#[derive(Debug, Clone)]
pub struct Measurement {
    /// Ticks between two back-to-back TIMER0 reads (one read's cost).
    pub read_pair_ticks: u32,
    /// The runs in order.
    pub runs: Vec<Run>,
    /// The firmware's `DEADLINE-MISSED k=… call=…` lines, as printed.
    pub missed_lines: Vec<String>,
}

/// The deadline checks of some runs: the watchdog-style limit of one generation
/// ([`DEADLINE_TICKS`], 10⁶ instructions) against every measured generation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DeadlineSummary {
    /// Generations checked by the firmware.
    pub checked: u32,
    /// Generations over the limit.
    pub missed: u32,
    /// The limit (instructions).
    pub limit_instructions: f64,
    /// The longest generation of any run (instructions).
    pub worst_instructions: f64,
}

impl Measurement {
    /// The deadline checks of the runs called `name` (`full`: the default configuration, whose
    /// budget the deadline is; `sweep`: the other configurations, some over budget on purpose).
    pub fn deadlines(&self, name: &str) -> DeadlineSummary {
        let runs = || self.runs.iter().filter(|r| r.name == name);
        let sum = |f: fn(&DeadlineReport) -> u32| runs().map(|r| f(&r.deadline)).sum();
        let worst = runs().map(|r| r.deadline.worst).max().unwrap_or(0);
        DeadlineSummary {
            checked: sum(|d| d.checked),
            missed: sum(|d| d.missed),
            limit_instructions: ticks_to_instructions(u64::from(DEADLINE_TICKS)),
            worst_instructions: ticks_to_instructions(u64::from(worst)),
        }
    }
}

/// Parses the timing firmware's output.
///
/// # Errors
/// The banner or the final `END ok` is missing, or a `GEN` line comes before any `RUN`.
pub fn parse_output(text: &str) -> Result<Measurement> {
    if !text.lines().any(|l| l.trim() == BANNER) {
        bail!("not the output of the timing firmware (no `{BANNER}` line)");
    }
    let mut m = Measurement { read_pair_ticks: 0, runs: Vec::new(), missed_lines: Vec::new() };
    // Runs whose `DEADLINE` line has been read.
    let mut checked_runs = 0;
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
                capacity: num("cap").or_else(|_| num("p"))?,
                grid: num("g")?,
                points_per_camera: num("points_per_camera")?,
                walked_per_camera: num("walked_per_camera").or_else(|_| num("points_per_camera"))?,
                frame: (num("width").unwrap_or(0), num("height").unwrap_or(0)),
                generations: Vec::new(),
                deadline: DeadlineReport::default(),
            });
        } else if line.starts_with("GEN ") {
            let g = GenLine::parse(line).ok_or_else(|| anyhow!("malformed line `{line}`"))?;
            m.runs.last_mut().ok_or_else(|| anyhow!("GEN before RUN"))?.generations.push(g);
        } else if line.starts_with("DEADLINE-MISSED") {
            m.missed_lines.push(line.to_owned());
        } else if line.starts_with("DEADLINE ") {
            let d = DeadlineReport::parse(line).ok_or_else(|| anyhow!("malformed line `{line}`"))?;
            let run = m.runs.last_mut().ok_or_else(|| anyhow!("DEADLINE before RUN"))?;
            if d.checked as usize != run.generations.len() {
                bail!("`{line}` checked {} generations, the run printed {}", d.checked, run.generations.len());
            }
            run.deadline = d;
            checked_runs += 1;
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
    if checked_runs != m.runs.len() {
        bail!(
            "the timing firmware printed {} `DEADLINE` lines for {} runs (rebuild it: `{}`)",
            checked_runs,
            m.runs.len(),
            super::Board::M4.build_hint
        );
    }
    Ok(m)
}

/// Runs the timing image `elf` of `board` under QEMU (log in `workdir/timing-firmware.log`)
/// and parses it.
///
/// # Errors
/// As [`run_qemu`] and [`parse_output`].
pub fn measure(qemu: &Path, board: &Board, elf: &Path, workdir: &Path) -> Result<Measurement> {
    parse_output(&run_qemu(qemu, board, elf, workdir, "timing-firmware.log", true)?)
}

/// Parses `stack high-water mark: N of M bytes` from the firmware's log.
pub(super) fn painted_stack(log: &str) -> Option<(u32, u32)> {
    let line = log.lines().rev().find(|l| l.contains("stack high-water mark:"))?;
    let rest = line.split("stack high-water mark:").nth(1)?;
    let mut words = rest.split_whitespace();
    let used = words.next()?.parse().ok()?;
    let size = words.nth(1)?.parse().ok()?;
    Some((used, size))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn output_is_parsed() {
        let text = "EVOREC-TIMING v1\nCALIBRATION read_pair=25\nRUN name=full p=40 g=8 frames=1 points_per_camera=480 width=160 height=120\n\
                    GEN p=40 g=8 k=0 kind=blank status=lost method=ff tshift=0 call=2048 ff=1024 eval=512 breed=256 stack=4000 fitness=0\n\
                    DEADLINE limit=25600000 checked=1 missed=0 worst=2048\nEND ok\n";
        let m = parse_output(text).unwrap();
        assert_eq!(m.read_pair_ticks, 25);
        let s = m.runs[0].stats();
        assert_eq!(s.call.max, 80.0);
        assert_eq!(m.runs[0].frame, (160, 120));
        assert_eq!(s.points_per_individual, 960);
        assert_eq!(s.walked_per_individual, 960, "no walked_per_camera= means every model point is walked");
        let walked = text.replace("points_per_camera=480", "points_per_camera=480 walked_per_camera=384");
        let s = parse_output(&walked).unwrap().runs[0].stats();
        assert_eq!((s.points_per_individual, s.walked_per_individual), (960, 768));
        assert_eq!(s.per_point.max * 960.0, s.per_walked_point.max * 768.0);
        assert_eq!((s.population, s.capacity), (40, 40), "no cap= means the population is the capacity");
        let with_cap = text.replace("RUN name=full p=40", "RUN name=full p=40 cap=64");
        assert_eq!(parse_output(&with_cap).unwrap().runs[0].stats().capacity, 64);
        assert!(parse_output("EVOREC-TIMING v1\nEND failed\n").is_err());
        assert!(parse_output("hello\n").is_err());
        let d = m.deadlines("full");
        assert_eq!((d.checked, d.missed, d.worst_instructions, d.limit_instructions), (1, 0, 80.0, 1.0e6));
        // A run without its deadline check, or a check of another number of generations.
        assert!(parse_output(&text.replace("DEADLINE limit=25600000 checked=1 missed=0 worst=2048\n", "")).is_err());
        assert!(parse_output(&text.replace("checked=1", "checked=2")).is_err());
        assert_eq!(painted_stack("[INFO ] stack high-water mark: 13892 of 90000 bytes"), Some((13892, 90000)));
    }

    #[test]
    fn missed_deadlines_are_counted() {
        let text = "EVOREC-TIMING v1\nCALIBRATION read_pair=25\nRUN name=full p=40 g=8 frames=2 points_per_camera=480\n\
                    GEN p=40 g=8 k=0 kind=blank status=lost method=ff tshift=0 call=2048 ff=1024 eval=512 breed=256 stack=4000 fitness=0\n\
                    DEADLINE-MISSED k=1 call=25600001\n\
                    GEN p=40 g=8 k=1 kind=blank status=lost method=ff tshift=0 call=25600001 ff=1024 eval=512 breed=256 stack=4000 fitness=0\n\
                    DEADLINE limit=25600000 checked=2 missed=1 worst=25600001\nEND ok\n";
        let m = parse_output(text).unwrap();
        assert_eq!(m.deadlines("full").missed, 1);
        assert!(m.deadlines("full").worst_instructions > 1.0e6);
        assert_eq!(m.deadlines("sweep").checked, 0);
        assert_eq!(m.missed_lines, ["DEADLINE-MISSED k=1 call=25600001"]);
    }

    #[test]
    fn target_shifts_of_the_ff_target_run_are_counted() {
        let text = "EVOREC-TIMING v1\nCALIBRATION read_pair=25\nRUN name=target method=ff+target p=40 g=8 frames=3 points_per_camera=480\n\
                    GEN p=40 g=8 k=0 kind=conveyor status=tracking method=ff+target tshift=0 call=2048 ff=1024 eval=512 breed=256 stack=4000 fitness=0.9\n\
                    GEN p=40 g=8 k=1 kind=conveyor status=tracking method=ff+target tshift=1 call=4096 ff=1024 eval=512 breed=256 stack=4000 fitness=0.9\n\
                    GEN p=40 g=8 k=2 kind=conveyor status=tracking method=ff+target tshift=1 call=3072 ff=1024 eval=512 breed=256 stack=4000 fitness=0.9\n\
                    DEADLINE limit=25600000 checked=3 missed=0 worst=4096\nEND ok\n";
        let m = parse_output(text).unwrap();
        assert_eq!(m.runs[0].name, "target");
        let s = m.runs[0].stats();
        assert_eq!(s.target_shifts, 2);
        let c = s.target_shift_call.unwrap();
        assert_eq!((c.min, c.max), (120.0, 160.0));
        assert_eq!(m.deadlines("target").checked, 3);
        // Without a shifted generation there is no range.
        assert_eq!(
            parse_output(&text.replace("tshift=1", "tshift=0")).unwrap().runs[0].stats().target_shift_call,
            None
        );
    }

    #[test]
    fn a_source_changed_after_the_image_is_reported() {
        let dir = tempfile::tempdir().unwrap();
        let (image, src) = (dir.path().join("image.elf"), dir.path().join("src"));
        fs::create_dir(&src).unwrap();
        let (old, new) = (src.join("old.rs"), src.join("new.rs"));
        for f in [&image, &old, &new] {
            fs::write(f, "x").unwrap();
        }
        let t0 = std::time::SystemTime::UNIX_EPOCH + Duration::from_secs(1_000_000);
        let at = |f: &Path, s: u64| {
            fs::File::options().write(true).open(f).unwrap().set_modified(t0 + Duration::from_secs(s)).unwrap()
        };
        at(&old, 0);
        at(&image, 10);
        at(&new, 20);
        let roots = [src.clone(), dir.path().join("missing")];
        assert_eq!(newer_source(&image, &roots), Some(new.clone()));
        // Built after every source: nothing to report.
        at(&image, 30);
        assert_eq!(newer_source(&image, &roots), None);
        // A missing image is not stale (find_image reports it).
        assert_eq!(newer_source(&dir.path().join("none.elf"), &roots), None);
    }
}
