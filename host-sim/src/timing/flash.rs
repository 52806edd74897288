//! Flash wait states of an STM32F4 at 168 MHz behind its ART accelerator, added to the
//! per-class cycle estimate.
//!
//! The part: 5 wait states at 168 MHz (RM0090, "Relation between CPU clock frequency and Flash
//! memory read time", 2.7–3.6 V), so a flash access that misses the ART takes 6 cycles instead
//! of 1. The ART has a 64-line instruction cache and an 8-line data cache of 128-bit lines and a
//! prefetch buffer that reads the next 128-bit line while the current one executes.
//!
//! The model, per instruction of the disassembly (each item a worst case unless it says so):
//! - **data from flash**: a load whose address is in flash (a PC-relative literal, a `tbb`/`tbh`
//!   table, or a load through a register holding a flash address: set by `movw`/`movt`, `adr`
//!   or a literal load, tracked forward through the function) misses the data cache: +5;
//! - **branches**: every branch (conditional ones counted as taken, as in the class model)
//!   lands on a line that misses the instruction cache: +5;
//! - **sequential fetch**: the prefetch buffer has the next line after 6 cycles; a line whose
//!   instructions execute in fewer cycles stalls for the difference;
//! - **hot loop**: when the fitness kernel's unrolled point code spans at most the 1 KiB
//!   instruction cache, it hits after its first pass: its branches and lines cost nothing
//!   extra, except one miss per line per kernel call (the rest of the generation may evict it).

use std::collections::HashMap;

use super::cycles::classify;
use super::disasm::{Function, Insn};
use super::elf::FlashImage;

/// Flash wait states at 168 MHz.
pub const WAIT_STATES: f64 = 5.0;
/// Bytes of one ART line (128 bits).
pub const LINE_BYTES: u32 = 16;
/// Bytes of the ART instruction cache (64 lines of 128 bits).
pub const ICACHE_BYTES: u32 = 1024;

/// What an instruction reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Load {
    /// Not a load.
    None,
    /// From the stack (RAM).
    Stack,
    /// From flash (literal pool, jump table, or through a register holding a flash address).
    Flash,
    /// Through a register of unknown provenance (RAM in the model; see the sensitivity).
    Other,
}

fn is_load(m: &str) -> bool {
    let m = m.trim_end_matches(".w").trim_end_matches(".n");
    m.starts_with("ldr")
        || m.starts_with("ldm")
        || m.starts_with("vldr")
        || m.starts_with("vldm")
        || m == "pop"
        || m == "vpop"
}

/// The register written by an instruction (its first operand), if it writes one.
fn written_register(i: &Insn) -> Option<&str> {
    let m = i.mnemonic.trim_end_matches(".w").trim_end_matches(".n");
    let no_dest =
        ["str", "stm", "push", "vstr", "vstm", "vpush", "cmp", "cmn", "tst", "teq", "it", "vcmp", "b", "cb", "tb"];
    if no_dest.iter().any(|p| m.starts_with(p))
        && !m.starts_with("bic")
        && !m.starts_with("bfi")
        && !m.starts_with("bfc")
    {
        return None;
    }
    i.operands.split(',').next().map(str::trim).filter(|r| !r.is_empty())
}

fn base_register(ops: &str) -> Option<&str> {
    ops.split_once('[').map(|(_, r)| r.split([',', ']']).next().unwrap_or("").trim())
}

fn imm(s: &str) -> Option<u32> {
    super::disasm::imm(s)
}

