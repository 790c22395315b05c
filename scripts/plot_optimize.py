#!/usr/bin/python3
"""Figures of one `scratchlight optimize` output directory (the report's figures).

usage: scripts/plot_optimize.py OUTDIR [--title TEXT] [--print]
Reads OUTDIR/{summary.json, loss.csv, plot-data.json, view-*.png (or initial.png, render.png)},
summary.json by the keys src/io/OptimizeOutDir.h lists (scripts/outdir_contract.py), and
writes, each atomically:
  OUTDIR/plot-envmap.png  the optimized env map as a lat-long plot (azimuth 0-360 deg on x,
                          elevation -90..90 deg on y, horizon, camera and mirror direction, the
                          brightest directions labelled) and a polar plot of the upper hemisphere
  OUTDIR/plot-loss.png    the loss on a log axis (when every value is > 0) with the held-out loss
  OUTDIR/overview.png     the renders under your lamp and under E*, the env map and the loss
`optimize` draws the same figures itself, in-process (src/app/report/OptimizeFigures.h); run this by
hand to redraw them with matplotlib (to restyle them, say). It prints nothing unless --print.
The env-map convention is not restated here: plot-data.json carries each texel column's azimuth and row's elevation as
scene/EnvMapBasis.h defines them. Exit code 3: matplotlib is missing (use Debian's
/usr/bin/python3 with python3-matplotlib). PNGs carry no software/date metadata, so they are
byte-identical from run to run.
"""
import argparse
import csv
import json
import math
import os
import sys

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.image as mpimg  # noqa: E402
    import matplotlib.pyplot as plt  # noqa: E402
    from matplotlib import ticker  # noqa: E402
except ImportError as e:  # the caller reports "figure not made: ..."
    print(f"plot_optimize: matplotlib is missing ({e})", file=sys.stderr)
    sys.exit(3)

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from atomic_save import savefig  # noqa: E402  scripts/atomic_save.py, beside this script
from outdir_contract import at, read_summary  # noqa: E402  scripts/outdir_contract.py

METADATA = {"Software": None}  # no version string: the same bytes from every matplotlib run


def save(fig, path, dpi):
    savefig(fig, path, dpi=dpi, metadata=METADATA)
    plt.close(fig)


def read_loss(path):
    it, loss, hit, held = [], [], [], []
    with open(path) as f:
        for row in csv.DictReader(f):
            it.append(int(row["iteration"]))
            loss.append(float(row["loss"]))
            if row.get("heldout_loss"):  # written every --heldout-every rows and on the last
                hit.append(int(row["iteration"]))
                held.append(float(row["heldout_loss"]))
    return it, loss, hit, held


def edges(centres, lo, hi):
    """Cell edges around sorted or reverse-sorted centres, clipped to [lo, hi]."""
    e = [(a + b) / 2 for a, b in zip(centres, centres[1:])]
    first = centres[0] - (e[0] - centres[0]) if e else centres[0] - 1
    last = centres[-1] + (centres[-1] - e[-1]) if e else centres[-1] + 1
    return [min(hi, max(lo, v)) for v in [first] + e + [last]]


def grid(data, name):
    w, h = data["width"], data["height"]
    v = data["lights"][name]
    return [v[j * w:(j + 1) * w] for j in range(h)]


def direction_label(d):
    return f"az {d['azimuth_deg']:.0f}°, el {d['elevation_deg']:.0f}°"


def draw_latlong(ax, data, dirs, name="optimized", title=None, labels=True):
    az, el = data["azimuth_deg"], data["elevation_deg"]
    xe, ye = edges(az, 0.0, 360.0), edges(el, -90.0, 90.0)
    values = grid(data, name)
    m = ax.pcolormesh(xe, ye, values, cmap="inferno", shading="flat", vmin=0,
                      vmax=max(1e-9, max(max(r) for r in values)))
    ax.axhline(0, color="#7fd0ff", lw=1.2, ls="--")
    ax.text(358, 2, "horizon", color="#7fd0ff", ha="right", va="bottom", fontsize=8)
    ax.set_xlim(0, 360)
    ax.set_ylim(-90, 90)
    ax.set_xticks(range(0, 361, 45))
    ax.set_yticks(range(-90, 91, 30))
    ax.xaxis.set_major_formatter(ticker.FuncFormatter(lambda v, _: f"{v:.0f}°"))
    ax.yaxis.set_major_formatter(ticker.FuncFormatter(lambda v, _: f"{v:.0f}°"))
    ax.set_xlabel("azimuth (0° toward −z, 90° toward +x)")
    ax.set_ylabel("elevation (90° = up, +Y)")
    ax.set_title(title or "optimized env map E*")
    if labels:
        mark_directions(ax, dirs, polar=False)
    return m


