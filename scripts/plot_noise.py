#!/usr/bin/python3
"""Plot `scratchlight bench noise` results: held-out loss against total seconds.

usage: scripts/plot_noise.py bench-noise.csv [-o bench-noise.png]
Left: each objective's E* scored with its own objective on the shared high-spp estimate.
Right: every E* scored with the paper's eq. 2 there (the common yardstick).
One line per objective and optimizer through the medians over training seeds, bars from the
smallest to the largest seed's score, points labelled with the training spp.
Uses Debian's python3-matplotlib.
"""
from atomic_save import savefig  # scripts/atomic_save.py, beside this script
import argparse
import csv
import os
import statistics
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

STYLES = {"paper": ("tab:red", "o"), "unbiased": ("tab:blue", "s")}
DASHES = ["-", "--", ":", "-."]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("csv")
    ap.add_argument("-o", "--output")
    a = ap.parse_args()
    if not os.path.exists(a.csv):
        sys.exit(f"plot_noise: {a.csv} not found: run `scratchlight bench noise` first")
    with open(a.csv) as f:
        rows = list(csv.DictReader(f))
    if not rows:
        sys.exit(f"plot_noise: {a.csv} has no rows")
    need = {"spp", "objective", "optimizer", "total_s", "heldout_loss", "heldout_paper_loss"}
    if not need <= set(rows[0]):
        sys.exit(f"plot_noise: {a.csv} lacks columns {sorted(need - set(rows[0]))}: "
                 "re-run `scratchlight bench noise`")
    out = a.output or os.path.splitext(a.csv)[0] + ".png"
    optimizers = sorted({r["optimizer"] for r in rows})
    seeds = len({r.get("seed", "0") for r in rows})
    fig, axes = plt.subplots(1, 2, figsize=(13, 5))
    for ax, key, title in [(axes[0], "heldout_loss", "own objective on the held-out estimate"),
                           (axes[1], "heldout_paper_loss", "paper's eq. 2 on the held-out estimate")]:
        for obj, (colour, marker) in STYLES.items():
            for k, opt in enumerate(optimizers):
                sel = [r for r in rows if r["objective"] == obj and r["optimizer"] == opt]
                spps = sorted({int(r["spp"]) for r in sel})
                if not spps:
                    continue
                x, y, lo, hi = [], [], [], []
                for s in spps:
                    g = [r for r in sel if int(r["spp"]) == s]
                    v = [float(r[key]) for r in g]
                    x.append(statistics.median(float(r["total_s"]) for r in g))
                    y.append(statistics.median(v))
                    lo.append(y[-1] - min(v))
                    hi.append(max(v) - y[-1])
                ax.errorbar(x, y, yerr=[lo, hi], color=colour, marker=marker,
                            linestyle=DASHES[k % len(DASHES)], capsize=3, label=f"{obj}, {opt}")
                for s, xi, yi in zip(spps, x, y):
                    ax.annotate(str(s), (xi, yi), textcoords="offset points", xytext=(4, 4),
                                fontsize=8, color=colour)
        ax.set_xscale("log")
        ax.set_xlabel("precompute + optimize seconds (median)")
        ax.set_ylabel("held-out loss (lower is better)")
        ax.set_title(title)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(f"bench noise: held-out estimate at {rows[0]['heldout_spp']} spp; "
                 f"medians over {seeds} training seed(s), bars = min..max; labels = training spp")
    fig.tight_layout()
    savefig(fig, out, dpi=80)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
