#!/usr/bin/env python3
"""Pareto plot of `scratchlight bench race`: seconds (precompute + search) against the judge's
U, one point per configuration (median over seeds), one panel per part.
Usage: plot_race.py race.csv race.png"""
from atomic_save import savefig  # scripts/atomic_save.py, beside this script
import csv
import sys
from collections import defaultdict
from statistics import median

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read_runs(src):
    """The race CSV's rows as {(part, config): [(seconds, judge U), ...]} and the parts in the
    order they first appear (`bench race` and `bench settings` write the same columns; the
    studio lamp's reference rows, which take no seconds, are left out)."""
    runs = defaultdict(list)
    parts = []
    for r in csv.DictReader(open(src)):
        if r["config"] == "studio-lamp":
            continue
        if r["part"] not in parts:
            parts.append(r["part"])
        runs[(r["part"], r["config"])].append((float(r["seconds"]), float(r["unbiased"])))
    return runs, parts


def pareto_front(points):
    """The (seconds, U) points no cheaper point beats, cheapest first."""
    front, best = [], float("inf")
    for s, u in sorted(points):
        if u < best:
            front.append((s, u))
            best = u
    return front


def main(src, dst):
    runs, parts = read_runs(src)
    fig, axes = plt.subplots(1, len(parts), figsize=(5.5 * len(parts), 4.5), squeeze=False)
    for ax, part in zip(axes[0], parts):
        pts = []
        for (p, cfg), v in runs.items():
            if p != part:
                continue
            s, u = median(x[0] for x in v), median(x[1] for x in v)
            pts.append((s, u, cfg))
            ax.scatter(s, u, s=30, color="black" if cfg == "paper-loop" else "C0")
            ax.annotate(cfg, (s, u), fontsize=7, xytext=(3, 3), textcoords="offset points")
        front = pareto_front([(s, u) for s, u, _ in pts])
        ax.plot([f[0] for f in front], [f[1] for f in front], "C1--", lw=1, label="Pareto front")
        ax.set_xscale("log")
        ax.set_xlabel("seconds (precompute + search, median over seeds)")
        ax.set_ylabel("judge U at 1024 spp (lower is better)")
        ax.set_title(part)
        ax.legend(fontsize=8)
    fig.tight_layout()
    savefig(fig, dst, dpi=110)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
