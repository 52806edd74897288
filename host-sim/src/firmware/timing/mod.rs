//! `evorec timing --out DIR [--profile m4|m7]`: worst-case instructions, stack and memory of one
//! GA generation on the board (the Cortex-M4 profile at 160×120, or the Cortex-M7 profile at
//! 320×240, see [`Board`]), measured under QEMU, and a cycle estimate for its part (a 168 MHz
//! STM32F4 or a 480 MHz STM32H743).
//!
//! What it does (it builds nothing; a missing image or tool is reported with the command that
//! provides it):
//! 1. runs the timing firmware (`evorec-timing`, see `hil-stubs/src/bin/evorec-timing.rs`)
//!    under `qemu-system-arm -machine mps2-an386 -icount shift=10` (`mps2-an500` for the M7,
//!    whose image is the same code built with feature `m7`). The firmware makes its
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
//!    measurement) for the board's part with per-class worst-case cycle costs and its flash
//!    wait states behind its caches;
//! 5. writes `DIR/timing.json`, `DIR/timing.md` and the raw QEMU logs.

mod cycles;
mod disasm;
mod elf;
mod flash;
mod profile;
mod qemu;
mod report;
mod stack;
mod stats;

use std::fs;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, anyhow, bail};
use evorec_firmware::timing::ICOUNT_SHIFT;

pub use cycles::{CycleEstimate, Mix, MixAnalysis};
pub use elf::MemoryUse;
pub use flash::{HotLoop, Waits};
pub use profile::{Board, MemorySystem};
pub use qemu::{
    DeadlineSummary, Measurement, Run, find_image, find_llvm_tool, find_qemu, find_stack_sizes_image, measure,
    parse_output, run_qemu,
};
pub use stack::{StackAnalysis, StackPath};
pub use stats::{Range, RunStats};

use cycles::{analyse_mix, estimate};
use elf::{memory_use, sections};
use qemu::painted_stack;
use stack::analyse_stack;

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
/// Longest a QEMU run may take.
pub const QEMU_TIMEOUT: Duration = Duration::from_secs(600);
/// The target triple of the firmware.
const TARGET: &str = "thumbv7em-none-eabihf";
/// Start of RAM on mps2-an386 and mps2-an500 (`memory.x`, both profiles).
const RAM_ORIGIN: u64 = 0x2000_0000;

/// Everything one `evorec timing` run measured and derived; the report writers' input.
struct Results {
    /// The board measured.
    board: Board,
    /// The default configuration's long run.
    full: RunStats,
    /// The default configuration's run with the target's motion fed forward too (`ff+target`;
    /// `None` for a firmware without it).
    target: Option<RunStats>,
    /// Cycle estimate of the worst `ff+target` generation.
    cyc_target: Option<CycleEstimate>,
    /// The firmware's deadline checks of the `ff+target` run.
    deadline_target: DeadlineSummary,
    /// The sweep over population × points per row (empty on the M7).
    sweep: Vec<RunStats>,
    /// Ticks of two back-to-back TIMER0 reads.
    read_pair_ticks: u32,
    /// Static stack of one generation (`.stack_sizes` if available).
    stack: StackAnalysis,
    /// The same from the prologues of the measured image, when `stack` used `.stack_sizes`.
    stack_prologue: Option<StackAnalysis>,
    /// Instruction mix of the generation's code.
    mix: MixAnalysis,
    /// Cycle estimate of the worst generation.
    cyc: CycleEstimate,
    /// Cycle estimate of the worst Evaluate phase.
    cyc_eval: CycleEstimate,
    /// Cycle estimate with 2-cycle branches.
    cyc_b2: CycleEstimate,
    /// Marginal instructions of one more sample point.
    marginal: Option<f64>,
    /// Flash and static RAM of the firmware.
    fw_mem: MemoryUse,
    /// Flash and static RAM of the timing firmware.
    timing_mem: MemoryUse,
    /// The firmware demo's painted stack (used, region size).
    demo_stack: Option<(u32, u32)>,
    /// The firmware's per-generation deadline checks of the default configuration.
    deadline: DeadlineSummary,
    /// The same for the sweep's configurations (informational: some are over budget).
    deadline_sweep: DeadlineSummary,
    /// The timing image measured.
    timing_elf: PathBuf,
    /// The firmware image measured.
    firmware_elf: PathBuf,
}

