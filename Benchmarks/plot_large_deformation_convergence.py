#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""Relative residual against time of the large-deformation solves, from the CSV that
Benchmarks/large_deformation_drag.py writes (--csv): per scene, the full move from rest and the first
0.5 mm drag steps (the first after the move, and the last of the series, whose factor was made
ahead of it), Precomputed against Newton, every iterate marked.

Run with Debian's Python (/usr/bin/python3, package python3-matplotlib):

    Benchmarks/plot_large_deformation_convergence.py <convergence.csv> <out.png>
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

TOLERANCE = 1e-9


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    series = {}
    with open(sys.argv[1], newline="") as f:
        for r in csv.DictReader(f):
            key = (r["scene"], r["case"], r["solver"])
            series.setdefault(key, []).append((float(r["time_ms"]), float(r["relative_residual"])))
    scenes = sorted({k[0] for k in series}, key=lambda s: ["lefort1", "bsso", "genioplasty", "cut"].index(s)
                    if s in ("lefort1", "bsso", "genioplasty", "cut") else 9)
    if not scenes:
        sys.exit("no iterates in " + sys.argv[1])
    cases = [("full_move", "full move from rest"), ("drag_step", "first 0.5 mm drag step"),
             ("later_drag_step", "last 0.5 mm drag step")]
    fig, axes = plt.subplots(len(cases), len(scenes), figsize=(3.4 * len(scenes), 9.0), squeeze=False)
    for row, (case, title) in enumerate(cases):
        for col, scene in enumerate(scenes):
            ax = axes[row][col]
            times = []
            for solver, colour in (("Precomputed", "tab:blue"), ("Newton", "tab:red")):
                points = series.get((scene, case, solver))
                if not points:
                    continue
                t = [p[0] for p in points]
                times += t
                r = [max(p[1], 1e-16) for p in points]
                ax.semilogy(t, r, marker="o", markersize=3, color=colour,
                            label="%s (%d iterates)" % (solver, len(points) - 1))
            ax.axhline(TOLERANCE, color="gray", linestyle=":", linewidth=1)
            # A logarithmic time axis only where the times span a decade or more: within one, its
            # labels are mantissa-and-exponent clutter.
            if times and min(times) > 0.0 and max(times) >= 10.0 * min(times):
                ax.set_xscale("log")
            ax.set_title("%s: %s" % (scene, title), fontsize=9)
            ax.set_xlabel("time since the solve started (ms)", fontsize=8)
            if col == 0:
                ax.set_ylabel("relative residual", fontsize=8)
            ax.tick_params(labelsize=7)
            ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(sys.argv[2], dpi=100)


if __name__ == "__main__":
    main()
