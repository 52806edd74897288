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
