#include "detect/SelfSimMap.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "core/Error.h"
#include "core/Interrupt.h"
#include "core/PolynomialFit.h"
#include "detect/Extent.h"
#include "detect/ReliefLevels.h"

namespace sl {

namespace {

constexpr double kPi = 3.14159265358979323846;

inline int clampi(int v, int lo, int hi) {
    return v < lo ? lo : (v > hi ? hi : v);
}

// Whether sample (x, y) of a W×H map lies inside its border of `border` samples (the samples the
// map never marks), and the same for the sample at index i (row-major).
inline bool insideBorder(int x, int y, int W, int H, int border) {
    return x >= border && y >= border && x < W - border && y < H - border;
}
inline bool insideBorder(size_t i, int W, int H, int border) {
    return insideBorder(static_cast<int>(i % W), static_cast<int>(i / W), W, H, border);
}

double medianOf(std::vector<float>& v) {
    if (v.empty()) return 0.0;
    const size_t m = v.size() / 2;
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(m), v.end());
    return v[m];
}

// The median of `v` and its robust σ, 1.4826 × the median absolute deviation from it (steps 5,
// 8l, 8r and 8t); `v` is left holding the absolute deviations |v − median|.
struct RobustScale {
    double median = 0.0, sigma = 0.0;
};
RobustScale robustScaleOf(std::vector<float>& v) {
    RobustScale s;
    s.median = medianOf(v);
    for (float& t : v) t = static_cast<float>(std::abs(t - s.median));
    s.sigma = 1.4826 * medianOf(v);
    return s;
}

// Step 1: g = h − the least-squares quadratic surface (coordinates scaled to [−1, 1]).
std::vector<float> removeQuadratic(std::span<const float> h, int W, int H) {
    // core/PolynomialFit.h; on a map one or two samples wide the terms it cannot tell apart
    // are left out (the same surface)
    const std::optional<PolynomialSurface> s =
        fitPolynomialSurface(h, static_cast<size_t>(W), static_cast<size_t>(H), 2);
    std::vector<float> g(h.size());
    tbb::parallel_for(0, H, [&](int y) {
        std::vector<double> f(static_cast<size_t>(W), 0.0);
        if (s) s->row(static_cast<size_t>(y), f);
        for (int x = 0; x < W; ++x) {
            const size_t k = static_cast<size_t>(y) * W + x;
            g[k] = static_cast<float>(h[k] - f[static_cast<size_t>(x)]);
        }
    });
    return g;
}

// Separable Gaussian blur of σ (radius 3σ), edges replicated.
std::vector<float> gaussianBlur(const std::vector<float>& img, int W, int H, double sigma) {
    const int r = std::max(1, static_cast<int>(std::ceil(3.0 * sigma)));
    std::vector<double> w(static_cast<size_t>(2 * r + 1));
    double sum = 0.0;
    for (int k = -r; k <= r; ++k) sum += w[k + r] = std::exp(-0.5 * k * k / (sigma * sigma));
    for (double& v : w) v /= sum;
    std::vector<float> tmp(img.size()), out(img.size());
    tbb::parallel_for(0, H, [&](int y) {
        const float* in = img.data() + static_cast<size_t>(y) * W;
        for (int x = 0; x < W; ++x) {
            double s = 0.0;
            for (int k = -r; k <= r; ++k) s += w[k + r] * in[clampi(x + k, 0, W - 1)];
            tmp[static_cast<size_t>(y) * W + x] = static_cast<float>(s);
        }
    });
    tbb::parallel_for(0, H, [&](int y) {
        for (int x = 0; x < W; ++x) {
            double s = 0.0;
            for (int k = -r; k <= r; ++k)
                s += w[k + r] * tmp[static_cast<size_t>(clampi(y + k, 0, H - 1)) * W + x];
            out[static_cast<size_t>(y) * W + x] = static_cast<float>(s);
        }
    });
    return out;
}

// Step 6 with roughnessCutoff: the RMS of a map's roughness outside the border -- the map less its
// Gaussian low-pass of cutoff wavelength λc (ISO 16610-61's weighting function: σ = λc·√(ln 2 /
// 2)/π), the form and waviness a roughness filter takes out
double roughnessRmsOf(const std::vector<float>& g, int W, int H, int b, double cutoff) {
    const std::vector<float> form =
        gaussianBlur(g, W, H, cutoff * std::sqrt(std::log(2.0) / 2.0) / kPi);
    double sum = 0.0;
    size_t count = 0;
    for (int y = b; y < H - b; ++y)
        for (int x = b; x < W - b; ++x) {
            const size_t i = static_cast<size_t>(y) * W + x;
            const double v = static_cast<double>(g[i]) - form[i];
            sum += v * v;
            ++count;
        }
    return count > 0 ? std::sqrt(sum / static_cast<double>(count)) : 0.0;
}

// Step 8k's rows: points (the hollows' centroids, x and z) linked when at most `gap` apart
// (Euclidean), in groups (single linkage); a group of at least `least` points whose extent
// (extentFromMoments) is at least `elongation` is a row. Each row's points' indices.
std::vector<std::vector<size_t>> rowsOf(std::span<const std::array<double, 2>> p, double gap,
                                        int least, double elongation) {
    std::vector<size_t> parent(p.size());
    for (size_t i = 0; i < p.size(); ++i) parent[i] = i;
    const auto root = [&](size_t i) {
        while (parent[i] != i) i = parent[i] = parent[parent[i]];
        return i;
    };
    for (size_t i = 0; i < p.size(); ++i)
        for (size_t j = i + 1; j < p.size(); ++j)
            if (std::hypot(p[i][0] - p[j][0], p[i][1] - p[j][1]) <= gap) parent[root(i)] = root(j);
    std::vector<std::vector<size_t>> groups(p.size()), rows;
    for (size_t i = 0; i < p.size(); ++i) groups[root(i)].push_back(i);
    for (std::vector<size_t>& g : groups) {
        if (static_cast<int>(g.size()) < least || g.empty()) continue;
        double mx = 0.0, mz = 0.0;
        for (const size_t i : g) mx += p[i][0], mz += p[i][1];
        const double m = static_cast<double>(g.size());
        mx /= m;
        mz /= m;
        double cxx = 0.0, czz = 0.0, cxz = 0.0;
        for (const size_t i : g) {
            const double dx = p[i][0] - mx, dz = p[i][1] - mz;
            cxx += dx * dx, czz += dz * dz, cxz += dx * dz;
        }
        Extent e;
        extentFromMoments(e, cxx / m, czz / m, cxz / m);
        if (e.elongation >= elongation) rows.push_back(std::move(g));
    }
    return rows;
}

// Step 8p's chains: runs of at least `least` points (the hollows' centroids, x and z), evenly
// spaced along a straight line: from each point i and each point j at most `gap` from it (and
// at least 1), the chain steps on by its mean step so far, taking the point nearest where the
// next step lands when it lies within `tolerance` × the step of it; a chain is kept when no
// point lies where the step back from i lands (its first point is i). Each chain's points'
// indices, in order (a chain and its reverse both).
std::vector<std::vector<size_t>> chainsOf(std::span<const std::array<double, 2>> p, double gap,
                                          int least, double tolerance) {
    std::vector<std::vector<size_t>> chains;
    // the point nearest (x, z), and its distance
    const auto nearest = [&](double x, double z) {
        size_t k = 0;
        double best = std::numeric_limits<double>::infinity();
        for (size_t m = 0; m < p.size(); ++m) {
            const double d = std::hypot(p[m][0] - x, p[m][1] - z);
            if (d < best) best = d, k = m;
        }
        return std::pair{k, best};
    };
    std::vector<size_t> chain;
    for (size_t i = 0; i < p.size(); ++i)
        for (size_t j = 0; j < p.size(); ++j) {
            const double d = std::hypot(p[j][0] - p[i][0], p[j][1] - p[i][1]);
            if (j == i || d > gap || d < 1.0) continue;
            chain = {i, j};
            double sx = p[j][0] - p[i][0], sz = p[j][1] - p[i][1];
            for (;;) {
                const auto [k, e] = nearest(p[chain.back()][0] + sx, p[chain.back()][1] + sz);
                if (e > tolerance * std::hypot(sx, sz) ||
                    std::find(chain.begin(), chain.end(), k) != chain.end())
                    break;
                chain.push_back(k);
                const double steps = static_cast<double>(chain.size() - 1);
                sx = (p[k][0] - p[i][0]) / steps;
                sz = (p[k][1] - p[i][1]) / steps;
            }
            const auto [k, e] = nearest(p[i][0] - sx, p[i][1] - sz);
            if (e <= tolerance * std::hypot(sx, sz) &&
                std::find(chain.begin(), chain.end(), k) == chain.end())
                continue;  // i is not the chain's first point
            if (static_cast<int>(chain.size()) >= least) chains.push_back(chain);
        }
    return chains;
}

// Whether at least `share` of the samples' Σ|r| lies on the side `sign` of the texture (+1
// above, -1 below); false when Σ|r| is 0 (steps 8c, 8e, 8k)
bool mostlyOfSign(std::span<const size_t> samples, const std::vector<float>& r, float sign,
                  double share) {
    double side = 0.0, all = 0.0;
    for (const size_t i : samples) {
        side += std::max(0.0f, sign * r[i]);
        all += std::abs(r[i]);
    }
    return all > 0.0 && side >= share * all;
}

// Step 8c: a region is a particle when it stands above the texture (at least `raisedShare` of
// its Σ|r| is positive) and is compact: its extent's elongation below `elongation`.
bool isParticle(const std::vector<size_t>& samples, const std::vector<float>& r, int W,
                double elongation, double raisedShare) {
    if (samples.empty()) return false;
    if (!mostlyOfSign(samples, r, 1.0f, raisedShare)) return false;
    return extentOf(samples, W).elongation < elongation;
}

// Step 8i: a piece is a line crossing the texture's lay when its extent is at least
// `elongation` and its long axis lies at least `angle` degrees (mod 180°) from the lay's
// direction `lay` (radians from the x axis, in [0, π)).
bool crossesLay(const Extent& e, double lay, double elongation, double angle) {
    if (!(e.elongation >= elongation)) return false;
    double d = std::abs(e.axis - lay);
    d = std::min(d, kPi - d);
    return d * 180.0 / kPi >= angle;
}

// Felzenszwalb and Huttenlocher's exact squared distance transform of a sampled function, in one
// dimension: d[q] = min_p (q − p)² + f[p] over the n samples (f +inf where nothing is)
void squaredDistance1d(const std::vector<double>& f, std::vector<double>& d, int n,
                       std::vector<int>& v, std::vector<double>& z) {
    constexpr double kInf = std::numeric_limits<double>::infinity();
    int k = -1;
    for (int q = 0; q < n; ++q) {
        if (!(f[q] < kInf)) continue;
        while (k >= 0) {
            const double s =
                ((f[q] + double(q) * q) - (f[v[k]] + double(v[k]) * v[k])) / (2.0 * (q - v[k]));
            if (s > z[k]) break;
            --k;
        }
        ++k;
        v[k] = q;
        z[k] = k == 0 ? -kInf
                      : ((f[q] + double(q) * q) - (f[v[k - 1]] + double(v[k - 1]) * v[k - 1])) /
                            (2.0 * (q - v[k - 1]));
        z[k + 1] = kInf;
    }
    for (int q = 0, j = 0; q < n; ++q) {
        if (k < 0) {
            d[q] = kInf;
            continue;
        }
        while (z[j + 1] < q) ++j;
        d[q] = (q - v[j]) * double(q - v[j]) + f[v[j]];
    }
}

// The exact Euclidean distance of every sample of a w×h grid to the nearest sample where `at`
// is set (squared; +inf when none is)
std::vector<double> squaredDistanceTo(const std::vector<uint8_t>& at, int w, int h) {
    constexpr double kInf = std::numeric_limits<double>::infinity();
    std::vector<double> d(at.size()), f(std::max(w, h)), g(std::max(w, h));
    std::vector<int> v(std::max(w, h));
    std::vector<double> z(std::max(w, h) + 1);
    for (size_t i = 0; i < at.size(); ++i) d[i] = at[i] ? 0.0 : kInf;
    for (int x = 0; x < w; ++x) {
        for (int y = 0; y < h; ++y) f[y] = d[static_cast<size_t>(y) * w + x];
        squaredDistance1d(f, g, h, v, z);
        for (int y = 0; y < h; ++y) d[static_cast<size_t>(y) * w + x] = g[y];
    }
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) f[x] = d[static_cast<size_t>(y) * w + x];
        squaredDistance1d(f, g, w, v, z);
        for (int x = 0; x < w; ++x) d[static_cast<size_t>(y) * w + x] = g[x];
    }
    return d;
}

// A mark's width (steps 8g, 8o and 8s): twice the largest distance (Euclidean, exact) of a
// sample of it from the samples outside it, in a box one sample wider than it (the samples
// outside the map are outside it)
double markWidth(std::span<const size_t> mark, int W) {
    int x0 = std::numeric_limits<int>::max(), y0 = x0, x1 = -1, y1 = -1;
    for (const size_t i : mark) {
        const int px = static_cast<int>(i % W), py = static_cast<int>(i / W);
        x0 = std::min(x0, px), x1 = std::max(x1, px), y0 = std::min(y0, py), y1 = std::max(y1, py);
    }
    const int bw = x1 - x0 + 3, bh = y1 - y0 + 3;
    std::vector<uint8_t> outside(static_cast<size_t>(bw) * bh, 1);
    for (const size_t i : mark)
        outside[static_cast<size_t>(static_cast<int>(i / W) - y0 + 1) * bw +
                (static_cast<int>(i % W) - x0 + 1)] = 0;
    const std::vector<double> depth = squaredDistanceTo(outside, bw, bh);
    double deepest = 0.0;
    for (size_t k = 0; k < depth.size(); ++k)
        if (!outside[k]) deepest = std::max(deepest, depth[k]);
    return 2.0 * std::sqrt(deepest);
}

// Step 8g (SelfSimMap.h) on one mark (its 8-connected samples; `before` the marks as they stood
// before this step): when it lies below the texture (at least `share` of its Σ|r| negative) and
// is a line (its samples at least `length` × its width²), it takes the samples above the texture
// scoring at least `grow` at the growth's scales, not marked, inside the border, that lie within
// `widthShare` × its width (twice the largest distance of its samples from the samples outside
// it) of it and are 8-connected to it through such samples: a groove's banks, as wide as the
// groove. Step 8o (SelfSimMap.h) calls it with a lower `grow` and `raisedShare` > 0: then the
// mark takes anything only when at least that share of the Σ|r| of the samples within that
// reach of it (not marked, inside the border) lies above the texture (raised rims along it).
// Returns the samples added to `map`.
size_t takeGrooveBanks(std::span<const size_t> mark, const std::vector<uint8_t>& before,
                       std::vector<uint8_t>& map, const std::vector<float>& r,
                       const std::vector<float>& zGrow, int W, int H, int border, double grow,
                       double share, double widthShare, double length, double raisedShare = 0.0) {
    size_t added = 0;
    const auto inside = [&](int x, int y) { return insideBorder(x, y, W, H, border); };
    const auto bank = [&](size_t q) {
        return !before[q] && r[q] > 0.0f && zGrow[q] >= static_cast<float>(grow) &&
               inside(static_cast<int>(q % W), static_cast<int>(q / W));
    };
    int x0 = W, y0 = H, x1 = -1, y1 = -1;
    double below = 0.0, all = 0.0;
    for (const size_t i : mark) {
        const int px = static_cast<int>(i % W), py = static_cast<int>(i / W);
        x0 = std::min(x0, px), x1 = std::max(x1, px), y0 = std::min(y0, py), y1 = std::max(y1, py);
        all += std::abs(r[i]);
        if (r[i] < 0.0f) below -= r[i];
    }
    if (!(all > 0.0) || below < share * all) return 0;
    const double width = markWidth(mark, W);
    if (static_cast<double>(mark.size()) < length * width * width) return 0;
    const double reach = std::max(1.0, widthShare * width);
    // the distance to it over a box grown by the reach, and the banks flooded from it
    const int m = static_cast<int>(std::ceil(reach)) + 1;
    const int bx0 = std::max(0, x0 - m), by0 = std::max(0, y0 - m);
    const int bw = std::min(W - 1, x1 + m) - bx0 + 1;
    const int bh = std::min(H - 1, y1 + m) - by0 + 1;
    std::vector<uint8_t> mine(static_cast<size_t>(bw) * bh, 0);
    for (const size_t i : mark)
        mine[static_cast<size_t>(static_cast<int>(i / W) - by0) * bw +
             (static_cast<int>(i % W) - bx0)] = 1;
    const std::vector<double> dist = squaredDistanceTo(mine, bw, bh);
    const double reach2 = reach * reach;
    if (raisedShare > 0.0) {
        double raised = 0.0, around = 0.0;
        for (size_t k = 0; k < mine.size(); ++k) {
            if (mine[k] || dist[k] > reach2) continue;
            const int qx = static_cast<int>(k % bw) + bx0, qy = static_cast<int>(k / bw) + by0;
            const size_t q = static_cast<size_t>(qy) * W + qx;
            if (before[q] || !inside(qx, qy)) continue;
            around += std::abs(r[q]);
            raised += std::max(0.0f, r[q]);
        }
        if (!(around > 0.0) || raised < raisedShare * around) return 0;
    }
    std::vector<uint8_t> seen(mine);
    std::vector<size_t> front;
    for (size_t k = 0; k < mine.size(); ++k)
        if (mine[k]) front.push_back(k);
    for (size_t k = 0; k < front.size(); ++k) {
        const int lx = static_cast<int>(front[k] % bw), ly = static_cast<int>(front[k] / bw);
        for (int qy = std::max(0, ly - 1); qy <= std::min(bh - 1, ly + 1); ++qy)
            for (int qx = std::max(0, lx - 1); qx <= std::min(bw - 1, lx + 1); ++qx) {
                const size_t lq = static_cast<size_t>(qy) * bw + qx;
                if (seen[lq] || dist[lq] > reach2) continue;
                const size_t q = static_cast<size_t>(qy + by0) * W + (qx + bx0);
                if (!bank(q)) continue;
                seen[lq] = 1;
                front.push_back(lq);
                if (!map[q]) {
                    map[q] = 255;
                    ++added;
                }
            }
    }
    return added;
}

