#!/usr/bin/env python3
"""Compares two scripts/paper_seeds.py tables cell by cell: the median over the seeds of each
RMS entry in NEW against OLD, their ratio, and the entries whose ratio exceeds LIMIT (issue 9:
1.10 against the older tree; issue 12: 1.05 for FF + target against FF). Prints markdown.

NEW may hold a subset of OLD's cells (a screen with paper_seeds.py --cells); every cell of NEW
must be in OLD.

usage: scripts/compare_seeds.py NEW.csv OLD.csv [LIMIT]
"""
import csv, statistics, sys

KEYS = ['x_mm', 'y_mm', 'z_mm', 'e1', 'e2', 'e3']


def load(path):
    cells = {}
    for r in csv.DictReader(open(path)):
        cells.setdefault((r['motion'], float(r['omega'])), []).append(r)
    return cells


def main():
    if len(sys.argv) not in (3, 4):
        raise SystemExit(__doc__)
    new, old = load(sys.argv[1]), load(sys.argv[2])
    limit = float(sys.argv[3]) if len(sys.argv) == 4 else 1.10
    missing = sorted(set(new) - set(old))
    if missing:
        raise SystemExit(f'cells of {sys.argv[1]} not in {sys.argv[2]}: {missing}')
    over = 0
    print('| motion | ω | seeds | RMS x mm | RMS y mm | RMS z mm | RMS ε₁ | RMS ε₂ | RMS ε₃ |')
    print('|---|---|---|---|---|---|---|---|---|')
    for cell in sorted(new):
        entries = []
        for k in KEYS:
            a = statistics.median(float(r[k]) for r in new[cell])
            b = statistics.median(float(r[k]) for r in old[cell])
            ratio = a / b
            fmt = '{:.2f}' if k.endswith('mm') else '{:.4f}'
            mark = ' ✘' if ratio > limit else ''
            over += ratio > limit
            entries.append(f'{fmt.format(a)} / {fmt.format(b)} ({ratio:.2f}{mark})')
        print(f'| {cell[0]} | {cell[1]:g} | {len(new[cell])} / {len(old[cell])} | ' + ' | '.join(entries) + ' |')
    print(f'\n{over} of {len(KEYS) * len(new)} entries above {limit} (ratios of unrounded medians)')


if __name__ == '__main__':
    main()
