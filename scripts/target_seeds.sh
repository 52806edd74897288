#!/usr/bin/env bash
# One scenario over GA seeds (issue 31): `evorec run SCENARIO --seed N --out OUT/seed-N` for
# N = A..B, two runs at a time (the machine's 2 cores), each run's output in OUT/seed-N/run.log;
# then, from each run's summary.json, a table per seed: RMS x/y/z (mm), RMS ε₁/ε₂/ε₃ and of |ε|
# (the RMS of the rotation-error vector's norm), F̄, the frames reported as tracking and whether
# any frame was reported lost (with the lost frames' count), and the median over the seeds;
# also written as OUT/seeds.csv.
# Usage: scripts/target_seeds.sh SCENARIO A B OUT
#   e.g. scripts/target_seeds.sh scenarios/approach_ff_target.toml 1 10 out/approach
# Needs the release binary (`cargo build --release -p evorec-sim`); EVOREC=path overrides it.
set -euo pipefail
if [ $# -ne 4 ]; then
  sed -n '2,10p' "$0" | sed 's/^# \{0,1\}//' >&2
  exit 2
fi
scenario=$1; first=$2; last=$3; out=$4
case "$first$last" in *[!0-9]*) echo "target_seeds.sh: seeds A and B must be integers ≥ 0, got $first $last" >&2; exit 2;; esac
if [ "$first" -gt "$last" ]; then echo "target_seeds.sh: A ($first) must not exceed B ($last)" >&2; exit 2; fi
[ -f "$scenario" ] || { echo "target_seeds.sh: no scenario file $scenario" >&2; exit 2; }
root=$(cd "$(dirname "$0")/.." && pwd)
bin=${EVOREC:-${CARGO_TARGET_DIR:-$root/target}/release/evorec}
[ -x "$bin" ] || { echo "target_seeds.sh: no binary $bin (cargo build --release -p evorec-sim)" >&2; exit 2; }
mkdir -p "$out"

run_seed() {
  local n=$1 dir="$out/seed-$1"
  mkdir -p "$dir"
  if "$bin" run "$scenario" --seed "$n" --out "$dir" > "$dir/run.log" 2>&1; then
    echo "seed $n: $(head -n 1 "$dir/run.log")"
  else
    echo "seed $n FAILED (see $dir/run.log): $(tail -n 1 "$dir/run.log")" >&2
    return 1
  fi
}

# Two at a time: start a run whenever fewer than two are running; remember any failure.
failed=0
pids=()
for n in $(seq "$first" "$last"); do
  while [ "$(jobs -rp | wc -l)" -ge 2 ]; do wait -n || failed=1; done
  run_seed "$n" &
  pids+=("$!")
done
for pid in "${pids[@]}"; do wait "$pid" || failed=1; done
[ "$failed" -eq 0 ] || { echo "target_seeds.sh: some runs failed" >&2; exit 1; }

python3 - "$out" "$first" "$last" "$scenario" <<'PY'
import csv, json, math, statistics, sys

out, first, last, scenario = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
cols = ['x_mm', 'y_mm', 'z_mm', 'e1', 'e2', 'e3', 'eps', 'F_mean', 'tracking_pct']
rows = []
for n in range(first, last + 1):
    s = json.load(open(f'{out}/seed-{n}/summary.json'))
    st = s['status']
    frames = max(s['frames'], 1)
    eps = math.sqrt(s['rms_e1'] ** 2 + s['rms_e2'] ** 2 + s['rms_e3'] ** 2)
    values = [s['rms_x_mm'], s['rms_y_mm'], s['rms_z_mm'], s['rms_e1'], s['rms_e2'], s['rms_e3'], eps,
              s['F_mean'], 100.0 * st['tracking'] / frames]
    rows.append((n, values, st['lost']))

with open(f'{out}/seeds.csv', 'w', newline='') as f:
    w = csv.writer(f)
    w.writerow(['seed'] + ['rms_' + c if c not in ('F_mean', 'tracking_pct') else c for c in cols]
               + ['lost', 'lost_frames'])
    for n, v, lost in rows:
        w.writerow([n] + [f'{x:.6f}' for x in v] + [int(lost > 0), lost])

fmt = ['{:.2f}'] * 3 + ['{:.4f}'] * 4 + ['{:.4f}', '{:.0f} %']
print(f'\n{scenario}, GA seeds {first}-{last} (RMS over every frame; |ε|: RMS of the norm of (ε₁, ε₂, ε₃))\n')
print('| seed | RMS x mm | RMS y mm | RMS z mm | RMS ε₁ | RMS ε₂ | RMS ε₃ | RMS \\|ε\\| | F̄ | tracking | lost |')
print('|---|---|---|---|---|---|---|---|---|---|---|')
for n, v, lost in rows:
    cells = [f.format(x) for f, x in zip(fmt, v)]
    print(f'| {n} | ' + ' | '.join(cells) + f" | {'yes (%d frames)' % lost if lost else 'no'} |")
med = [statistics.median(v[i] for _, v, _ in rows) for i in range(len(cols))]
n_lost = sum(1 for *_, lost in rows if lost)
print(f'| median | ' + ' | '.join(f.format(x) for f, x in zip(fmt, med)) + f' | {n_lost} of {len(rows)} lost |')
print(f'\nwrote {out}/seeds.csv')
PY
