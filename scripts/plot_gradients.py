#!/usr/bin/python3
"""Plots of `scratchlight bench gradients` (Debian's python3-matplotlib, no numpy needed).

usage: scripts/plot_gradients.py DIR

Reads DIR/gradients.csv (one row per method and setting) and, if present, DIR/optimization.csv
(loss of every iterate against wall-clock seconds), and writes
  DIR/speed-vs-error.png   seconds per gradient against relative L2 error vs autodiff (log-log)
  DIR/loss-vs-time.png     loss against wall-clock seconds for whole optimizations
"""
from atomic_save import savefig  # scripts/atomic_save.py, beside this script
import csv
import os
import re
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

FLOOR = 1e-17  # where an error of exactly 0 (the reference itself) is drawn


def read_rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def speed_vs_error(rows, out):
    fig, ax = plt.subplots(figsize=(8.5, 6))
    groups = {}
    for r in rows:
        crn = r["crn"] == "1"
        m = r["method"]
        key = m
        if m == "fd-fresh":
            key = "fd (fresh seeds)"
        elif m == "fd":
            key = "fd central (CRN)"
        elif m == "fd-forward":
            key = "fd forward (CRN)"
        elif m == "spsa":
            c = re.search(r"c=([0-9.e+-]+)", r["settings"])
            key = "spsa c=%s (%s)" % (c.group(1) if c else "?", "CRN" if crn else "fresh seeds")
        groups.setdefault(key, []).append(r)
    styles = {
        "exact": dict(marker="*", ms=16, color="tab:green"),
        "exact+precompute": dict(marker="*", ms=12, color="tab:olive"),
        "autodiff": dict(marker="D", ms=9, color="black"),
        "autodiff-T": dict(marker="d", ms=9, color="tab:gray"),
        "fd central (CRN)": dict(marker="o", color="tab:blue"),
        "fd forward (CRN)": dict(marker="v", color="tab:cyan"),
        "fd (fresh seeds)": dict(marker="s", color="tab:red"),
    }
    for key, rs in groups.items():
        xs = [max(float(r["relative_error"]), FLOOR) for r in rs]
        ys = [float(r["seconds_per_gradient"]) for r in rs]
        st = styles.get(key, dict(marker="^") if key.startswith("spsa") else dict(marker="o"))
        line = "-" if len(rs) > 1 else ""
        ax.plot(xs, ys, linestyle=line, label=key, **st)
        for r, x, y in zip(rs, xs, ys):
            m = r["method"]
            if m.startswith("fd"):
                txt = "h=%g" % float(r["parameter"])
            elif m == "spsa":
                txt = "q=%d" % int(float(r["parameter"]))
            elif m == "autodiff":
                txt = "reference (error 0)"
            else:
                txt = ""
            if txt:
                ax.annotate(txt, (x, y), textcoords="offset points", xytext=(5, 4), fontsize=7)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("relative L2 error of the gradient vs autodiff")
    ax.set_ylabel("seconds per gradient (median)")
    ax.set_title("Speed against error of the loss gradient (every texel of E)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="best")
    fig.tight_layout()
    savefig(fig, out, dpi=130)
    plt.close(fig)


def loss_vs_time(rows, out):
    fig, ax = plt.subplots(figsize=(8.5, 5.5))
    series = {}
    for r in rows:
        series.setdefault(r["method"], []).append((float(r["seconds"]), float(r["loss"])))
    for m, pts in series.items():
        pts.sort()
        # A tiny positive time for the starting point so it shows on the log axis.
        xs = [max(p[0], 1e-5) for p in pts]
        ax.plot(xs, [p[1] for p in pts], marker=".", ms=3, label=m)
    ax.set_xscale("log")
    ax.set_xlabel("wall-clock seconds")
    ax.set_ylabel("loss (noise-free: T·E with the same samples)")
    ax.set_title("Whole optimizations from the same start")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    savefig(fig, out, dpi=130)
    plt.close(fig)


def main():
    if len(sys.argv) != 2:
        sys.stderr.write(__doc__)
        return 2
    d = sys.argv[1]
    g = os.path.join(d, "gradients.csv")
    if not os.path.exists(g):
        sys.stderr.write("error: %s not found (run scratchlight bench gradients)\n" % g)
        return 1
    speed_vs_error(read_rows(g), os.path.join(d, "speed-vs-error.png"))
    print("wrote", os.path.join(d, "speed-vs-error.png"))
    o = os.path.join(d, "optimization.csv")
    if os.path.exists(o):
        loss_vs_time(read_rows(o), os.path.join(d, "loss-vs-time.png"))
        print("wrote", os.path.join(d, "loss-vs-time.png"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
