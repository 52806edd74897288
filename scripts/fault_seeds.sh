#!/usr/bin/env bash
# Link faults over GA seeds: for each GA seed N of scenarios/hil_motion_a_ff.toml,
# one fault-free `evorec run` and one `evorec hil --faults RATE --fault-seed N` (QEMU), then a
# CSV of both runs' summary.json per seed.
# Usage: scripts/fault_seeds.sh RATE FIRST LAST OUT   (e.g. 0.01 1 40 out/faults)
# Needs the release host binary and the firmware: `cargo build --release -p evorec-sim` and
# `(cd hil-stubs && cargo build --release)`. About 1.5-2 min per faulted run.
set -euo pipefail
cd "$(dirname "$0")/.."
rate=${1:?rate}; first=${2:?first seed}; last=${3:?last seed}; out=${4:?output dir}
bin="${CARGO_TARGET_DIR:-$PWD/target}/release/evorec"
mkdir -p "$out"
for n in $(seq "$first" "$last"); do
  sed "s/^seed = 1$/seed = $n/" scenarios/hil_motion_a_ff.toml > "$out/seed$n.toml"
  "$bin" run "$out/seed$n.toml" --out "$out/free$n" > "$out/free$n.log"
  "$bin" hil "$out/seed$n.toml" --faults "$rate" --fault-seed "$n" --out "$out/faults$n" > "$out/faults$n.log"
done
python3 - "$out" "$first" "$last" <<'PY'
import csv, json, sys
out, first, last = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
keys = ['F_mean', 'rms_x_mm', 'rms_y_mm', 'rms_z_mm', 'rms_e1', 'rms_e2', 'rms_e3']
with open(f'{out}/seeds.csv', 'w', newline='') as f:
    w = csv.writer(f)
    w.writerow(['ga_seed', 'run'] + keys + ['accepted'])
    for n in range(first, last + 1):
        for run, d in (('no faults', f'free{n}'), ('faults', f'faults{n}')):
            s = json.load(open(f'{out}/{d}/summary.json'))
            w.writerow([n, run] + [f'{s[k]:.5f}' for k in keys] + [s['frames']])
print(f'wrote {out}/seeds.csv')
PY