/// Classifies the loads of `f` by where they read (see the module docs).
pub(super) fn loads(f: &Function, flash: &FlashImage) -> Vec<Load> {
    let mut known: HashMap<String, u32> = HashMap::new();
    let mut out = Vec::with_capacity(f.insns.len());
    for (_, i) in &f.insns {
        let m = i.mnemonic.trim_end_matches(".w").trim_end_matches(".n");
        let ops: Vec<&str> = i.operands.split(',').map(str::trim).collect();
        let kind = if m == "tbb" || m == "tbh" {
            Load::Flash
        } else if !is_load(m) {
            Load::None
        } else if m == "pop" || m == "vpop" {
            Load::Stack
        } else {
            match base_register(&i.operands) {
                Some("pc") => Load::Flash,
                Some("sp") => Load::Stack,
                Some(r) if known.get(r).is_some_and(|&a| flash.contains(a)) => Load::Flash,
                Some(_) => Load::Other,
                None if m.starts_with("ldm") || m.starts_with("vldm") => {
                    let r = i.operands.split([',', '!']).next().unwrap_or("").trim();
                    if r == "sp" {
                        Load::Stack
                    } else if known.get(r).is_some_and(|&a| flash.contains(a)) {
                        Load::Flash
                    } else {
                        Load::Other
                    }
                }
                None => Load::Other,
            }
        };
        out.push(kind);
        // Track registers that hold a known address.
        let dest = written_register(i).map(str::to_owned);
        match (m, dest) {
            ("movw", Some(d)) => {
                if let Some(v) = ops.get(1).and_then(|v| imm(v)) {
                    known.insert(d, v);
                } else {
                    known.remove(&d);
                }
            }
            ("movt", Some(d)) => {
                let lo = known.get(&d).copied().unwrap_or(0) & 0xffff;
                match ops.get(1).and_then(|v| imm(v)) {
                    Some(v) => known.insert(d, lo | (v << 16)),
                    None => known.remove(&d),
                };
            }
            ("adr", Some(d)) => {
                match i.comment_addr {
                    Some(a) => known.insert(d, a),
                    None => known.remove(&d),
                };
            }
            ("ldr", Some(d)) if base_register(&i.operands) == Some("pc") => {
                match i.comment_addr.and_then(|a| flash.word(a)) {
                    Some(v) => known.insert(d, v),
                    None => known.remove(&d),
                };
            }
            (_, Some(d)) => {
                known.remove(&d);
            }
            _ => {}
        }
        if m == "bl" || m == "blx" {
            for r in ["r0", "r1", "r2", "r3", "r12"] {
                known.remove(r);
            }
        }
    }
    out
}

/// Wait-state inputs of a set of instructions (totals, or per point after averaging).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Waits {
    /// Loads from flash.
    pub flash_loads: f64,
    /// Loads through a register of unknown provenance.
    pub other_loads: f64,
    /// Branches.
    pub branches: f64,
    /// Sequential-fetch stall cycles (lines executing in fewer than 6 cycles).
    pub fetch_stall: f64,
}

impl Waits {
    /// Adds instruction `k` of `f` (with its load class) to the counts; line stalls are added
    /// separately by [`Waits::add_line_stalls`].
    pub(super) fn add(&mut self, i: &Insn, load: Load) {
        match load {
            Load::Flash => self.flash_loads += 1.0,
            Load::Other => self.other_loads += 1.0,
            Load::None | Load::Stack => {}
        }
        if super::disasm::is_branch(&i.mnemonic) {
            self.branches += 1.0;
        }
    }

    /// Adds the sequential-fetch stalls of the instructions `insns` (address order).
    pub(super) fn add_line_stalls<'a>(&mut self, insns: impl IntoIterator<Item = &'a (u32, Insn)>) {
        let mut lines: HashMap<u32, f64> = HashMap::new();
        for (addr, i) in insns {
            *lines.entry(addr / LINE_BYTES).or_default() += f64::from(classify(i).1);
        }
        self.fetch_stall += lines.values().map(|c| (WAIT_STATES + 1.0 - c).max(0.0)).sum::<f64>();
    }

    /// Divides every count by `n`.
    pub(super) fn scaled(self, n: f64) -> Self {
        Self {
            flash_loads: self.flash_loads / n,
            other_loads: self.other_loads / n,
            branches: self.branches / n,
            fetch_stall: self.fetch_stall / n,
        }
    }

    /// Extra cycles when the code misses the instruction cache: data from flash, every branch
    /// to a missing line, sequential stalls; `other_as_flash` also counts loads of unknown
    /// provenance as flash loads.
    pub fn cycles_uncached(&self, other_as_flash: bool) -> f64 {
        self.cycles_cached(other_as_flash) + WAIT_STATES * self.branches + self.fetch_stall
    }

    /// Extra cycles when the code hits the instruction cache: data from flash only.
    pub fn cycles_cached(&self, other_as_flash: bool) -> f64 {
        let other = if other_as_flash { self.other_loads } else { 0.0 };
        WAIT_STATES * (self.flash_loads + other)
    }
}

