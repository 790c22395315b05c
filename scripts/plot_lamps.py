#!/usr/bin/env python3
"""The lamps over E*: a polar plot of the upper hemisphere (zenith at the centre, the horizon at
the rim; azimuth 0 deg toward -z, 90 deg toward +x, as scene/Lamp.h) with E*'s texels as the
background and each lamp's outline, written by `scratchlight lamps` as OUTDIR/plot-lamps.png
from OUTDIR/plot-lamps.json (the grid's directions come from the job: no convention here)."""
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from atomic_save import savefig  # noqa: E402


def lamp_outline(lamp):
    """Points (azimuth rad, zenith deg) around the lamp's edge."""
    kind = lamp["kind"]
    el = math.radians(lamp["elevation_deg"])
    if kind == "ring":
        lo, hi = lamp["elevation_band_deg"]
        t = np.linspace(0, 2 * math.pi, 200)
        return [(t, np.full_like(t, 90 - min(hi, 90))), (t, np.full_like(t, 90 - max(lo, -90)))]
    az = math.radians(lamp["azimuth_deg"])
    c = np.array([math.sin(az) * math.cos(el), math.sin(el), -math.cos(az) * math.cos(el)])
    ephi = np.array([math.cos(az), 0.0, math.sin(az)])
    eel = np.array([-math.sin(az) * math.sin(el), math.cos(el), math.cos(az) * math.sin(el)])
    pts = []
    if kind == "disk":
        r = math.radians(lamp["angular_radius_deg"])
        for t in np.linspace(0, 2 * math.pi, 100):
            pts.append(math.cos(r) * c + math.sin(r) * (math.cos(t) * ephi + math.sin(t) * eel))
    else:
        a = math.radians(lamp["angular_length_deg"] / 2)
        b = math.radians(lamp["angular_width_deg"] / 2)
        roll = math.radians(lamp["roll_deg"])
        e1 = math.cos(roll) * ephi + math.sin(roll) * eel
        e2 = math.cos(roll) * eel - math.sin(roll) * ephi
        edge = []
        for x in np.linspace(-a, a, 40):
            edge.append((x, -b))
        for y in np.linspace(-b, b, 10):
            edge.append((a, y))
        for x in np.linspace(a, -a, 40):
            edge.append((x, b))
        for y in np.linspace(b, -b, 10):
            edge.append((-a, y))
        for x, y in edge:
            pts.append(math.cos(y) * (math.cos(x) * c + math.sin(x) * e1) + math.sin(y) * e2)
    pts = np.array(pts)
    azs = np.arctan2(pts[:, 0], -pts[:, 2])
    zen = 90 - np.degrees(np.arcsin(np.clip(pts[:, 1], -1, 1)))
    return [(azs, zen)]


def main():
    out = sys.argv[1]
    with open(os.path.join(out, "plot-lamps.json")) as f:
        d = json.load(f)
    w, h = d["width"], d["height"]
    target = np.array(d["target"]).reshape(h, w)
    az = np.radians(np.array(d["column_azimuth_deg"]))
    el = np.array(d["row_elevation_deg"])
    rows = el >= -1e-9
    fig = plt.figure(figsize=(10, 5))
    panels = [("target", "E* and the lamps"), ("lamps_envmap", "the lamps' env map")]
    for k, (key, title) in enumerate(panels):
        img = np.array(d[key]).reshape(h, w) if key != "target" else target
        ax = fig.add_subplot(1, 2, k + 1, projection="polar")
        ax.set_theta_zero_location("N")
        ax.set_theta_direction(-1)
        zen = 90 - el[rows]
        ax.grid(False)
        mesh = ax.pcolormesh(az, zen, img[rows], shading="nearest", cmap="magma", vmin=0,
                             vmax=max(1e-9, float(target.max())))
        ax.set_ylim(0, 90)
        ax.set_yticks([30, 60, 90])
        ax.set_yticklabels(["60°", "30°", "0°"])
        ax.set_title(title)
        ax.grid(True, alpha=0.3)
        if key == "target":
            for i, lamp in enumerate(d["lamps"]):
                for a_, z_ in lamp_outline(lamp):
                    ax.plot(a_, z_, color="cyan", lw=1.5)
                if lamp["kind"] != "ring":
                    ax.text(math.radians(lamp["azimuth_deg"]), 90 - lamp["elevation_deg"], str(i + 1),
                            color="cyan", ha="center", va="center", fontsize=12, weight="bold")
        fig.colorbar(mesh, ax=ax, shrink=0.7, label="E")
    fig.suptitle("zenith at the centre, horizon at the rim; azimuth 0° toward −z, 90° toward +x")
    savefig(fig, os.path.join(out, "plot-lamps.png"), dpi=110)


if __name__ == "__main__":
    main()
