//! Disassembly of the firmware (`llvm-objdump`), its call graph, and the cycle cost of each
//! instruction class ([`classify`], shared by the class model and the flash model).

use std::collections::BTreeSet;
use std::path::Path;
use std::process::Command;

use anyhow::{Context, Result, bail};

use super::LLVM_HINT;

/// One disassembled instruction.
#[derive(Debug, Clone)]
pub(super) struct Insn {
    /// Mnemonic with its width suffix (`ldr.w`).
    pub(super) mnemonic: String,
    /// Operands, comments dropped.
    pub(super) operands: String,
    /// The address llvm-objdump's comment names (`@ 0x9334 <…>`: a PC-relative load's literal,
    /// an `adr`'s address), if any.
    pub(super) comment_addr: Option<u32>,
}

/// One function of the disassembly.
#[derive(Debug, Clone)]
pub(super) struct Function {
    /// Demangled name.
    pub(super) name: String,
    /// First address.
    pub(super) addr: u32,
    /// Address of the last instruction.
    pub(super) end: u32,
    /// Instructions with their addresses.
    pub(super) insns: Vec<(u32, Insn)>,
}

/// Parses `llvm-objdump -d --no-show-raw-insn` output into functions (ARM mapping symbols
/// `$t`, `$d` do not start a function; data words are dropped).
pub(super) fn parse_disassembly(text: &str) -> Vec<Function> {
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
        let mut halves = rest.splitn(2, " @ ");
        let rest = halves.next().unwrap_or("").trim();
        let comment_addr = halves.next().and_then(|c| {
            c.split_whitespace().next().and_then(|w| w.strip_prefix("0x")).and_then(|h| u32::from_str_radix(h, 16).ok())
        });
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
            f.insns.push((addr, Insn { mnemonic: mnemonic.to_owned(), operands: operands.to_owned(), comment_addr }));
            f.end = addr;
        }
    }
    funcs
}

/// Disassembles `elf` with demangled names.
pub(super) fn disassemble(objdump: &Path, elf: &Path) -> Result<Vec<Function>> {
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

/// Registers in a `{r4, r5-r7}` list.
pub(super) fn reg_count(list: &str) -> u32 {
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

/// An immediate `#12`, `#0x1f` or `12`.
pub(super) fn imm(s: &str) -> Option<u32> {
    let v = s.trim().trim_start_matches('#');
    match v.strip_prefix("0x") {
        Some(h) => u32::from_str_radix(h, 16).ok(),
        None => v.parse().ok(),
    }
}

/// Whether a mnemonic is a branch (calls and table branches included).
pub(super) fn is_branch(m: &str) -> bool {
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

/// The first hexadecimal address among the operands.
fn target_addr(operands: &str) -> Option<u32> {
    operands.split([' ', ',']).find_map(|w| w.strip_prefix("0x").and_then(|h| u32::from_str_radix(h, 16).ok()))
}

/// Calls out of each function: direct callees (`bl`, `blx #imm`, branches to another
/// function = tail calls) and the number of indirect calls (`blx rN`, `bx rN` other than `lr`).
#[derive(Debug, Clone, Default)]
pub(super) struct Calls {
    /// Indices of the direct callees.
    pub(super) direct: BTreeSet<usize>,
    /// Indirect calls.
    pub(super) indirect: u32,
}

/// The calls out of every function.
pub(super) fn call_graph(funcs: &[Function]) -> Vec<Calls> {
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

/// The call graph of a disassembly with each function's frame bytes.
pub(super) struct Graph<'a> {
    /// The functions.
    pub(super) funcs: &'a [Function],
    /// Calls out of each function.
    pub(super) calls: Vec<Calls>,
    /// Frame bytes of each function (empty when only the graph is needed).
    pub(super) frame: Vec<u32>,
}

impl Graph<'_> {
    /// The first function whose name satisfies `pred`.
    pub(super) fn find(&self, pred: impl Fn(&str) -> bool) -> Option<usize> {
        self.funcs.iter().position(|f| pred(&f.name))
    }

    /// Every function reachable from `root` (itself included).
    pub(super) fn reachable(&self, root: usize) -> BTreeSet<usize> {
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
pub(super) fn is_default_generation(name: &str) -> bool {
    name.contains("P40G8") && name.contains("generation")
}

/// Instruction classes with their worst-case Cortex-M4 cycle costs (Cortex-M4 TRM r0p1,
/// §3.3 "Processor instruction timings" and the FPU chapter's instruction timings), for
/// zero-wait-state memory; a taken branch refills the pipeline (1 + P, P ≤ 3).
pub(super) fn classify(i: &Insn) -> (&'static str, u32) {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classes_and_costs() {
        let i = |m: &str, o: &str| Insn { mnemonic: m.to_owned(), operands: o.to_owned(), comment_addr: None };
        assert_eq!(classify(&i("vdiv.f32", "s0, s1, s2")).1, 14);
        assert_eq!(classify(&i("vmla.f32", "s0, s1, s2")).1, 3);
        assert_eq!(classify(&i("ldrb.w", "r1, [r11, r2]")).1, 2);
        assert_eq!(classify(&i("bhs", "0x67cc <$t+0x1d4>")).1, 4);
        assert_eq!(classify(&i("pop", "{r4, r5, pc}")).1, 7);
        assert_eq!(classify(&i("umlal", "r2, r4, r3, r6")).1, 1);
        assert_eq!(classify(&i("adds", "r2, r1, r0")).1, 1);
    }
}