// Step 8l's residual (SelfSimMap.h): each sample's estimate is the median of its copies at the
// offsets of its tile whose component across the tile's lay (the direction of its best offset,
// the tile's first) exceeds `width` samples, so that no copy of a line along the lay lands on
// the line itself; the scores are that residual over its own robust σ (its MAD about its
// median over the samples inside the border that have at least 3 such copies): the texture's
// residual under the same copies. 0 where a sample has fewer than 3 such copies; all 0 when no
// sample inside the border has. `sigmaOut` is set to that σ (left as it is when it is 0).
std::vector<float> acrossLayScores(const std::vector<float>& g, const std::vector<float>& copies,
                                   const std::vector<float>& copySsd,
                                   const std::vector<std::vector<int>>& tileOffsets, int W, int H,
                                   int T, int tilesX, int K, int border, double width,
                                   double& sigmaOut) {
    const size_t n = static_cast<size_t>(W) * static_cast<size_t>(H);
    std::vector<float> r(n, 0.0f);
    std::vector<uint8_t> has(n, 0);
    tbb::parallel_for(0, H, [&](int y) {
        std::vector<float> v;
        for (int x = 0; x < W; ++x) {
            const size_t i = static_cast<size_t>(y) * W + x;
            const std::vector<int>& d =
                tileOffsets[static_cast<size_t>(y / T) * tilesX + static_cast<size_t>(x / T)];
            if (d.size() < 2) continue;
            const double len = std::hypot(static_cast<double>(d[0]), static_cast<double>(d[1]));
            if (!(len > 0.0)) continue;
            const double ux = d[0] / len, uz = d[1] / len;
            v.clear();
            for (int k = 0; k < K && 2 * static_cast<size_t>(k) + 1 < d.size(); ++k) {
                const double across = std::abs(d[2 * k] * uz - d[2 * k + 1] * ux);
                const size_t j = static_cast<size_t>(k) * n + i;
                if (across > width && std::isfinite(copySsd[j])) v.push_back(copies[j]);
            }
            if (v.size() < 3) continue;
            std::sort(v.begin(), v.end());
            const float est =
                v.size() % 2 ? v[v.size() / 2] : 0.5f * (v[v.size() / 2 - 1] + v[v.size() / 2]);
            r[i] = g[i] - est;
            has[i] = 1;
        }
    });
    std::vector<float> vals;
    for (int y = border; y < H - border; ++y)
        for (int x = border; x < W - border; ++x) {
            const size_t i = static_cast<size_t>(y) * W + x;
            if (has[i]) vals.push_back(r[i]);
        }
    std::vector<float> z(n, 0.0f);
    if (vals.empty()) return z;
    const auto [med, sigma] = robustScaleOf(vals);
    if (!(sigma > 0.0)) return z;
    sigmaOut = sigma;
    for (size_t i = 0; i < n; ++i)
        if (has[i]) z[i] = static_cast<float>(std::abs(r[i] - med) / sigma);
    return z;
}

// The mark holding i0: the samples of `marks` 8-connected to it, in flood order, each set in
// `seen` (steps 8l, 8r, 8s and 8t)
void floodMark(const std::vector<uint8_t>& marks, size_t i0, std::vector<uint8_t>& seen,
               std::vector<size_t>& mark, int W, int H) {
    mark.assign(1, i0);
    seen[i0] = 1;
    for (size_t k = 0; k < mark.size(); ++k) {
        const int px = static_cast<int>(mark[k] % W), py = static_cast<int>(mark[k] / W);
        for (int qy = std::max(0, py - 1); qy <= std::min(H - 1, py + 1); ++qy)
            for (int qx = std::max(0, px - 1); qx <= std::min(W - 1, px + 1); ++qx) {
                const size_t q = static_cast<size_t>(qy) * W + qx;
                if (marks[q] && !seen[q]) {
                    seen[q] = 1;
                    mark.push_back(q);
                }
            }
    }
}

// The angle in degrees between a long axis and a lay, both in radians in [0, π): at most 90
// (steps 8l and 8r)
double degreesOffLay(double axis, double lay) {
    double d = std::abs(axis - lay);
    d = std::min(d, kPi - d);
    return d * 180.0 / kPi;
}

// A mark's extent when it is a line along its tile's lay: at least `minSize` samples, its
// extent at least `elongation`, its long axis within `angle` degrees of the lay `layAt(cx, cz)`
// gives for its centroid (negative: the tile has no lay); none otherwise (steps 8l and 8r)
template <class LayAt>
std::optional<Extent> lineAlongLay(std::span<const size_t> mark, int W, int minSize,
                                   double elongation, double angle, LayAt&& layAt) {
    if (static_cast<int>(mark.size()) < minSize) return std::nullopt;
    const Extent e = extentOf(mark, W);
    if (!(e.elongation >= elongation)) return std::nullopt;
    const double lay = layAt(e.cx, e.cz);
    if (lay < 0.0 || degreesOffLay(e.axis, lay) > angle) return std::nullopt;
    return e;
}

// Step 8l (SelfSimMap.h) on the marks as they stand (`map`): each mark (8-connected) of at
// least `minSize` samples that is a line along its tile's lay -- its extent at least
// `elongation`, its long axis within `angle` degrees of the lay `layAt(cx, cz)` gives for its
// centroid (negative: the tile has no lay) -- and whose median score on step 8l's residual
// (`zAcross`, whose σ is `sigmaAcross`) is at least `standOut` (and, with `standOutMax` > 0, at
// most that: a line standing that far out already has its width), and (with `kept` > 0) whose
// median |r| is at most `kept` × its median |r_x| (a line the copies along the lay explain in
// part) takes the samples inside the border, not marked, within `reach` samples (Chebyshev) of
// it, that score at least `sigma` on step 8l's residual and are 8-connected to it through such
// samples. Returns (lines, samples added).
template <class LayAt>
std::pair<size_t, size_t> takeLayLines(std::vector<uint8_t>& map, const std::vector<float>& zAcross,
                                       double sigmaAcross, const std::vector<float>& r, int W,
                                       int H, int border, int minSize, double elongation,
                                       double angle, double standOut, double standOutMax,
                                       double kept, int reach, double sigma, LayAt&& layAt) {
    const size_t n = map.size();
    const std::vector<uint8_t> before = map;
    const auto inside = [&](int x, int y) { return insideBorder(x, y, W, H, border); };
    std::vector<uint8_t> seen(n, 0);
    std::vector<size_t> band(n, n);  // the mark (its first sample) whose reach holds the sample
    std::vector<size_t> mark, front;
    std::vector<float> scores;
    size_t lines = 0, added = 0;
    for (size_t i0 = 0; i0 < n; ++i0) {
        if (!before[i0] || seen[i0]) continue;
        floodMark(before, i0, seen, mark, W, H);
        if (!lineAlongLay(mark, W, minSize, elongation, angle, layAt)) continue;
        // ... that stands out of the texture once no copy lands on it: its median score
        scores.clear();
        for (const size_t i : mark) scores.push_back(zAcross[i]);
        const double across = medianOf(scores);
        if (across < standOut) continue;
        if (standOutMax > 0.0 && across > standOutMax) continue;
        // ... and that the residual of all its copies explains in part: it keeps at most `kept`
        // of what the copies across the lay leave (a line explained by itself)
        if (kept > 0.0) {
            scores.clear();
            for (const size_t i : mark) scores.push_back(std::abs(r[i]));
            if (medianOf(scores) > kept * across * sigmaAcross) continue;
        }
        ++lines;
        const size_t id = i0;
        for (const size_t i : mark) {
            const int px = static_cast<int>(i % W), py = static_cast<int>(i / W);
            for (int qy = std::max(0, py - reach); qy <= std::min(H - 1, py + reach); ++qy)
                for (int qx = std::max(0, px - reach); qx <= std::min(W - 1, px + reach); ++qx)
                    band[static_cast<size_t>(qy) * W + qx] = id;
        }
        front.assign(mark.begin(), mark.end());
        for (size_t k = 0; k < front.size(); ++k) {
            const int px = static_cast<int>(front[k] % W), py = static_cast<int>(front[k] / W);
            for (int qy = py - 1; qy <= py + 1; ++qy)
                for (int qx = px - 1; qx <= px + 1; ++qx) {
                    if (!inside(qx, qy)) continue;
                    const size_t q = static_cast<size_t>(qy) * W + qx;
                    if (map[q] || band[q] != id || !(zAcross[q] >= static_cast<float>(sigma)))
                        continue;
                    map[q] = 255;
                    ++added;
                    front.push_back(q);
                }
        }
    }
    return {lines, added};
}

// Step 8r (SelfSimMap.h) on the marks as they stand (`map`): each mark (8-connected) of at
// least `minSize` samples that is a line along its tile's lay (extent at least
// kLineCopiesElongation, its long axis within kLineCopiesAngle degrees of `layAt(cx, cz)`) gets
// copies chosen for it: the offsets on a grid of refine + 1 samples within `radius` (Chebyshev)
// that cross the line by more than twice its half-width + kLineCopiesMargin, the
// kLineCopiesOffsets of least median |g(x) − g(x + d)| over the band beside it (the texture
// there, off every mark), each refined per sample within ± refine to the least patch
// difference. r_L = g − the median of those copies, over σ_L (its robust σ on the band); the
// samples of the line's corridor (its half-width + kLineCopiesMargin about its long axis,
// prolonged by kLineCopiesReach beyond its ends), inside the border and not marked, whose r_L
// has the line's sign and scores at least `sigma` and that are 8-connected to it through such
// samples are taken. Returns (lines judged, samples added).
template <class LayAt>
std::pair<size_t, size_t> takeLineCopies(std::vector<uint8_t>& map, const std::vector<float>& g,
                                         int W, int H, int border, int minSize, int patch,
                                         int refine, int radius, double sigma, LayAt&& layAt) {
    const size_t n = map.size();
    const std::vector<uint8_t> before = map;
    // the samples within 2 of a mark: never the texture the band measures
    std::vector<uint8_t> nearMark(n, 0);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            if (!before[static_cast<size_t>(y) * W + x]) continue;
            for (int qy = std::max(0, y - 2); qy <= std::min(H - 1, y + 2); ++qy)
                for (int qx = std::max(0, x - 2); qx <= std::min(W - 1, x + 2); ++qx)
                    nearMark[static_cast<size_t>(qy) * W + qx] = 1;
        }
    const auto inside = [&](int x, int y) { return insideBorder(x, y, W, H, border); };
    const int pr = patch / 2;
    // the copy of sample (x, y) at offset (dx0, dz0) refined within ± refine: the value at the
    // least patch difference (the patch clipped at the map's edges); NaN when the offset's
    // end is outside the map
    const auto copyAt = [&](int x, int y, int dx0, int dz0) {
        if (x + dx0 < 0 || x + dx0 >= W || y + dz0 < 0 || y + dz0 >= H)
            return std::numeric_limits<float>::quiet_NaN();
        double best = std::numeric_limits<double>::infinity();
        float value = std::numeric_limits<float>::quiet_NaN();
        for (int ez = -refine; ez <= refine; ++ez)
            for (int ex = -refine; ex <= refine; ++ex) {
                const int dx = dx0 + ex, dz = dz0 + ez;
                if (x + dx < 0 || x + dx >= W || y + dz < 0 || y + dz >= H) continue;
                double ssd = 0.0;
                for (int py = std::max({0, y - pr, -dz});
                     py <= std::min({H - 1, y + pr, H - 1 - dz}); ++py)
                    for (int px = std::max({0, x - pr, -dx});
                         px <= std::min({W - 1, x + pr, W - 1 - dx}); ++px) {
                        const double d = g[static_cast<size_t>(py) * W + px] -
                                         g[static_cast<size_t>(py + dz) * W + px + dx];
                        ssd += d * d;
                    }
                if (ssd < best) {
                    best = ssd;
                    value = g[static_cast<size_t>(y + dz) * W + x + dx];
                }
            }
        return value;
    };
    std::vector<uint8_t> seen(n, 0), corridor(n, 0);
    std::vector<size_t> mark, band, inCorridor, front;
    std::vector<float> rL(n, 0.0f), v, diff;
    std::vector<double> across;
    size_t lines = 0, added = 0;
    for (size_t i0 = 0; i0 < n; ++i0) {
        if (!before[i0] || seen[i0]) continue;
        floodMark(before, i0, seen, mark, W, H);
        const std::optional<Extent> line =
            lineAlongLay(mark, W, minSize, kLineCopiesElongation, kLineCopiesAngle, layAt);
        if (!line) continue;
        const Extent& e = *line;
        // the line's frame: along its long axis, across it (its normal)
        const double lx = std::cos(e.axis), lz = std::sin(e.axis), nx = -lz, nz = lx;
        double lo = std::numeric_limits<double>::infinity(), hi = -lo;
        across.clear();
        for (const size_t i : mark) {
            const double x = static_cast<double>(i % W) - e.cx,
                         z = static_cast<double>(i / W) - e.cz;
            lo = std::min(lo, x * lx + z * lz);
            hi = std::max(hi, x * lx + z * lz);
            across.push_back(std::abs(x * nx + z * nz));
        }
        const size_t q95 = static_cast<size_t>(0.95 * static_cast<double>(across.size() - 1));
        std::nth_element(across.begin(), across.begin() + static_cast<std::ptrdiff_t>(q95),
                         across.end());
        const double half = across[q95] + kLineCopiesMargin;  // the corridor's half-width
        const double cut = 2.0 * across[q95] + kLineCopiesMargin;
        if (cut >= radius) continue;  // no offset crosses it within the search
        lo -= kLineCopiesReach;
        hi += kLineCopiesReach;
        const double outer = half + kLineCopiesBand;
        // the corridor and the band beside it, in the box holding both
        const double ex = std::abs(lx) * std::max(-lo, hi) + std::abs(nx) * outer,
                     ez = std::abs(lz) * std::max(-lo, hi) + std::abs(nz) * outer;
        const int x0 = std::max(0, static_cast<int>(std::floor(e.cx - ex))),
                  x1 = std::min(W - 1, static_cast<int>(std::ceil(e.cx + ex))),
                  z0 = std::max(0, static_cast<int>(std::floor(e.cz - ez))),
                  z1 = std::min(H - 1, static_cast<int>(std::ceil(e.cz + ez)));
        band.clear();
        inCorridor.clear();
        for (int y = z0; y <= z1; ++y)
            for (int x = x0; x <= x1; ++x) {
                const double ax = x - e.cx, az = y - e.cz, along = ax * lx + az * lz,
                             off = std::abs(ax * nx + az * nz);
                if (along < lo || along > hi || off > outer) continue;
                const size_t i = static_cast<size_t>(y) * W + x;
                if (off <= half) {
                    if (inside(x, y) && !before[i]) inCorridor.push_back(i);
                } else if (!nearMark[i]) {
                    band.push_back(i);
                }
            }
        if (band.size() < 16 || inCorridor.empty()) continue;
        // the band's samples the offsets are judged on (~1 k, every step-th) and its σ on (~4 k)
        const size_t step = std::max<size_t>(1, band.size() / 1024);
        struct Cand {
            int dx, dz;
            float score;
        };
        std::vector<Cand> cands;
        const int grid = refine + 1;
        for (int dz = -radius; dz <= radius; dz += grid)
            for (int dx = -radius; dx <= radius; dx += grid) {
                if (!(std::abs(dx * nx + dz * nz) > cut)) continue;
                diff.clear();
                for (size_t k = 0; k < band.size(); k += step) {
                    const int x = static_cast<int>(band[k] % W), y = static_cast<int>(band[k] / W);
                    if (x + dx < 0 || x + dx >= W || y + dz < 0 || y + dz >= H) continue;
                    diff.push_back(
                        std::abs(g[band[k]] - g[static_cast<size_t>(y + dz) * W + x + dx]));
                }
                if (diff.size() < 16) continue;
                cands.push_back({dx, dz, static_cast<float>(medianOf(diff))});
            }
        std::stable_sort(cands.begin(), cands.end(),
                         [](const Cand& p, const Cand& q) { return p.score < q.score; });
        std::vector<std::array<int, 2>> kept;
        for (const Cand& c : cands) {
            if (static_cast<int>(kept.size()) >= kLineCopiesOffsets) break;
            bool far = true;
            for (const auto& k : kept)
                far =
                    far && std::max(std::abs(c.dx - k[0]), std::abs(c.dz - k[1])) > 2 * refine + 1;
            if (far) kept.push_back({c.dx, c.dz});
        }
        if (kept.size() < 3) continue;
        // r_L at a sample: g less the median of its copies (NaN with fewer than 3)
        const auto residualAt = [&](size_t i) {
            const int x = static_cast<int>(i % W), y = static_cast<int>(i / W);
            v.clear();
            for (const auto& k : kept) {
                const float c = copyAt(x, y, k[0], k[1]);
                if (std::isfinite(c)) v.push_back(c);
            }
            if (v.size() < 3) return std::numeric_limits<float>::quiet_NaN();
            std::sort(v.begin(), v.end());
            const float est =
                v.size() % 2 ? v[v.size() / 2] : 0.5f * (v[v.size() / 2 - 1] + v[v.size() / 2]);
            return g[i] - est;
        };
        std::vector<float> bandR;
        const size_t sigmaStep = std::max<size_t>(1, band.size() / 4096);
        for (size_t k = 0; k < band.size(); k += sigmaStep) {
            const float r = residualAt(band[k]);
            if (std::isfinite(r)) bandR.push_back(r);
        }
        if (bandR.size() < 16) continue;
        const auto [med, sigmaL] = robustScaleOf(bandR);
        if (!(sigmaL > 0.0)) continue;
        // the line's sign: its median r_L
        std::vector<float> onMark;
        for (const size_t i : mark) {
            const float r = residualAt(i);
            if (std::isfinite(r)) onMark.push_back(r);
        }
        if (onMark.empty()) continue;
        const double sign = medianOf(onMark) < 0.0 ? -1.0 : 1.0;
        ++lines;
        for (const size_t i : inCorridor) {
            corridor[i] = 1;
            const float r = residualAt(i);
            rL[i] = std::isfinite(r) ? static_cast<float>(sign * (r - med) / sigmaL) : 0.0f;
        }
        front.assign(mark.begin(), mark.end());
        for (size_t k = 0; k < front.size(); ++k) {
            const int px = static_cast<int>(front[k] % W), py = static_cast<int>(front[k] / W);
            for (int qy = std::max(0, py - 1); qy <= std::min(H - 1, py + 1); ++qy)
                for (int qx = std::max(0, px - 1); qx <= std::min(W - 1, px + 1); ++qx) {
                    const size_t q = static_cast<size_t>(qy) * W + qx;
                    if (!corridor[q] || map[q] || !(rL[q] >= static_cast<float>(sigma))) continue;
                    map[q] = 255;
                    ++added;
                    front.push_back(q);
                }
        }
        for (const size_t i : inCorridor) corridor[i] = 0;
    }
    return {lines, added};
}