/// `evorec timing --out DIR --profile NAME` on `board`: see the module docs.
///
/// # Errors
/// A missing image, QEMU or llvm-objdump (the message says how to get it), a failed QEMU
/// run, or an output file that cannot be written.
pub fn run(out: &Path, board: Board) -> Result<()> {
    let timing_elf = find_image(&board, TIMING_IMAGE)?;
    let firmware_elf = find_image(&board, FIRMWARE_IMAGE)?;
    for image in [&timing_elf, &firmware_elf] {
        qemu::warn_if_stale(&board, image);
    }
    let qemu = find_qemu()?;
    let objdump = find_llvm_tool("llvm-objdump")?;
    fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;

    eprintln!("timing: running {} under QEMU -icount shift={ICOUNT_SHIFT}", timing_elf.display());
    let started = Instant::now();
    let m = measure(&qemu, &board, &timing_elf, out)?;
    eprintln!("timing: {} runs measured in {:.1} s", m.runs.len(), started.elapsed().as_secs_f64());
    let full = m.runs.iter().find(|r| r.name == "full").ok_or_else(|| anyhow!("no full run in the output"))?;
    check_frame(full, &board, &timing_elf)?;
    let full = full.stats();
    let target = m.runs.iter().find(|r| r.name == "target").map(Run::stats);
    let sweep: Vec<RunStats> = m.runs.iter().filter(|r| r.name == "sweep").map(Run::stats).collect();

    // The normal firmware's demo (no FIFOs in its working directory): painted stack of 30
    // frames including the tracker's construction.
    let demo_dir = out.join("firmware-demo");
    let _ = fs::remove_dir_all(&demo_dir);
    let demo_log = run_qemu(&qemu, &board, &firmware_elf, &demo_dir, "firmware.log", false)?;
    let demo_stack = painted_stack(&demo_log);

    let fw_mem = memory_use(&sections(&fs::read(&firmware_elf)?)?);
    let timing_mem = memory_use(&sections(&fs::read(&timing_elf)?)?);

    let (stack, stack_prologue) = stack_analyses(&objdump, &board, &timing_elf)?;
    let mix = analyse_mix(&objdump, &timing_elf, &board.memory)?;
    // The points the kernel walks (the cycle model's point mix is one walked point).
    let points = f64::from(full.population) * f64::from(full.walked_per_individual);
    // Kernel calls whose hot loop may start cold in the ART cache: the integer walk
    // (`walk_edge`) runs once per edge, 3 faces x 4 edges per camera, with the per-row float
    // code (larger than the cache) in between.
    let calls = 2.0 * f64::from(full.population) * 12.0;
    let cyc = estimate(&board, &mix, full.call.max, points, calls, board.branch_cycles);
    let cyc_eval = estimate(&board, &mix, full.evaluate.max, points, calls, board.branch_cycles);
    // Sensitivity: every branch at 2 cycles (taken with a 1-cycle refill; not-taken ones cost 1).
    let cyc_b2 = estimate(&board, &mix, full.call.max, points, calls, 2.0);
    let cyc_target = target.as_ref().map(|t| estimate(&board, &mix, t.call.max, points, calls, board.branch_cycles));
    let marginal = marginal(&full, &sweep);

    let r = Results {
        board,
        full,
        target,
        cyc_target,
        deadline_target: m.deadlines("target"),
        sweep,
        read_pair_ticks: m.read_pair_ticks,
        stack,
        stack_prologue,
        mix,
        cyc,
        cyc_eval,
        cyc_b2,
        marginal,
        fw_mem,
        timing_mem,
        demo_stack,
        deadline: m.deadlines("full"),
        deadline_sweep: m.deadlines("sweep"),
        timing_elf,
        firmware_elf,
    };
    let json_path = out.join("timing.json");
    crate::output::io::write_json(&json_path, &report::json(&r))?;
    let md_path = out.join("timing.md");
    crate::output::io::write_bytes(&md_path, report::markdown(&r).as_bytes())?;
    println!("{}", report::summary(&r));
    println!("wrote {} and {}", json_path.display(), md_path.display());
    check_deadlines(&r, &m.missed_lines)
}

/// The timing image must have run at the profile's frame size.
fn check_frame(full: &Run, board: &Board, timing_elf: &Path) -> Result<()> {
    let frame = (u32::from(board.profile.frame_width), u32::from(board.profile.frame_height));
    if full.frame != frame {
        bail!(
            "{} ran at {}×{}, not the {} profile's {}: build it with `{}`",
            timing_elf.display(),
            full.frame.0,
            full.frame.1,
            board.profile.name,
            board.frame_size(),
            board.build_hint
        );
    }
    Ok(())
}

/// The static stack of the measured image: from its `.stack_sizes` build when that is not older
/// than the image (then the prologue analysis too, as a cross-check), else from its prologues.
fn stack_analyses(objdump: &Path, board: &Board, timing_elf: &Path) -> Result<(StackAnalysis, Option<StackAnalysis>)> {
    // The `.stack_sizes` build is used only if it is not older than the measured image.
    let modified = |p: &Path| fs::metadata(p).and_then(|m| m.modified()).ok();
    let stack_image = find_stack_sizes_image(board, TIMING_IMAGE).filter(|p| {
        let fresh = modified(p) >= modified(timing_elf);
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
    let stack = analyse_stack(objdump, stack_image.as_deref().unwrap_or(timing_elf))?;
    let stack_prologue = match &stack_image {
        Some(_) => Some(analyse_stack(objdump, timing_elf)?),
        None => None,
    };
    Ok((stack, stack_prologue))
}

/// An error naming every generation of the default configuration (`ff` and `ff+target`) over
/// the firmware's deadline.
fn check_deadlines(r: &Results, missed_lines: &[String]) -> Result<()> {
    let (missed, checked) =
        (r.deadline.missed + r.deadline_target.missed, r.deadline.checked + r.deadline_target.checked);
    if missed > 0 {
        bail!(
            "{} of {} generations of the default configuration (ff and ff+target) missed the deadline of {:.0} \
             instructions (worst {:.0}): {}",
            missed,
            checked,
            r.deadline.limit_instructions,
            r.deadline.worst_instructions.max(r.deadline_target.worst_instructions),
            missed_lines.join("; ")
        );
    }
    Ok(())
}

/// Marginal instructions of one more model point per row: Evaluate (mean) at 8 minus 4 points
/// per row, population 40 (rows of 8 are the `full` run, rows of 4 a sweep run), over the
/// 2 · 60 · 4 model points (2 · 48 · 4 walked ones: × 1.25 per walked point). `None` without
/// the sweep (the M7 profile).
fn marginal(full: &RunStats, sweep: &[RunStats]) -> Option<f64> {
    let eval_at = |g: u32| {
        std::iter::once(full).chain(sweep).find(|s| s.population == 40 && s.grid == g).map(|s| s.evaluate.mean)
    };
    Some((eval_at(8)? - eval_at(4)?) / (40.0 * 2.0 * 60.0 * 4.0))
}
