// Synthetic NC-machined surfaces, the defects: scratches, gouges, dents, chatter bands, the
// pocket-edge burr, cracks and measurement spikes (stages 3, 4, 4b-4e, 6b), and the truth
// labels' table. See SurfaceGenerator.h for the model and conventions. The crack's shape
// (crackPaths, crackOffset) is public: insert-defects (synth/DefectInsert.h) cuts the same one.
#include <algorithm>
#include <cmath>
#include <string>

#include "core/Rng.h"
#include "synth/SurfaceGenerator.h"
#include "synth/SurfaceGeneratorDetail.h"

namespace sl::surfacegen {
namespace {

Segment makeSegment(double x0, double z0, double x1, double z1, double reach, double pitch, int W,
                    int H) {
    Segment g{};
    g.ax = x0;
    g.az = z0;
    g.L = std::hypot(x1 - x0, z1 - z0);
    g.ux = (x1 - x0) / g.L;
    g.uz = (z1 - z0) / g.L;
    double cx = 0.5 * (W - 1), cz = 0.5 * (H - 1);
    auto toIdx = [&](double v, double c, int n, bool lo) {
        double k = lo ? std::floor(v / pitch + c) : std::ceil(v / pitch + c);
        return static_cast<int>(std::clamp(k, -1.0, static_cast<double>(n)));
    };
    g.i0 = std::max(0, toIdx(std::min(x0, x1) - reach, cx, W, true));
    g.i1 = std::min(W - 1, toIdx(std::max(x0, x1) + reach, cx, W, false));
    g.j0 = std::max(0, toIdx(std::min(z0, z1) - reach, cz, H, true));
    g.j1 = std::min(H - 1, toIdx(std::max(z0, z1) + reach, cz, H, false));
    return g;
}

}  // namespace

/// Scratch height offset at (x, z); sets `cut` when inside the groove (truth), `lip` where the
/// lip is ≥ 10% of its height.
double scratchOffset(const Scratch& c, double x, double z, bool& cut, bool& lip) {
    const Segment& g = c.seg;
    double px = x - g.ax, pz = z - g.az;
    double along = px * g.ux + pz * g.uz;
    if (along <= 0 || along >= g.L) return 0.0;
    double d = std::abs(-px * g.uz + pz * g.ux);
    double w = c.spec.width;
    double u = 2.0 * d / w;
    if (u >= 2.0) return 0.0;
    double fade = smoothstep01(std::min(along, g.L - along) / c.taper);
    double D = c.spec.depth * fade;
    if (u < 1.0) {
        if (fade >= 0.1) cut = true;
        return c.spec.shape == ScratchSpec::Shape::V ? -D * (1.0 - u) : -D * (1.0 - u * u);
    }
    double v = (u - 1.5) * 2.0;  // lip centred at 0.75·w, half-width 0.25·w
    double b = 1.0 - v * v;
    if (fade >= 0.1 && b * b >= 0.1) lip = true;
    return c.spec.burr * D * b * b;
}

/// Height of the gouge's swept sphere at (x, z) (relative to the cut plane y = 0), or +inf.
double gougeSurface(const Gouge& gg, double x, double z) {
    const Segment& g = gg.seg;
    constexpr int kSteps = 96;
    double R = gg.radius, R2 = R * R;
    double best = kInf;
    double px = x - g.ax, pz = z - g.az;
    double along = px * g.ux + pz * g.uz;
    double d = -px * g.uz + pz * g.ux;
    double d2 = d * d;
    if (d2 >= R2) return kInf;
    for (int n = 0; n <= kSteps; ++n) {
        double tau = static_cast<double>(n) / kSteps;
        double dt = along - tau * g.L;
        double r2 = dt * dt + d2;
        if (r2 >= R2) continue;
        double h = sphereRise(R, r2) - gg.spec.depth * std::sin(kPi * tau);
        best = std::min(best, h);
    }
    return best;
}

/// Stage 3: the scratches, given or drawn (stratified) from the seed; their specs into `out`.
std::vector<Scratch> placeScratches(const SurfaceSpec& spec, const Frame& fr,
                                    GeneratedSurface& out) {
    const int W = fr.W, H = fr.H;
    const double pitch = fr.pitch, extX = fr.extX, extZ = fr.extZ;
    std::vector<Scratch> scratches;
    if (!spec.scratches.empty()) {
        out.scratches = spec.scratches;
    } else {
        // Centres stratified (Latin hypercube over x and z) so scratches spread over the map.
        Pcg32 rng(mix64(spec.seed ^ kScratchStream), kScratchStream);
        const int count = spec.scratchCount;
        std::vector<int> sx(static_cast<size_t>(count)), sz(static_cast<size_t>(count));
        for (int n = 0; n < count; ++n) sx[static_cast<size_t>(n)] = sz[static_cast<size_t>(n)] = n;
        for (std::vector<int>* perm : {&sx, &sz})
            for (int n = count - 1; n > 0; --n)
                std::swap((*perm)[static_cast<size_t>(n)],
                          (*perm)[rng.nextU32() % static_cast<uint32_t>(n + 1)]);
        double shorter = std::min(extX, extZ);
        for (int n = 0; n < count; ++n) {
            double ux = (sx[static_cast<size_t>(n)] + rng.nextDouble()) / count;
            double uz = (sz[static_cast<size_t>(n)] + rng.nextDouble()) / count;
            double mx = (ux - 0.5) * 0.8 * extX;
            double mz = (uz - 0.5) * 0.8 * extZ;
            double len = (0.15 + 0.35 * rng.nextDouble()) * shorter;
            const double uth = rng.nextDouble();
            // Spread 180°: any direction (the draw of before the spread existed, bit for bit).
            const double th =
                spec.scratchDirectionSpreadDeg >= 180
                    ? kPi * uth
                    : (spec.scratchDirectionDeg + spec.scratchDirectionSpreadDeg * (uth - 0.5)) *
                          kPi / 180.0;
            const double dMin = spec.scratchDepthMin, wMin = spec.scratchWidthMin;
            ScratchSpec c;
            c.depth = spec.scratchDepth * (dMin + (1.0 - dMin) * rng.nextDouble());
            c.width = spec.scratchWidth * (wMin + (1.0 - wMin) * rng.nextDouble());
            c.shape = rng.nextDouble() < 0.5 ? ScratchSpec::Shape::V : ScratchSpec::Shape::Round;
            c.x0 = mx - 0.5 * len * std::cos(th);
            c.z0 = mz - 0.5 * len * std::sin(th);
            c.x1 = mx + 0.5 * len * std::cos(th);
            c.z1 = mz + 0.5 * len * std::sin(th);
            out.scratches.push_back(c);
        }
    }
    for (const ScratchSpec& c : out.scratches) {
        Scratch sc{makeSegment(c.x0, c.z0, c.x1, c.z1, c.width, pitch, W, H), c, 0.0};
        sc.taper = std::min(0.25 * sc.seg.L, 5.0 * c.width);
        scratches.push_back(sc);
    }

    return scratches;
}

/// Stage 4: the gouges (tool digs), given or drawn from the seed off the pocket edge.
std::vector<Gouge> placeGouges(const SurfaceSpec& spec, const Frame& fr, const ToolMarks& tm,
                               GeneratedSurface& out) {
    const int W = fr.W, H = fr.H;
    const double pitch = fr.pitch, extX = fr.extX, extZ = fr.extZ;
    const bool ball = fr.ball;
    std::vector<Gouge> gouges;
    const double gougeRadius = ball || fr.process == SurfaceSpec::Process::Ground ? spec.toolRadius
                               : fr.process == SurfaceSpec::Process::FlatEndPocket
                                   ? spec.toolCornerRadius
                                   : spec.insertNoseRadius;
    if (!spec.gouges.empty()) {
        out.gouges = spec.gouges;
    } else {
        // Kept off the pocket edge (redrawn up to 64 times), so that defects and the macro edge
        // stay apart and a detector's hits on either can be told apart.
        Pcg32 rng(mix64(spec.seed ^ kGougeStream), kGougeStream);
        const double keepOut = std::isfinite(out.pocketEdgeX)
                                   ? out.pocketEdgeHalfWidth + 0.5 * spec.gougeLength +
                                         std::sqrt(2.0 * gougeRadius * spec.gougeDepth) +
                                         0.5 * spec.stepover + 0.1
                                   : -1.0;
        for (int n = 0; n < spec.gougeCount; ++n) {
            double mx = 0, mz = 0;
            for (int attempt = 0; attempt < 64; ++attempt) {
                mx = (rng.nextDouble() - 0.5) * 0.6 * extX;
                mz = (rng.nextDouble() - 0.5) * 0.6 * extZ;
                if (!(std::abs(mx - out.pocketEdgeX) < keepOut)) break;
            }
            double t = mx * tm.cosA + mz * tm.sinA;
            double p = -mx * tm.sinA + mz * tm.cosA;
            if (ball) p = tm.off + std::nearbyint((p - tm.off) / tm.s) * tm.s;  // on a path
            double h = 0.5 * spec.gougeLength;
            GougeSpec g;
            g.depth = spec.gougeDepth;
            g.x0 = (t - h) * tm.cosA - p * tm.sinA;
            g.z0 = (t - h) * tm.sinA + p * tm.cosA;
            g.x1 = (t + h) * tm.cosA - p * tm.sinA;
            g.z1 = (t + h) * tm.sinA + p * tm.cosA;
            out.gouges.push_back(g);
        }
    }
    for (const GougeSpec& g : out.gouges) {
        // The crater ends where the sphere has risen above the lowest tool mark (−chatter):
        // rise(r) = D + A, i.e. r² = e·(2R − e) with e = D + A.
        double e = std::min(g.depth + tm.maxA, gougeRadius);
        double reach = std::min(std::sqrt(e * (2 * gougeRadius - e)) + 2 * pitch, gougeRadius);
        gouges.push_back({makeSegment(g.x0, g.z0, g.x1, g.z1, reach, pitch, W, H), g, gougeRadius});
    }

    return gouges;
}

/// Dent height offset (≤ 0) at (x, z); sets `hit` where it lowers by ≥ 10% of the depth.
double dentOffset(const Dent& d, double x, double z, bool& hit) {
    double dx = x - d.spec.x, dz = z - d.spec.z;
    double r2 = dx * dx + dz * dz;
    if (r2 >= d.reach2) return 0.0;
    double lower = d.spec.depth - sphereRise(d.spec.radius, r2);
    if (lower <= 0) return 0.0;
    if (lower >= 0.1 * d.spec.depth) hit = true;
    return -lower;
}

/// Stage 4b: the dents, given or drawn from the seed (uniform over the inner 80% of the map,
/// off the pocket edge).
std::vector<Dent> placeDents(const SurfaceSpec& spec, const Frame& fr, GeneratedSurface& out) {
    if (!spec.dents.empty()) {
        out.dents = spec.dents;
    } else if (spec.dentCount > 0) {
        Pcg32 rng(mix64(spec.seed ^ kDentStream), kDentStream);
        const double R = spec.dentRadius, D = spec.dentDepth;
        const double keepOut = std::isfinite(out.pocketEdgeX)
                                   ? out.pocketEdgeHalfWidth + std::sqrt(D * (2 * R - D)) + 0.1
                                   : -1.0;
        for (int n = 0; n < spec.dentCount; ++n) {
            DentSpec d;
            for (int attempt = 0; attempt < 64; ++attempt) {
                d.x = (rng.nextDouble() - 0.5) * 0.8 * fr.extX;
                d.z = (rng.nextDouble() - 0.5) * 0.8 * fr.extZ;
                if (!(std::abs(d.x - out.pocketEdgeX) < keepOut)) break;
            }
            d.depth = D * (0.5 + 0.5 * rng.nextDouble());
            d.radius = R;
            out.dents.push_back(d);
        }
    }
    std::vector<Dent> dents;
    for (const DentSpec& d : out.dents) {
        Dent dt;
        dt.spec = d;
        dt.reach2 = d.depth * (2 * d.radius - d.depth);
        double reach = std::sqrt(dt.reach2) + fr.pitch;
        auto lo = [&](double v, double c, int n) {
            return static_cast<int>(std::clamp(std::floor(v / fr.pitch + c), 0.0, n - 1.0));
        };
        auto hi = [&](double v, double c, int n) {
            return static_cast<int>(std::clamp(std::ceil(v / fr.pitch + c), -1.0, n - 1.0));
        };
        if (d.x + reach < -0.5 * fr.extX || d.x - reach > 0.5 * fr.extX ||
            d.z + reach < -0.5 * fr.extZ || d.z - reach > 0.5 * fr.extZ)
            continue;  // off the map
        dt.i0 = lo(d.x - reach, fr.cx, fr.W);
        dt.i1 = hi(d.x + reach, fr.cx, fr.W);
        dt.j0 = lo(d.z - reach, fr.cz, fr.H);
        dt.j1 = hi(d.z + reach, fr.cz, fr.H);
        dents.push_back(dt);
    }
    return dents;
}

/// The range of the across-path coordinate c over the map: p for milling, the distance to the
/// turning centre for Turned.
std::pair<double, double> acrossRange(const Frame& fr, const ToolMarks& tm) {
    const double hx = 0.5 * fr.extX, hz = 0.5 * fr.extZ;
    if (fr.process == SurfaceSpec::Process::Turned) {
        double nx = std::max(0.0, std::abs(tm.xc) - hx), nz = std::max(0.0, std::abs(tm.zc) - hz);
        return {std::hypot(nx, nz), std::hypot(std::abs(tm.xc) + hx, std::abs(tm.zc) + hz)};
    }
    double h = std::abs(tm.sinA) * hx + std::abs(tm.cosA) * hz;
    return {-h, h};
}

/// Stage 4c: the chatter bands' centres (across-path coordinate), uniform over the map's range.
std::vector<double> placeChatterBands(const SurfaceSpec& spec, const Frame& fr,
                                      const ToolMarks& tm) {
    std::vector<double> bands;
    if (spec.chatterBands <= 0) return bands;
    Pcg32 rng(mix64(spec.seed ^ kBandStream), kBandStream);
    auto [lo, hi] = acrossRange(fr, tm);
    const double w = spec.chatterBandWidth;
    for (int n = 0; n < spec.chatterBands; ++n) {
        const double u = rng.nextDouble();
        // A band wider than the map's range is centred on it.
        bands.push_back(hi - lo > w ? lo + 0.5 * w + u * (hi - lo - w) : 0.5 * (lo + hi));
    }
    return bands;
}

/// Stage 4d: the burr on the pocket's top edge (see the header).
Burr placeBurr(const SurfaceSpec& spec, const Frame& fr, const GeneratedSurface& out) {
    Burr b;
    if (!(spec.pocketBurrHeight > 0) || !std::isfinite(out.pocketEdgeX)) return b;
    b.across.assign(static_cast<size_t>(fr.W), 0.0);
    b.along.assign(static_cast<size_t>(fr.H), 0.0);
    const double xTop = out.pocketEdgeX - out.pocketEdgeHalfWidth;
    const double half = 0.5 * spec.pocketBurrWidth;
    for (int i = 0; i < fr.W; ++i) {
        double u = ((i - fr.cx) * fr.pitch - xTop) / half;
        double v = 1.0 - u * u;
        b.across[static_cast<size_t>(i)] = std::abs(u) < 1.0 ? v * v : 0.0;
    }
    constexpr double kSpacing = 0.25;  // mm between the random values along the edge
    for (int j = 0; j < fr.H; ++j) {
        double a = (j * fr.pitch) / kSpacing;  // from the map's −z edge
        double fl = std::floor(a);
        auto k = static_cast<int64_t>(fl);
        double v0 = hashUniform(spec.seed, kBurrStream, k);
        double v1 = hashUniform(spec.seed, kBurrStream, k + 1);
        double g = 0.5 + 0.5 * (v0 + (v1 - v0) * smoothstep01(a - fl));
        b.along[static_cast<size_t>(j)] = spec.pocketBurrHeight * g;
    }
    return b;
}

/// Stage 4e: the cracks, drawn from the seed (centres uniform over the inner 60% of the map, off
/// the pocket edge; see SurfaceSpec).
std::vector<Crack> placeCracks(const SurfaceSpec& spec, const Frame& fr, GeneratedSurface& out) {
    std::vector<Crack> cracks;
    if (spec.crackCount <= 0) return cracks;
    Pcg32 rng(mix64(spec.seed ^ kCrackStream), kCrackStream);
    const double keepOut = std::isfinite(out.pocketEdgeX)
                               ? out.pocketEdgeHalfWidth + 0.5 * spec.crackLength + 0.1
                               : -1.0;
    for (int n = 0; n < spec.crackCount; ++n) {
        CrackSpec c;
        for (int attempt = 0; attempt < 64; ++attempt) {
            c.x = (rng.nextDouble() - 0.5) * 0.6 * fr.extX;
            c.z = (rng.nextDouble() - 0.5) * 0.6 * fr.extZ;
            if (!(std::abs(c.x - out.pocketEdgeX) < keepOut)) break;
        }
        c.angleDeg = 180.0 * rng.nextDouble();
        c.length = spec.crackLength * (0.75 + 0.25 * rng.nextDouble());
        c.width = spec.crackWidth * (0.5 + 0.5 * rng.nextDouble());
        c.depth = spec.crackDepth * (0.5 + 0.5 * rng.nextDouble());
        c.branches = spec.crackBranches;
        c.seed = (static_cast<uint64_t>(rng.nextU32()) << 32) | rng.nextU32();
        out.cracks.push_back(c);
    }
    for (const CrackSpec& c : out.cracks) {
        Crack k;
        k.spec = c;
        k.paths = crackPaths(c);
        double x0 = kInf, x1 = -kInf, z0 = kInf, z1 = -kInf;
        for (const CrackPath& p : k.paths) {
            const auto [xa, xb] = std::minmax_element(p.x.begin(), p.x.end());
            const auto [za, zb] = std::minmax_element(p.z.begin(), p.z.end());
            x0 = std::min(x0, *xa);
            x1 = std::max(x1, *xb);
            z0 = std::min(z0, *za);
            z1 = std::max(z1, *zb);
        }
        const double reach = 0.5 * c.width + fr.pitch;
        auto lo = [&](double v, double cc, int n) {
            return static_cast<int>(std::clamp(std::floor(v / fr.pitch + cc), 0.0, n - 1.0));
        };
        auto hi = [&](double v, double cc, int n) {
            return static_cast<int>(std::clamp(std::ceil(v / fr.pitch + cc), -1.0, n - 1.0));
        };
        k.i0 = lo(x0 - reach, fr.cx, fr.W);
        k.i1 = hi(x1 + reach, fr.cx, fr.W);
        k.j0 = lo(z0 - reach, fr.cz, fr.H);
        k.j1 = hi(z1 + reach, fr.cz, fr.H);
        cracks.push_back(std::move(k));
    }
    return cracks;
}

/// Stage 6b: measurement spikes at random samples (after everything).
void addSpikes(const SurfaceSpec& spec, GeneratedSurface& out) {
    if (spec.spikeCount <= 0) return;
    Pcg32 rng(mix64(spec.seed ^ kSpikeStream), kSpikeStream);
    for (int n = 0; n < spec.spikeCount; ++n) {
        Spike sp;
        sp.i = std::min(out.width - 1, static_cast<int>(rng.nextDouble() * out.width));
        sp.j = std::min(out.height - 1, static_cast<int>(rng.nextDouble() * out.height));
        double sign = rng.nextDouble() < 0.5 ? -1.0 : 1.0;
        sp.height = sign * spec.spikeHeight * (0.5 + 0.5 * rng.nextDouble());
        float& h = out.heights[static_cast<size_t>(sp.j) * out.width + sp.i];
        h = static_cast<float>(h + sp.height);
        out.spikes.push_back(sp);
    }
}

}  // namespace sl::surfacegen

