//! Flash wait states behind the part's caches, added to the per-class cycle estimate; the part
//! is a [`MemorySystem`] (STM32F4 at 168 MHz behind its ART accelerator: 5 wait states, 16-byte
//! lines, 1 KiB instruction cache; STM32H743 at 480 MHz behind the Cortex-M7's L1 caches).
//!
//! The model, per instruction of the disassembly (each item a worst case unless it says so;
//! `W` = [`MemorySystem::miss_cycles`]):
//! - **data from flash**: a load whose address is in flash (a PC-relative literal, a `tbb`/`tbh`
//!   table, or a load through a register holding a flash address: set by `movw`/`movt`, `adr`
//!   or a literal load, tracked forward through the function) misses the data cache: +W;
//! - **branches**: every branch (conditional ones counted as taken, as in the class model)
//!   lands on a line that misses the instruction cache: +W;
//! - **sequential fetch**: the prefetch has the next line after W + 1 cycles; a line whose
//!   instructions execute in fewer cycles stalls for the difference;
//! - **hot loop**: when the fitness kernel's unrolled point code spans at most the
//!   instruction cache, it hits after its first pass: its branches and lines cost nothing
//!   extra, except one miss per line per kernel call (the rest of the generation may evict it).

use std::collections::HashMap;

use super::disasm::{Function, Insn, classify};
use super::elf::FlashImage;
use super::profile::MemorySystem;

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
    /// Sequential-fetch stall cycles (lines executing in fewer than `W + 1` cycles).
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
    pub(super) fn add_line_stalls<'a>(&mut self, insns: impl IntoIterator<Item = &'a (u32, Insn)>, mem: &MemorySystem) {
        let mut lines: HashMap<u32, f64> = HashMap::new();
        for (addr, i) in insns {
            *lines.entry(addr / mem.line_bytes).or_default() += f64::from(classify(i).1);
        }
        self.fetch_stall += lines.values().map(|c| (mem.miss_cycles + 1.0 - c).max(0.0)).sum::<f64>();
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
    pub fn cycles_uncached(&self, other_as_flash: bool, mem: &MemorySystem) -> f64 {
        self.cycles_cached(other_as_flash, mem) + mem.miss_cycles * self.branches + self.fetch_stall
    }

    /// Extra cycles when the code hits the instruction cache: data from flash only.
    pub fn cycles_cached(&self, other_as_flash: bool, mem: &MemorySystem) -> f64 {
        let other = if other_as_flash { self.other_loads } else { 0.0 };
        mem.miss_cycles * (self.flash_loads + other)
    }
}

/// Whether the hot loop fits the instruction cache, and its cold misses per kernel call.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HotLoop {
    /// Bytes from the first to the last point window of the kernel.
    pub span_bytes: u32,
    /// `span_bytes ≤` [`MemorySystem::icache_bytes`].
    pub cached: bool,
    /// Cycles of refilling the loop's lines once (one kernel call).
    pub cold_cycles: f64,
}

impl HotLoop {
    /// The hot loop spanning `start..end` in the memory system `mem`.
    pub fn new(start: u32, end: u32, mem: &MemorySystem) -> Self {
        let span_bytes = end.saturating_sub(start);
        Self {
            span_bytes,
            cached: span_bytes <= mem.icache_bytes,
            cold_cycles: f64::from(span_bytes.div_ceil(mem.line_bytes)) * mem.miss_cycles,
        }
    }
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
        let f4 = MemorySystem::STM32F4;
        w.add_line_stalls(&code.insns, &f4);
        assert_eq!(w.fetch_stall, 0.0);
        let mut w = Waits::default();
        w.add_line_stalls(&code.insns[..2], &f4);
        assert_eq!(w.fetch_stall, 4.0);
        assert!(HotLoop::new(0x100, 0x500, &f4).cached && !HotLoop::new(0x100, 0x501, &f4).cached);
        assert_eq!(HotLoop::new(0, 32, &f4).cold_cycles, 10.0);
        // The M7's 32-byte lines at +9: two instructions of one line stall for 8 cycles.
        let h7 = MemorySystem::STM32H7;
        let mut w = Waits::default();
        w.add_line_stalls(&code.insns[..2], &h7);
        assert_eq!(w.fetch_stall, 8.0);
        assert!(HotLoop::new(0, 4096, &h7).cached);
        assert_eq!(HotLoop::new(0, 64, &h7).cold_cycles, 18.0);
    }
}