// Every sample's nearest sample of `source` within `reach` samples (Euclidean; of two as near, the
// one first in the map's order), by a scan of the box about each source sample (steps 8s and 8v;
// a map of fewer than 2^32 samples): its squared distance (infinite beyond the reach) and index.
struct NearestWithin {
    std::vector<float> d2;
    std::vector<uint32_t> from;
};
NearestWithin nearestWithin(const std::vector<uint8_t>& source, int W, int H, double reach) {
    const size_t n = source.size();
    NearestWithin out{std::vector<float>(n, std::numeric_limits<float>::infinity()),
                      std::vector<uint32_t>(n, 0)};
    const int R = static_cast<int>(std::ceil(reach));
    const double R2 = reach * reach;
    for (size_t p = 0; p < n; ++p) {
        if (!source[p]) continue;
        const int px = static_cast<int>(p % W), py = static_cast<int>(p / W);
        for (int qy = std::max(0, py - R); qy <= std::min(H - 1, py + R); ++qy)
            for (int qx = std::max(0, px - R); qx <= std::min(W - 1, px + R); ++qx) {
                const size_t q = static_cast<size_t>(qy) * W + qx;
                const int d2 = (qx - px) * (qx - px) + (qy - py) * (qy - py);
                if (d2 > R2 || !(static_cast<float>(d2) < out.d2[q])) continue;
                out.d2[q] = static_cast<float>(d2);
                out.from[q] = static_cast<uint32_t>(p);
            }
    }
    return out;
}

// Step 8s (SelfSimMap.h) on the marks as they stand (`map`; samples added to it): each mark
// (8-connected) of at least kRimBandMarkMin samples that lies below the texture (at least
// kRimBandGrooveShare of its Σ|r| negative) and is a line (its samples at least kRimBandLength ×
// its markWidth²) has a band beside it: the samples not marked, inside the border, whose nearest
// sample of a mark below the texture (r < 0; its core) is one of this mark's, at most `reach` × its
// core's width away (twice the 95th percentile of its core's distances from the samples outside the
// core; at least kRimBandReachMin). The band is cut into segments along the mark: the cell of
// `segment` × its width (at least kRimBandCellMin samples) that holds that nearest core sample.
// A segment of at least kRimBandSegmentMin samples whose mean r/σ_0 is at least `mean` and whose
// share of samples above the texture is at least `share` gives its samples above the texture
// (r > 0) to `map`. Returns (segments taken, samples added).
std::pair<size_t, size_t> takeRimBands(std::vector<uint8_t>& map, const std::vector<float>& r,
                                       double sigma, int W, int H, int border, double mean,
                                       double share, double reach, double segment) {
    const size_t n = map.size();
    const std::vector<uint8_t> before = map;
    // (the nearest core sample is held as 32 bits: a map of 2^32 samples takes no rims)
    if (!(sigma > 0.0) || n > std::numeric_limits<uint32_t>::max()) return {0, 0};
    std::vector<uint8_t> notCore(n);
    for (size_t i = 0; i < n; ++i) notCore[i] = before[i] && r[i] < 0.0f ? 0 : 1;
    const std::vector<double> innerCore = squaredDistanceTo(notCore, W, H);
    struct Groove {
        double reach2 = -1.0;  // < 0: not a groove
        int cell = 0;
    };
    std::vector<Groove> grooves;
    std::vector<int> markOf(n, -1);
    std::vector<uint8_t> seen(n, 0);
    std::vector<size_t> mark;
    std::vector<double> coreDepth;
    double reachMax = 0.0;
    for (size_t i0 = 0; i0 < n; ++i0) {
        if (!before[i0] || seen[i0]) continue;
        floodMark(before, i0, seen, mark, W, H);
        const int id = static_cast<int>(grooves.size());
        grooves.emplace_back();
        double below = 0.0, all = 0.0;
        coreDepth.clear();
        for (const size_t i : mark) {
            markOf[i] = id;
            all += std::abs(r[i]);
            if (r[i] < 0.0f) {
                below -= r[i];
                coreDepth.push_back(std::sqrt(innerCore[i]));
            }
        }
        const double width = markWidth(mark, W);
        if (mark.size() < kRimBandMarkMin || !(all > 0.0) || below < kRimBandGrooveShare * all ||
            static_cast<double>(mark.size()) < kRimBandLength * width * width || coreDepth.empty())
            continue;
        // the 95th percentile of the core's depths, interpolated between order statistics
        std::sort(coreDepth.begin(), coreDepth.end());
        const double at = 0.95 * static_cast<double>(coreDepth.size() - 1);
        const size_t lo = static_cast<size_t>(at);
        const size_t hi = std::min(lo + 1, coreDepth.size() - 1);
        const double coreWidth = 2.0 * (coreDepth[lo] + (at - static_cast<double>(lo)) *
                                                            (coreDepth[hi] - coreDepth[lo]));
        const double rc = std::max(kRimBandReachMin, reach * coreWidth);
        grooves[id].reach2 = rc * rc;
        grooves[id].cell = std::max(kRimBandCellMin, static_cast<int>(segment * width));
        reachMax = std::max(reachMax, rc);
    }
    if (!(reachMax > 0.0)) return {0, 0};
    // each sample's nearest core sample within the largest reach
    std::vector<uint8_t> core(n);
    for (size_t i = 0; i < n; ++i) core[i] = notCore[i] ? 0 : 1;
    const auto [best, from] = nearestWithin(core, W, H, reachMax);
    // the band's samples, their segment (mark, cell of the nearest core sample) and its tally
    struct Tally {
        size_t count = 0, raised = 0;
        double sum = 0.0;
    };
    std::unordered_map<uint64_t, Tally> tallies;
    std::vector<std::pair<size_t, uint64_t>> band;  // a sample and its segment
    for (size_t q = 0; q < n; ++q) {
        if (before[q] || !std::isfinite(best[q]) || !insideBorder(q, W, H, border)) continue;
        const size_t p = from[q];
        const Groove& gr = grooves[static_cast<size_t>(markOf[p])];
        if (gr.reach2 < 0.0 || static_cast<double>(best[q]) > gr.reach2) continue;
        const uint64_t key = (static_cast<uint64_t>(markOf[p]) << 40) |
                             (static_cast<uint64_t>(static_cast<int>(p / W) / gr.cell) << 20) |
                             static_cast<uint64_t>(static_cast<int>(p % W) / gr.cell);
        Tally& t = tallies[key];
        ++t.count;
        t.sum += r[q] / sigma;
        if (r[q] > 0.0f) ++t.raised;
        band.emplace_back(q, key);
    }
    const auto passes = [&](const Tally& t) {
        return t.count >= kRimBandSegmentMin && t.sum >= mean * static_cast<double>(t.count) &&
               static_cast<double>(t.raised) >= share * static_cast<double>(t.count);
    };
    size_t segments = 0, added = 0;
    for (const auto& [key, t] : tallies)
        if (passes(t)) ++segments;
    for (const auto& [q, key] : band) {
        if (r[q] <= 0.0f || !passes(tallies[key])) continue;
        if (!map[q]) {
            map[q] = 255;
            ++added;
        }
    }
    return {segments, added};
}

}  // namespace

// Step 8t's response (SelfSimMap.h): at each sample, the largest over kValleyOrientations
// directions θ of the mean, over the kValleyLength samples of the line along θ through it (the
// grid samples a line of that length at θ passes), of (g(x + kValleyOffset·n) + g(x −
// kValleyOffset·n))/2 − g(x), n the normal of θ, g read bilinearly and clamped at the map's
// edges: how deep a straight valley lies below the ground on both sides of it.
std::vector<float> valleyResponse(const std::vector<float>& g, int W, int H) {
    const size_t n = g.size();
    const auto at = [&](double x, double y) {
        x = std::clamp(x, 0.0, static_cast<double>(W - 1));
        y = std::clamp(y, 0.0, static_cast<double>(H - 1));
        const int x0 = std::min(static_cast<int>(x), W - 2 < 0 ? 0 : W - 2),
                  y0 = std::min(static_cast<int>(y), H - 2 < 0 ? 0 : H - 2);
        const int x1 = std::min(x0 + 1, W - 1), y1 = std::min(y0 + 1, H - 1);
        const double fx = x - x0, fy = y - y0;
        const auto v = [&](int px, int py) {
            return static_cast<double>(g[static_cast<size_t>(py) * W + px]);
        };
        return (1 - fy) * ((1 - fx) * v(x0, y0) + fx * v(x1, y0)) +
               fy * ((1 - fx) * v(x0, y1) + fx * v(x1, y1));
    };
    std::vector<float> best(n, -std::numeric_limits<float>::infinity()), d(n);
    const int c = kValleyLength / 2;
    for (int k = 0; k < kValleyOrientations; ++k) {
        const double th = kPi * k / kValleyOrientations;
        const double nx = -std::sin(th), nz = std::cos(th), s = kValleyOffset;
        tbb::parallel_for(0, H, [&](int y) {
            for (int x = 0; x < W; ++x)
                d[static_cast<size_t>(y) * W + x] = static_cast<float>(
                    0.5 * (at(x + s * nx, y + s * nz) + at(x - s * nx, y - s * nz)) -
                    g[static_cast<size_t>(y) * W + x]);
        });
        // the line's samples: the grid samples at 4 × its length points along it
        std::vector<std::array<int, 2>> line;
        for (int i = 0; i < 4 * kValleyLength; ++i) {
            const double t = -c + 2.0 * c * i / (4 * kValleyLength - 1);
            const std::array<int, 2> o{static_cast<int>(std::lround(t * std::cos(th))),
                                       static_cast<int>(std::lround(t * std::sin(th)))};
            if (std::find(line.begin(), line.end(), o) == line.end()) line.push_back(o);
        }
        tbb::parallel_for(0, H, [&](int y) {
            for (int x = 0; x < W; ++x) {
                double sum = 0.0;
                for (const auto& o : line)
                    sum += d[static_cast<size_t>(std::clamp(y + o[1], 0, H - 1)) * W +
                             std::clamp(x + o[0], 0, W - 1)];
                const size_t i = static_cast<size_t>(y) * W + x;
                best[i] =
                    std::max(best[i], static_cast<float>(sum / static_cast<double>(line.size())));
            }
        });
    }
    return best;
}

// Steps 8t and 8v (SelfSimMap.h): the valley response of g in robust σ of the texture, the
// samples inside the border farther than kValleyTextureMargin from every mark of `map`; the gate
// is open when at most `gate` of the texture reaches `seed`.
ValleyScores scoreValleys(const std::vector<uint8_t>& map, const std::vector<float>& g, int W,
                          int H, int border, double seed, double gate) {
    const size_t n = map.size();
    ValleyScores out;
    const std::vector<float> v = valleyResponse(g, W, H);
    const std::vector<double> toMark = squaredDistanceTo(map, W, H);
    std::vector<float> texture;
    for (size_t i = 0; i < n; ++i)
        if (insideBorder(i, W, H, border) &&
            toMark[i] > kValleyTextureMargin * kValleyTextureMargin)
            texture.push_back(v[i]);
    if (texture.size() < 64) return out;
    std::vector<float> work = texture;
    const auto [med, sigma] = robustScaleOf(work);
    if (!(sigma > 0.0)) return out;
    size_t high = 0;
    for (const float t : texture) high += (t - med) / sigma >= seed ? 1 : 0;
    out.open = static_cast<double>(high) <= gate * static_cast<double>(texture.size());
    out.z.resize(n);
    for (size_t i = 0; i < n; ++i) out.z[i] = static_cast<float>((v[i] - med) / sigma);
    return out;
}