namespace sl {

using surfacegen::kPi;

std::vector<CrackPath> crackPaths(const CrackSpec& c) {
    using surfacegen::kCrackShapeStream;
    Pcg32 rng(mix64(c.seed ^ kCrackShapeStream), kCrackShapeStream);
    auto U = [&rng](double a, double b) { return a + (b - a) * rng.nextDouble(); };
    constexpr double kDeg = kPi / 180.0;
    constexpr int kTrunkPieces = 16, kBranchPieces = 8;
    // A zig-zag from (x, z) along `heading`: each piece deflected by a grain, pulled back toward
    // the mean direction.
    auto walk = [&](double x, double z, double heading, double length, int pieces, CrackPath& p) {
        p.x = {x};
        p.z = {z};
        const double step = length / pieces;
        double phi = U(-30, 30) * kDeg;
        for (int k = 0; k < pieces; ++k) {
            if (k > 0) phi = 0.5 * phi + U(-30, 30) * kDeg;
            x += step * std::cos(heading + phi);
            z += step * std::sin(heading + phi);
            p.x.push_back(x);
            p.z.push_back(z);
        }
    };
    std::vector<CrackPath> paths(1);
    CrackPath& trunk = paths[0];
    trunk.width = c.width;
    trunk.depth = c.depth;
    walk(0.0, 0.0, c.angleDeg * kDeg, c.length, kTrunkPieces, trunk);
    const double mx = 0.5 * (trunk.x.front() + trunk.x.back());
    const double mz = 0.5 * (trunk.z.front() + trunk.z.back());
    for (size_t k = 0; k < trunk.x.size(); ++k) {
        trunk.x[k] += c.x - mx;
        trunk.z[k] += c.z - mz;
    }
    for (int b = 0; b < c.branches; ++b) {
        const auto k = static_cast<size_t>(3 + rng.nextU32() % 11);  // vertex 3..13
        const double heading =
            std::atan2(paths[0].z[k + 1] - paths[0].z[k], paths[0].x[k + 1] - paths[0].x[k]) +
            (rng.nextDouble() < 0.5 ? -1.0 : 1.0) * U(25, 50) * kDeg;
        const double length = U(0.25, 0.5) * c.length;
        // The trunk's opening at vertex k (arc k·L/16): the ellipse's √(1 − (2t/L − 1)²).
        const double u = 2.0 * static_cast<double>(k) / kTrunkPieces - 1.0;
        const double e = std::sqrt(1.0 - u * u);
        CrackPath br;
        br.branch = true;
        br.width = 0.6 * e * c.width;
        br.depth = 0.6 * e * c.depth;
        walk(paths[0].x[k], paths[0].z[k], heading, length, kBranchPieces, br);
        paths.push_back(std::move(br));
    }
    return paths;
}

double crackPathOffset(const CrackPath& p, double x, double z) {
    // The nearest point of the polyline: its distance s and its arc position t.
    double best = surfacegen::kInf, arc = 0, acc = 0;
    for (size_t k = 0; k + 1 < p.x.size(); ++k) {
        const double dx = p.x[k + 1] - p.x[k], dz = p.z[k + 1] - p.z[k];
        const double len2 = dx * dx + dz * dz, len = std::sqrt(len2);
        double t = len2 > 0 ? ((x - p.x[k]) * dx + (z - p.z[k]) * dz) / len2 : 0.0;
        t = std::clamp(t, 0.0, 1.0);
        const double qx = p.x[k] + t * dx - x, qz = p.z[k] + t * dz - z;
        const double d2 = qx * qx + qz * qz;
        if (d2 < best) {
            best = d2;
            arc = acc + t * len;
        }
        acc += len;
    }
    if (!(acc > 0)) return 0.0;
    const double u = arc / acc;
    const double e = p.branch ? std::sqrt(std::max(0.0, 1.0 - u))
                              : std::sqrt(std::max(0.0, 1.0 - (2 * u - 1) * (2 * u - 1)));
    const double half = 0.5 * p.width * e, s = std::sqrt(best);
    if (!(s < half)) return 0.0;
    return -p.depth * e * (1.0 - s / half);
}

double crackOffset(const std::vector<CrackPath>& paths, double x, double z) {
    double v = 0.0;
    for (const CrackPath& p : paths) v = std::min(v, crackPathOffset(p, x, z));
    return v;
}

namespace {

constexpr TruthKind kTruthKinds[] = {
    {kTruthDefect, "defect", "scratch grooves and gouges"},
    {kTruthScratch, "scratch", "inserted scratches (insert-defects, model A)"},
    {kTruthGouge, "gouge", "inserted gouges (insert-defects, model B)"},
    {kTruthPit, "pit", "inserted pits (insert-defects, model A)"},
    {kTruthPitChain, "pit-chain", "inserted chains of pits (insert-defects, model B)"},
    {kTruthCrack, "crack", "cracks: narrow meandering, branching fissures with no rim"},
    {kTruthDent, "dent", "spherical dents"},
    {kTruthToolChange, "tool-change-step", "the ramp of a tool-change step"},
    {kTruthBurr, "burr", "the pocket-edge burr and labelled scratch lips"},
    {kTruthChatterBand, "chatter-band", "chatter bands"},
    {kTruthChatter, "chatter", "the confined chatter region"},
};

}  // namespace

std::span<const TruthKind> truthKinds() {
    return kTruthKinds;
}

std::vector<RegionLabel> truthLegend(const std::vector<uint8_t>& truth) {
    bool present[256] = {};
    for (uint8_t v : truth) present[v] = true;
    std::vector<RegionLabel> legend;
    for (const TruthKind& k : kTruthKinds)
        if (k.value == kTruthDefect || present[k.value]) legend.push_back({k.value, k.name});
    for (int v = 255; v >= 1; --v) {
        if (!present[v]) continue;
        bool known = false;
        for (const TruthKind& k : kTruthKinds) known = known || k.value == v;
        if (!known) legend.push_back({static_cast<uint8_t>(v), "label-" + std::to_string(v)});
    }
    return legend;
}

}  // namespace sl
