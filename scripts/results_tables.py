#!/usr/bin/env python3
"""Writes the main table of docs/results.md for one evaluation report: one row per method, from the report's
summary.csv (rows of target `all`: the mean and standard deviation over the folds).

Usage: scripts/results_tables.py REPORT_DIR "hand (synthetic), 7 folds"   (prints Markdown on standard output)
"""
import csv
import sys

# methods in the order of the table, with the label each row carries
METHODS = [
    ("stargan", "stargan (`handemo` preset)"),
    ("stargan-retargeted", "stargan-retargeted (from a foreign rig, scored back)"),
    ("stargan-ungated", "stargan-ungated (G's whole change, no gate)"),
    ("stargan-g", "stargan-g (G and gate, without the amplitude stage)"),
    ("amplitude-only", "amplitude-only (no G)"),
    ("statistics", "statistics (every learned part but G: the bar G must clear)"),
    ("identity", "identity"),
    ("mean-offset", "mean-offset"),
    ("nearest-neighbour", "nearest-neighbour"),
    ("oracle", "oracle (the floor per-take variation leaves)"),
    ("real", "real (reference)"),
]
COLUMNS = [("rmse_real", "RMSE to real (deg)", True), ("emotion_acc", "emotion, centroid judge (%)", True),
           ("emotion_acc_full", "emotion, full-rate judge (%)", True), ("content_acc", "content kept (%)", False),
           ("rmse_input", "RMSE to input", False), ("rom_error", "ROM err", False), ("speed_error", "speed err", False),
           ("duration_error", "duration err", False)]


def table(report_dir, title):
    rows = {}
    with open(f"{report_dir}/summary.csv", newline="") as f:
        for r in csv.DictReader(f):
            if r["target"] == "all":
                rows[(r["method"], r["metric"])] = (float(r["mean"]), float(r["std"]))
    if not rows:
        raise SystemExit(f"results_tables.py: {report_dir}/summary.csv has no rows of target 'all'")
    out = [f"| {title} | " + " | ".join(c[1] for c in COLUMNS) + " |", "|---" * (len(COLUMNS) + 1) + "|"]
    for method, label in METHODS:
        if not any((method, c[0]) in rows for c in COLUMNS):
            continue
        cells = []
        for metric, _, with_std in COLUMNS:
            v = rows.get((method, metric))
            cells.append("" if v is None else f"{v[0]:.2f} +- {v[1]:.2f}" if with_std else f"{v[0]:.2f}")
        if method == "stargan":
            cells[0], cells[1] = f"**{cells[0]}**", f"**{cells[1]}**"
        out.append(f"| {label} | " + " | ".join(cells) + " |")
    return "\n".join(out) + "\n"


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    sys.stdout.write(table(sys.argv[1], sys.argv[2]))
