#!/usr/bin/python3
"""Plot `scratchlight bench noise` results: held-out loss against total seconds.

usage: scripts/plot_noise.py bench-noise.csv [-o bench-noise.png]
Left: each objective's E* scored with its own objective on the shared high-spp estimate.
Right: every E* scored with the paper's eq. 2 there (the common yardstick).
One line per objective, points labelled with the training spp. Uses Debian's python3-matplotlib.
"""
import argparse
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("csv")
    ap.add_argument("-o", "--output")
    a = ap.parse_args()
    if not os.path.exists(a.csv):
        sys.exit(f"plot_noise: {a.csv} not found: run `scratchlight bench noise` first")
    rows = list(csv.DictReader(open(a.csv)))
    if not rows:
        sys.exit(f"plot_noise: {a.csv} has no rows")
    out = a.output or os.path.splitext(a.csv)[0] + ".png"
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.6))
    for ax, key, title in [(axes[0], "heldout_loss", "own objective on the held-out estimate"),
                           (axes[1], "heldout_paper_loss", "paper's eq. 2 on the held-out estimate")]:
        for obj, style in [("paper", "o-"), ("unbiased", "s-")]:
            sel = sorted((r for r in rows if r["objective"] == obj), key=lambda r: int(r["spp"]))
            x = [float(r["total_s"]) for r in sel]
            y = [float(r[key]) for r in sel]
            ax.plot(x, y, style, label=obj)
            for r, xi, yi in zip(sel, x, y):
                ax.annotate(r["spp"], (xi, yi), textcoords="offset points", xytext=(4, 4),
                            fontsize=8)
        ax.set_xscale("log")
        ax.set_xlabel("precompute + optimize seconds")
        ax.set_ylabel("held-out loss (lower is better)")
        ax.set_title(title)
        ax.grid(alpha=0.3)
        ax.legend()
    fig.suptitle(f"bench noise: held-out estimate at {rows[0]['heldout_spp']} spp")
    fig.tight_layout()
    fig.savefig(out, dpi=80)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