def mark_directions(ax, dirs, polar):
    def pos(d):
        if polar:
            return math.radians(d["azimuth_deg"]), 90 - d["elevation_deg"]
        return d["azimuth_deg"], d["elevation_deg"]

    def shown(d):
        return not polar or d["elevation_deg"] >= 0

    for key, marker, colour, text in [("camera", "o", "#00e5ff", "camera"),
                                      ("mirror", "X", "#7CFC00", "mirror")]:
        d = dirs.get(key)
        if d and shown(d):
            x, y = pos(d)
            ax.plot([x], [y], marker=marker, color=colour, mec="black", ms=8, ls="none",
                    label=f"{text} ({direction_label(d)})")
    # The brightest directions, labelled beside their marker; offsets alternate so that labels
    # of nearby peaks do not overlap.
    offsets = [(10, 10), (10, -16), (-10, 14)]
    for k, d in enumerate(dirs.get("brightest", [])):
        if not shown(d):
            continue
        x, y = pos(d)
        ax.plot([x], [y], marker="*", color="white", mec="black", ms=12, ls="none")
        dx, dy = offsets[k % len(offsets)]
        if not polar and d["azimuth_deg"] > 300:
            dx = -abs(dx)
        ax.annotate(f"{k + 1}: {direction_label(d)}", (x, y), xytext=(dx, dy),
                    textcoords="offset points", fontsize=8, color="black",
                    ha="left" if dx > 0 else "right",
                    bbox=dict(boxstyle="round,pad=0.2", fc="white", ec="none", alpha=0.85))


def draw_hemisphere(ax, data, dirs):
    az, el = data["azimuth_deg"], data["elevation_deg"]
    values = grid(data, "optimized")
    rows = [j for j, e in enumerate(el) if e >= -1e-9]
    ax.grid(False)  # pcolormesh on a polar grid: draw the grid again afterwards
    xe = [math.radians(v) for v in edges(az, 0.0, 360.0)]
    ye = [90 - v for v in edges([el[j] for j in rows], 0.0, 90.0)]
    ax.pcolormesh(xe, ye, [values[j] for j in rows], cmap="inferno", shading="flat", vmin=0,
                  vmax=max(1e-9, max(max(r) for r in values)))
    ax.grid(True, alpha=0.4)
    ax.set_theta_zero_location("N")
    ax.set_theta_direction(-1)
    ax.set_ylim(0, 90)
    ax.set_yticks([30, 60, 90])
    ax.set_yticklabels(["el 60°", "el 30°", "horizon"], fontsize=7)
    ax.set_xticks([math.radians(a) for a in range(0, 360, 45)])
    ax.set_xticklabels(["0° (−z)", "45°", "90° (+x)", "135°", "180° (+z)", "225°", "270° (−x)",
                        "315°"], fontsize=8)
    ax.set_title("upper hemisphere seen from above", pad=14)
    mark_directions(ax, dirs, polar=True)


def draw_loss(ax, it, loss, hit, held, s):
    ax.plot(it, loss, color="#1f77b4", lw=1.5, label="training loss")
    if held:
        ax.plot(hit, held, color="#d62728", lw=1.2, ls="--", marker="o", ms=4,
                label="the same loss on the independent estimate")
    values = [v for v in loss + held if math.isfinite(v)]
    if values and min(values) > 0:
        ax.set_yscale("log")
        lo, hi = min(values), max(values)
        subs = (1.0, 2.0, 5.0) if hi / lo > 20 else (1.0, 1.5, 2.0, 3.0, 4.0, 5.0, 7.0)
        ax.yaxis.set_major_locator(ticker.LogLocator(base=10, subs=subs))
        ax.yaxis.set_major_formatter(ticker.FuncFormatter(lambda v, _: f"{v:.3g}"))
        ax.yaxis.set_minor_formatter(ticker.NullFormatter())
        ax.set_ylabel("loss (log scale; lower is better)")
    else:
        ax.set_ylabel("loss (lower is better; linear: some values ≤ 0)")
    ax.xaxis.set_major_locator(ticker.MaxNLocator(nbins=6, integer=True))
    ax.set_xlabel("iteration")
    ax.set_title(f"{at(s, '/optimizer', '?')} on {at(s, '/objective', '?')}, "
                 f"λ = {at(s, '/lambda', float('nan')):g}")
    ax.grid(alpha=0.3, which="major")
    ax.legend(fontsize=8, loc="upper right")


