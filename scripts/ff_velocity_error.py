#!/usr/bin/env python3
"""The target velocity fed forward against the truth, over runs of a conveyor scenario.

usage: scripts/ff_velocity_error.py DIR SEED...   (DIR/sSEED/trace.csv from `evorec run`)

Per run, over the frames after 3 s with the filter trusted: the RMS error of `ff_target_v*`
against `true_target_v*` per world axis, and for the belt's axis (y) a least-squares fit of the
error on the true acceleration (np.gradient of the true velocity): the lag (s) and the RMS of
what the fit leaves. Prints each run and the medians over the runs.

Requires: Python >= 3.8 and NumPy.
"""
import csv
import statistics
import sys

import numpy as np


def run(path):
    rows = list(csv.DictReader(open(path)))
    col = lambda k: np.array([float(r[k]) for r in rows])
    t = col("t")
    keep = (t > 3.0) & (col("target_trusted") > 0)
    err = {a: (col(f"ff_target_v{a}") - col(f"true_target_v{a}"))[keep] for a in "xyz"}
    acc = np.gradient(col("true_target_vy"), t)[keep]
    design = np.stack([acc, np.ones_like(acc)], 1)
    coef = np.linalg.lstsq(design, err["y"], rcond=None)[0]
    resid = err["y"] - design @ coef
    rms = lambda e: float(np.sqrt((e**2).mean()))
    return {"y": rms(err["y"]), "lag_s": -float(coef[0]), "resid": rms(resid), "x": rms(err["x"]), "z": rms(err["z"])}


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    out = [run(f"{sys.argv[1]}/s{s}/trace.csv") for s in sys.argv[2:]]
    for s, r in zip(sys.argv[2:], out):
        print(f"seed {s}: " + " ".join(f"{k} {v:.4f}" for k, v in r.items()))
    print("median: " + " ".join(f"{k} {statistics.median(r[k] for r in out):.4f}" for k in out[0]))


if __name__ == "__main__":
    main()