// Step 8t (SelfSimMap.h) on the marks as they stand (`map`) and the valley scores of g: when the
// gate is open, each 8-connected component of the unmarked samples inside the border scoring at
// least `grow` that holds a sample scoring at least `seed`, has at least `minSize` samples and
// lies within kValleyReach samples (Euclidean) of a mark is marked. Returns (components taken,
// samples added).
std::pair<size_t, size_t> takeValleyLines(std::vector<uint8_t>& map, const ValleyScores& scores,
                                          int W, int H, int border, int minSize, double seed,
                                          double grow) {
    if (!scores.open || scores.z.size() != map.size()) return {0, 0};
    const size_t n = map.size();
    const std::vector<uint8_t> before = map;
    const std::vector<float>& z = scores.z;
    const std::vector<double> toMark = squaredDistanceTo(before, W, H);
    const auto inside = [&](size_t i) { return insideBorder(i, W, H, border); };
    // the samples a valley may take, flooded a component at a time
    std::vector<uint8_t> low(n, 0);
    for (size_t i = 0; i < n; ++i) low[i] = !before[i] && inside(i) && z[i] >= grow ? 1 : 0;
    const double reach2 = static_cast<double>(kValleyReach) * kValleyReach;
    std::vector<uint8_t> seen(n, 0);
    std::vector<size_t> comp;
    size_t taken = 0, added = 0;
    for (size_t i0 = 0; i0 < n; ++i0) {
        if (!low[i0] || seen[i0]) continue;
        floodMark(low, i0, seen, comp, W, H);
        if (comp.size() < static_cast<size_t>(minSize) ||
            std::none_of(comp.begin(), comp.end(), [&](size_t i) { return z[i] >= seed; }) ||
            std::none_of(comp.begin(), comp.end(), [&](size_t i) { return toMark[i] <= reach2; }))
            continue;
        ++taken;
        for (const size_t i : comp) map[i] = 255;
        added += comp.size();
    }
    return {taken, added};
}

std::pair<size_t, size_t> takeValleyLines(std::vector<uint8_t>& map, const std::vector<float>& g,
                                          int W, int H, int border, int minSize, double seed,
                                          double grow, double gate) {
    return takeValleyLines(map, scoreValleys(map, g, W, H, border, seed, gate), W, H, border,
                           minSize, seed, grow);
}

// Step 8v (SelfSimMap.h) on the marks as they stand (`map`; samples added to it), the heights g
// and step 8t's valley scores: the valley lines (the marked samples of the components of samples
// inside the border scoring at least `grow` that hold one at `seed`), each 8-connected line of at
// least kValleyRimLineMin samples with a band: the samples inside the border whose nearest
// sample of the lines is one of its own, at most `reach` × its width away, and beyond it the
// ground, kValleyRimGround samples further. Band and ground are cut into segments by the
// kValleyRimCell cell of that nearest sample and the side (the signs of the offset from it); a
// segment of at least kValleyRimSegmentMin band and ground samples whose heights stand above its
// ground's median by a mean of at least `mean` × the ground's robust σ, at least `share` of them
// above it, gives its unmarked samples above that median to the map. Returns (segments taken,
// samples added).
std::pair<size_t, size_t> takeValleyRims(std::vector<uint8_t>& map, const std::vector<float>& g,
                                         const ValleyScores& scores, int W, int H, int border,
                                         double seed, double grow, double mean, double share,
                                         double reach) {
    if (!scores.open || scores.z.size() != map.size() ||
        map.size() > std::numeric_limits<uint32_t>::max())
        return {0, 0};
    const size_t n = map.size();
    const std::vector<float>& z = scores.z;
    const auto inside = [&](size_t i) { return insideBorder(i, W, H, border); };
    // the valley lines: the marked samples of the seeded components
    std::vector<uint8_t> low(n, 0), line(n, 0), seen(n, 0);
    for (size_t i = 0; i < n; ++i) low[i] = inside(i) && z[i] >= grow ? 1 : 0;
    std::vector<size_t> comp;
    for (size_t i0 = 0; i0 < n; ++i0) {
        if (!low[i0] || seen[i0]) continue;
        floodMark(low, i0, seen, comp, W, H);
        if (std::none_of(comp.begin(), comp.end(), [&](size_t i) { return z[i] >= seed; }))
            continue;
        for (const size_t i : comp)
            if (map[i]) line[i] = 1;
    }
    // each line's reach (its width, 8g's), and every sample's nearest line sample within the
    // largest reach and the ground beyond it
    std::fill(seen.begin(), seen.end(), 0);
    std::vector<int> lineOf(n, -1);
    std::vector<double> reachOf;
    double reachMax = 0.0;
    for (size_t i0 = 0; i0 < n; ++i0) {
        if (!line[i0] || seen[i0]) continue;
        floodMark(line, i0, seen, comp, W, H);
        const int id = static_cast<int>(reachOf.size());
        for (const size_t i : comp) lineOf[i] = id;
        const double rc =
            comp.size() < kValleyRimLineMin ? -1.0 : reach * std::max(2.0, markWidth(comp, W));
        reachOf.push_back(rc);
        reachMax = std::max(reachMax, rc);
    }
    if (!(reachMax > 0.0)) return {0, 0};
    const auto [best, from] = nearestWithin(line, W, H, reachMax + kValleyRimGround);
    // band and ground samples by segment: (line, cell of the nearest line sample, side)
    struct Segment {
        std::vector<float> band, ground;
        std::vector<size_t> bandAt;
    };
    std::unordered_map<uint64_t, Segment> segments;
    for (size_t q = 0; q < n; ++q) {
        if (line[q] || !std::isfinite(best[q]) || !inside(q)) continue;
        const size_t p = from[q];
        const double rc = reachOf[static_cast<size_t>(lineOf[p])];
        if (rc < 0.0) continue;
        const double d = std::sqrt(static_cast<double>(best[q]));
        const bool inBand = d <= rc;
        if (!inBand && d > rc + kValleyRimGround) continue;
        const int px = static_cast<int>(p % W), py = static_cast<int>(p / W);
        const int qx = static_cast<int>(q % W), qy = static_cast<int>(q / W);
        const uint64_t side = static_cast<uint64_t>((qy > py) - (qy < py) + 1) * 3 +
                              static_cast<uint64_t>((qx > px) - (qx < px) + 1);
        const uint64_t key = (static_cast<uint64_t>(lineOf[p]) << 36) |
                             (static_cast<uint64_t>(py / kValleyRimCell) << 20) |
                             (static_cast<uint64_t>(px / kValleyRimCell) << 4) | side;
        Segment& s = segments[key];
        if (inBand) {
            s.band.push_back(g[q]);
            s.bandAt.push_back(q);
        } else {
            s.ground.push_back(g[q]);
        }
    }
    size_t taken = 0, added = 0;
    for (auto& [key, s] : segments) {
        if (s.band.size() < kValleyRimSegmentMin || s.ground.size() < kValleyRimSegmentMin)
            continue;
        const auto [groundMedian, groundSigma] = robustScaleOf(s.ground);  // (s.ground spent)
        if (!(groundSigma > 0.0)) continue;
        double sum = 0.0;
        size_t above = 0;
        for (const float h : s.band) {
            sum += h - groundMedian;
            above += h > groundMedian ? 1 : 0;
        }
        const double count = static_cast<double>(s.band.size());
        if (sum < mean * groundSigma * count || static_cast<double>(above) < share * count)
            continue;
        ++taken;
        for (const size_t q : s.bandAt)
            if (!map[q] && g[q] > groundMedian) {  // each band sample is in one segment
                map[q] = 255;
                ++added;
            }
    }
    return {taken, added};
}

// Step 8u (SelfSimMap.h): the ring about the marks as they stand, a cell of the grid at a time.
std::pair<size_t, size_t> takeEdgeRing(std::vector<uint8_t>& map, const std::vector<float>& r,
                                       double sigma, int W, int H, int border, double score,
                                       double share, int cell) {
    if (!(sigma > 0.0) || cell < 1) return {0, 0};
    const int cx = (W + cell - 1) / cell, cy = (H + cell - 1) / cell;
    std::vector<size_t> ring(static_cast<size_t>(cx) * cy, 0), hits(ring.size(), 0);
    std::vector<size_t> hit;  // the ring's hits, in order (the map changes only after the scan)
    const auto cellOf = [&](int x, int y) { return static_cast<size_t>(y / cell) * cx + x / cell; };
    for (int y = border; y < H - border; ++y)
        for (int x = border; x < W - border; ++x) {
            const size_t i = static_cast<size_t>(y) * W + x;
            if (map[i]) continue;
            // the sum of its marked 4-neighbours' r (none: not on the ring)
            double around = 0.0;
            bool onRing = false;
            const auto add = [&](size_t q) {
                if (!map[q]) return;
                onRing = true;
                around += r[q];
            };
            if (x > 0) add(i - 1);
            if (x + 1 < W) add(i + 1);
            if (y > 0) add(i - W);
            if (y + 1 < H) add(i + W);
            if (!onRing) continue;
            const size_t c = cellOf(x, y);
            ++ring[c];
            const double z = r[i] / sigma;
            if (std::abs(z) >= score && ((z > 0.0 && around > 0.0) || (z < 0.0 && around < 0.0))) {
                ++hits[c];
                hit.push_back(i);
            }
        }
    const auto passes = [&](size_t c) {
        return ring[c] >= kEdgeRingCellMin &&
               static_cast<double>(hits[c]) >= share * static_cast<double>(ring[c]);
    };
    size_t cells = 0, added = 0;
    for (size_t c = 0; c < ring.size(); ++c)
        if (passes(c)) ++cells;
    for (const size_t i : hit) {
        if (!passes(cellOf(static_cast<int>(i % W), static_cast<int>(i / W)))) continue;
        map[i] = 255;
        ++added;
    }
    return {cells, added};
}

double textureTailThreshold(std::span<const float> peaks, double quantile, double nfa) {
    // too few responses to measure a tail on: no threshold from the texture
    if (peaks.size() < kTextureTailMinRegions || !(nfa > 0.0)) return 0.0;
    std::vector<float> v(peaks.begin(), peaks.end());
    std::sort(v.begin(), v.end());
    const size_t k =
        std::min(v.size() - 1, static_cast<size_t>(quantile * static_cast<double>(v.size())));
    const double u = v[k];
    std::vector<float> excess;
    for (size_t j = k; j < v.size(); ++j)
        if (v[j] > u) excess.push_back(static_cast<float>(v[j] - u));
    const double beta = excess.empty() ? 0.0 : medianOf(excess) / std::log(2.0);
    const double tail = static_cast<double>(v.size()) * (1.0 - quantile);
    return u + beta * std::max(0.0, std::log(tail / nfa));
}

double gaussianTailInverse(double p) {
    // Φ̄(z) = erfc(z/√2)/2 decreases in z: bisection on [0, 40]
    double lo = 0.0, hi = 40.0;
    for (int i = 0; i < 200; ++i) {
        const double mid = 0.5 * (lo + hi);
        if (0.5 * std::erfc(mid / std::sqrt(2.0)) > p)
            lo = mid;
        else
            hi = mid;
    }
    return 0.5 * (lo + hi);
}

