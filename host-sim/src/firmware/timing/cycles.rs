//! Instruction mix and the cycle ESTIMATE (never a measurement) for the board's part (a
//! 168 MHz Cortex-M4F or a 480 MHz Cortex-M7, see [`Board`]).

use std::collections::BTreeMap;
use std::fs;
use std::path::Path;

use anyhow::{Context, Result, anyhow};

use super::disasm::{Graph, Insn, call_graph, classify, disassemble, is_default_generation};
use super::elf::FlashImage;
use super::flash::{self, HotLoop, Waits};
use super::profile::{Board, MemorySystem};

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
    /// The mix of one sample point: the instructions between consecutive pixel loads (one per
    /// point, see `is_pixel_load`) of the fitness kernel's integer walk (`walk_edge`,
    /// unrolled rows), averaged over those windows.
    pub point: Mix,
    /// Number of point windows found.
    pub windows: usize,
    /// Static mix of every other instruction reachable from the generation function.
    pub rest: Mix,
    /// Flash wait-state inputs of one sample point (averaged over the windows).
    pub point_waits: Waits,
    /// Flash wait-state inputs of the rest (totals over its static instructions).
    pub rest_waits: Waits,
    /// The point windows' code span and whether it fits the ART instruction cache.
    pub hot: HotLoop,
}

/// One sample point's pixel load in the fitness kernel's walk: the RGB565 walk's halfword load
/// through a register index scaled by 2 (`ldrh rT, [rPixels, rIndex, lsl #1]`, unconditional:
/// a point outside the image reads pixel 0), or the predicated byte/halfword load of a walk
/// that skips the load outside the image (`ldrblo`/`ldrhlo`).
pub(super) fn is_pixel_load(i: &Insn) -> bool {
    let m = i.mnemonic.as_str();
    m.starts_with("ldrblo")
        || m.starts_with("ldrhlo")
        || (m.trim_end_matches(".w") == "ldrh" && i.operands.replace(' ', "").ends_with(",lsl#1]"))
}

