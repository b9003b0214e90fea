#!/usr/bin/env python3
"""The change gate checked inside the training sets of a `handemo eval` report (README, "How the defaults were chosen").

Usage: scripts/gate_check.py REPORT_DIR [REPORT_DIR ...]

Reads every fold's gate/gate.csv (and gate/gate_margins.csv when the margin was chosen by --gate-auto-margin) and
prints, pooled over the folds' (target emotion) rows, weighted by their held-out pairs:
  inside   the chosen settings scored on the inner pairs that chose them (optimistic),
  checked  the rule's choices made on one inner group and scored on the other (rmse_cross, emotion_cross),
  real     the real inner held-out clips' recognition, G's whole change and no change,
and the margins chosen per fold. Only training-set numbers: no held-out fold is read.
"""
import csv
import glob
import math
import os
import sys


def pooled(rows, key):
    num = den = 0.0
    for r in rows:
        v = float(r[key])
        if math.isnan(v):
            continue
        num += v * float(r["pairs"])
        den += float(r["pairs"])
    return num / den if den else float("nan")


def main(dirs):
    if not dirs:
        sys.exit(__doc__)
    print("| report | folds | inside: RMSE / recognised | checked: RMSE / recognised | real recognised | G's whole change | no change RMSE | margins chosen |")
    print("|---|---|---|---|---|---|---|---|")
    for d in dirs:
        files = sorted(glob.glob(os.path.join(d, "folds", "*", "gate", "gate.csv")))
        if not files:
            sys.exit(f"gate_check: {d}: no folds/*/gate/gate.csv (was the report made with --gate-folds 0?)")
        rows, margins = [], []
        for f in files:
            with open(f, newline="") as fh:
                part = list(csv.DictReader(fh))
            if part and "rmse_cross" not in part[0]:
                sys.exit(f"gate_check: {f}: no rmse_cross column (made by a version before the check; refit with --reuse-models)")
            rows += part
            m = os.path.join(os.path.dirname(f), "gate_margins.csv")
            if os.path.exists(m):
                with open(m, newline="") as fh:
                    margins += [r["margin"] for r in csv.DictReader(fh) if r["chosen"] == "1"]
        pct = lambda v: f"{100 * v:.1f}%"
        print(f"| {d} | {len(files)} | {pooled(rows, 'rmse_gated'):.2f} / {pct(pooled(rows, 'emotion_gated'))} "
              f"| {pooled(rows, 'rmse_cross'):.2f} / {pct(pooled(rows, 'emotion_cross'))} | {pct(pooled(rows, 'emotion_real'))} "
              f"| {pooled(rows, 'rmse_full'):.2f} / {pct(pooled(rows, 'emotion_full'))} | {pooled(rows, 'rmse_none'):.2f} "
              f"| {' '.join(margins) if margins else '(fixed)'} |")


if __name__ == "__main__":
    main(sys.argv[1:])