/// Whether the hot loop fits the ART instruction cache, and its cold misses per kernel call.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HotLoop {
    /// Bytes from the first to the last point window of the kernel.
    pub span_bytes: u32,
    /// `span_bytes ≤` [`ICACHE_BYTES`].
    pub cached: bool,
}

impl HotLoop {
    /// The hot loop spanning `start..end`.
    pub fn new(start: u32, end: u32) -> Self {
        let span_bytes = end.saturating_sub(start);
        Self { span_bytes, cached: span_bytes <= ICACHE_BYTES }
    }

    /// Cycles of refilling the loop's lines once (one kernel call).
    pub fn cold_cycles(&self) -> f64 {
        f64::from(self.span_bytes.div_ceil(LINE_BYTES)) * WAIT_STATES
    }
}

/// The assumptions of the wait-state model, as stated in the report.
pub(super) fn assumptions() -> Vec<&'static str> {
    vec![
        "flash: STM32F4 at 168 MHz with 5 wait states (RM0090, 2.7-3.6 V) behind the ART accelerator (64 x 128-bit instruction cache, 8 x 128-bit data cache, prefetch buffer): a flash access that misses the ART costs +5 cycles",
        "data: every load from flash misses the ART data cache (+5): PC-relative literals, tbb/tbh tables, and loads through a register holding a flash address (movw/movt, adr or a literal load, tracked forward through each function; e.g. constant tables in .rodata, the RGB565 -> hue table); the frames, the tracker and the stack are in SRAM (0 wait states)",
        "code outside the hot loop: every branch lands on a line that misses the instruction cache (+5); sequential fetch is covered by the prefetch buffer except a 16-byte line whose instructions execute in fewer than 6 cycles stalls for the difference; in the rest of the code, loads through registers of unknown provenance are counted as flash loads too",
        "hot loop (the sample points of the fitness kernel): if its unrolled code spans at most 1 KiB it hits the instruction cache after one miss per line per kernel call (population x 2 cameras calls per generation); otherwise it is costed like the rest of the code",
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn f(insns: &[(&str, &str, Option<u32>)]) -> Function {
        Function {
            name: "f".into(),
            addr: 0,
            end: 0,
            insns: insns
                .iter()
                .enumerate()
                .map(|(k, (m, o, c))| {
                    (2 * k as u32, Insn { mnemonic: (*m).into(), operands: (*o).into(), comment_addr: *c })
                })
                .collect(),
        }
    }

    #[test]
    fn loads_are_traced_to_flash() {
        let mut elf = FlashImage::default();
        elf.set_test_range(0x1000, 0x100);
        let code = f(&[
            ("movw", "r4, #0x1010", None),
            ("movt", "r4, #0x0", None),
            ("ldrb", "r0, [r4, r1]", None),
            ("ldr", "r2, [sp, #0x4]", None),
            ("ldrb.w", "r3, [r11, r2]", None),
            ("vldr", "s0, [pc, #8]", Some(0x20)),
            ("adds", "r4, #1", None),
            ("ldrb", "r0, [r4, r1]", None),
            ("pop", "{r4, pc}", None),
        ]);
        let l = loads(&code, &elf);
        assert_eq!(
            l,
            [
                Load::None,
                Load::None,
                Load::Flash,
                Load::Stack,
                Load::Other,
                Load::Flash,
                Load::None,
                Load::Other,
                Load::Stack
            ]
        );
    }

    #[test]
    fn line_stalls_and_hot_loop() {
        let mut w = Waits::default();
        let code = f(&[("adds", "r0, r1", None), ("adds", "r0, r1", None), ("vdiv.f32", "s0, s1, s2", None)]);
        w.add_line_stalls(&code.insns);
        assert_eq!(w.fetch_stall, 0.0);
        let mut w = Waits::default();
        w.add_line_stalls(&code.insns[..2]);
        assert_eq!(w.fetch_stall, 4.0);
        assert!(HotLoop::new(0x100, 0x500).cached && !HotLoop::new(0x100, 0x501).cached);
        assert_eq!(HotLoop::new(0, 32).cold_cycles(), 10.0);
    }
}
