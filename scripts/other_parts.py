#!/usr/bin/python3
"""A second part generator, independent of scratchlight's own (src/synth): numpy models written
from machining geometry without looking at gen-surface's code, so that the answers can be checked
on parts scratchlight's generator did not make.

    scripts/other_parts.py KIND SEED OUTDIR [--n 256] [--pitch 0.008] [--view 128]

KIND: ballend (ball-end raster scallops, feed marks, a chatter band; scratches named),
      facemill (overlapping cutter arcs, a pocket with a filleted wall; scratches and pits),
      polished (isotropic Gaussian-filtered roughness; shallow scratches, 0.3-1 Sq deep),
      turned (rings about a centre off the part, a tool-change step; dents and a gouge).
Writes OUTDIR/part.npy (heights in mm, float32), OUTDIR/part-truth.png (8-bit labels in
height-map space), OUTDIR/part-truth.json (the legend) and OUTDIR/scene.json.
"""
import argparse
import json
import os
import struct
import sys
import zlib

import numpy as np


def png_gray8(path, a):
    """An 8-bit grayscale PNG of a (rows, cols) uint8 array, values stored raw."""
    a = np.ascontiguousarray(a, dtype=np.uint8)
    h, w = a.shape
    raw = b"".join(b"\x00" + a[j].tobytes() for j in range(h))

    def chunk(tag, data):
        c = struct.pack(">I", len(data)) + tag + data
        return c + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
        f.write(chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0)))
        f.write(chunk(b"IDAT", zlib.compress(raw, 9)))
        f.write(chunk(b"IEND", b""))


def smooth_noise(rng, n, sigma_px):
    """Gaussian-filtered white noise (FFT), unit rms."""
    w = rng.standard_normal((n, n))
    f = np.fft.fftfreq(n)
    kx, ky = np.meshgrid(f, f)
    g = np.exp(-2 * (np.pi * sigma_px) ** 2 * (kx**2 + ky**2))
    s = np.real(np.fft.ifft2(np.fft.fft2(w) * g))
    return s / (s.std() + 1e-30)


def curve(rng, n, length_frac):
    """A smooth random curve of points (x, y) in samples: a gently bending path."""
    steps = int(n * length_frac)
    x, y = rng.uniform(0.15 * n, 0.85 * n, 2)
    ang = rng.uniform(0, np.pi)
    pts = []
    for _ in range(steps):
        ang += rng.normal(0, 0.01)
        x += np.cos(ang)
        y += np.sin(ang)
        if not (2 <= x < n - 2 and 2 <= y < n - 2):
            break
        pts.append((x, y))
    return np.array(pts)


def distance_to_points(n, pts):
    """Distance (samples) of every sample to the nearest point of a dense polyline."""
    yy, xx = np.mgrid[0:n, 0:n].astype(np.float64)
    d = np.full((n, n), np.inf)
    for k in range(0, len(pts), 2):
        x, y = pts[k]
        x0, x1 = int(max(0, x - 12)), int(min(n, x + 13))
        y0, y1 = int(max(0, y - 12)), int(min(n, y + 13))
        dd = np.hypot(xx[y0:y1, x0:x1] - x, yy[y0:y1, x0:x1] - y)
        d[y0:y1, x0:x1] = np.minimum(d[y0:y1, x0:x1], dd)
    return d


def add_scratch(h, labels, value, rng, depth, width_px):
    """A groove of the given depth (mm) and half-width (samples) along a random curve, the
    removed material piled up beside it (a rim of ~40 % of the groove's area on each side)."""
    n = h.shape[0]
    pts = curve(rng, n, rng.uniform(0.4, 0.8))
    if len(pts) < 10:
        return
    d = distance_to_points(n, pts)
    u = d / width_px
    groove = -depth * np.clip(1 - u**2, 0, None)
    rim = 0.4 * depth * np.exp(-((u - 1.6) ** 2) / 0.18) * (u > 1)
    h += groove + rim
    labels[u <= 1.0] = value


def add_pit(h, labels, value, rng, depth, radius_px):
    n = h.shape[0]
    x, y = rng.uniform(0.1 * n, 0.9 * n, 2)
    yy, xx = np.mgrid[0:n, 0:n]
    r = np.hypot(xx - x, yy - y) / radius_px
    h += -depth * np.clip(1 - r**2, 0, None) + 0.25 * depth * np.exp(-((r - 1.3) ** 2) / 0.1)
    labels[r <= 1.0] = value


