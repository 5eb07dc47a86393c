#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""Plots of the error-against-run-time report from <out>/results.csv.

Run with Debian's Python (/usr/bin/python3, package python3-matplotlib); scripts/report calls it.
Writes <out>/plots/error_vs_time.png (per-edit time), error_vs_total_time.png (precompute + one
edit), convergence.png (analytic hollow sphere) and one error_vs_time_<scene>.png per scene.
"""
import csv
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

FLOOR = 1e-17  # where an error of exactly 0 (the reference itself) is drawn

STYLE = {  # path -> (colour, marker)
    "reference (full sparse direct, double)": ("black", "s"),
    "condensed CachedFactor": ("tab:blue", "o"),
    "condensed DenseResponse": ("tab:cyan", "D"),
    "PCG IncompleteCholesky": ("tab:orange", "."),
    "PCG IncompleteCholesky warm": ("tab:red", "^"),
    "PCG Jacobi": ("tab:brown", "."),
    "PCG float IncompleteCholesky": ("tab:pink", "."),
    "float Cholesky": ("tab:purple", "v"),
    "float Cholesky + 2 refinements": ("tab:purple", "P"),
    "traditional band Cholesky (RCM, 1 thread)": ("tab:green", "X"),
    "CalculiX ccx (C3D4)": ("tab:olive", "*"),
    "mass-spring (edge springs)": ("tab:gray", "h"),
}
CURVES = {"PCG IncompleteCholesky", "PCG Jacobi", "PCG float IncompleteCholesky"}


def num(v):
    try:
        x = float(v)
        return x if math.isfinite(x) else None
    except (TypeError, ValueError):
        return None


def load(path):
    with open(path, newline="") as f:
        rows = [r for r in csv.DictReader(f) if r["ran"] == "1"]
    for r in rows:
        for k in list(r):
            if k.endswith(("_ms_median", "_ms_lo", "_ms_hi", "_err")) or k in ("h", "tets", "tolerance"):
                r[k] = num(r[k])
    return rows


def style(path):
    if path in STYLE:
        return STYLE[path]
    return ("tab:red", "d") if path.startswith("CUDA") else ("k", "x")


def draw_scene(ax, rows, total):
    def t(r):
        e = r["edit_ms_median"]
        return e + (r["precompute_ms_median"] or 0.0) if total else e

    def lohi(r):
        if total:
            return None
        lo, hi = r["edit_ms_lo"], r["edit_ms_hi"]
        if lo is None or hi is None:
            return None
        return [[max(0.0, r["edit_ms_median"] - lo)], [max(0.0, hi - r["edit_ms_median"])]]

    paths = []
    for r in rows:
        if r["path"] not in paths:
            paths.append(r["path"])
    for p in paths:
        pr = [r for r in rows if r["path"] == p and r["edit_ms_median"] and r["max_rel_err"] is not None]
        if not pr:
            continue
        colour, marker = style(p)
        xs = [t(r) for r in pr]
        ys = [max(r["max_rel_err"], FLOOR) for r in pr]
        if p in CURVES:
            pts = sorted(zip([r["tolerance"] or 0 for r in pr], xs, ys), reverse=True)
            ax.plot([q[1] for q in pts], [q[2] for q in pts], "-", marker="o", ms=3, color=colour, label=p)
            for tol, x, y in pts:
                if tol and round(math.log10(tol)) % 2 == 0:
                    ax.annotate(f"{tol:.0e}", (x, y), fontsize=5, color=colour, xytext=(2, 2),
                                textcoords="offset points")
        else:
            for r, x, y in zip(pr, xs, ys):
                err = lohi(r)
                ax.errorbar([x], [y], xerr=err, fmt=marker, color=colour, ms=6, capsize=2,
                            label=p + (f" ({r['variant']})" if "warm" in p else ""))
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.axhline(1e-16, color="0.8", lw=0.8, ls=":")
    ax.grid(True, which="major", alpha=0.3)


def figure(rows, scenes, total, path):
    n = len(scenes)
    cols = 3 if n > 4 else n
    nrows = math.ceil(n / cols)
    width = max(5.2 * cols, 10.0)
    ncol = 4 if width >= 12 else 3
    fig, axes = plt.subplots(nrows, cols, figsize=(width, 4.0 * nrows + 1.2), squeeze=False)
    for i, s in enumerate(scenes):
        ax = axes[i // cols][i % cols]
        sr = [r for r in rows if r["scene"] == s]
        draw_scene(ax, sr, total)
        tets = int(sr[0]["tets"]) if sr else 0
        ax.set_title(f"{s} ({tets:,} tets)", fontsize=10)
        ax.set_xlabel(("precompute + one edit" if total else "per-edit time") + " [ms]", fontsize=8)
        ax.set_ylabel("max kept-node error / max |u_ref|", fontsize=8)
        ax.tick_params(labelsize=7)
    for j in range(n, nrows * cols):
        axes[j // cols][j % cols].axis("off")
    handles, labels = {}, []
    for ax in axes.flat:
        for h, l in zip(*ax.get_legend_handles_labels()):
            if l not in handles:
                handles[l] = h
                labels.append(l)
    fig.legend([handles[l] for l in labels], labels, loc="lower center", ncol=ncol, fontsize=7, frameon=False)
    fig.suptitle("Relative error against " + ("precompute + one edit" if total else "per-edit")
                 + " run time (0 drawn at 1e-17; dotted: 1e-16)", fontsize=10)
    height = 4.0 * nrows + 1.2
    legend_in = 0.16 * math.ceil(len(labels) / ncol) + 0.25
    fig.tight_layout(rect=(0, legend_in / height, 1, 1 - 0.45 / height))
    fig.savefig(path, dpi=110)
    plt.close(fig)


def convergence(rows, path):
    sph = [r for r in rows if r["scene"].startswith("sphere") and r["l2_analytic_rel_err"] is not None]
    if not sph:
        return False
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12, 4.8))
    keys = []
    for r in sph:
        key = r["path"] + ("" if r["path"] not in CURVES else f" {r['variant']}")
        if r["path"] in CURVES and r["variant"] not in ("tol 1e-02", "tol 1e-04", "tol 1e-06", "tol 1e-10"):
            continue
        if r["path"] == "PCG float IncompleteCholesky" or "warm" in r["path"]:
            continue
        if key not in keys:
            keys.append(key)
    for k in keys:
        pr = [r for r in sph if r["path"] + ("" if r["path"] not in CURVES else f" {r['variant']}") == k]
        pr.sort(key=lambda r: -r["h"])
        path_name = pr[0]["path"]
        colour, marker = style(path_name)
        ls = "-"
        if path_name in CURVES:
            ls = {"tol 1e-02": ":", "tol 1e-04": "-.", "tol 1e-06": "--"}.get(pr[0]["variant"], "-")
            marker = "o"
        hs = [r["h"] for r in pr]
        es = [r["l2_analytic_rel_err"] for r in pr]
        ts = [r["edit_ms_median"] + (r["precompute_ms_median"] or 0) for r in pr]
        a1.plot(hs, es, ls, marker=marker, color=colour, label=k, ms=5)
        a2.plot(ts, es, ls, marker=marker, color=colour, label=k, ms=5)
    ref = sorted([r for r in sph if r["path"].startswith("reference")], key=lambda r: -r["h"])
    if len(ref) >= 2:
        h0, e0 = ref[0]["h"], ref[0]["l2_analytic_rel_err"]
        hs = [r["h"] for r in ref]
        a1.plot(hs, [e0 * (h / h0) ** 2 for h in hs], color="0.6", lw=0.8, ls="--", label="slope 2")
    for a in (a1, a2):
        a.set_xscale("log")
        a.set_yscale("log")
        a.grid(True, which="both", alpha=0.3)
        a.set_ylabel("relative L2 error against the analytic solution")
    a1.set_xlabel("mesh size h = (b - a) / layers")
    a2.set_xlabel("time for one solve from scratch (precompute + edit) [ms]")
    a1.set_title("discretisation error against mesh size")
    a2.set_title("... against run time: what each extra second buys")
    a1.invert_xaxis()
    a2.legend(fontsize=6, loc="upper right")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return True


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "out/report"
    rows = load(os.path.join(out, "results.csv"))
    scenes = []
    for r in rows:
        if r["scene"] not in scenes:
            scenes.append(r["scene"])
    plots = os.path.join(out, "plots")
    os.makedirs(plots, exist_ok=True)
    figure(rows, scenes, False, os.path.join(plots, "error_vs_time.png"))
    figure(rows, scenes, True, os.path.join(plots, "error_vs_total_time.png"))
    for s in scenes:
        figure(rows, [s], False, os.path.join(plots, f"error_vs_time_{s}.png"))
    convergence(rows, os.path.join(plots, "convergence.png"))
    print(f"plots in {plots}")


if __name__ == "__main__":
    main()
