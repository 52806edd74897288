#!/usr/bin/env python3
"""RMS rotation error of `evorec run` traces, in degrees: of the whole turn from the truth to the
estimate, and of its components about the camera's x, y and z axes (the rotation vector of
Q_est ⊗ Q_true⁻¹, which is expressed in the camera frame). Prints the median over the runs of
each directory.

usage: scripts/rotation_error.py DIR [DIR ...]   (each DIR holds run directories with trace.csv)

Requires: Python >= 3.8, standard library only.
"""
import csv, math, os, statistics, sys


def quat(e):
    return (math.sqrt(max(0.0, 1.0 - sum(x * x for x in e))),) + tuple(e)


def mul(a, b):
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return (w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2)


def run_errors(trace):
    total, axes, n = 0.0, [0.0, 0.0, 0.0], 0
    for r in csv.DictReader(open(trace)):
        t = quat([float(r[k]) for k in ('e1', 'e2', 'e3')])
        e = quat([float(r[k]) for k in ('est_e1', 'est_e2', 'est_e3')])
        d = mul(e, (t[0], -t[1], -t[2], -t[3]))
        if d[0] < 0:
            d = tuple(-x for x in d)
        s = math.sqrt(d[1] ** 2 + d[2] ** 2 + d[3] ** 2)
        angle = 2.0 * math.atan2(s, d[0])
        total += angle * angle
        for k in range(3):
            axes[k] += (angle * d[k + 1] / s if s > 0 else 0.0) ** 2
        n += 1
    return [math.degrees(math.sqrt(v / n)) for v in [total] + axes]


def main():
    if len(sys.argv) < 2:
        raise SystemExit(__doc__)
    for top in sys.argv[1:]:
        runs = sorted(d for d in os.listdir(top) if os.path.exists(os.path.join(top, d, 'trace.csv')))
        errs = [run_errors(os.path.join(top, d, 'trace.csv')) for d in runs]
        med = [statistics.median(e[k] for e in errs) for k in range(4)]
        print(f'{top}: {len(runs)} runs, median RMS rotation {med[0]:.3f} deg, about camera x / y / z '
              f'{med[1]:.3f} / {med[2]:.3f} / {med[3]:.3f} deg')


if __name__ == '__main__':
    main()
