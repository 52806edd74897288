//! Static worst-case stack of one generation: frame sizes from `.stack_sizes` or the function
//! prologues, and the deepest path of the call graph.

use std::collections::HashMap;
use std::fs;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow};

use super::disasm::{Function, Graph, call_graph, disassemble, imm, is_default_generation, reg_count};
use super::elf::{sections, stack_sizes};

/// Frame bytes from a function's prologue: `push`/`stmdb sp!` (4 per register), `vpush` (4 per
/// s, 8 per d register) and `sub sp` (immediate, or a register set by `movw`/`movt`), up to
/// the first branch.
pub(super) fn prologue_frame(f: &Function) -> u32 {
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

impl Graph<'_> {
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
}

/// Static worst-case stack of the default configuration's generation in `elf`.
pub(super) fn analyse_stack(objdump: &Path, elf: &Path) -> Result<StackAnalysis> {
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
        g.find(is_default_generation).ok_or_else(|| anyhow!("no P40G8 generation function in {}", elf.display()))?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::firmware::timing::disasm::parse_disassembly;

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
}
