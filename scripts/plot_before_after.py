#!/usr/bin/python3
"""The README's picture: one optimize OUTDIR's renders under the user's lamp, the paper's light
and the optimized light, side by side, titled with the judge's defect visibility of each.

usage: scripts/plot_before_after.py OUTDIR OUT.png
Reads OUTDIR/summary.json ("compare", by the keys src/io/OptimizeOutDir.h lists, through
scripts/outdir_contract.py) and OUTDIR/view-{lamp,paper,optimized}.png (each render exposed on its
own, as optimize's report shows them). Uses Debian's python3-matplotlib.
"""
from atomic_save import savefig  # scripts/atomic_save.py, beside this script
from outdir_contract import at, read_summary  # scripts/outdir_contract.py, beside this script
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.image as mpimg  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402


def visibility(summary, key):
    """The judge's defect visibility of one light (the first region), or None."""
    regions = at(summary, "/compare/%s/judge/visibility" % key) or []
    return regions[0].get("visibility") if regions else None


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__.split("\n\n")[1])
    outdir, out = sys.argv[1], sys.argv[2]
    summary = read_summary(outdir)
    if not at(summary, "/compare"):
        sys.exit("%s/summary.json has no comparison (run optimize with a judge estimate)" % outdir)
    panels = [("lamp", "your lamp (%s)" % at(summary, "/compare/lamp/name", "studio preset")),
              ("paper", "the paper's light"), ("optimized", "optimized light")]
    fig, axes = plt.subplots(1, 3, figsize=(12, 4.4))
    for ax, (key, title) in zip(axes, panels):
        img = mpimg.imread(os.path.join(outdir, "view-%s.png" % key))
        ax.imshow(img, cmap="gray", vmin=0.0, vmax=1.0)
        v = visibility(summary, key)
        ax.set_title(title + ("\ndefect visibility %.3g" % v if v is not None else ""))
        ax.axis("off")
    fig.text(0.5, 0.01, "the same part under three lights; judge: an independent %d-spp estimate"
             % at(summary, "/compare/judge_spp", 0), ha="center")
    fig.tight_layout(rect=(0, 0.04, 1, 1))
    savefig(fig, out, dpi=80, bbox_inches="tight", metadata={"Software": None})


if __name__ == "__main__":
    main()
