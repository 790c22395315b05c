#!/usr/bin/env python3
"""Speed against error, from `scratchlight bench settings`: seconds (precompute + search) against
the judge's U of E*, one point per setting (median over seeds): colour = direction sampler,
marker size = spp, label = max_depth; the dashed line is the Pareto front (the cheapest setting
for each accuracy). One panel per part.
Usage: plot_settings.py settings.csv settings.png"""
from atomic_save import savefig  # scripts/atomic_save.py, beside this script
from plot_race import pareto_front, read_runs  # the same CSV, beside this script
import re
import sys
from statistics import median

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

COLOURS = {"bsdf": "C0", "stratified": "C2", "mis": "C3"}


def main(src, dst):
    runs, parts = read_runs(src)
    fig, axes = plt.subplots(1, len(parts), figsize=(6.5 * len(parts), 5), squeeze=False)
    for ax, part in zip(axes[0], parts):
        pts, seen = [], set()
        for (p, cfg), v in runs.items():
            m = re.fullmatch(r"spp(\d+)-(\w+)-d(\d+)", cfg)
            if p != part or not m:
                continue
            spp, sampler, depth = int(m.group(1)), m.group(2), m.group(3)
            s, u = median(x[0] for x in v), median(x[1] for x in v)
            pts.append((s, u))
            label = sampler if sampler not in seen else None
            seen.add(sampler)
            ax.scatter(s, u, s=12 * spp ** 0.6, color=COLOURS.get(sampler, "C7"), alpha=0.8,
                       label=label, edgecolors="black", linewidths=0.4)
            ax.annotate(f"{spp}/d{depth}", (s, u), fontsize=6, xytext=(3, 3),
                        textcoords="offset points")
        front = pareto_front(pts)
        ax.plot([f[0] for f in front], [f[1] for f in front], "k--", lw=0.8, label="Pareto front")
        ax.set_xscale("log")
        ax.set_xlabel("seconds (precompute + search, median over seeds)")
        ax.set_ylabel("judge U of E* (lower is better)")
        ax.set_title(f"{part}: labels spp/max_depth, size ~ spp")
        ax.legend(fontsize=8)
    fig.tight_layout()
    savefig(fig, dst, dpi=110)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
