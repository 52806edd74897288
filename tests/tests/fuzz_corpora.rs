//! Replays every kept fuzz input — the corpora under `fuzz/corpus/<target>/` and the crash
//! inputs under `fuzz/artifacts/<target>/` — through the fuzz targets' bodies without
//! libFuzzer (the bodies are `fuzz/src/lib.rs`, included here), so every finding fixed once
//! stays fixed in `cargo test --workspace`. New inputs come from `scripts/fuzz.sh`.

use std::path::{Path, PathBuf};

#[allow(dead_code, missing_docs, clippy::all)]
#[path = "../../fuzz/src/lib.rs"]
mod bodies;

fn inputs(dir: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else { return Vec::new() };
    let mut files: Vec<PathBuf> = entries.filter_map(Result::ok).map(|e| e.path()).filter(|p| p.is_file()).collect();
    files.sort();
    files
}

#[test]
fn every_corpus_and_crash_input_passes() {
    let fuzz = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz");
    for (target, body) in bodies::TARGETS {
        let corpus = inputs(&fuzz.join("corpus").join(target));
        assert!(!corpus.is_empty(), "fuzz/corpus/{target}/ holds no inputs");
        let crashes = inputs(&fuzz.join("artifacts").join(target));
        for path in corpus.iter().chain(&crashes) {
            let data = std::fs::read(path).unwrap_or_else(|e| panic!("reading {}: {e}", path.display()));
            let outcome = std::panic::catch_unwind(|| body(&data));
            assert!(outcome.is_ok(), "fuzz target {target} fails on {}", path.display());
        }
    }
}

/// Mutated inputs per target in [`mutated_corpus_inputs_pass`]; `EVOREC_FUZZ_MUTATIONS` sets
/// another number (e.g. 100000 for a longer search without libFuzzer).
const MUTATIONS_PER_TARGET: usize = 4000;

/// A small deterministic generator (SplitMix64), so every run mutates the same way and a
/// failure names an input that can be made again.
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// A number in `0..n` (`n > 0`).
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

/// One libFuzzer-like mutation of `data`, `other` being a second corpus input to splice from:
/// a bit flip, an interesting byte, a byte inserted or removed, a chunk repeated, a cut, or a
/// splice.
fn mutate(rng: &mut SplitMix, data: &[u8], other: &[u8]) -> Vec<u8> {
    const INTERESTING: [u8; 8] = [0, 1, 0x7F, 0x80, 0xFF, b'\n', b'"', b'='];
    let mut out = data.to_vec();
    let kind = rng.below(7);
    if out.is_empty() {
        out.push(INTERESTING[rng.below(INTERESTING.len())]);
        return out;
    }
    let at = rng.below(out.len());
    match kind {
        0 => out[at] ^= 1 << rng.below(8),
        1 => out[at] = INTERESTING[rng.below(INTERESTING.len())],
        2 => out.insert(at, rng.next() as u8),
        3 => {
            out.remove(at);
        }
        4 => {
            let len = 1 + rng.below((out.len() - at).min(64));
            let chunk = out[at..at + len].to_vec();
            let to = rng.below(out.len() + 1);
            out.splice(to..to, chunk);
        }
        5 => out.truncate(at),
        _ => {
            let cut = rng.below(other.len() + 1);
            out.truncate(at);
            out.extend_from_slice(&other[cut..]);
        }
    }
    out
}

/// A cheap stand-in for fuzzing inside `cargo test`: every target's body gets a fixed number of
/// mutated corpus inputs (one to three mutations each). libFuzzer's coverage-guided search is
/// `scripts/fuzz.sh`; this catches a change that breaks on inputs near the kept ones.
#[test]
fn mutated_corpus_inputs_pass() {
    let count =
        std::env::var("EVOREC_FUZZ_MUTATIONS").ok().and_then(|v| v.parse().ok()).unwrap_or(MUTATIONS_PER_TARGET);
    let fuzz = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz");
    for (index, (target, body)) in bodies::TARGETS.iter().enumerate() {
        let corpus: Vec<Vec<u8>> = inputs(&fuzz.join("corpus").join(target))
            .iter()
            .map(|p| std::fs::read(p).unwrap_or_else(|e| panic!("reading {}: {e}", p.display())))
            .collect();
        assert!(!corpus.is_empty(), "fuzz/corpus/{target}/ holds no inputs");
        let mut rng = SplitMix(0xEB0_5EC0 + index as u64);
        for case in 0..count {
            let base = &corpus[rng.below(corpus.len())];
            let other = &corpus[rng.below(corpus.len())];
            let mut data = mutate(&mut rng, base, other);
            for _ in 0..rng.below(3) {
                data = mutate(&mut rng, &data, other);
            }
            let outcome = std::panic::catch_unwind(|| body(&data));
            if outcome.is_err() {
                let path = std::env::temp_dir().join(format!("evorec-fuzz-{target}-{case}"));
                let kept = std::fs::write(&path, &data).map(|()| path.display().to_string());
                panic!("fuzz target {target} fails on mutated input {case} (written to {kept:?})");
            }
        }
    }
}
