#!/usr/bin/env python3
"""Compares two `evorec paper --seeds` tables (cells_FIRST_LAST.csv) cell by cell, or two
`scripts/target_seeds.sh` tables (seeds.csv: one scene, shown as motion "–"): the median
over the seeds of each RMS entry in NEW against OLD, their ratio, and the entries whose ratio
exceeds LIMIT (e.g. 1.10 for a tree against an older one, 1.05 for FF + target against FF).
Prints markdown.

NEW and OLD may each be several tables joined with commas (e.g. seeds 1-20 and 21-40 run
separately); a cell's seeds are then pooled, and a seed that appears twice in one side is an
error. NEW may hold a subset of OLD's cells (a screen with --cells); every cell
of NEW must be in OLD.

--ci adds, per entry, a 95 % bootstrap interval of the ratio of medians: the seeds present in
both sides are resampled together (the two methods of one seed share the scene's noise), 2000
resamples from a fixed seed, so the same tables give the same interval.

usage: scripts/compare_seeds.py NEW.csv[,NEW2.csv] OLD.csv[,OLD2.csv] [LIMIT] [--ci]

Requires: Python >= 3.8, standard library only.
"""
import csv, random, statistics, sys

KEYS = ['x_mm', 'y_mm', 'z_mm', 'e1', 'e2', 'e3']
RESAMPLES = 2000


def load(paths):
    cells = {}
    for path in paths.split(','):
        for r in csv.DictReader(open(path)):
            if 'motion' not in r:
                # A target_seeds.sh table: one scene, its entries named rms_x_mm, rms_e1, ...
                r = dict(r, motion='–', omega='0', **{k: r['rms_' + k] for k in KEYS})
            seeds = cells.setdefault((r['motion'], float(r['omega'])), {})
            seed = int(r['seed'])
            if seed in seeds:
                raise SystemExit(f'{path}: seed {seed} of cell {r["motion"]} {r["omega"]} is already in {paths}')
            seeds[seed] = r
    return cells


def ratio_ci(new, old, key, rng):
    """95 % bootstrap interval of median(new) / median(old) over the seeds both sides have."""
    seeds = sorted(set(new) & set(old))
    if len(seeds) < 2:
        return None
    ratios = []
    for _ in range(RESAMPLES):
        pick = [rng.choice(seeds) for _ in seeds]
        a = statistics.median(float(new[s][key]) for s in pick)
        b = statistics.median(float(old[s][key]) for s in pick)
        ratios.append(a / b)
    ratios.sort()
    return ratios[int(0.025 * RESAMPLES)], ratios[int(0.975 * RESAMPLES) - 1]


def main():
    args = [a for a in sys.argv[1:] if a != '--ci']
    with_ci = len(args) != len(sys.argv) - 1
    if len(args) not in (2, 3):
        raise SystemExit(__doc__)
    new, old = load(args[0]), load(args[1])
    limit = float(args[2]) if len(args) == 3 else 1.10
    missing = sorted(set(new) - set(old))
    if missing:
        raise SystemExit(f'cells of {args[0]} not in {args[1]}: {missing}')
    rng = random.Random(12)
    over = 0
    print('| motion | ω | seeds | RMS x mm | RMS y mm | RMS z mm | RMS ε₁ | RMS ε₂ | RMS ε₃ |')
    print('|---|---|---|---|---|---|---|---|---|')
    for cell in sorted(new):
        entries = []
        for k in KEYS:
            a = statistics.median(float(r[k]) for r in new[cell].values())
            b = statistics.median(float(r[k]) for r in old[cell].values())
            ratio = a / b
            fmt = '{:.2f}' if k.endswith('mm') else '{:.4f}'
            mark = ' ✘' if ratio > limit else ''
            over += ratio > limit
            ci = ratio_ci(new[cell], old[cell], k, rng) if with_ci else None
            ci_text = f', {ci[0]:.2f}–{ci[1]:.2f}' if ci else ''
            entries.append(f'{fmt.format(a)} / {fmt.format(b)} ({ratio:.2f}{mark}{ci_text})')
        print(f'| {cell[0]} | {cell[1]:g} | {len(new[cell])} / {len(old[cell])} | ' + ' | '.join(entries) + ' |')
    print(f'\n{over} of {len(KEYS) * len(new)} entries above {limit} (ratios of unrounded medians)')


if __name__ == '__main__':
    main()