/// The point and rest mixes of the generation in `elf`, flash and caches as in `mem`.
pub(super) fn analyse_mix(objdump: &Path, elf: &Path, mem: &MemorySystem) -> Result<MixAnalysis> {
    let funcs = disassemble(objdump, elf)?;
    let image = FlashImage::new(fs::read(elf).with_context(|| format!("reading {}", elf.display()))?)?;
    let g = Graph { funcs: &funcs, calls: call_graph(&funcs), frame: Vec::new() };
    let root =
        g.find(is_default_generation).ok_or_else(|| anyhow!("no P40G8 generation function in {}", elf.display()))?;
    let reach = g.reachable(root);
    let kernel = reach
        .iter()
        .copied()
        .find(|&f| funcs.get(f).is_some_and(|x| x.name.contains("walk_edge")))
        .ok_or_else(|| anyhow!("no fitness walk_edge reachable from the generation in {}", elf.display()))?;
    // Windows from one point's pixel load to the next (a point each), where the row is
    // unrolled; the row and edge bookkeeping makes the longer windows, left out below.
    let kf = funcs.get(kernel).ok_or_else(|| anyhow!("kernel index"))?;
    let divs: Vec<usize> = kf.insns.iter().enumerate().filter(|(_, (_, i))| is_pixel_load(i)).map(|(k, _)| k).collect();
    let mut gaps: Vec<usize> = divs.windows(2).map(|w| w[1] - w[0]).collect();
    gaps.sort_unstable();
    let median = gaps.get(gaps.len() / 2).copied().unwrap_or(0);
    let mut in_window = vec![false; kf.insns.len()];
    let kernel_loads = flash::loads(kf, &image);
    let mut point = Mix::default();
    let mut point_waits = Waits::default();
    let (mut lo, mut hi) = (u32::MAX, 0u32);
    let mut windows = 0usize;
    for w in divs.windows(2) {
        let (a, b) = (w[0], w[1]);
        if b - a <= median + median / 4 {
            windows += 1;
            let window = kf.insns.get(a..b).unwrap_or_default();
            point_waits.add_line_stalls(window, mem);
            lo = lo.min(window.first().map_or(u32::MAX, |x| x.0));
            hi = hi.max(kf.insns.get(b).map_or(0, |x| x.0));
            for k in a..b {
                if let Some((_, i)) = kf.insns.get(k) {
                    point.add(i, 1.0);
                    point_waits.add(i, kernel_loads.get(k).copied().unwrap_or(flash::Load::Other));
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
        point_waits = point_waits.scaled(n);
    }
    let mut rest = Mix::default();
    let mut rest_waits = Waits::default();
    for &f in &reach {
        let Some(func) = funcs.get(f) else { continue };
        let fl = flash::loads(func, &image);
        let outside = |k: usize| !(f == kernel && in_window.get(k).copied().unwrap_or(false));
        for (k, (_, i)) in func.insns.iter().enumerate().filter(|(k, _)| outside(*k)) {
            rest.add(i, 1.0);
            rest_waits.add(i, fl.get(k).copied().unwrap_or(flash::Load::Other));
        }
        rest_waits.add_line_stalls(func.insns.iter().enumerate().filter(|(k, _)| outside(*k)).map(|(_, x)| x), mem);
    }
    let hot = HotLoop::new(lo.min(hi), hi, mem);
    Ok(MixAnalysis { point, windows, rest, point_waits, rest_waits, hot })
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
    /// At the board's clock.
    pub microseconds: f64,
    /// Flash wait-state cycles of the sample points (data loads; code fetch unless the hot
    /// loop hits the ART instruction cache, then its cold misses per kernel call).
    pub flash_point_cycles: f64,
    /// Flash wait-state cycles of the rest (code misses and data loads at worst).
    pub flash_rest_cycles: f64,
    /// Worst case with flash wait states: `cycles + flash_point_cycles + flash_rest_cycles`.
    pub flash_cycles: f64,
    /// `flash_cycles` at the board's clock.
    pub flash_microseconds: f64,
    /// Sensitivity: the sample points' code missing the instruction cache too and every load of
    /// unknown provenance in them read from flash (µs at the board's clock).
    pub flash_uncached_microseconds: f64,
}

/// The estimate on `board` for `worst_instructions` of which `points` are sample points in
/// `calls` kernel calls (population × 2 cameras × 12 edges), every branch at `branch` cycles.
pub(super) fn estimate(
    board: &Board,
    mix: &MixAnalysis,
    worst_instructions: f64,
    points: f64,
    calls: f64,
    branch: f64,
) -> CycleEstimate {
    let mem = &board.memory;
    let cpi = |m: &Mix| if m.instructions > 0.0 { cycles_with_branch_cost(m, branch) / m.instructions } else { 0.0 };
    let point_ins = (points * mix.point.instructions).min(worst_instructions);
    let point_cycles = point_ins * cpi(&mix.point);
    let rest_ins = worst_instructions - point_ins;
    let rest_cycles = rest_ins * cpi(&mix.rest);
    let cycles = point_cycles + rest_cycles;
    let points_done = if mix.point.instructions > 0.0 { point_ins / mix.point.instructions } else { 0.0 };
    let flash_point_cycles = if mix.hot.cached {
        points_done * mix.point_waits.cycles_cached(false, mem) + calls * mix.hot.cold_cycles
    } else {
        points_done * mix.point_waits.cycles_uncached(false, mem)
    };
    let per_rest = if mix.rest.instructions > 0.0 {
        mix.rest_waits.cycles_uncached(true, mem) / mix.rest.instructions
    } else {
        0.0
    };
    let flash_rest_cycles = rest_ins * per_rest;
    let flash_cycles = cycles + flash_point_cycles + flash_rest_cycles;
    let uncached = cycles + points_done * mix.point_waits.cycles_uncached(true, mem) + flash_rest_cycles;
    let us = |c: f64| c / board.clock_hz * 1e6;
    CycleEstimate {
        point_cycles,
        rest_cycles,
        cycles,
        microseconds: us(cycles),
        flash_point_cycles,
        flash_rest_cycles,
        flash_cycles,
        flash_microseconds: us(flash_cycles),
        flash_uncached_microseconds: us(uncached),
    }
}

/// The assumptions of the estimate, as stated in the report.
pub(super) fn assumptions(board: &Board) -> Vec<&'static str> {
    vec![
        board.pipeline,
        "the zero-wait-state figure assumes every code and data access at 0 wait states, the flash figure adds the wait states of the model below",
        "per-class worst-case costs from the Cortex-M4 TRM: ALU/IT 1, MUL/UMULL/UMLAL 1, MLA/MLS 2, SDIV/UDIV 12, LDR/STR 2, LDRD/STRD 3, LDM/STM/PUSH/POP 1+N (+3 if PC is loaded), every branch 1+P (P = 3 on the M4: pipeline refill, conditional branches counted as taken; the board's branch cost above replaces it), VADD/VSUB/VMUL/VCVT/VMOV/VCMP 1, VMLA/VMLS 3, VDIV.F32/VSQRT.F32 14, VLDR/VSTR 2, VLDM/VSTM/VPUSH/VPOP 1+N words",
        "instruction mix: sample points = measured points x the mean static mix of one point (the instructions between consecutive pixel loads in the unrolled integer walk of the fitness kernel, walk_edge (the RGB565 walk's ldrh [pixels, index, lsl #1], one per point, or a predicated ldrblo/ldrhlo); the per-row perspective divisions are in the rest); every other measured instruction x the cycles per instruction of the static mix of all other code reachable from the generation function (llvm-objdump)",
        "no interrupts, no DMA contention, FPU lazy stacking not triggered",
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pixel_loads_of_the_walk() {
        let i = |m: &str, o: &str| Insn { mnemonic: m.to_owned(), operands: o.to_owned(), comment_addr: None };
        assert!(is_pixel_load(&i("ldrh.w", "r4, [lr, r4, lsl #1]")));
        assert!(is_pixel_load(&i("ldrhlo.w", "r3, [r3, r6, lsl #1]")));
        assert!(is_pixel_load(&i("ldrblo", "r3, [r5, r2]")));
        // The hue table and plane loads, and other halfword loads, are not.
        assert!(!is_pixel_load(&i("ldrb.w", "r0, [r8, r0]")));
        assert!(!is_pixel_load(&i("ldrh", "r4, [r0, #10]")));
        assert!(!is_pixel_load(&i("ldrh.w", "r4, [r0, r1]")));
    }
}