def make(kind, seed, n, pitch):
    rng = np.random.default_rng(1000 * seed + {"ballend": 1, "facemill": 2, "polished": 3,
                                               "turned": 4}[kind])
    yy, xx = np.mgrid[0:n, 0:n].astype(np.float64) * pitch  # mm
    labels = np.zeros((n, n), np.uint8)
    legend = []
    if kind == "ballend":
        R, step = rng.uniform(1.5, 4.0), rng.uniform(0.10, 0.2)
        ang = rng.uniform(-0.3, 0.3)
        u = xx * np.cos(ang) + yy * np.sin(ang)
        v = -xx * np.sin(ang) + yy * np.cos(ang)
        d = (u % step) - step / 2
        h = R - np.sqrt(R * R - d * d)
        feed = rng.uniform(0.03, 0.06)
        h += 0.05 * h.max() * np.cos(2 * np.pi * v / feed + 7 * np.floor(u / step))
        band = (v > 0.35 * n * pitch) & (v < 0.6 * n * pitch)
        h += band * rng.uniform(0.2, 0.4) * h.max() * np.sin(2 * np.pi * v / rng.uniform(0.15, 0.3))
        h += 0.03 * h.max() * smooth_noise(rng, n, 1.5)
        sq = h.std()
        legend.append({"value": 255, "name": "scratch"})
        for _ in range(rng.integers(2, 4)):
            add_scratch(h, labels, 255, rng, rng.uniform(0.5, 2.0) * sq, rng.uniform(1.2, 2.5))
    elif kind == "facemill":
        Rc, f = rng.uniform(3, 6), rng.uniform(0.06, 0.12)
        cy = rng.uniform(-0.5, 0.5) * n * pitch
        phase = (xx + Rc - np.sqrt(np.clip(Rc * Rc - (yy - cy) ** 2, 0, None))) / f
        a = rng.uniform(0.5, 1.5) * 1e-3
        h = a * (np.mod(phase, 1.0) - 0.5) ** 2 * 4
        h += 0.08 * a * smooth_noise(rng, n, 1.2)
        # A pocket: a rectangle lowered by 30-60 um, a filleted wall.
        x0, x1 = sorted(rng.uniform(0.2, 0.8, 2) * n * pitch)
        y0, y1 = sorted(rng.uniform(0.2, 0.8, 2) * n * pitch)
        if x1 - x0 < 0.2 * n * pitch:
            x1 = min(0.95 * n * pitch, x0 + 0.3 * n * pitch)
        if y1 - y0 < 0.2 * n * pitch:
            y1 = min(0.95 * n * pitch, y0 + 0.3 * n * pitch)
        inside = np.minimum.reduce([xx - x0, x1 - xx, yy - y0, y1 - yy])
        fillet = 4 * pitch
        depth = rng.uniform(0.03, 0.06)
        h -= depth * np.clip(0.5 + inside / (2 * fillet), 0, 1)
        sq = (a * 4 * (np.mod(phase, 1.0) - 0.5) ** 2).std()
        legend += [{"value": 255, "name": "scratch"}, {"value": 128, "name": "pit"}]
        for _ in range(rng.integers(1, 3)):
            add_scratch(h, labels, 255, rng, rng.uniform(0.7, 2.5) * sq, rng.uniform(1.2, 2.5))
        for _ in range(rng.integers(2, 5)):
            add_pit(h, labels, 128, rng, rng.uniform(1.0, 3.0) * sq, rng.uniform(2, 4))
    elif kind == "polished":
        sq = rng.uniform(0.02, 0.06) * 1e-3
        h = sq * smooth_noise(rng, n, rng.uniform(0.8, 2.5))
        legend.append({"value": 255, "name": "scratch"})
        for _ in range(rng.integers(2, 5)):
            add_scratch(h, labels, 255, rng, rng.uniform(0.3, 1.0) * sq * 3, rng.uniform(1.0, 2.0))
    elif kind == "turned":
        cx, cy = rng.uniform(-1, 2) * n * pitch, rng.uniform(-3, -1) * n * pitch
        r = np.hypot(xx - cx, yy - cy)
        f = rng.uniform(0.05, 0.1)
        a = rng.uniform(0.3, 1.0) * 1e-3
        h = a * np.abs(np.sin(np.pi * r / f))
        step_r = np.median(r)
        h += rng.uniform(0.2, 0.5) * a * (r > step_r)
        h += 0.05 * a * smooth_noise(rng, n, 1.0)
        sq = h.std()
        legend += [{"value": 255, "name": "dent"}, {"value": 128, "name": "gouge"}]
        for _ in range(rng.integers(2, 4)):
            add_pit(h, labels, 255, rng, rng.uniform(1.0, 2.5) * sq, rng.uniform(3, 6))
        add_scratch(h, labels, 128, rng, rng.uniform(1.0, 2.0) * sq, rng.uniform(2.0, 3.0))
    else:
        raise SystemExit(f"other_parts.py: unknown kind {kind!r}")
    h -= h.mean()
    return h.astype(np.float32), labels, legend


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("kind")
    ap.add_argument("seed", type=int)
    ap.add_argument("outdir")
    ap.add_argument("--n", type=int, default=256)
    ap.add_argument("--pitch", type=float, default=0.008)
    ap.add_argument("--view", type=int, default=128)
    a = ap.parse_args()
    os.makedirs(a.outdir, exist_ok=True)
    h, labels, legend = make(a.kind, a.seed, a.n, a.pitch)
    np.save(os.path.join(a.outdir, "part.npy"), np.ascontiguousarray(h))
    png_gray8(os.path.join(a.outdir, "part-truth.png"), labels)
    with open(os.path.join(a.outdir, "part-truth.json"), "w") as f:
        json.dump({"labels": legend}, f)
    scene = {
        "description": f"other_parts.py {a.kind} seed {a.seed}: {a.n}x{a.n} @ {a.pitch} mm",
        "heightmap": {"path": "part.npy", "pixel_pitch": a.pitch},
        "camera": {"width": a.view, "height": a.view},
    }
    with open(os.path.join(a.outdir, "scene.json"), "w") as f:
        json.dump(scene, f, indent=2)
    print(f"{a.kind} seed {a.seed}: Sq {h.std() * 1e3:.3f} um, "
          f"{int((labels > 0).sum())} labelled samples -> {a.outdir}")


if __name__ == "__main__":
    sys.exit(main())
