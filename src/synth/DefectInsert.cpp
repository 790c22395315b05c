#include "synth/DefectInsert.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "core/Error.h"
#include "core/PolynomialFit.h"
#include "core/Registry.h"
#include "core/Rng.h"
#include "synth/SurfaceGenerator.h"

namespace sl {

namespace {

constexpr double kPi = std::numbers::pi;

constexpr InsertKindRow kKinds[] = {
    {InsertKind::Scratch, "scratch", DefectModel::A, kTruthScratch,
     "model A: a V or rounded groove along a smooth curve, pile-up rims beside it"},
    {InsertKind::Pit, "pit", DefectModel::A, kTruthPit, "model A: a rounded crater with a rim"},
    {InsertKind::Burr, "burr", DefectModel::A, kTruthBurr,
     "model A: a raised lip along an edge segment, steep on one side"},
    {InsertKind::Gouge, "gouge", DefectModel::B, kTruthGouge,
     "model B: a straight gouge, steep wall on one side, a ramp on the other, no rim"},
    {InsertKind::PitChain, "pit-chain", DefectModel::B, kTruthPitChain,
     "model B: 4-8 small pits along a line, no rims"},
    {InsertKind::Dent, "dent", DefectModel::B, kTruthDent, "model B: a spherical dent with no rim"},
    {InsertKind::Crack, "crack", DefectModel::B, kTruthCrack,
     "model B, only when named: a narrow meandering, branching fissure with no rim", false},
};

double bump(double u) {  // (1 − u²)² on [−1, 1], 0 outside; ∫ = 16/15
    if (u <= -1 || u >= 1) return 0;
    const double a = 1 - u * u;
    return a * a;
}

/// Distance from (x, z) to the polyline, and the arc position of the nearest point.
void nearestOnPolyline(const std::vector<double>& px, const std::vector<double>& pz, double x,
                       double z, double& dist, double& arc, double& side) {
    double best = 1e300, acc = 0;
    for (size_t k = 0; k + 1 < px.size(); ++k) {
        const double dx = px[k + 1] - px[k], dz = pz[k + 1] - pz[k];
        const double len2 = dx * dx + dz * dz, len = std::sqrt(len2);
        double t = len2 > 0 ? ((x - px[k]) * dx + (z - pz[k]) * dz) / len2 : 0;
        t = std::clamp(t, 0.0, 1.0);
        const double qx = px[k] + t * dx - x, qz = pz[k] + t * dz - z;
        const double d2 = qx * qx + qz * qz;
        if (d2 < best) {
            best = d2;
            arc = acc + t * len;
            side = dx * (z - pz[k]) - dz * (x - px[k]);  // sign: which side of the curve
        }
        acc += len;
    }
    dist = std::sqrt(best);
}

double polylineLength(const std::vector<double>& px, const std::vector<double>& pz) {
    double L = 0;
    for (size_t k = 0; k + 1 < px.size(); ++k)
        L += std::hypot(px[k + 1] - px[k], pz[k + 1] - pz[k]);
    return L;
}

struct Box {
    int x0, z0, x1, z1;
    bool overlaps(const Box& o, int pad) const {
        return !(x1 + pad < o.x0 || o.x1 + pad < x0 || z1 + pad < o.z0 || o.z1 + pad < z0);
    }
};

/// A defect's offset field on its box: value(x, z) and the label threshold.
struct Stamp {
    Box box{};
    std::vector<double> off;  // box-sized
    double labelAt = 0;       // |offset| >= labelAt is labelled
};

template <class F>
Stamp makeStamp(Box b, int W, int H, F&& value, double labelAt) {
    b.x0 = std::max(b.x0, 0);
    b.z0 = std::max(b.z0, 0);
    b.x1 = std::min(b.x1, W - 1);
    b.z1 = std::min(b.z1, H - 1);
    Stamp s;
    s.box = b;
    s.labelAt = labelAt;
    s.off.assign(static_cast<size_t>(b.x1 - b.x0 + 1) * (b.z1 - b.z0 + 1), 0.0);
    size_t k = 0;
    for (int z = b.z0; z <= b.z1; ++z)
        for (int x = b.x0; x <= b.x1; ++x) s.off[k++] = value(x, z);
    return s;
}

Box polylineBox(const std::vector<double>& px, const std::vector<double>& pz, double reach) {
    auto [xa, xb] = std::minmax_element(px.begin(), px.end());
    auto [za, zb] = std::minmax_element(pz.begin(), pz.end());
    return {static_cast<int>(std::floor(*xa - reach)), static_cast<int>(std::floor(*za - reach)),
            static_cast<int>(std::ceil(*xb + reach)), static_cast<int>(std::ceil(*zb + reach))};
}

}  // namespace

std::span<const InsertKindRow> insertKindTable() {
    return kKinds;
}

const InsertKindRow& insertKindRow(InsertKind kind) {
    return registryRow(insertKindTable(), kind);
}

InsertKind parseInsertKind(std::string_view name, const std::string& where) {
    if (const InsertKindRow* r = findRegistryRow(insertKindTable(), name)) return r->value;
    throw inputError(where, "unknown defect kind '" + std::string(name) + "'",
                     "Use one of: " + registryNames(insertKindTable()));
}

std::vector<InsertKind> modelKinds(DefectModel model) {
    std::vector<InsertKind> k;
    for (const InsertKindRow& r : kKinds)
        if (r.model == model && r.byDefault) k.push_back(r.value);
    return k;
}

double grooveRimHeight(double width, double depth, bool rounded, double pileUp) {
    const double area = rounded ? 2.0 * depth * width / 3.0 : depth * width / 2.0;
    const double rim = width;  // each rim is as wide as the groove
    return pileUp * area / (2.0 * rim * 8.0 / 15.0);
}

double grooveProfile(const Groove& g, double s, double t, double length) {
    const double taperLen = std::min(length / 4.0, 3.0 * g.width);
    double taper = 1;
    if (taperLen > 0) taper = std::clamp(std::min(t, length - t) / taperLen, 0.0, 1.0);
    taper = taper * taper * (3 - 2 * taper);
    const double a = std::abs(s), half = g.width / 2;
    double v = 0;
    if (a < half) {
        const double u = a / half;
        v = -g.depth * (g.rounded ? 1 - u * u : 1 - u);
    }
    const double rim = g.width;
    v += grooveRimHeight(g.width, g.depth, g.rounded, g.pileUp) *
         bump((a - half - rim / 2) / (rim / 2));
    return taper * v;
}

double pitRimHeight(double radius, double depth, double pileUp) {
    const double r = radius / 2, volume = kPi * radius * radius * depth / 2;
    return pileUp * volume / (2 * kPi * (radius + r / 2) * r * 8.0 / 15.0);
}

double pitProfile(double radius, double depth, double pileUp, double rho) {
    double v = 0;
    if (rho < radius) v = -depth * (1 - (rho / radius) * (rho / radius));
    const double r = radius / 2;
    return v + pitRimHeight(radius, depth, pileUp) * bump((rho - radius - r / 2) / (r / 2));
}

double textureSq(std::span<const float> h, int W, int H) {
    // The form: the least-squares quadratic surface (core/PolynomialFit.h).
    const std::optional<PolynomialSurface> form =
        fitPolynomialSurface(h, static_cast<size_t>(W), static_cast<size_t>(H), 2);
    std::vector<double> res(static_cast<size_t>(W) * H), fit(static_cast<size_t>(W), 0.0);
    for (int j = 0; j < H; ++j) {
        if (form) form->row(static_cast<size_t>(j), fit);
        for (int i = 0; i < W; ++i)
            res[static_cast<size_t>(j) * W + i] =
                h[static_cast<size_t>(j) * W + i] - fit[static_cast<size_t>(i)];
    }
    // The L-filter: twice a separable box mean of min(W, H)/5 samples (edges clamped).
    std::vector<double> low = res, tmp(res.size());
    const int half = std::max(1, std::min(W, H) / 10);
    auto boxPass = [&](bool alongX) {
        const int n = alongX ? W : H, lines = alongX ? H : W;
        for (int l = 0; l < lines; ++l) {
            auto at = [&](int k) -> double& {
                return alongX ? low[static_cast<size_t>(l) * W + k]
                              : low[static_cast<size_t>(k) * W + l];
            };
            std::vector<double> prefix(n + 1, 0.0);
            for (int k = 0; k < n; ++k) prefix[k + 1] = prefix[k] + at(k);
            for (int k = 0; k < n; ++k) {
                const int ka = std::max(0, k - half), kb = std::min(n - 1, k + half);
                const double m = (prefix[kb + 1] - prefix[ka]) / (kb - ka + 1);
                (alongX ? tmp[static_cast<size_t>(l) * W + k]
                        : tmp[static_cast<size_t>(k) * W + l]) = m;
            }
        }
        low.swap(tmp);
    };
    for (int pass = 0; pass < 2; ++pass) {
        boxPass(true);
        boxPass(false);
    }
    double ss = 0;
    for (size_t k = 0; k < res.size(); ++k) ss += (res[k] - low[k]) * (res[k] - low[k]);
    return std::sqrt(ss / static_cast<double>(res.size()));
}

double resampleToMaxSide(std::vector<float>& h, int& W, int& H, int maxSide) {
    if (maxSide <= 0 || std::max(W, H) <= maxSide) return 1.0;
    if (maxSide < 2) throw inputError(option("size"), "must be at least 2", "");
    const double f = static_cast<double>(std::max(W, H)) / maxSide;
    const int nw = std::max(2, static_cast<int>(std::lround(W / f)));
    const int nh = std::max(2, static_cast<int>(std::lround(H / f)));
    // Box average over each new sample's footprint (f × f old samples, centred on it).
    std::vector<float> out(static_cast<size_t>(nw) * nh);
    const double half = f / 2;
    for (int j = 0; j < nh; ++j)
        for (int i = 0; i < nw; ++i) {
            const double x = (i + 0.5) * f - 0.5, z = (j + 0.5) * f - 0.5;
            const int xa = std::max(0, static_cast<int>(std::ceil(x - half))),
                      xb = std::min(W - 1, static_cast<int>(std::floor(x + half)));
            const int za = std::max(0, static_cast<int>(std::ceil(z - half))),
                      zb = std::min(H - 1, static_cast<int>(std::floor(z + half)));
            double s = 0;
            int n = 0;
            for (int zz = za; zz <= zb; ++zz)
                for (int xx = xa; xx <= xb; ++xx, ++n) s += h[static_cast<size_t>(zz) * W + xx];
            if (n == 0) {  // cannot happen for f > 1; nearest sample otherwise
                const int xi = std::clamp(static_cast<int>(std::lround(x)), 0, W - 1),
                          zi = std::clamp(static_cast<int>(std::lround(z)), 0, H - 1);
                s = h[static_cast<size_t>(zi) * W + xi];
                n = 1;
            }
            out[static_cast<size_t>(j) * nw + i] = static_cast<float>(s / n);
        }
    const double factor = static_cast<double>(W) / nw;
    h = std::move(out);
    W = nw;
    H = nh;
    return factor;
}

InsertResult insertDefects(std::span<const float> heights, int W, int H, const InsertSpec& spec) {
    if (W <= 0 || H <= 0 || heights.size() != static_cast<size_t>(W) * H)
        throw inputError("height map", "size does not match its width × height");
    if (spec.count < 0) throw inputError(option("count"), "must be >= 0");
    if (spec.faint < 0) throw inputError(option("faint"), "must be >= 0");
    if (!(spec.depth > 0) || !std::isfinite(spec.depth))
        throw inputError(option("depth"), "must be a positive height");
    if (!(spec.faintDepth > 0) || !std::isfinite(spec.faintDepth))
        throw inputError(option("faint-depth"), "must be a positive height");
    if (!(spec.sizeScale > 0) || !std::isfinite(spec.sizeScale))
        throw inputError(option("size-scale"), "must be > 0");
    if (!(spec.pileUp >= 0) || !std::isfinite(spec.pileUp))
        throw inputError(option("pile-up"), "must be >= 0");
    if (spec.margin < 0) throw inputError(option("margin"), "must be >= 0");
    if (std::min(W, H) < 2 * spec.margin + 16)
        throw inputError("height map",
                         std::to_string(W) + "x" + std::to_string(H) +
                             " samples is too small for defects kept " +
                             std::to_string(spec.margin) + " samples from its edges",
                         "Give a larger map or a smaller " + option("margin"));
    std::vector<InsertKind> kinds = spec.kinds.empty() ? modelKinds(spec.model) : spec.kinds;
    for (InsertKind k : kinds)
        if (insertKindRow(k).model != spec.model)
            throw inputError(option("kinds"),
                             std::string("kind '") + insertKindRow(k).name + "' is model " +
                                 (insertKindRow(k).model == DefectModel::A ? "A" : "B") +
                                 "'s, not the chosen model's",
                             "Choose kinds of the model");

    InsertResult res;
    res.heights.assign(heights.begin(), heights.end());
    res.truth.assign(heights.size(), 0);
    std::vector<Box> taken;
    Pcg32 rng(mix64(spec.seed ^ 0x5eedULL), mix64(spec.seed + 0x1234567ULL));
    auto U = [&rng](double a, double b) { return a + (b - a) * rng.nextDouble(); };
    const double S = std::min(W, H), sc = spec.sizeScale;
    const double lo = spec.margin, hxi = W - 1 - spec.margin, hzi = H - 1 - spec.margin;
    auto inside = [&](const Box& b) {
        return b.x0 >= lo && b.z0 >= lo && b.x1 <= hxi && b.z1 <= hzi;
    };

    // One defect of `kind` at depth d: tries placements until one fits, then stamps it.
    auto place = [&](InsertKind kind, double d, bool labelled) {
        for (int attempt = 0; attempt < 200; ++attempt) {
            InsertedDefect def;
            def.kind = kind;
            def.labelled = labelled;
            def.depth = d;
            Stamp st;
            const double cx = U(lo, hxi), cz = U(lo, hzi), th = U(0, kPi);
            const double ux = std::cos(th), uz = std::sin(th);
            switch (kind) {
                case InsertKind::Scratch: {
                    Groove g;
                    g.width = U(4, 8) * sc;
                    g.depth = d;
                    g.rounded = rng.nextDouble() < 0.5;
                    g.pileUp = spec.pileUp;
                    const double len = U(0.3, 0.6) * S, bend = U(-0.15, 0.15) * len;
                    const double ax = cx - ux * len / 2, az = cz - uz * len / 2;
                    const double bx = cx + ux * len / 2, bz = cz + uz * len / 2;
                    const double mx = cx - uz * bend * 2, mz = cz + ux * bend * 2;  // control
                    for (int k = 0; k <= 48; ++k) {
                        const double t = k / 48.0, a = (1 - t) * (1 - t), b = 2 * t * (1 - t),
                                     c = t * t;
                        g.px.push_back(a * ax + b * mx + c * bx);
                        g.pz.push_back(a * az + b * mz + c * bz);
                    }
                    const double L = polylineLength(g.px, g.pz), reach = 1.5 * g.width + 2;
                    st = makeStamp(
                        polylineBox(g.px, g.pz, reach), W, H,
                        [&](int x, int z) {
                            double dist = 0, arc = 0, side = 0;
                            nearestOnPolyline(g.px, g.pz, x, z, dist, arc, side);
                            return grooveProfile(g, dist, arc, L);
                        },
                        0.1 * d);
                    def.size = g.width;
                    break;
                }
                case InsertKind::Pit: {
                    const double r = U(4, 10) * sc, reach = 1.5 * r + 2;
                    st = makeStamp(
                        Box{static_cast<int>(cx - reach), static_cast<int>(cz - reach),
                            static_cast<int>(cx + reach) + 1, static_cast<int>(cz + reach) + 1},
                        W, H,
                        [&](int x, int z) {
                            return pitProfile(r, d, spec.pileUp, std::hypot(x - cx, z - cz));
                        },
                        0.1 * d);
                    def.size = r;
                    break;
                }
                case InsertKind::Burr: {
                    const double len = U(0.1, 0.25) * S, wb = U(3, 6) * sc;
                    const double ax = cx - ux * len / 2, az = cz - uz * len / 2;
                    const double side = rng.nextDouble() < 0.5 ? -1.0 : 1.0;
                    const double reach = wb + 2;
                    st = makeStamp(
                        polylineBox({ax, ax + ux * len}, {az, az + uz * len}, reach), W, H,
                        [&](int x, int z) {
                            const double t = ((x - ax) * ux + (z - az) * uz) / len;
                            const double s = side * (-(x - ax) * uz + (z - az) * ux);
                            if (t <= 0 || t >= 1) return 0.0;
                            const double g = std::sqrt(std::sin(kPi * t));
                            if (s < -1) return 0.0;
                            if (s < 0) return d * g * (1 + s);  // the 1-sample edge
                            if (s >= wb) return 0.0;
                            const double q = 1 - s / wb;
                            return d * g * q * q;
                        },
                        0.1 * d);
                    def.size = wb;
                    break;
                }
                case InsertKind::Gouge: {
                    const double len = U(0.15, 0.3) * S, w1 = U(1, 2), w2 = U(4, 8) * sc;
                    const double ax = cx - ux * len / 2, az = cz - uz * len / 2;
                    const double side = rng.nextDouble() < 0.5 ? -1.0 : 1.0;
                    st = makeStamp(
                        polylineBox({ax, ax + ux * len}, {az, az + uz * len}, w2 + 2), W, H,
                        [&](int x, int z) {
                            const double t = ((x - ax) * ux + (z - az) * uz) / len;
                            const double s = side * (-(x - ax) * uz + (z - az) * ux);
                            if (t <= 0 || t >= 1) return 0.0;
                            const double g = std::sin(kPi * t);
                            if (s <= -w1 || s >= w2) return 0.0;
                            if (s < 0) return -d * g * (1 + s / w1);
                            const double q = 1 - s / w2;
                            return -d * g * q * q;
                        },
                        0.1 * d);
                    def.size = w1 + w2;
                    break;
                }
                case InsertKind::PitChain: {
                    const int n = 4 + static_cast<int>(rng.nextU32() % 5);
                    const double r = U(2, 4) * sc, gap = U(2.5, 4) * r;
                    std::vector<double> px, pz, dd;
                    for (int k = 0; k < n; ++k) {
                        const double o = (k - (n - 1) / 2.0) * gap;
                        px.push_back(cx + ux * o);
                        pz.push_back(cz + uz * o);
                        dd.push_back(d * U(0.7, 1.0));
                    }
                    st = makeStamp(
                        polylineBox(px, pz, r + 2), W, H,
                        [&](int x, int z) {
                            double v = 0;
                            for (int k = 0; k < n; ++k) {
                                const double rho = std::hypot(x - px[k], z - pz[k]);
                                if (rho < r) v -= dd[k] * (1 - (rho / r) * (rho / r));
                            }
                            return v;
                        },
                        0.1 * d);
                    def.size = r;
                    break;
                }
                case InsertKind::Dent: {
                    const double r = U(10, 25) * sc, R = (r * r + d * d) / (2 * d);
                    st = makeStamp(
                        Box{static_cast<int>(cx - r - 2), static_cast<int>(cz - r - 2),
                            static_cast<int>(cx + r) + 3, static_cast<int>(cz + r) + 3},
                        W, H,
                        [&](int x, int z) {
                            const double rho = std::hypot(x - cx, z - cz);
                            if (rho >= r) return 0.0;
                            return -(d - (R - std::sqrt(R * R - rho * rho)));
                        },
                        0.1 * d);
                    def.size = r;
                    break;
                }
                case InsertKind::Crack: {
                    CrackSpec c;
                    c.x = cx;
                    c.z = cz;
                    c.angleDeg = th * 180.0 / kPi;
                    c.length = U(0.15, 0.3) * S;
                    c.width = U(2, 4) * sc;
                    c.depth = d;
                    c.branches = 1 + static_cast<int>(rng.nextU32() % 3);
                    c.seed = (static_cast<uint64_t>(rng.nextU32()) << 32) | rng.nextU32();
                    const std::vector<CrackPath> paths = crackPaths(c);
                    std::vector<double> px, pz;
                    for (const CrackPath& p : paths) {
                        px.insert(px.end(), p.x.begin(), p.x.end());
                        pz.insert(pz.end(), p.z.begin(), p.z.end());
                    }
                    st = makeStamp(
                        polylineBox(px, pz, 0.5 * c.width + 2), W, H,
                        [&](int x, int z) { return crackOffset(paths, x, z); }, 0.1 * d);
                    def.size = c.width;
                    break;
                }
            }
            if (!inside(st.box)) continue;
            bool free = true;
            for (const Box& b : taken) free = free && !b.overlaps(st.box, 4);
            if (!free) continue;
            taken.push_back(st.box);
            const uint8_t label = insertKindRow(kind).label;
            size_t k = 0;
            for (int z = st.box.z0; z <= st.box.z1; ++z)
                for (int x = st.box.x0; x <= st.box.x1; ++x, ++k) {
                    const size_t i = static_cast<size_t>(z) * W + x;
                    res.heights[i] += static_cast<float>(st.off[k]);
                    if (labelled && std::abs(st.off[k]) >= st.labelAt) {
                        res.truth[i] = std::max(res.truth[i], label);
                        ++def.samples;
                    }
                }
            def.x = cx;
            def.z = cz;
            def.x0 = st.box.x0;
            def.z0 = st.box.z0;
            def.x1 = st.box.x1;
            def.z1 = st.box.z1;
            res.defects.push_back(def);
            return;
        }
        ++res.skipped;
    };
    // Labelled defects first (kind by kind, so a seed gives the same first defects whatever
    // the count), then the faint ones.
    for (InsertKind k : kinds)
        for (int n = 0; n < spec.count; ++n) place(k, spec.depth * U(0.7, 1.3), true);
    for (InsertKind k : kinds)
        for (int n = 0; n < spec.faint; ++n) place(k, spec.faintDepth, false);
    return res;
}

}  // namespace sl
