#include "detect/RingModel.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "detect/ImageFilters.h"

namespace sl::defectmap {

namespace {

constexpr double kTwoPi = 6.28318530717958647692;
constexpr int kGrooveStep = 3;  // grooves between the arcs of grooveMedian

/// Bilinear value of img at (x, z); false outside [0, W−1]×[0, H−1].
bool bilinear(const float* img, int W, int H, double x, double z, float& v) {
    if (!(x >= 0.0 && z >= 0.0 && x <= W - 1 && z <= H - 1)) return false;
    const int x0 = std::min(static_cast<int>(x), W - 2), z0 = std::min(static_cast<int>(z), H - 2);
    const double fx = x - x0, fz = z - z0;
    const float* a = img + static_cast<size_t>(z0) * W + x0;
    v = static_cast<float>((1 - fz) * ((1 - fx) * a[0] + fx * a[1]) +
                           fz * ((1 - fx) * a[W] + fx * a[W + 1]));
    return true;
}

/// The median of img along the ring (the spiral of constant r − hand·pitch·φ/2π) through
/// sample (x, z): `half` samples of arc length on either side, inward until the spiral reaches
/// the centre. NaN at the centre (r < 1) or with fewer than half + 1 of the arc's samples on
/// the map.
float arcMedian(const float* img, int W, int H, const RingFit& f, double x, double z, int half,
                std::vector<float>& buf) {
    const double dx = x - f.cx, dz = z - f.cz;
    const double r = std::hypot(dx, dz);
    if (r < 1.0) return std::numeric_limits<float>::quiet_NaN();
    const double phi0 = std::atan2(dz, dx);
    const double grow = f.hand * f.pitch / kTwoPi;  // radius per radian along the spiral
    buf.clear();
    float v = 0.0f;
    if (bilinear(img, W, H, x, z, v)) buf.push_back(v);
    for (int dir = -1; dir <= 1; dir += 2) {
        double a = 0.0, rr = r;
        for (int j = 1; j <= half; ++j) {
            a += dir / std::hypot(rr, grow);  // one sample of arc length
            rr = r + grow * a;
            if (rr < 0.5) break;
            if (bilinear(img, W, H, f.cx + rr * std::cos(phi0 + a), f.cz + rr * std::sin(phi0 + a),
                         v))
                buf.push_back(v);
        }
    }
    if (buf.size() < static_cast<size_t>(half) + 1) return std::numeric_limits<float>::quiet_NaN();
    auto mid = buf.begin() + static_cast<std::ptrdiff_t>(buf.size() / 2);
    std::nth_element(buf.begin(), mid, buf.end());
    return *mid;
}

/// The periodic part of the ring model at sample (x, z): the median of the arc medians
/// (arcMedian) through it and through the points kGrooveStep pitches further out and in along
/// its radius (the same phase of the spiral on other grooves; the mean of two where one lies
/// past the centre). A ring-shaped change of level (a step) differs between the grooves and
/// stays out of it, as does a defect along a groove narrower than kGrooveStep pitches.
float grooveMedian(const float* img, int W, int H, const RingFit& f, int x, int z, int half,
                   std::vector<float>& buf) {
    const double dx = x - f.cx, dz = z - f.cz;
    const double r = std::hypot(dx, dz);
    if (r < 1.0) return std::numeric_limits<float>::quiet_NaN();
    float m[3];
    int n = 0;
    for (int k = -kGrooveStep; k <= kGrooveStep; k += kGrooveStep) {
        const double s = (r + k * f.pitch) / r;
        if (r + k * f.pitch < 1.0) continue;
        const float v = arcMedian(img, W, H, f, f.cx + s * dx, f.cz + s * dz, half, buf);
        if (!std::isnan(v)) m[n++] = v;
    }
    if (n == 0) return std::numeric_limits<float>::quiet_NaN();
    if (n == 1) return m[0];
    if (n == 2) return 0.5f * (m[0] + m[1]);
    return std::max(std::min(m[0], m[1]), std::min(std::max(m[0], m[1]), m[2]));
}

/// Mean |d − arc median of d| over the samples `pts` (flat indices); +inf with none valid.
/// Summed in the points' order (the result does not depend on the thread count).
double arcCost(const std::vector<float>& d, int W, int H, const RingFit& f, int half,
               const std::vector<size_t>& pts) {
    std::vector<float> res(pts.size());
    tbb::parallel_for(size_t{0}, pts.size(), [&](size_t i) {
        thread_local std::vector<float> buf;
        const size_t k = pts[i];
        const int x = static_cast<int>(k % static_cast<size_t>(W));
        const int z = static_cast<int>(k / static_cast<size_t>(W));
        const float m = arcMedian(d.data(), W, H, f, x, z, half, buf);
        res[i] = std::isnan(m) ? -1.0f : std::abs(d[k] - m);
    });
    double sum = 0.0;
    size_t cnt = 0;
    for (float v : res)
        if (v >= 0.0f) {
            sum += v;
            ++cnt;
        }
    return cnt ? sum / static_cast<double>(cnt) : std::numeric_limits<double>::infinity();
}

/// Fits the ring model to d = h − macro (W×H): centre, hand and the two decision statistics
/// (header, step 4b); `pitch` is d's dominantPeriod, which the notch pass found.
RingFit fitRings(const std::vector<float>& d, int W, int H, const DefectMapOptions& o,
                 double pitch) {
    RingFit f;
    f.residual = std::numeric_limits<double>::infinity();
    // structure tensor per 16×16 block: the line through the block along its gradient
    constexpr int kB = 16;
    struct Line {
        double px, pz, tx, tz, w;
    };
    std::vector<Line> lines;
    for (int by = 0; by + kB <= H; by += kB)
        for (int bx = 0; bx + kB <= W; bx += kB) {
            double jxx = 0, jxz = 0, jzz = 0;
            for (int y = std::max(by, 1); y < std::min(by + kB, H - 1); ++y)
                for (int x = std::max(bx, 1); x < std::min(bx + kB, W - 1); ++x) {
                    const size_t k = static_cast<size_t>(y) * W + x;
                    const double gx = 0.5 * (d[k + 1] - d[k - 1]);
                    const double gz = 0.5 * (d[k + W] - d[k - W]);
                    jxx += gx * gx;
                    jxz += gx * gz;
                    jzz += gz * gz;
                }
            const double tr = jxx + jzz;
            if (!(tr > 0.0)) continue;
            const double coh = std::hypot(jxx - jzz, 2.0 * jxz) / tr;
            const double phi = 0.5 * std::atan2(2.0 * jxz, jxx - jzz);  // the gradient's
            lines.push_back({bx + 0.5 * (kB - 1), by + 0.5 * (kB - 1), -std::sin(phi),
                             std::cos(phi), coh * coh});
        }
    if (lines.size() < 4) return f;
    auto solve = [&](const std::vector<double>& w, double& cx, double& cz, double& iso) {
        double a = 0, b = 0, c = 0, u = 0, v = 0;  // Σ w t tᵀ = [a b; b c], Σ w (t·p) t
        for (size_t i = 0; i < lines.size(); ++i) {
            const Line& l = lines[i];
            const double tp = l.tx * l.px + l.tz * l.pz;
            a += w[i] * l.tx * l.tx;
            b += w[i] * l.tx * l.tz;
            c += w[i] * l.tz * l.tz;
            u += w[i] * tp * l.tx;
            v += w[i] * tp * l.tz;
        }
        const double det = a * c - b * b, half = 0.5 * (a + c);
        const double disc = std::sqrt(std::max(0.0, 0.25 * (a - c) * (a - c) + b * b));
        iso = half + disc > 0.0 ? (half - disc) / (half + disc) : 0.0;
        if (!(det > 1e-12 * (a + c) * (a + c))) return false;
        cx = (c * u - b * v) / det;
        cz = (a * v - b * u) / det;
        return true;
    };
    std::vector<double> w0(lines.size()), w(lines.size());
    for (size_t i = 0; i < lines.size(); ++i) w0[i] = lines[i].w;
    double iso = 0.0, isoRobust = 0.0;
    if (!solve(w0, f.cx, f.cz, iso)) return f;
    f.isotropy = iso;
    if (iso < o.ringIsotropy) return f;  // parallel paths: no centre to find
    const double delta = 2.0 * kB;       // Cauchy scale of a line's distance from the centre
    for (int it = 0; it < 6; ++it) {
        for (size_t i = 0; i < lines.size(); ++i) {
            const Line& l = lines[i];
            const double dist = (f.cx - l.px) * l.tx + (f.cz - l.pz) * l.tz;
            w[i] = w0[i] / (1.0 + (dist / delta) * (dist / delta));
        }
        double cx = 0, cz = 0;
        if (!solve(w, cx, cz, isoRobust)) break;
        f.cx = cx;
        f.cz = cz;
    }
    f.pitch = pitch;
    const int half = o.ringWindow / 2;
    // the hand: the one that explains more of d where the rings curve most (10–120 samples
    // from the centre; the whole map's grid when too few of those lie on the map)
    auto grid = [&](int step, double rMin, double rMax) {
        std::vector<size_t> pts;
        for (int z = step / 2; z < H; z += step)
            for (int x = step / 2; x < W; x += step) {
                const double r = std::hypot(x - f.cx, z - f.cz);
                if (r >= rMin && r <= rMax) pts.push_back(static_cast<size_t>(z) * W + x);
            }
        return pts;
    };
    std::vector<size_t> pts = grid(6, 10.0, 120.0);
    if (pts.size() < 200)
        pts = grid(std::max(2, static_cast<int>(std::sqrt(W * 1.0 * H / 4000))), 0.0,
                   std::numeric_limits<double>::infinity());
    f.hand = 1;
    {
        RingFit g = f;
        g.hand = -1;
        if (arcCost(d, W, H, g, half, pts) < arcCost(d, W, H, f, half, pts)) f.hand = -1;
    }
    // the decision statistic ρ on a grid over the whole map
    {
        const int step = std::max(2, static_cast<int>(std::sqrt(W * 1.0 * H / 16000)));
        const std::vector<size_t> all = grid(step, 0.0, std::numeric_limits<double>::infinity());
        std::vector<float> res(all.size()), mag(all.size());
        tbb::parallel_for(size_t{0}, all.size(), [&](size_t i) {
            thread_local std::vector<float> buf;
            const size_t k = all[i];
            const float m = arcMedian(d.data(), W, H, f, static_cast<double>(k % W),
                                      static_cast<double>(k / W), half, buf);
            res[i] = std::isnan(m) ? -1.0f : std::abs(d[k] - m);
            mag[i] = std::isnan(m) ? -1.0f : std::abs(d[k]);
        });
        auto med = [](std::vector<float>& v) {
            v.erase(std::remove(v.begin(), v.end(), -1.0f), v.end());
            if (v.empty()) return 0.0;
            auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
            std::nth_element(v.begin(), mid, v.end());
            return static_cast<double>(*mid);
        };
        const double mr = med(res), mm = med(mag);
        if (mm > 0.0) f.residual = mr / mm;
    }
    return f;
}

}  // namespace

RingFit ringFit(std::span<const float> h, const std::vector<float>& macro, int W, int H,
                const DefectMapOptions& o, double pitch, DefectMap& info) {
    std::vector<float> d(h.size());
    for (size_t k = 0; k < d.size(); ++k) d[k] = h[k] - macro[k];
    const RingFit f = fitRings(d, W, H, o, pitch);
    info.ringCentreX = f.cx;
    info.ringCentreZ = f.cz;
    info.ringPitch = f.pitch;
    info.ringHand = f.hand;
    info.ringIsotropy = f.isotropy;
    info.ringResidual = f.residual;
    info.ringUsed = f.pitch > 0.0 && f.isotropy >= o.ringIsotropy && f.residual <= o.ringResidual;
    return f;
}

void ringLevel(std::span<const float> h, const std::vector<float>& macro, std::vector<float>& A,
               int W, int H, const DefectMapOptions& o, double floorSigma, const RingFit& f,
               DefectMap& info) {
    if (!info.ringUsed) return;
    std::vector<float> d(h.size());
    for (size_t k = 0; k < d.size(); ++k) d[k] = h[k] - macro[k];
    const float medA = static_cast<float>(medianAbs(A));
    const float limit = static_cast<float>(o.growSigma * std::max(1.4826 * medA, floorSigma));
    const float ratio = static_cast<float>(o.ringRatio);
    const int half = o.ringWindow / 2;
    tbb::enumerable_thread_specific<size_t> lowered(size_t{0});
    tbb::parallel_for(0, H, [&](int z) {
        thread_local std::vector<float> buf;
        for (int x = 0; x < W; ++x) {
            const size_t k = static_cast<size_t>(z) * W + x;
            if (!(std::abs(A[k]) >= limit)) continue;
            const float m = grooveMedian(d.data(), W, H, f, x, z, half, buf);
            if (std::isnan(m)) continue;
            const float ar = d[k] - m;
            if (std::abs(ar) <= ratio * std::abs(A[k])) {
                A[k] = std::copysign(std::max(std::abs(ar), medA), ar);
                ++lowered.local();
            }
        }
    });
    for (size_t c : lowered) info.ringLowered += c;
}

}  // namespace sl::defectmap
