#!/usr/bin/python3
"""Overview figure of one `scratchlight optimize` output directory.

usage: scripts/plot_optimize.py OUTDIR [--title TEXT]
Reads OUTDIR/{initial.png, render.png, envmap.png, loss.csv, summary.json} and writes
OUTDIR/overview.png: the render before and after, the optimized env map, and the loss curve.
Uses Debian's python3-matplotlib (run with /usr/bin/python3).
"""
from atomic_save import savefig  # scripts/atomic_save.py, beside this script
import argparse
import csv
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.image as mpimg  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("outdir")
    ap.add_argument("--title", default="")
    a = ap.parse_args()
    need = ["initial.png", "render.png", "envmap.png", "loss.csv", "summary.json"]
    missing = [f for f in need if not os.path.exists(os.path.join(a.outdir, f))]
    if missing:
        sys.exit(f"plot_optimize: {a.outdir} lacks {', '.join(missing)}: "
                 "is it the output directory of `scratchlight optimize`?")
    with open(os.path.join(a.outdir, "summary.json")) as f:
        s = json.load(f)
    it, loss, git, lgrad = [], [], [], []
    with open(os.path.join(a.outdir, "loss.csv")) as f:
        for row in csv.DictReader(f):
            it.append(int(row["iteration"]))
            loss.append(float(row["loss"]))
            if row["L_grad"]:  # written every --heldout-every rows
                git.append(int(row["iteration"]))
                lgrad.append(float(row["L_grad"]))

    fig = plt.figure(figsize=(16, 4.6))
    gs = fig.add_gridspec(1, 4, width_ratios=[1, 1, 1.6, 1.2])
    for k, (name, title) in enumerate([("initial.png", f"initial ({s['init']})"),
                                       ("render.png", "optimized")]):
        ax = fig.add_subplot(gs[0, k])
        img = mpimg.imread(os.path.join(a.outdir, name))
        ax.imshow(img, cmap="gray", vmin=0, vmax=1, interpolation="nearest")
        ax.set_title(title)
        ax.axis("off")
    ax = fig.add_subplot(gs[0, 2])
    ax.imshow(mpimg.imread(os.path.join(a.outdir, "envmap.png")), cmap="gray", vmin=0, vmax=1,
              interpolation="nearest")
    ax.set_title("optimized env map (row 0 = +Y, u = atan2(x, -z)/2pi)")
    ax.axis("off")
    ax = fig.add_subplot(gs[0, 3])
    ax.plot(it, loss, label="loss")
    ax.plot(git, lgrad, label="L_grad", linestyle="--", marker=".")
    ax.set_yscale("log")
    ax.set_xlabel("iteration")
    ax.set_title(f"{s['optimizer']}, lambda = {s['lambda']:g}")
    ax.legend()
    ax.grid(alpha=0.3)
    fig.suptitle(a.title or f"scratchlight optimize: loss {s['initial_loss']:.4g} -> "
                 f"{s['final_loss']:.4g} in {s['seconds_optimize']:.3f} s")
    fig.tight_layout()
    out = os.path.join(a.outdir, "overview.png")
    savefig(fig, out, dpi=80)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
