#!/usr/bin/env python3
"""The paper grid's FF cells over GA seeds, for checks of a change against another tree
(10 %) or of FF + target against FF (5 %).

A single seed cannot carry a 10 % comparison (the spread between seeds is about that), so each
cell (motion A at ω = 0, 0.125, 0.25, 0.5, 1 rad/s; motion B at 0.125 … 1, B at rest being A at
rest) is run once per GA seed with `evorec run S --out DIR`, S = the tree's
`scenarios/motion_{a,b}_ff.toml` with `seed = N`, the `[robot]` `omega_rad_s` set to the cell's
ω and, with --method, the scenario's method replaced. This reproduces `evorec paper`'s cell for
the same seed, and it works with the binary and scenarios of an older tree as well, which is
what the comparison needs. Writes OUT/cells_FIRST_LAST.csv (one row per cell and seed); runs
already in OUT are reused.

usage: scripts/paper_seeds.py EVOREC TREE OUT FIRST LAST [--method ff+target] [--jobs 2]
                              [--cells A:0,A:0.25]
e.g.   scripts/paper_seeds.py target/release/evorec . out/seeds-ff 1 20
(--cells runs only the listed cells, MOTION:OMEGA, for a quick screen of a change.)
"""
import argparse, json, os, re, subprocess
from concurrent.futures import ThreadPoolExecutor

CELLS = [('A', w) for w in (0, 0.125, 0.25, 0.5, 1)] + [('B', w) for w in (0.125, 0.25, 0.5, 1)]
KEYS = ('F_mean', 'rms_x_mm', 'rms_y_mm', 'rms_z_mm', 'rms_e1', 'rms_e2', 'rms_e3')


def scenario(tree, motion, omega, seed, method):
    text = open(f'{tree}/scenarios/motion_{motion.lower()}_ff.toml').read()
    text, n = re.subn(r'(?m)^seed = \d+$', f'seed = {seed}', text)
    if n != 1:
        raise SystemExit(f'{tree}/scenarios/motion_{motion.lower()}_ff.toml: no single `seed = N` line')
    if method:
        text, n = re.subn(r'(?m)^method = "ff"$', f'method = "{method}"', text)
        if n != 1:
            raise SystemExit(f'{tree}: the FF scenario has no `method = "ff"` line to replace')
    head, robot = text.split('\n[robot]\n', 1)
    robot, n = re.subn(r'(?m)^omega_rad_s = .*$', f'omega_rad_s = {omega}', robot, count=1)
    if n != 1:
        raise SystemExit(f'{tree}: [robot] has no omega_rad_s line')
    return head + '\n[robot]\n' + robot


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('evorec'), ap.add_argument('tree'), ap.add_argument('out')
    ap.add_argument('first', type=int), ap.add_argument('last', type=int)
    ap.add_argument('--method', help='replaces the scenarios\' method "ff" (e.g. ff+target)')
    ap.add_argument('--jobs', type=int, default=os.cpu_count() or 2)
    ap.add_argument('--cells', help='only these cells, e.g. A:0,A:0.25,B:1 (default: all nine)')
    a = ap.parse_args()
    cells = CELLS
    if a.cells:
        cells = []
        for item in a.cells.split(','):
            m, _, w = item.partition(':')
            try:
                cell = (m.strip().upper(), float(w))
            except ValueError:
                raise SystemExit(f'--cells: `{item}` is not MOTION:OMEGA (e.g. A:0.25)')
            known = [c for c in CELLS if c[0] == cell[0] and float(c[1]) == cell[1]]
            if not known:
                raise SystemExit(f'--cells: `{item}` is not a cell of the paper grid {CELLS}')
            cells.append(known[0])
    evorec = os.path.abspath(a.evorec)
    os.makedirs(a.out, exist_ok=True)

    def run(job):
        motion, omega, seed = job
        d = f'{a.out}/{motion}_{omega}_s{seed}'
        if not os.path.exists(f'{d}/summary.json'):
            os.makedirs(d, exist_ok=True)
            with open(f'{d}/scenario.toml', 'w') as f:
                f.write(scenario(a.tree, motion, omega, seed, a.method))
            subprocess.run([evorec, 'run', f'{d}/scenario.toml', '--out', d], check=True,
                           stdout=subprocess.DEVNULL)
        s = json.load(open(f'{d}/summary.json'))
        return [motion, omega, seed] + [s[k] for k in KEYS]

    jobs = [(m, w, s) for s in range(a.first, a.last + 1) for (m, w) in cells]
    with ThreadPoolExecutor(a.jobs) as ex:
        rows = list(ex.map(run, jobs))
    path = f'{a.out}/cells_{a.first}_{a.last}.csv'
    with open(path, 'w') as f:
        f.write('motion,omega,seed,F,x_mm,y_mm,z_mm,e1,e2,e3\n')
        for r in rows:
            f.write(','.join(f'{v:.6g}' if isinstance(v, float) else str(v) for v in r) + '\n')
    print(f'{len(rows)} runs -> {path}')


if __name__ == '__main__':
    main()