void checkSelfSimMapOptions(const SelfSimMapOptions& o) {
    if (o.patch < 1 || o.patch % 2 == 0)
        throw inputError(option("selfsim-patch"),
                         "must be odd and >= 1 (got " + std::to_string(o.patch) + ")",
                         "The default is 7 samples");
    if (o.offsets < 3)
        throw inputError(option("selfsim-offsets"), "must be >= 3", "The default is 16");
    if (o.exclusion < 1)
        throw inputError(option("selfsim-exclusion"), "must be >= 1", "The default is 16");
    if (o.searchRadius <= o.exclusion)
        throw inputError(option("selfsim-search-radius"),
                         "must be larger than the exclusion (" + std::to_string(o.exclusion) + ")",
                         "The default is 48 samples");
    if (o.refine < 0)
        throw inputError(option("selfsim-refine"), "must be >= 0", "The default is 0.5");
    if (o.sectors < 1)
        throw inputError(option("selfsim-sectors"), "must be >= 1", "The default is 8");
    if (o.perSector < 1)
        throw inputError(option("selfsim-per-sector"), "must be >= 1", "The default is 4");
    if (!(o.quality >= 1.0))
        throw inputError(option("selfsim-quality"), "must be >= 1", "The default is 2");
    if (o.tile < 0)
        throw inputError(option("selfsim-tile"), "must be >= 0", "The default is 64 samples");
    if (o.context < 0)
        throw inputError(option("selfsim-context"), "must be >= 0", "The default is 32 samples");
    if (!(o.keep > 0.0 && o.keep <= 1.0))
        throw inputError(option("selfsim-keep"), "must be in (0, 1]", "The default is 1");
    if (o.scales < 1 || o.scales > 6)
        throw inputError(option("selfsim-scales"), "must be in 1..6", "The default is 4");
    if (!(o.nfa > 0.0)) throw inputError(option("selfsim-nfa"), "must be > 0", "The default is 1");
    if (!(o.tailQuantile >= 0.0 && o.tailQuantile < 1.0))
        throw inputError(option("selfsim-tail-quantile"), "must be in [0, 1)",
                         "The default is 0 (off)");
    if (!(o.grooveLength >= 0.0))
        throw inputError(option("selfsim-groove-length"), "must be >= 0", "The default is 5");
    if (!(o.textureRms >= 0.0))
        throw inputError(option("selfsim-texture-rms"), "must be >= 0", "The default is 1");
    if (!(o.textureNfa >= 0.0))
        throw inputError(option("selfsim-texture-nfa"), "must be >= 0",
                         "The default is 1 (0: off)");
    if (!(o.lineNfa >= 0.0))
        throw inputError(option("selfsim-line-nfa"), "must be >= 0", "The default is 1 (0: off)");
    if (!(o.textureQuantile >= 0.0 && o.textureQuantile < 1.0))
        throw inputError(option("selfsim-texture-quantile"), "must be in [0, 1)",
                         "The default is 0.75");
    if (!(o.growSigma > 0.0))
        throw inputError(option("selfsim-grow-sigma"), "must be > 0", "The default is 2.5");
    if (o.growScale < 0 || o.growScale >= o.scales)
        throw inputError(option("selfsim-grow-scale"), "must be in 0..scales-1",
                         "The default is 0");
    if (o.extendSteps < 0)
        throw inputError(option("selfsim-extend-steps"), "must be >= 0",
                         "The default is 1 (0: off)");
    if (!(o.extendSigma > 0.0))
        throw inputError(option("selfsim-extend-sigma"), "must be > 0", "The default is 1");
    if (!(o.extendShare >= 0.0 && o.extendShare < 1.0))
        throw inputError(option("selfsim-extend-share"), "must be in [0, 1)", "The default is 0.1");
    if (!(o.trimShare >= 0.0 && o.trimShare < 1.0))
        throw inputError(option("selfsim-trim-share"), "must be in [0, 1)",
                         "The default is 0.08 (0: off)");
    if (!(o.particleElongation >= 0.0))
        throw inputError(option("selfsim-particle-elongation"), "must be >= 0",
                         "The default is 0 (off; 3 drops particles)");
    if (!(o.particleRaisedShare > 0.0 && o.particleRaisedShare <= 1.0))
        throw inputError(option("selfsim-particle-raised-share"), "must be in (0, 1]",
                         "The default is 0.8");
    if (!(o.borderPieceFill >= 0.0 && o.borderPieceFill < 1.0))
        throw inputError(option("selfsim-border-piece-fill"), "must be in [0, 1)",
                         "The default is 0.45 (0: off)");
    if (o.borderPieceMin < 1)
        throw inputError(option("selfsim-border-piece-min"), "must be >= 1", "The default is 40");
    if (o.borderPieceRim < 0)
        throw inputError(option("selfsim-border-piece-rim"), "must be >= 0",
                         "The default is 2 (0: off)");
    if (!(o.borderLevelStep == 0.0 || o.borderLevelStep > 1.0))
        throw inputError(option("selfsim-border-level-step"), "must be 0 (off) or > 1",
                         "The default is 1.25");
    if (!(o.borderLevelShape >= 0.0 && o.borderLevelShape < 1.0))
        throw inputError(option("selfsim-border-level-shape"), "must be in [0, 1)",
                         "The default is 0.35");
    if (!(o.borderLevelFill >= 0.0 && o.borderLevelFill < 1.0))
        throw inputError(option("selfsim-border-level-fill"), "must be in [0, 1)",
                         "The default is 0.6");
    if (!(o.borderBasin == 0.0 || o.borderBasin > 1.0))
        throw inputError(option("selfsim-border-basin"), "must be 0 (off) or > 1",
                         "The default is 1.1");
    if (!(o.lineElongation == 0.0 || o.lineElongation >= 1.0))
        throw inputError(option("selfsim-line-elongation"), "must be 0 (off) or >= 1",
                         "The default is 8");
    if (!(o.lineAngle >= 0.0 && o.lineAngle <= 90.0))
        throw inputError(option("selfsim-line-angle"), "must be in [0, 90] degrees",
                         "The default is 45");
    if (!(o.burrElongation == 0.0 || o.burrElongation >= 1.0))
        throw inputError(option("selfsim-burr-elongation"), "must be 0 (off) or >= 1",
                         "The default is 0 (off)");
    if (!(o.burrBasin == 0.0 || o.burrBasin > 1.0))
        throw inputError(option("selfsim-burr-basin"), "must be 0 (off) or > 1",
                         "The default is 0 (off); 1.1 measured");
    if (!(o.hollowRowGap >= 0.0))
        throw inputError(option("selfsim-hollow-row-gap"), "must be >= 0",
                         "The default is 16 samples (0: off)");
    if (o.hollowRowMembers < 2)
        throw inputError(option("selfsim-hollow-row-members"), "must be >= 2", "The default is 4");
    if (!(o.chainTolerance >= 0.0 && o.chainTolerance <= 0.5))
        throw inputError(option("selfsim-hollow-chain-tolerance"), "must be in [0, 0.5]",
                         "Use 0 (off) or a share of the chain's step, as 0.2");
    if (!(o.chainLayAngle >= 0.0 && o.chainLayAngle <= 90.0))
        throw inputError(option("selfsim-hollow-chain-lay-angle"), "must be in [0, 90]",
                         "Use 0 (no test) or an angle in degrees, as 30");
    if (!(o.farBankReach >= 0.0))
        throw inputError(option("selfsim-far-bank-reach"), "must be >= 0",
                         "Use 0 (off) or a distance in samples, as 10");
    if (!(o.lineLayContrast >= 1.0))
        throw inputError(option("selfsim-line-lay-contrast"), "must be >= 1", "The default is 1.5");
    if (!(o.borderBasinGrowth >= 0.0))
        throw inputError(option("selfsim-border-basin-growth"), "must be >= 0",
                         "The default is 0 (no bound)");
    if (!(o.borderPieceSigma >= 0.0 && o.borderPieceSigma < 1.0))
        throw inputError(option("selfsim-border-piece-sigma"), "must be in [0, 1)",
                         "The default is 0.01 (0: every map)");
    if (!(o.grooveBankWidth >= 0.0))
        throw inputError(option("selfsim-groove-bank-width"), "must be >= 0",
                         "The default is 1 (0: off)");
    if (!(o.grooveRimSigma >= 0.0))
        throw inputError(option("selfsim-groove-rim-sigma"), "must be >= 0",
                         "The default is 0 (off)");
    if (!(o.grooveRimLength >= 0.0))
        throw inputError(option("selfsim-groove-rim-length"), "must be >= 0", "The default is 15");
    if (!(o.grooveRimWidth > 0.0))
        throw inputError(option("selfsim-groove-rim-width"), "must be > 0", "The default is 1");
    if (!(o.grooveRimShare >= 0.0 && o.grooveRimShare < 1.0))
        throw inputError(option("selfsim-groove-rim-share"), "must be in [0, 1)",
                         "The default is 0.6 (0: no test)");
    if (o.pileUpReach < 0)
        throw inputError(option("selfsim-pile-up-reach"), "must be >= 0",
                         "The default is 1 (0: off)");
    if (!(o.pileUpSigma > 0.0))
        throw inputError(option("selfsim-pile-up-sigma"), "must be > 0", "The default is 1.5");
    if (!(o.pileUpShare > 0.0 && o.pileUpShare <= 1.0))
        throw inputError(option("selfsim-pile-up-share"), "must be in (0, 1]",
                         "The default is 0.6");
    if (!(o.roughnessCutoff >= 0.0))
        throw inputError(option("selfsim-roughness-cutoff"), "must be >= 0 (samples)",
                         "The default is 0 (off, the levelled heights' RMS; 96 measured)");
    if (!(o.layLineElongation == 0.0 || o.layLineElongation >= 1.0))
        throw inputError(option("selfsim-lay-line-elongation"), "must be 0 (off) or >= 1",
                         "The default is 4 (0: off)");
    if (!(o.layLineAngle >= 0.0 && o.layLineAngle <= 90.0))
        throw inputError(option("selfsim-lay-line-angle"), "must be in [0, 90] degrees",
                         "The default is 30");
    if (!(o.layLineStandOutMax >= 0.0))
        throw inputError(option("selfsim-lay-line-stand-out-max"), "must be >= 0",
                         "The default is 0 (no cap)");
    if (!(o.layLineStandOut >= 0.0))
        throw inputError(option("selfsim-lay-line-stand-out"), "must be >= 0",
                         "The default is 4 (0: no test)");
    if (!(o.layLineKept >= 0.0))
        throw inputError(option("selfsim-lay-line-kept"), "must be >= 0",
                         "The default is 1 (0: no test)");
    if (o.layLineReach < 1)
        throw inputError(option("selfsim-lay-line-reach"), "must be >= 1", "The default is 4");
    if (!(o.layLineSigma > 0.0))
        throw inputError(option("selfsim-lay-line-sigma"), "must be > 0", "The default is 2");
    if (!(o.layLineWidth > 0.0))
        throw inputError(option("selfsim-lay-line-width"), "must be > 0", "The default is 3");
    if (!(o.lineCopiesSigma >= 0.0))
        throw inputError(option("selfsim-line-copies-sigma"), "must be >= 0",
                         "The default is 0 (off; 4 measured)");
    if (!(o.rimBandMean >= 0.0))
        throw inputError(option("selfsim-rim-band-mean"), "must be >= 0",
                         "The default is 0.6 (0: off)");
    if (!(o.rimBandShare >= 0.0 && o.rimBandShare <= 1.0))
        throw inputError(option("selfsim-rim-band-share"), "must be in [0, 1]",
                         "The default is 0.65");
    if (!(o.rimBandReach > 0.0))
        throw inputError(option("selfsim-rim-band-reach"), "must be > 0", "The default is 0.9");
    if (!(o.rimBandSegment > 0.0))
        throw inputError(option("selfsim-rim-band-segment"), "must be > 0", "The default is 2");
    if (!(o.valleyRimMean >= 0.0))
        throw inputError(option("selfsim-valley-rim-mean"), "must be >= 0",
                         "The default is 0 (off; 0.5 measured)");
    if (!(o.valleyRimShare >= 0.0 && o.valleyRimShare <= 1.0))
        throw inputError(option("selfsim-valley-rim-share"), "must be in [0, 1]",
                         "The default is 0.7");
    if (!(o.valleyRimReach > 0.0))
        throw inputError(option("selfsim-valley-rim-reach"), "must be > 0", "The default is 1");
    if (!(o.edgeRingSigma >= 0.0))
        throw inputError(option("selfsim-edge-ring-sigma"), "must be >= 0",
                         "The default is 1 (0: off)");
    if (!(o.edgeRingShare > 0.0 && o.edgeRingShare <= 1.0))
        throw inputError(option("selfsim-edge-ring-share"), "must be in (0, 1]",
                         "The default is 0.5");
    if (o.edgeRingCell < 1)
        throw inputError(option("selfsim-edge-ring-cell"), "must be >= 1", "The default is 8");
    if (!(o.valleyLineSigma >= 0.0))
        throw inputError(option("selfsim-valley-line-sigma"), "must be >= 0",
                         "The default is 15 (0: off)");
    if (!(o.valleyLineGrow > 0.0 && o.valleyLineGrow <= o.valleyLineSigma) &&
        o.valleyLineSigma > 0.0)
        throw inputError(option("selfsim-valley-line-grow"),
                         "must be > 0 and at most " + option("selfsim-valley-line-sigma"),
                         "The default is 8");
    if (!(o.valleyLineGate >= 0.0 && o.valleyLineGate <= 1.0))
        throw inputError(option("selfsim-valley-line-gate"), "must be in [0, 1]",
                         "The default is 0.003");
    if (o.border < 0)
        throw inputError(option("selfsim-border"), "must be >= 0", "The default is 40");
    if (o.minRegion < 1)
        throw inputError(option("selfsim-min-region"), "must be >= 1", "The default is 12");
}