def image(outdir, *names):
    for n in names:
        p = os.path.join(outdir, n)
        if os.path.exists(p):
            return mpimg.imread(p)
    return None


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("outdir")
    ap.add_argument("--title", default="")
    ap.add_argument("--print", action="store_true", help="name the files written")
    a = ap.parse_args()
    need = ["loss.csv", "summary.json"]
    missing = [f for f in need if not os.path.exists(os.path.join(a.outdir, f))]
    if missing:
        sys.exit(f"plot_optimize: {a.outdir} lacks {', '.join(missing)}: "
                 "is it the output directory of `scratchlight optimize`?")
    s = read_summary(a.outdir)
    data = None
    if os.path.exists(os.path.join(a.outdir, "plot-data.json")):
        with open(os.path.join(a.outdir, "plot-data.json")) as f:
            data = json.load(f)
    dirs = {"camera": at(s, "/envmap_directions/camera"),
            "mirror": at(s, "/envmap_directions/mirror"),
            "brightest": at(s, "/envmap_directions/brightest", [])}
    it, loss, hit, held = read_loss(os.path.join(a.outdir, "loss.csv"))
    wrote = []

    if data:
        fig = plt.figure(figsize=(13, 4.8))
        gs = fig.add_gridspec(1, 2, width_ratios=[2.1, 1])
        ax = fig.add_subplot(gs[0, 0])
        m = draw_latlong(ax, data, dirs)
        fig.colorbar(m, ax=ax, label="E (luminance)", fraction=0.04, pad=0.02)
        ax.legend(fontsize=8, loc="lower left", framealpha=0.85)
        draw_hemisphere(fig.add_subplot(gs[0, 1], projection="polar"), data, dirs)
        fig.tight_layout()
        out = os.path.join(a.outdir, "plot-envmap.png")
        save(fig, out, dpi=90)
        wrote.append(out)

    fig, ax = plt.subplots(figsize=(7.5, 4.2))
    draw_loss(ax, it, loss, hit, held, s)
    fig.tight_layout()
    out = os.path.join(a.outdir, "plot-loss.png")
    save(fig, out, dpi=90)
    wrote.append(out)

    lamp = at(s, "/compare/lamp/name", "")
    fig = plt.figure(figsize=(17, 4.6))
    gs = fig.add_gridspec(1, 4, width_ratios=[1, 1, 1.7, 1.3])
    for k, (names, title) in enumerate([
            (("view-lamp.png", "initial.png"), f"your lamp ({lamp})" if lamp else "before"),
            (("view-optimized.png", "render.png"), "optimized")]):
        ax = fig.add_subplot(gs[0, k])
        img = image(a.outdir, *names)
        if img is not None:
            ax.imshow(img, cmap="gray", vmin=0, vmax=1, interpolation="nearest")
        ax.set_title(title)
        ax.axis("off")
    ax = fig.add_subplot(gs[0, 2])
    if data:
        draw_latlong(ax, data, dirs, labels=True)
    else:
        img = image(a.outdir, "envmap.png")
        if img is not None:
            ax.imshow(img, cmap="gray", vmin=0, vmax=1, interpolation="nearest")
        ax.set_title("optimized env map")
        ax.axis("off")
    draw_loss(fig.add_subplot(gs[0, 3]), it, loss, hit, held, s)
    # No timings in the figure: it is the same bytes for any run of the same inputs.
    fig.suptitle(a.title or f"scratchlight optimize: loss {s['initial_loss']:.4g} → "
                 f"{s['final_loss']:.4g}")
    fig.tight_layout()
    out = os.path.join(a.outdir, "overview.png")
    save(fig, out, dpi=80)
    wrote.append(out)
    if a.print:
        for w in wrote:
            print(f"wrote {w}")


if __name__ == "__main__":
    main()
