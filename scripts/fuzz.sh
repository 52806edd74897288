#!/usr/bin/env bash
# Runs every fuzz target (fuzz/, cargo fuzz + libFuzzer) for SECONDS each (default 60).
#
#   scripts/fuzz.sh [SECONDS]        e.g. scripts/fuzz.sh 60
#   FUZZ_TARGETS="link_decode tracker_step" scripts/fuzz.sh 600   only these targets
#   FUZZ_MERGE=1 scripts/fuzz.sh 600  also merge the inputs that found new coverage, minimised
#                                     (libFuzzer -merge=1), into the kept corpus fuzz/corpus/<target>/
#
# The kept corpus is read as seeds; new inputs go to target/fuzz-corpus/<target>/ (not kept). A
# crash, hang (> 10 s per input) or out-of-memory (> 2 GiB) stops with a non-zero status and
# leaves the input in fuzz/artifacts/<target>/: commit it with the fix, and
# tests/tests/fuzz_corpora.rs replays it in `cargo test --workspace` from then on.
#
# Toolchain: cargo fuzz passes -Z flags to rustc, so it needs nightly. The script uses the
# `nightly` rustup toolchain (installing it if it can); where rustup refuses extra toolchains it
# falls back to the stable toolchain with RUSTC_BOOTSTRAP=1, which makes stable rustc accept
# -Z flags. Builds are optimised with debug assertions and overflow checks on (-O -a), without a
# sanitizer (-s none): the crates fuzzed have no `unsafe`, so ASan would only slow the search.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-60}"

if rustup toolchain list | grep -q '^nightly' || rustup toolchain install nightly --profile minimal; then
    toolchain=(+nightly)
else
    echo "fuzz.sh: no nightly toolchain; using stable with RUSTC_BOOTSTRAP=1" >&2
    export RUSTC_BOOTSTRAP=1
    toolchain=()
fi
command -v cargo-fuzz >/dev/null || cargo install cargo-fuzz --locked
if ! command -v c++ >/dev/null; then # libfuzzer-sys compiles libFuzzer (C++)
    if [ "$(id -u)" = 0 ]; then apt-get update && apt-get install -y g++; else
        echo "fuzz.sh: a C++ compiler is missing: sudo apt-get install -y g++" >&2
        exit 1
    fi
fi

targets="${FUZZ_TARGETS:-$(cargo "${toolchain[@]}" fuzz list)}"
flags=(-O -a -s none)
cargo "${toolchain[@]}" fuzz build "${flags[@]}"
work="${CARGO_TARGET_DIR:-$PWD/target}/fuzz-corpus"
summary=""
for t in $targets; do
    mkdir -p "$work/$t" "fuzz/corpus/$t"
    log="$work/$t.log"
    echo "== fuzz $t for ${seconds} s (log: $log)"
    if ! cargo "${toolchain[@]}" fuzz run "${flags[@]}" "$t" "$work/$t" "fuzz/corpus/$t" -- \
        -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len=4096 -print_final_stats=1 \
        >"$log" 2>&1; then
        tail -n 40 "$log"
        echo "fuzz.sh: target $t FAILED; the input is in fuzz/artifacts/$t/" >&2
        exit 1
    fi
    runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)
    rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -n 1)
    summary+="$(printf '%-16s %12s runs %8s exec/s' "$t" "$runs" "$rate")"$'\n'
    if [ "${FUZZ_MERGE:-0}" = 1 ]; then
        cargo "${toolchain[@]}" fuzz run "${flags[@]}" "$t" "fuzz/corpus/$t" "$work/$t" -- -merge=1 \
            >"$work/$t.merge.log" 2>&1
    fi
done
echo "== fuzz summary (${seconds} s per target, no findings)"
printf '%s' "$summary"