SelfSimMap detectSelfSimDefects(std::span<const float> heights, int width, int height,
                                const SelfSimMapOptions& o) {
    checkSelfSimMapOptions(o);
    const int W = width, H = height;
    const size_t n = static_cast<size_t>(W) * static_cast<size_t>(H);
    SelfSimMap out;
    out.map.assign(n, 0);
    out.unjudged.assign(n, 0);
    out.residual.assign(n, 0.0f);
    if (W < 2 || H < 2 || heights.size() != n) return out;

    const std::vector<float> levelled = removeQuadratic(heights, W, H);
    throwIfInterrupted();
    const int b = std::min(o.border, (std::min(W, H) - 1) / 2);
    out.border = b;
    // step 1b: a relief's plateaus taken out (detect/ReliefLevels.h): g is then the plateaus'
    // texture, what the copies compare and whose RMS a region is judged against (step 6)
    ReliefLevels relief;
    if (o.relief) relief = findReliefLevels(levelled, W, H, b);
    const std::vector<float>& g = relief.relief ? relief.flattened : levelled;
    if (relief.relief) out.reliefLevels = relief.plateauLevels;

    // ---- steps 2–3, tile by tile: the texture's offsets and each sample's copies ----------
    const int R = std::min(o.searchRadius, std::max(W, H) - 1);
    const int T = o.tile > 0 ? o.tile : std::max(W, H);
    const int tilesX = (W + T - 1) / T, tilesZ = (H + T - 1) / T;
    const int K = o.offsets;
    constexpr float kInf = std::numeric_limits<float>::infinity();
    std::vector<float> copies(static_cast<size_t>(K) * n, kInf), copySsd(copies.size(), kInf);
    std::vector<std::vector<int>> tileOffsets(static_cast<size_t>(tilesX) * tilesZ);
    std::vector<float> tileLayContrast(tileOffsets.size(), 1.0f);  // step 8i
    const int pr = o.patch / 2;
    tbb::parallel_for(0, tilesX * tilesZ, [&](int tileIndex) {
        const int tx0 = (tileIndex % tilesX) * T, tz0 = (tileIndex / tilesX) * T;
        const int tx1 = std::min(W, tx0 + T), tz1 = std::min(H, tz0 + T);
        // step 2 on the tile grown by `context` (samples on a grid of ~4 k)
        const int cx0 = std::max(0, tx0 - o.context), cz0 = std::max(0, tz0 - o.context);
        const int cx1 = std::min(W, tx1 + o.context), cz1 = std::min(H, tz1 + o.context);
        const double area = static_cast<double>(cx1 - cx0) * (cz1 - cz0);
        const int step = std::max(1, static_cast<int>(std::sqrt(area / 1024.0)));
        struct Cand {
            int dx, dz;
            float score;
        };
        std::vector<Cand> cands;
        std::vector<float> diff;
        const int grid = o.refine + 1;  // offsets on a grid the refinement fills in
        for (int dz = -R; dz <= R; dz += grid) {
            if (interruptRequested()) return;  // a tile's search takes ~1 s on a loaded core
            for (int dx = -R; dx <= R; dx += grid) {
                if (std::max(std::abs(dx), std::abs(dz)) < o.exclusion) continue;
                diff.clear();
                for (int y = std::max(cz0, -dz); y < std::min(cz1, H - dz); y += step)
                    for (int x = std::max(cx0, -dx); x < std::min(cx1, W - dx); x += step)
                        diff.push_back(std::abs(g[static_cast<size_t>(y) * W + x] -
                                                g[static_cast<size_t>(y + dz) * W + x + dx]));
                if (diff.size() < 16) continue;
                cands.push_back({dx, dz, static_cast<float>(medianOf(diff))});
            }
        }
        std::stable_sort(cands.begin(), cands.end(),
                         [](const Cand& p, const Cand& q) { return p.score < q.score; });
        // step 8i's lay: how much better the tile's best offset is than the best one at
        // least 45° from it (mod 180°): a striated tile repeats along its striae only
        if (!cands.empty()) {
            const double best = std::atan2(static_cast<double>(cands.front().dz),
                                           static_cast<double>(cands.front().dx));
            for (const Cand& c : cands) {
                double d = std::abs(
                    std::atan2(static_cast<double>(c.dz), static_cast<double>(c.dx)) - best);
                d = std::fmod(d, kPi);
                if (std::min(d, kPi - d) < 0.25 * kPi) continue;
                const float least = cands.front().score;
                tileLayContrast[static_cast<size_t>(tileIndex)] =
                    least > 0.0f ? c.score / least : (c.score > 0.0f ? kInf : 1.0f);
                break;
            }
        }
        std::vector<int>& kept = tileOffsets[static_cast<size_t>(tileIndex)];
        const int sep = 2 * o.refine + 1;
        std::vector<int> perSector(static_cast<size_t>(o.sectors), 0);
        const float worst =
            cands.empty() ? 0.0f : static_cast<float>(o.quality) * cands.front().score;
        for (const Cand& c : cands) {
            if (static_cast<int>(kept.size()) / 2 >= K || c.score > worst) break;
            // the direction of d modulo 180°, in `sectors` sectors centred on the x axis
            double a = std::atan2(static_cast<double>(c.dz), static_cast<double>(c.dx));
            if (a < 0) a += kPi;
            const int sector = static_cast<int>(std::floor(a / kPi * o.sectors + 0.5)) % o.sectors;
            if (perSector[static_cast<size_t>(sector)] >= o.perSector) continue;
            bool far = true;
            for (size_t k = 0; k + 1 < kept.size() && far; k += 2)
                far = std::max(std::abs(c.dx - kept[k]), std::abs(c.dz - kept[k + 1])) > sep;
            if (!far) continue;
            kept.push_back(c.dx);
            kept.push_back(c.dz);
            ++perSector[static_cast<size_t>(sector)];
        }
        // step 3: the copies of the tile's samples, each offset refined per sample
        const int ex0 = std::max(0, tx0 - pr), ez0 = std::max(0, tz0 - pr);
        const int ex1 = std::min(W, tx1 + pr), ez1 = std::min(H, tz1 + pr);
        const int ew = ex1 - ex0, eh = ez1 - ez0;
        std::vector<float> e2(static_cast<size_t>(ew) * eh), rowSum(e2.size());
        std::vector<double> colSum(static_cast<size_t>(ew));
        for (size_t k = 0; k + 1 < kept.size(); k += 2) {
            const int dx0 = kept[k], dz0 = kept[k + 1];
            float* val = copies.data() + (k / 2) * n;
            float* best = copySsd.data() + (k / 2) * n;
            for (int ez = -o.refine; ez <= o.refine; ++ez)
                for (int ex = -o.refine; ex <= o.refine; ++ex) {
                    const int dx = dx0 + ex, dz = dz0 + ez;
                    for (int y = ez0; y < ez1; ++y) {
                        const int yy = clampi(y + dz, 0, H - 1);
                        for (int x = ex0; x < ex1; ++x) {
                            const float d =
                                g[static_cast<size_t>(y) * W + x] -
                                g[static_cast<size_t>(yy) * W + clampi(x + dx, 0, W - 1)];
                            e2[static_cast<size_t>(y - ez0) * ew + (x - ex0)] = d * d;
                        }
                    }
                    // the patch sums at the tile's samples (the patch clipped at the map's
                    // edges): rows, then columns
                    for (int y = 0; y < eh; ++y) {
                        const float* in = e2.data() + static_cast<size_t>(y) * ew;
                        float* sums = rowSum.data() + static_cast<size_t>(y) * ew;
                        double acc = 0.0;
                        for (int x = 0; x < std::min(ew, pr); ++x) acc += in[x];
                        for (int x = 0; x < ew; ++x) {
                            if (x + pr < ew) acc += in[x + pr];
                            sums[x] = static_cast<float>(acc);
                            if (x - pr >= 0) acc -= in[x - pr];
                        }
                    }
                    std::fill(colSum.begin(), colSum.end(), 0.0);
                    for (int y = 0; y < std::min(eh, pr); ++y)
                        for (int x = 0; x < ew; ++x)
                            colSum[x] += rowSum[static_cast<size_t>(y) * ew + x];
                    for (int y = 0; y < eh; ++y) {
                        if (y + pr < eh)
                            for (int x = 0; x < ew; ++x)
                                colSum[x] += rowSum[static_cast<size_t>(y + pr) * ew + x];
                        const int my = ez0 + y;
                        const int y0 = my + dz0, y1 = my + dz;
                        if (my >= tz0 && my < tz1 && y0 >= 0 && y0 < H && y1 >= 0 && y1 < H)
                            for (int mx = tx0; mx < tx1; ++mx) {
                                const int x0 = mx + dx0, x1 = mx + dx;
                                if (x0 < 0 || x0 >= W || x1 < 0 || x1 >= W) continue;
                                const float ssd = static_cast<float>(colSum[mx - ex0]);
                                const size_t i = static_cast<size_t>(my) * W + mx;
                                if (ssd < best[i]) {
                                    best[i] = ssd;
                                    val[i] = g[static_cast<size_t>(y1) * W + x1];
                                }
                            }
                        if (y - pr >= 0)
                            for (int x = 0; x < ew; ++x)
                                colSum[x] -= rowSum[static_cast<size_t>(y - pr) * ew + x];
                    }
                }
            if (interruptRequested()) return;
        }
    });
    throwIfInterrupted();
    for (const std::vector<int>& kept : tileOffsets)
        for (size_t k = 0; k + 1 < kept.size(); k += 2) {
            out.offsetX.push_back(kept[k]);
            out.offsetZ.push_back(kept[k + 1]);
        }

    // ---- step 4: the estimate and the residual -------------------------------------------
    tbb::parallel_for(0, H, [&](int y) {
        std::vector<std::pair<float, float>> c;  // (patch difference, copy)
        std::vector<float> v;
        for (int x = 0; x < W; ++x) {
            const size_t i = static_cast<size_t>(y) * W + x;
            c.clear();
            for (int k = 0; k < K; ++k) {
                const size_t j = static_cast<size_t>(k) * n + i;
                if (std::isfinite(copySsd[j])) c.emplace_back(copySsd[j], copies[j]);
            }
            if (c.empty()) {
                out.residual[i] = 0.0f;
                continue;
            }
            size_t m = c.size();
            if (o.keep < 1.0) {
                m = std::max<size_t>(
                    1, static_cast<size_t>(std::ceil(o.keep * static_cast<double>(c.size()))));
                std::nth_element(c.begin(), c.begin() + static_cast<std::ptrdiff_t>(m - 1),
                                 c.end());
            }
            v.clear();
            for (size_t j = 0; j < m; ++j) v.push_back(c[j].second);
            std::sort(v.begin(), v.end());
            const float est =
                v.size() % 2 ? v[v.size() / 2] : 0.5f * (v[v.size() / 2 - 1] + v[v.size() / 2]);
            out.residual[i] = g[i] - est;
        }
    });
    if (relief.relief)  // a step's ramp is the relief's, never a defect's
        for (size_t i = 0; i < n; ++i)
            if (relief.ramp[i]) out.residual[i] = 0.0f;
    // step 8l's residual, from the copies that cross the lay (not on a relief)
    std::vector<float> zAcross;
    double sigmaAcross = 0.0;
    if (o.layLineElongation > 0.0 && !relief.relief)
        zAcross = acrossLayScores(g, copies, copySsd, tileOffsets, W, H, T, tilesX, K, b,
                                  o.layLineWidth, sigmaAcross);
    copies.clear();
    copies.shrink_to_fit();
    copySsd.clear();
    copySsd.shrink_to_fit();
    throwIfInterrupted();

    // ---- step 5: detection in noise at several scales -------------------------------------
    auto inside = [&](int x, int y) { return insideBorder(x, y, W, H, b); };
    size_t interior = 0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) interior += inside(x, y) ? 1 : 0;
    if (interior == 0) return out;
    const double tests = static_cast<double>(interior) * o.scales;
    out.threshold = gaussianTailInverse(std::min(0.5, o.nfa / (2.0 * tests)));
    // σ floor: 1e-3 of the levelled heights' RMS (a flat background, as a logo's, leaves a
    // residual of rounding whose MAD is 0; that alone is no anomaly), on a relief at least its
    // levels' half band (two samples of one plateau differ by up to a band's width)
    double rms = 0.0;
    for (float v : levelled) rms += static_cast<double>(v) * v;
    const double sigmaFloor = std::max(1e-3 * std::sqrt(rms / static_cast<double>(n)),
                                       relief.relief ? relief.halfWidth : 0.0);
    {
        double sum = 0.0;
        for (int y = b; y < H - b; ++y)
            for (int x = b; x < W - b; ++x) {
                const double v = g[static_cast<size_t>(y) * W + x];
                sum += v * v;
            }
        out.textureRms = std::sqrt(sum / static_cast<double>(interior));
    }
    out.shallowRms =
        o.roughnessCutoff > 0.0 ? roughnessRmsOf(g, W, H, b, o.roughnessCutoff) : out.textureRms;
    std::vector<float> zDetect(n, 0.0f), zGrow(n, 0.0f);
    for (int s = 0; s < o.scales; ++s) {
        throwIfInterrupted();
        const std::vector<float> rs =
            s == 0 ? out.residual : gaussianBlur(out.residual, W, H, std::ldexp(1.0, s - 1));
        std::vector<float> vals;
        vals.reserve(interior);
        for (int y = b; y < H - b; ++y)
            for (int x = b; x < W - b; ++x) vals.push_back(rs[static_cast<size_t>(y) * W + x]);
        const RobustScale scale = robustScaleOf(vals);
        const double med = scale.median;
        double sigma = scale.sigma;
        if (o.tailQuantile > 0.0) {
            // the Gaussian whose tailQuantile-quantile of |r_s| is the residual's: a texture's
            // heavy tail (particles, wandering striae) raises σ_s where the MAD does not see it
            const size_t q =
                std::min(vals.size() - 1,
                         static_cast<size_t>(o.tailQuantile * static_cast<double>(vals.size())));
            std::nth_element(vals.begin(), vals.begin() + static_cast<std::ptrdiff_t>(q),
                             vals.end());
            sigma = std::max(sigma, vals[q] / gaussianTailInverse(0.5 * (1.0 - o.tailQuantile)));
        }
        sigma = std::max(sigma, sigmaFloor);
        if (s == 0) out.sigma = sigma;
        if (!(sigma > 0.0)) continue;  // a constant residual: nothing stands out
        for (size_t i = 0; i < n; ++i) {
            const float z = static_cast<float>(std::abs(rs[i] - med) / sigma);
            zDetect[i] = std::max(zDetect[i], z);
            if (s <= o.growScale) zGrow[i] = std::max(zGrow[i], z);
        }
    }

    // ---- step 6: regions -----------------------------------------------------------------
    // 6a: every region the growth makes (the detector's responses all over the map) with its
    // peak score; 6b: the texture's own tail of those peaks; 6c: the regions kept
    const float thr = static_cast<float>(out.threshold);
    const float grow = static_cast<float>(std::min(o.growSigma, out.threshold));
    // f(q) for each of the 8 neighbours q of sample i that lie inside the border (and i itself)
    auto forEachNeighbour = [&](size_t i, auto&& f) {
        const int px = static_cast<int>(i % W), py = static_cast<int>(i / W);
        for (int qy = py - 1; qy <= py + 1; ++qy)
            for (int qx = px - 1; qx <= px + 1; ++qx)
                if (inside(qx, qy)) f(static_cast<size_t>(qy) * W + qx);
    };
    // The 8-connected region from sample i0 over the samples inside the border that `accept`
    // admits and `seen` does not hold yet: appended to `samples` in the order reached (the
    // vector is the flood's queue), each marked in `seen`. True when it reaches the border's
    // inner line.
    auto floodRegion = [&](size_t i0, std::vector<uint8_t>& seen, std::vector<size_t>& samples,
                           auto&& accept) {
        const size_t begin = samples.size();
        samples.push_back(i0);
        seen[i0] = 1;
        bool atBorder = false;
        for (size_t j = begin; j < samples.size(); ++j) {
            const size_t i = samples[j];
            const int px = static_cast<int>(i % W), py = static_cast<int>(i / W);
            if (px == b || py == b || px == W - b - 1 || py == H - b - 1) atBorder = true;
            forEachNeighbour(i, [&](size_t q) {
                if (seen[q] || !accept(q)) return;
                seen[q] = 1;
                samples.push_back(q);
            });
        }
        return atBorder;
    };
    auto peakOf = [&](std::span<const size_t> samples) {
        float peak = 0.0f;
        for (const size_t i : samples) peak = std::max(peak, zDetect[i]);
        return peak;
    };
    // step 7b's line score of a set of samples: its mean score at the growth's scales × the
    // root of its elongation (the number of its width's cells along its length)
    auto lineScore = [&](std::span<const size_t> samples) {
        if (samples.empty()) return 0.0;
        double sum = 0.0;
        for (const size_t i : samples) sum += zGrow[i];
        return sum / static_cast<double>(samples.size()) *
               std::sqrt(extentOf(samples, W).elongation);
    };
    struct Region {
        size_t begin, end;  // its samples in `members`
        float peak;         // its largest zDetect
        bool atBorder;
    };
    std::vector<Region> regions;
    std::vector<size_t> members;
    std::vector<uint8_t> seen(n, 0);
    const auto grows = [&](size_t q) { return zGrow[q] >= grow; };
    for (int y = b; y < H - b; ++y)
        for (int x = b; x < W - b; ++x) {
            const size_t i0 = static_cast<size_t>(y) * W + x;
            if (zDetect[i0] >= thr) ++out.detections;
            if (seen[i0] || !grows(i0)) continue;
            Region reg{members.size(), 0, 0.0f, false};
            reg.atBorder = floodRegion(i0, seen, members, grows);
            reg.end = members.size();
            reg.peak = peakOf({members.data() + reg.begin, reg.end - reg.begin});
            regions.push_back(reg);
        }
    out.candidates = regions.size();
    // step 7b's pieces of a region: at the levels growSigma × borderLevelStep^k up to its
    // largest score (k = 0, 1, ...), its 8-connected samples of one sign scoring at least the
    // level and not marked yet; `visit(piece, atBorder, k)`
    const bool lineTest = o.lineNfa > 0.0 && o.textureNfa > 0.0 && !relief.relief;
    std::vector<uint8_t> lineSeen(lineTest ? n : 0, 0), lineIn(lineSeen.size(), 0);
    std::vector<size_t> linePiece;
    auto forEachLevelPiece = [&](const Region& reg, auto&& visit) {
        float top = 0.0f;
        for (size_t k = reg.begin; k < reg.end; ++k) {
            top = std::max(top, zGrow[members[k]]);
            lineIn[members[k]] = 1;
        }
        size_t index = 0;
        for (double level = grow; level <= top; level *= o.borderLevelStep, ++index) {
            for (size_t k = reg.begin; k < reg.end; ++k) lineSeen[members[k]] = 0;
            const float cut = static_cast<float>(level);
            for (size_t k = reg.begin; k < reg.end; ++k) {
                const size_t i0 = members[k];
                if (lineSeen[i0] || out.map[i0] || zGrow[i0] < cut) continue;
                const bool negative = out.residual[i0] < 0.0f;
                const auto accept = [&](size_t q) {
                    return lineIn[q] && !out.map[q] && zGrow[q] >= cut &&
                           (out.residual[q] < 0.0f) == negative;
                };
                linePiece.clear();
                const bool atBorder = floodRegion(i0, lineSeen, linePiece, accept);
                visit(std::span<const size_t>(linePiece), atBorder, index);
            }
            if (!(o.borderLevelStep > 1.0)) break;  // the growth's level alone
        }
        for (size_t k = reg.begin; k < reg.end; ++k) lineIn[members[k]] = 0;
    };
    // (not on a relief: its plateaus, flat to within their band, leave no texture whose tail
    // the regions would sample -- nearly all of them are the defects)
    if (o.textureNfa > 0.0 && !relief.relief) {
        std::vector<float> peaks;
        peaks.reserve(regions.size());
        for (const Region& reg : regions) peaks.push_back(reg.peak);
        out.textureThreshold = textureTailThreshold(peaks, o.textureQuantile, o.textureNfa);
    }
    // step 7b: the texture's own tail of line scores, per level, over every piece of every
    // region at that level (the levels are as many tests: lineNfa shared among them); a level
    // with too few pieces to measure a tail on keeps none
    std::vector<double> lineThresholds;
    if (lineTest) {
        std::vector<std::vector<float>> scores;
        for (const Region& reg : regions)
            forEachLevelPiece(reg, [&](std::span<const size_t> part, bool, size_t level) {
                if (scores.size() <= level) scores.resize(level + 1);
                scores[level].push_back(static_cast<float>(lineScore(part)));
            });
        const double nfa = o.lineNfa / static_cast<double>(std::max<size_t>(1, scores.size()));
        for (const std::vector<float>& level : scores) {
            const double t = textureTailThreshold(level, o.textureQuantile, nfa);
            lineThresholds.push_back(t > 0.0 ? t : std::numeric_limits<double>::infinity());
        }
        if (!lineThresholds.empty()) out.lineThreshold = lineThresholds.front();
    }
    // steps 6-7's gates on a region (or a border piece) with its peak score: a detection and
    // minRegion samples, its largest |r| at least textureRms × the texture's RMS, its peak
    // above the texture's own tail
    enum class Gate { Small, Shallow, Texture, Pass };
    // step 6's RMS gate: the samples' largest |r| below textureRms × the texture's RMS
    auto shallow = [&](std::span<const size_t> samples) {
        if (!(o.textureRms > 0.0)) return false;
        float deepest = 0.0f;
        for (const size_t i : samples) deepest = std::max(deepest, std::abs(out.residual[i]));
        return deepest < o.textureRms * out.shallowRms;
    };
    auto gate = [&](std::span<const size_t> samples, float peak) {
        if (!(peak >= thr) || static_cast<int>(samples.size()) < o.minRegion) return Gate::Small;
        if (shallow(samples)) return Gate::Shallow;
        if (peak < out.textureThreshold) return Gate::Texture;
        return Gate::Pass;
    };
    std::vector<size_t> stack;
    std::vector<int8_t> regionSign(o.extendSteps > 0 ? n : 0, 0);
    std::vector<float> regionLevel(regionSign.size(), 0.0f);
    std::vector<size_t> kept;
    // step 8e: a region below the texture takes its pile-up, the samples above the texture
    // within pileUpReach samples of it scoring at least pileUpSigma
    auto takePileUp = [&](std::span<const size_t> samples) {
        if (o.pileUpReach <= 0) return;
        if (!mostlyOfSign(samples, out.residual, -1.0f, o.pileUpShare)) return;
        const int reach = o.pileUpReach;
        for (const size_t i : samples) {
            const int px = static_cast<int>(i % W), py = static_cast<int>(i / W);
            for (int qy = py - reach; qy <= py + reach; ++qy)
                for (int qx = px - reach; qx <= px + reach; ++qx) {
                    if (!inside(qx, qy)) continue;
                    const size_t q = static_cast<size_t>(qy) * W + qx;
                    if (out.map[q] || !(out.residual[q] > 0.0f) ||
                        !(zGrow[q] >= static_cast<float>(o.pileUpSigma)))
                        continue;
                    out.map[q] = 255;
                    ++out.pileUp;
                }
        }
    };
    // step 8i: a border piece that is a line crossing its tile's lay (a groove across the
    // striae; one along them is a stria); where the tile has no lay, any line
    // the lay of the tile holding (cx, cz): its best offset's direction (radians from the x axis,
    // in [0, π)) when the tile is striated (lineLayContrast), else -1 (steps 8i, 8l)
    const auto tileLay = [&](double cx, double cz) {
        const size_t tile =
            static_cast<size_t>(std::min(tilesZ - 1, static_cast<int>(cz) / T)) * tilesX +
            static_cast<size_t>(std::min(tilesX - 1, static_cast<int>(cx) / T));
        const std::vector<int>& d = tileOffsets[tile];
        if (d.size() < 2 || !(tileLayContrast[tile] >= o.lineLayContrast)) return -1.0;
        double lay = std::atan2(static_cast<double>(d[1]), static_cast<double>(d[0]));
        if (lay < 0.0) lay += kPi;
        return lay;
    };
    auto crossingLine = [&](std::span<const size_t> samples, double elongation) {
        if (!(elongation > 0.0) || samples.empty()) return false;
        const Extent e = extentOf(samples, W);
        const double lay = tileLay(e.cx, e.cz);
        const bool striated = lay >= 0.0;
        return crossesLay(e, striated ? lay : 0.0, elongation, striated ? o.lineAngle : 0.0);
    };
    // steps 8a and 8c on a region's (or a border piece's) samples, then the map and step 8b's
    // first frontier; a border piece (steps 8d, 8f) also has to be shaped as a defect: at least
    // borderPieceMin samples after the trim, and its mean score at least `fill` of its largest
    // (borderPieceFill, borderLevelFill), or be a line crossing the lay (its extent at least
    // `line`), counted in `lines`. False when nothing is marked.
    auto keepRegion = [&](std::span<const size_t> samples, float peak, bool piece, double fill,
                          double cutAt, double line, size_t& lines) {
        // step 8b's sign: that of the region's largest |r| (a groove's or a dent's below the
        // texture, a burr's or a particle's above) ...
        size_t top = samples.front();
        for (const size_t i : samples)
            if (std::abs(out.residual[i]) > std::abs(out.residual[top])) top = i;
        const int8_t sign = out.residual[top] < 0.0f ? -1 : 1;
        // ... and its level: extendShare of its peak score, at least extendSigma
        const float level =
            std::max(static_cast<float>(o.extendSigma), static_cast<float>(o.extendShare) * peak);
        // step 8a: the region's extent is where it scores at least trimShare of its largest
        // score at the growth's scales (and growSigma): a deep defect's 2.5-sigma halo, and
        // texture that the growth joined to it at a small share of its depth, are left out
        float top0 = 0.0f;
        for (const size_t i : samples) top0 = std::max(top0, zGrow[i]);
        const float cut = static_cast<float>(o.trimShare) * top0;
        kept.clear();
        for (const size_t i : samples)
            if (zGrow[i] >= cut) kept.push_back(i);
        // step 8c: a particle (raised, compact) is the texture's, not a defect
        if (o.particleElongation > 0.0 &&
            isParticle(kept, out.residual, W, o.particleElongation, o.particleRaisedShare)) {
            ++out.droppedParticles;
            return false;
        }
        if (piece) {
            if (static_cast<int>(kept.size()) < o.borderPieceMin) return false;
            double sum = 0.0;
            float most = 0.0f;
            for (const size_t i : kept) {
                sum += zGrow[i];
                most = std::max(most, zGrow[i]);
            }
            // step 8f's piece cut at level `cutAt`: its mean excess over the level at least
            // borderLevelShape of its largest (a depression's shape, whatever the level)
            const double m = static_cast<double>(kept.size());
            const bool shaped =
                sum >= fill * most * m &&
                !(cutAt > 0.0 && !(sum - m * cutAt >= o.borderLevelShape * (most - cutAt) * m));
            if (!shaped) {
                if (!crossingLine(kept, line)) return false;
                ++lines;  // step 8i (8j): a groove (a burr) across the lay, whatever its profile
            }
        }
        out.trimmed += samples.size() - kept.size();
        for (const size_t i : kept) {
            out.map[i] = 255;
            if (regionSign.empty()) continue;
            regionSign[i] = sign;
            regionLevel[i] = level;
            stack.push_back(i);  // step 8b's first frontier
        }
        takePileUp(kept);
        return true;
    };
    // step 8d: a region reaching the border, split into the pieces that lie below the texture
    // (8-connected samples of the region whose residual is negative: material removed, as by a
    // groove, a pit or a dent); the pieces that do not reach the border are judged as regions
    // (steps 6-7), then by their shape (keepRegion)
    // ... on a texture only: where the map's own repeats explain it to within
    // borderPieceSigma of its RMS (a relief on a flat background, as a logo, not a texture),
    // a step of the relief leaves a band below it as smooth as a defect
    const bool splitBorder =
        o.borderPieceFill > 0.0 && !(out.sigma < o.borderPieceSigma * out.textureRms);
    std::vector<uint8_t> pieceSeen(splitBorder ? n : 0, 0), inRegion(pieceSeen.size(), 0);
    std::vector<size_t> piece;
    const auto below = [&](size_t q) { return grows(q) && out.residual[q] < 0.0f; };
    std::vector<uint8_t> levelSeen(splitBorder && o.borderLevelStep > 1.0 ? n : 0, 0);
    // a kept piece's pile-up: the region's samples above the texture within borderPieceRim
    // samples (Chebyshev) of what the piece kept
    auto takeRim = [&] {
        const int reach = o.borderPieceRim;
        for (const size_t i : kept) {
            const int px = static_cast<int>(i % W), py = static_cast<int>(i / W);
            for (int qy = std::max(0, py - reach); qy <= std::min(H - 1, py + reach); ++qy)
                for (int qx = std::max(0, px - reach); qx <= std::min(W - 1, px + reach); ++qx) {
                    const size_t q = static_cast<size_t>(qy) * W + qx;
                    if (inRegion[q] && !out.map[q] && out.residual[q] >= 0.0f) {
                        out.map[q] = 255;
                        ++out.borderRim;
                    }
                }
        }
    };
    // step 8h: a piece step 8f kept takes back its basin, the region's samples below the texture
    // that flood to it before they flood to the texture, down to growSigma: from the level it
    // was cut at, the level falls by borderBasin at a time; at each level the region's samples
    // below the texture that score at least it (and are not marked) are taken, layer by layer,
    // by the piece and by the texture's markers -- every other sample of the piece's level and
    // each one a level newly holds that neither reaches (a new maximum of the texture); a sample
    // both reach in the same layer is the texture's. The basin is given up (the piece kept
    // alone) when it holds more than borderBasinGrowth × the piece's samples.
    // Step 8n floods a burr's basin the same way, above the texture (side +1; 8h's is -1).
    std::vector<uint8_t> basinOwner(
        splitBorder && o.borderLevelStep > 1.0 && (o.borderBasin > 1.0 || o.burrBasin > 1.0) ? n
                                                                                             : 0,
        0);
    std::vector<size_t> basinPiece, basinTexture, basinNew;
    auto takeBasin = [&](const Region& reg, double level, double fall, float side) {
        enum : uint8_t { kNone = 0, kPiece = 1, kTexture = 2 };
        basinPiece.assign(piece.begin(), piece.end());
        basinTexture.clear();
        for (const size_t i : piece) basinOwner[i] = kPiece;
        float lv = static_cast<float>(level);
        const auto candidate = [&](size_t q) {
            return inRegion[q] && !out.map[q] && side * out.residual[q] > 0.0f && zGrow[q] >= lv &&
                   basinOwner[q] == kNone;
        };
        for (size_t k = reg.begin; k < reg.end; ++k)
            if (candidate(members[k])) {
                basinOwner[members[k]] = kTexture;
                basinTexture.push_back(members[k]);
            }
        // each layer of the flood: the texture's claims first, so a tie is the texture's
        auto floodLayer = [&](std::vector<size_t>& owned, size_t from, uint8_t owner) {
            const size_t end = owned.size();
            for (size_t j = from; j < end; ++j)
                forEachNeighbour(owned[j], [&](size_t q) {
                    if (!candidate(q)) return;
                    basinOwner[q] = owner;
                    owned.push_back(q);
                });
            return end;
        };
        while (lv > grow) {
            lv = std::max(grow, static_cast<float>(lv / fall));
            size_t fromPiece = 0, fromTexture = 0;
            for (;;) {
                const size_t nPiece = basinPiece.size(), nTexture = basinTexture.size();
                fromTexture = floodLayer(basinTexture, fromTexture, kTexture);
                fromPiece = floodLayer(basinPiece, fromPiece, kPiece);
                if (basinPiece.size() == nPiece && basinTexture.size() == nTexture) break;
            }
            for (size_t k = reg.begin; k < reg.end; ++k)
                if (candidate(members[k])) {
                    basinOwner[members[k]] = kTexture;
                    basinTexture.push_back(members[k]);
                }
        }
        basinNew.clear();
        for (const size_t i : basinPiece)
            if (!out.map[i]) basinNew.push_back(i);
        for (const size_t i : basinPiece) basinOwner[i] = kNone;
        for (const size_t i : basinTexture) basinOwner[i] = kNone;
        if (o.borderBasinGrowth > 0.0 && static_cast<double>(basinNew.size()) >
                                             o.borderBasinGrowth * static_cast<double>(kept.size()))
            return;
        const size_t from = kept.front();
        for (const size_t i : basinNew) {
            out.map[i] = 255;
            kept.push_back(i);
            if (regionSign.empty()) continue;
            regionSign[i] = regionSign[from];
            regionLevel[i] = regionLevel[from];
            stack.push_back(i);  // step 8b's frontier
        }
        (side < 0.0f ? out.borderBasin : out.burrBasin) += basinNew.size();
        takePileUp(basinNew);
    };
    // step 8j: a burr across the lay. The region at the border split at the levels of step 8f
    // (from growSigma, rising by borderLevelStep) into its pieces above the texture; a piece
    // off the border that passes steps 6-7's gates, keeps borderPieceMin samples after the trim
    // and is a line at least burrElongation long crossing its tile's lay (step 8i's test)
    // is kept; a piece not kept is split again at the next level. Raised pieces are kept on no
    // other shape: a land's shoulders are raised plateaus as smooth as a defect.
    std::vector<uint8_t> raisedSeen(splitBorder && o.burrElongation > 0.0 ? n : 0, 0);
    auto keepRaisedLines = [&](const Region& reg) {
        float top = 0.0f;
        for (size_t k = reg.begin; k < reg.end; ++k) top = std::max(top, zGrow[members[k]]);
        // the levels: growSigma, then growSigma × borderLevelStep^k below the region's top
        for (double level = grow; level < top; level *= o.borderLevelStep) {
            for (size_t k = reg.begin; k < reg.end; ++k) raisedSeen[members[k]] = 0;
            const float cut = static_cast<float>(level);
            const auto raised = [&](size_t q) {
                return inRegion[q] && !out.map[q] && zGrow[q] >= cut && out.residual[q] > 0.0f;
            };
            for (size_t k = reg.begin; k < reg.end; ++k) {
                const size_t i0 = members[k];
                if (raisedSeen[i0] || !raised(i0)) continue;
                piece.clear();
                const bool atBorder = floodRegion(i0, raisedSeen, piece, raised);
                const float peak = peakOf(piece);
                if (atBorder || gate(piece, peak) != Gate::Pass) continue;
                // no fill passes (an infinite share): the line test alone decides
                if (!keepRegion(piece, peak, true, std::numeric_limits<double>::infinity(), 0.0,
                                o.burrElongation, out.raisedLines))
                    continue;
                // step 8n: the burr takes back its basin, its flanks above the texture down to
                // growSigma that flood to it before they flood to the texture's raised patches
                if (o.burrBasin > 1.0 && !basinOwner.empty())
                    takeBasin(reg, level, o.burrBasin, 1.0f);
            }
            if (!(o.borderLevelStep > 1.0)) break;  // step 8f off: the growth's level alone
        }
    };
    auto keepBorderPieces = [&](const Region& reg) {
        for (size_t k = reg.begin; k < reg.end; ++k) inRegion[members[k]] = 1;
        for (size_t k = reg.begin; k < reg.end; ++k) {
            const size_t i0 = members[k];
            if (pieceSeen[i0] || !(out.residual[i0] < 0.0f)) continue;
            piece.clear();
            const bool atBorder = floodRegion(i0, pieceSeen, piece, below);
            const float peak = peakOf(piece);
            if (atBorder || gate(piece, peak) != Gate::Pass) continue;
            if (!keepRegion(piece, peak, true, o.borderPieceFill, 0.0, o.lineElongation,
                            out.borderLines))
                continue;
            ++out.borderPieces;
            takeRim();
        }
        // step 8f: the region split again at rising levels of its own score (a component
        // tree): at each level L = growSigma × borderLevelStep^k below the region's largest
        // score, its samples below the texture scoring at least L and not marked yet, in
        // 8-connected pieces; a piece off the border is judged as step 8d's (the gates, the
        // trim, borderPieceMin) with borderLevelFill for its fill and borderLevelShape for its
        // excess over the level, and a piece that is not kept is split again at the next level
        if (o.borderLevelStep > 1.0) {
            float top = 0.0f;
            for (size_t k = reg.begin; k < reg.end; ++k) top = std::max(top, zGrow[members[k]]);
            for (double level = grow * o.borderLevelStep; level < top; level *= o.borderLevelStep) {
                for (size_t k = reg.begin; k < reg.end; ++k) levelSeen[members[k]] = 0;
                const float cut = static_cast<float>(level);
                const auto above = [&](size_t q) {
                    return inRegion[q] && !out.map[q] && zGrow[q] >= cut && out.residual[q] < 0.0f;
                };
                for (size_t k = reg.begin; k < reg.end; ++k) {
                    const size_t i0 = members[k];
                    if (levelSeen[i0] || !above(i0)) continue;
                    piece.clear();
                    const bool atBorder = floodRegion(i0, levelSeen, piece, above);
                    const float peak = peakOf(piece);
                    if (atBorder || gate(piece, peak) != Gate::Pass) continue;
                    if (!keepRegion(piece, peak, true, o.borderLevelFill, level, o.lineElongation,
                                    out.borderLines))
                        continue;
                    ++out.borderPieces;
                    ++out.borderLevelPieces;
                    if (o.borderBasin > 1.0 && !basinOwner.empty())
                        takeBasin(reg, level, o.borderBasin, -1.0f);
                    takeRim();
                }
            }
        }
        if (!raisedSeen.empty()) keepRaisedLines(reg);  // step 8j
        for (size_t k = reg.begin; k < reg.end; ++k) inRegion[members[k]] = 0;
    };
    // step 8k's record: each region's verdict and whether it was kept
    std::vector<Gate> verdicts(o.hollowRowGap > 0.0 ? regions.size() : 0, Gate::Small);
    std::vector<uint8_t> regionKept(verdicts.size(), 0);
    std::vector<size_t> borderRegions;  // the regions that pass the gates and reach the border
    for (const Region& reg : regions) {
        const std::span<const size_t> samples(members.data() + reg.begin, reg.end - reg.begin);
        const Gate verdict = gate(samples, reg.peak);
        if (!verdicts.empty()) verdicts[static_cast<size_t>(&reg - regions.data())] = verdict;
        if (verdict == Gate::Small) continue;
        if (verdict == Gate::Shallow) {
            ++out.droppedShallow;
            continue;
        }
        if (verdict == Gate::Texture) {
            ++out.droppedTexture;
            // step 7b: its pieces that are lines above the texture's own tail of line scores
            if (lineThresholds.empty()) continue;
            forEachLevelPiece(reg, [&](std::span<const size_t> part, bool atBorder, size_t level) {
                // (every level of a region had a piece when the tails were read, before
                // anything was marked; the bound only guards that)
                if (atBorder || level >= lineThresholds.size() ||
                    static_cast<int>(part.size()) < o.minRegion ||
                    !(lineScore(part) >= lineThresholds[level]) || shallow(part))
                    return;
                if (keepRegion(part, peakOf(part), false, 0.0, 0.0, 0.0, out.borderLines))
                    ++out.textureLines;
            });
            continue;
        }
        if (o.dropBorderRegions && b > 0 && reg.atBorder) {
            ++out.droppedBorder;
            borderRegions.push_back(static_cast<size_t>(&reg - regions.data()));
            if (!pieceSeen.empty()) keepBorderPieces(reg);
            continue;
        }
        if (!keepRegion(samples, reg.peak, false, 0.0, 0.0, 0.0, out.borderLines)) continue;
        ++out.regions;
        if (!regionKept.empty()) regionKept[static_cast<size_t>(&reg - regions.data())] = 1;
    }
    // step 8k: a row of hollows. The regions off the border that hold a detection and minRegion
    // samples, lie below the texture (at least kHollowShare of their Σ|r| negative) and are
    // compact (extent below kHollowCompact), their centroids linked when at most hollowRowGap
    // apart; a group of at least hollowRowMembers that is a line (its centroids' extent at least
    // kHollowRowElongation) is a row, and its regions that steps 6-7 dropped (under the
    // texture's RMS or its tail) are kept: a pit chain, each pit too small alone, the row a line
    if (o.hollowRowGap > 0.0) {
        std::vector<size_t> hollow;
        std::vector<std::array<double, 2>> at;
        for (size_t k = 0; k < regions.size(); ++k) {
            const Region& reg = regions[k];
            const std::span<const size_t> samples(members.data() + reg.begin, reg.end - reg.begin);
            if (reg.atBorder || verdicts[k] == Gate::Small) continue;
            if (!mostlyOfSign(samples, out.residual, -1.0f, kHollowShare)) continue;
            const Extent e = extentOf(samples, W);
            if (!(e.elongation < kHollowCompact)) continue;
            hollow.push_back(k);
            at.push_back({e.cx, e.cz});
        }
        for (const std::vector<size_t>& row :
             rowsOf(at, o.hollowRowGap, o.hollowRowMembers, kHollowRowElongation)) {
            size_t taken = 0;
            for (const size_t j : row) {
                const Region& reg = regions[hollow[j]];
                if (regionKept[hollow[j]]) continue;
                const std::span<const size_t> samples(members.data() + reg.begin,
                                                      reg.end - reg.begin);
                if (keepRegion(samples, reg.peak, false, 0.0, 0.0, 0.0, out.borderLines)) ++taken;
            }
            out.rowHollows += taken;
            out.hollowRows += taken > 0 ? 1 : 0;
        }
    }
    // step 8p: a chain of hollows on a rough stretch. The regions steps 6-7 keep that reach the
    // border (8d-8i judge their pieces, at least borderPieceMin samples each) are cut at step 8f's
    // levels; at each level their pieces below the texture, not marked, off the border, holding a
    // detection and minRegion samples and compact (8k's hollows), with 8k's hollows off the
    // border, are points; a chain of at least hollowRowMembers of them evenly spaced on a line
    // (chainsOf, chainTolerance; steps at most hollowRowGap) is kept, piece by piece
    if (o.chainTolerance > 0.0 && o.hollowRowGap > 0.0 && o.dropBorderRegions && b > 0) {
        std::vector<uint8_t> rough(n, 0), pieceAt(n, 0);
        std::vector<size_t> roughSamples;
        float top = 0.0f;
        std::vector<size_t> offBorder;  // 8k's hollows: regions off the border
        for (size_t k = 0; k < regions.size(); ++k) {
            const Region& reg = regions[k];
            const std::span<const size_t> samples(members.data() + reg.begin, reg.end - reg.begin);
            if (reg.atBorder && verdicts[k] == Gate::Pass) {
                for (const size_t i : samples) {
                    if (!(out.residual[i] < 0.0f)) continue;
                    rough[i] = 1;
                    roughSamples.push_back(i);
                    top = std::max(top, zGrow[i]);
                }
            } else if (!reg.atBorder && verdicts[k] != Gate::Small &&
                       mostlyOfSign(samples, out.residual, -1.0f, kHollowShare) &&
                       extentOf(samples, W).elongation < kHollowCompact) {
                offBorder.push_back(k);
            }
        }
        const double step = o.borderLevelStep > 1.0 ? o.borderLevelStep : 1.25;
        std::vector<size_t> pool;
        std::vector<std::pair<size_t, size_t>> pieces;  // [begin, end) in pool
        std::vector<std::array<double, 2>> at;
        for (double level = grow; !roughSamples.empty() && level <= top; level *= step) {
            const auto lv = static_cast<float>(level);
            pool.clear();
            pieces.clear();
            at.clear();
            const auto inPiece = [&](size_t q) {
                return rough[q] && !out.map[q] && zGrow[q] >= lv;
            };
            for (const size_t i0 : roughSamples) {
                if (pieceAt[i0] || !inPiece(i0)) continue;
                const size_t begin = pool.size();
                const bool atBorder = floodRegion(i0, pieceAt, pool, inPiece);
                const std::span<const size_t> p(pool.data() + begin, pool.size() - begin);
                if (atBorder || static_cast<int>(p.size()) < o.minRegion || !(peakOf(p) >= thr))
                    continue;
                const Extent e = extentOf(p, W);
                if (!(e.elongation < kHollowCompact)) continue;
                pieces.emplace_back(begin, pool.size());
                at.push_back({e.cx, e.cz});
            }
            for (const size_t i : pool) pieceAt[i] = 0;
            if (pieces.empty()) continue;
            for (const size_t k : offBorder) {
                const Region& reg = regions[k];
                const Extent e = extentOf({members.data() + reg.begin, reg.end - reg.begin}, W);
                at.push_back({e.cx, e.cz});
            }
            for (const std::vector<size_t>& chain :
                 chainsOf(at, o.hollowRowGap, o.hollowRowMembers, o.chainTolerance)) {
                if (o.chainLayAngle > 0.0) {
                    // a chain along its tile's lay is a stria's own hollows
                    const auto& p0 = at[chain.front()];
                    const auto& p1 = at[chain.back()];
                    const double lay = tileLay(0.5 * (p0[0] + p1[0]), 0.5 * (p0[1] + p1[1]));
                    double dir = std::atan2(p1[1] - p0[1], p1[0] - p0[0]);
                    if (dir < 0.0) dir += kPi;
                    double off = std::abs(dir - lay);
                    off = std::min(off, kPi - off);
                    if (lay >= 0.0 && off < o.chainLayAngle * kPi / 180.0) continue;
                }
                size_t taken = 0;
                for (const size_t j : chain) {
                    std::span<const size_t> p;
                    float peak = 0.0f;
                    if (j < pieces.size()) {
                        p = {pool.data() + pieces[j].first, pieces[j].second - pieces[j].first};
                        peak = peakOf(p);
                    } else {
                        const size_t k = offBorder[j - pieces.size()];
                        p = {members.data() + regions[k].begin, regions[k].end - regions[k].begin};
                        peak = regions[k].peak;
                    }
                    // kept before (by steps 6-8k, or with a chain at this level)
                    if (std::any_of(p.begin(), p.end(), [&](size_t i) { return out.map[i] != 0; }))
                        continue;
                    if (keepRegion(p, peak, false, 0.0, 0.0, 0.0, out.borderLines)) ++taken;
                }
                out.chainHollows += taken;
                out.hollowChains += taken > 0 ? 1 : 0;
            }
        }
    }
    // ---- step 8: the kept regions' flanks --------------------------------------------------
    // a kept region grows `extendSteps` samples further, layer by layer, into samples whose
    // residual has the region's sign and a score of at least its level (below growSigma): a
    // defect's flanks and tapered ends, where its offset is a small share of its depth; only
    // from regions steps 6-7 kept and only into samples below growSigma (those above it are
    // another region, judged on its own: a texture region or one at the border is never
    // revived), at most extendSteps samples from them
    std::vector<size_t> next;
    for (int step = 0; step < o.extendSteps && !stack.empty(); ++step) {
        next.clear();
        for (const size_t i : stack)
            forEachNeighbour(i, [&](size_t q) {
                if (out.map[q] || !(zGrow[q] >= regionLevel[i]) || zGrow[q] >= grow) return;
                if ((out.residual[q] < 0.0f ? -1 : 1) != regionSign[i]) return;
                out.map[q] = 255;
                regionSign[q] = regionSign[i];
                regionLevel[q] = regionLevel[i];
                ++out.extended;
                next.push_back(q);
            });
        stack.swap(next);
    }
    // step 8g: the banks of the marks below the texture, on the final marks (each mark flooded
    // over the marks as they stand before the step)
    // (step 8o floods the same marks later)
    const std::vector<uint8_t> beforeBanks =
        o.grooveBankWidth > 0.0 || o.grooveRimSigma > 0.0 ? out.map : std::vector<uint8_t>();
    if (o.grooveBankWidth > 0.0) {
        std::vector<uint8_t> markSeen(n, 0);
        std::vector<size_t> mark;
        for (size_t i0 = 0; i0 < n; ++i0) {
            if (!beforeBanks[i0] || markSeen[i0]) continue;
            mark.clear();
            floodRegion(i0, markSeen, mark, [&](size_t q) { return beforeBanks[q] != 0; });
            out.grooveBanks +=
                takeGrooveBanks(mark, beforeBanks, out.map, out.residual, zGrow, W, H, b, grow,
                                o.pileUpShare, o.grooveBankWidth, o.grooveLength);
        }
    }
    // step 8l: a line along the lay takes the samples beside it that stand out of the texture
    // once no copy lands on the line itself
    if (!zAcross.empty()) {
        const auto [lines, added] = takeLayLines(
            out.map, zAcross, sigmaAcross, out.residual, W, H, b, o.minRegion, o.layLineElongation,
            o.layLineAngle, o.layLineStandOut, o.layLineStandOutMax, o.layLineKept, o.layLineReach,
            o.layLineSigma, tileLay);
        out.layLines = lines;
        out.layLineSamples = added;
    }
    // step 8o: a groove's raised rims, taken at a lower score when they stand along it (the
    // marks as they stood before step 8g)
    if (o.grooveRimSigma > 0.0) {
        std::vector<uint8_t> markSeen(n, 0);
        std::vector<size_t> mark;
        for (size_t i0 = 0; i0 < n; ++i0) {
            if (!beforeBanks[i0] || markSeen[i0]) continue;
            mark.clear();
            floodRegion(i0, markSeen, mark, [&](size_t q) { return beforeBanks[q] != 0; });
            out.grooveRims += takeGrooveBanks(mark, beforeBanks, out.map, out.residual, zGrow, W, H,
                                              b, o.grooveRimSigma, o.pileUpShare, o.grooveRimWidth,
                                              o.grooveRimLength, o.grooveRimShare);
        }
    }
    // step 8q: a groove's far banks. Each mark below the texture (pileUpShare of its Σ|r|) that
    // is a line (at least kFarBankGrooveMin samples, extent at least kFarBankElongation) takes
    // the regions of step 6 not marked that stand above the texture (at least kFarBankRaised of
    // their samples), are lines as well and run beside it: their long axis within
    // kFarBankAngle of its own, their centroid within farBankReach samples of its axis and
    // between its ends along it
    if (o.farBankReach > 0.0) {
        struct Groove {
            double cx, cz, ux, uz, from, to;  // centroid, axis, extent along it
        };
        std::vector<Groove> grooves;
        std::vector<uint8_t> markSeen(n, 0);
        std::vector<size_t> mark;
        for (size_t i0 = 0; i0 < n; ++i0) {
            if (!out.map[i0] || markSeen[i0]) continue;
            mark.clear();
            floodRegion(i0, markSeen, mark, [&](size_t q) { return out.map[q] != 0; });
            if (mark.size() < kFarBankGrooveMin ||
                !mostlyOfSign(mark, out.residual, -1.0f, o.pileUpShare))
                continue;
            const Extent e = extentOf(mark, W);
            if (!(e.elongation >= kFarBankElongation)) continue;
            Groove gr{e.cx, e.cz, std::cos(e.axis), std::sin(e.axis), 0.0, 0.0};
            gr.from = std::numeric_limits<double>::infinity();
            gr.to = -gr.from;
            for (const size_t i : mark) {
                const double s = (static_cast<double>(i % W) - gr.cx) * gr.ux +
                                 (static_cast<double>(i / W) - gr.cz) * gr.uz;
                gr.from = std::min(gr.from, s);
                gr.to = std::max(gr.to, s);
            }
            grooves.push_back(gr);
        }
        const double cosAngle = std::cos(kFarBankAngle * kPi / 180.0);
        for (size_t k = 0; k < regions.size() && !grooves.empty(); ++k) {
            const Region& reg = regions[k];
            const std::span<const size_t> samples(members.data() + reg.begin, reg.end - reg.begin);
            if (static_cast<int>(samples.size()) < o.minRegion) continue;
            if (std::any_of(samples.begin(), samples.end(),
                            [&](size_t i) { return out.map[i] != 0; }))
                continue;
            const auto raised = std::count_if(samples.begin(), samples.end(),
                                              [&](size_t i) { return out.residual[i] > 0.0f; });
            if (static_cast<double>(raised) < kFarBankRaised * static_cast<double>(samples.size()))
                continue;
            const Extent e = extentOf(samples, W);
            if (!(e.elongation >= kFarBankElongation)) continue;
            const double ux = std::cos(e.axis), uz = std::sin(e.axis);
            for (const Groove& gr : grooves) {
                if (std::abs(ux * gr.ux + uz * gr.uz) < cosAngle) continue;
                const double dx = e.cx - gr.cx, dz = e.cz - gr.cz;
                const double along = dx * gr.ux + dz * gr.uz;
                if (std::abs(dz * gr.ux - dx * gr.uz) > o.farBankReach || along < gr.from ||
                    along > gr.to)
                    continue;
                for (const size_t i : samples) out.map[i] = 255;
                out.farBankSamples += samples.size();
                ++out.farBanks;
                break;
            }
        }
    }
    // step 8r: a line along the lay judged on copies chosen for it, across it
    if (o.lineCopiesSigma > 0.0 && !relief.relief) {
        const auto [lines, added] = takeLineCopies(out.map, g, W, H, b, o.minRegion, o.patch,
                                                   o.refine, R, o.lineCopiesSigma, tileLay);
        out.lineCopyLines = lines;
        out.lineCopySamples = added;
    }
    // step 8t: a line the heights show as a valley beside a mark (before 8s takes its rims)
    ValleyScores valleys;
    if (o.valleyLineSigma > 0.0 && !relief.relief) {
        valleys = scoreValleys(out.map, g, W, H, b, o.valleyLineSigma, o.valleyLineGate);
        const auto [lines, added] = takeValleyLines(out.map, valleys, W, H, b, o.minRegion,
                                                    o.valleyLineSigma, o.valleyLineGrow);
        out.valleyLines = lines;
        out.valleyLineSamples = added;
    }
    // step 8s: a groove's rims judged along it, a segment of the band beside it at a time
    if (o.rimBandMean > 0.0 && !relief.relief) {
        const auto [segments, added] =
            takeRimBands(out.map, out.residual, out.sigma, W, H, b, o.rimBandMean, o.rimBandShare,
                         o.rimBandReach, o.rimBandSegment);
        out.rimBands = segments;
        out.rimBandSamples = added;
    }
    // step 8u: the marks' ring, a cell at a time, where it keeps their sign
    if (o.edgeRingSigma > 0.0 && !relief.relief) {
        const auto [cells, added] = takeEdgeRing(out.map, out.residual, out.sigma, W, H, b,
                                                 o.edgeRingSigma, o.edgeRingShare, o.edgeRingCell);
        out.edgeRingCells = cells;
        out.edgeRingSamples = added;
    }
    // step 8v: the rims the heights show beside a valley line (step 8t's scores and gate)
    if (o.valleyRimMean > 0.0 && o.valleyLineSigma > 0.0 && !relief.relief) {
        const auto [segments, added] =
            takeValleyRims(out.map, g, valleys, W, H, b, o.valleyLineSigma, o.valleyLineGrow,
                           o.valleyRimMean, o.valleyRimShare, o.valleyRimReach);
        out.valleyRims = segments;
        out.valleyRimSamples = added;
    }
    // what the map could not judge: the samples of the regions at the border that no step marked
    for (const size_t k : borderRegions) {
        bool any = false;
        for (size_t j = regions[k].begin; j < regions[k].end; ++j)
            if (!out.map[members[j]]) {
                out.unjudged[members[j]] = 255;
                any = true;
            }
        out.unjudgedRegions += any ? 1 : 0;
    }
    return out;
}

}  // namespace sl
