#include "detect/ReliefLevels.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <optional>

#include "core/PolynomialFit.h"

namespace sl {

namespace {

struct Band {
    double lo = 0, hi = 0;  // [lo, hi)
    double share = 0;       // of the samples counted
};

// The histogram of step 1 (bins of `bin` from the least value) and its bands.
struct Histogram {
    double origin = 0, bin = 1;
    std::vector<double> count;
    std::vector<Band> bands;

    int binOf(double v) const {
        const double k = std::floor((v - origin) / bin);
        return k >= 0 && k < static_cast<double>(count.size()) ? static_cast<int>(k) : -1;
    }
    // the band holding v, each widened by half a bin each side (a sample of the border, not
    // counted in the histogram, a rounding below the least value counted); -1: none
    int bandOfValue(double v) const {
        for (size_t k = 0; k < bands.size(); ++k)
            if (v >= bands[k].lo - 0.5 * bin && v < bands[k].hi + 0.5 * bin)
                return static_cast<int>(k);
        return -1;
    }
};

// Step 1 on the values v: the levels' bands, each at most cap bins each side of its peak (cap
// < 0: no limit). Empty when the histogram would be unreasonably long (a spike of 10^4 × rms).
Histogram levelBands(const std::vector<float>& v, double bin, const ReliefLevelsOptions& o,
                     int cap) {
    Histogram h;
    if (v.empty() || !(bin > 0)) return h;
    const auto [mn, mx] = std::minmax_element(v.begin(), v.end());
    const double bins = std::floor((static_cast<double>(*mx) - *mn) / bin) + 1.0;
    if (!(bins <= static_cast<double>(1 << 22))) return h;
    h.origin = *mn;
    h.bin = bin;
    h.count.assign(static_cast<size_t>(bins), 0.0);
    for (float x : v) {
        const int k = h.binOf(x);
        if (k >= 0) h.count[static_cast<size_t>(k)] += 1.0;
    }
    const int nb = static_cast<int>(h.count.size());
    std::vector<uint8_t> taken(h.count.size(), 0);
    const double total = static_cast<double>(v.size());
    for (;;) {
        int peak = -1;
        for (int k = 0; k < nb; ++k)
            if (!taken[k] && h.count[k] > 0 && (peak < 0 || h.count[k] > h.count[peak])) peak = k;
        if (peak < 0) break;
        const double floorCount = o.bandTail * h.count[peak];
        int a = peak, b = peak;
        while (a > 0 && !taken[a - 1] && h.count[a - 1] > floorCount && (cap < 0 || peak - a < cap))
            --a;
        while (b < nb - 1 && !taken[b + 1] && h.count[b + 1] > floorCount &&
               (cap < 0 || b - peak < cap))
            ++b;
        double sum = 0.0;
        for (int k = a; k <= b; ++k) {
            taken[k] = 1;
            sum += h.count[k];
        }
        if (sum < o.minLevelShare * total) break;
        Band band{h.origin + a * bin, h.origin + (b + 1) * bin, sum / total};
        // a band within two bins of a level taken before is that level's shoulder
        const bool shoulder = std::any_of(h.bands.begin(), h.bands.end(), [&](const Band& e) {
            return band.lo <= e.hi + 2 * bin && band.hi >= e.lo - 2 * bin;
        });
        if (shoulder) continue;
        h.bands.push_back(band);
    }
    return h;
}

std::vector<float> interiorValues(const std::vector<float>& g, int W, int H, int b) {
    std::vector<float> v;
    for (int y = b; y < H - b; ++y)
        for (int x = b; x < W - b; ++x) v.push_back(g[static_cast<size_t>(y) * W + x]);
    return v;
}

}  // namespace

ReliefLevels findReliefLevels(std::span<const float> heights, int W, int H, int border,
                              const ReliefLevelsOptions& o) {
    ReliefLevels out;
    const size_t n = static_cast<size_t>(W) * static_cast<size_t>(H);
    if (W < 3 || H < 3 || heights.size() != n) return out;
    const int b = std::clamp(border, 0, (std::min(W, H) - 1) / 2);
    std::vector<float> g(heights.begin(), heights.end());
    std::vector<float> v = interiorValues(g, W, H, b);
    double rms = 0.0;
    for (float x : v) rms += static_cast<double>(x) * x;
    rms = std::sqrt(rms / static_cast<double>(v.size()));
    if (!(rms > 0.0)) return out;
    const double bin = o.binShare * rms;

    // step 2: the first level's quadratic
    for (int it = 0; it < o.refits; ++it) {
        const Histogram h = levelBands(v, bin, o, -1);
        if (h.bands.empty()) return out;
        const Band& first = h.bands.front();
        std::vector<uint8_t> invalid(n);
        for (size_t i = 0; i < n; ++i) invalid[i] = !(g[i] >= first.lo && g[i] < first.hi);
        const std::optional<PolynomialSurface> s =
            fitPolynomialSurface(g, static_cast<size_t>(W), static_cast<size_t>(H), 2, invalid);
        if (!s) break;
        std::vector<double> f(static_cast<size_t>(W));
        for (int y = 0; y < H; ++y) {
            s->row(static_cast<size_t>(y), f);
            for (int x = 0; x < W; ++x)
                g[static_cast<size_t>(y) * W + x] -= static_cast<float>(f[x]);
        }
        v = interiorValues(g, W, H, b);
    }

    // step 1 again, each band at most as wide as the first
    Histogram h = levelBands(v, bin, o, -1);
    if (h.bands.empty()) return out;
    const int cap = static_cast<int>(std::lround((h.bands.front().hi - h.bands.front().lo) / bin));
    h = levelBands(v, bin, o, cap);
    if (h.bands.empty()) return out;

    // the levels' heights: the mean of each band's samples
    std::vector<double> sum(h.bands.size(), 0.0), cnt(h.bands.size(), 0.0);
    for (float x : v) {
        const int k = h.bandOfValue(x);
        if (k >= 0) {
            sum[k] += x;
            cnt[k] += 1.0;
        }
    }
    for (size_t k = 0; k < h.bands.size(); ++k) {
        out.levels.push_back(cnt[k] > 0 ? sum[k] / cnt[k] : 0.5 * (h.bands[k].lo + h.bands[k].hi));
    }
    out.halfWidth = 0.5 * (h.bands.front().hi - h.bands.front().lo);

    if (h.bands.size() < 2 || !(out.halfWidth <= o.maxHalfWidth * rms)) return out;

    // step 4: each sample's plateau (its band's level, or the nearest in-band sample's)
    std::vector<int> band(n);
    for (size_t i = 0; i < n; ++i) band[i] = h.bandOfValue(g[i]);
    // a plateau is a 4-connected piece of one band of at least minPlateau samples: where a pit
    // or a groove on a letter passes through another level's height, the samples at that height
    // are a thin ring or line, not a plateau (they are the defect's)
    {
        std::vector<uint8_t> seen(n, 0);
        std::vector<size_t> piece;
        for (size_t i0 = 0; i0 < n; ++i0) {
            if (band[i0] < 0 || seen[i0]) continue;
            piece.assign(1, i0);
            seen[i0] = 1;
            for (size_t q = 0; q < piece.size(); ++q) {
                const size_t i = piece[q];
                const int x = static_cast<int>(i % W), y = static_cast<int>(i / W);
                const size_t nb[4] = {x > 0 ? i - 1 : n, x < W - 1 ? i + 1 : n, y > 0 ? i - W : n,
                                      y < H - 1 ? i + W : n};
                for (size_t j : nb)
                    if (j < n && !seen[j] && band[j] == band[i0]) {
                        seen[j] = 1;
                        piece.push_back(j);
                    }
            }
            if (static_cast<int>(piece.size()) < o.minPlateau)
                for (size_t i : piece) band[i] = -1;
        }
    }
    // step 3: the gate, on the samples inside the border that lie on a plateau (a texture
    // stored with a coarse height quantum has its heights on a few levels too, but in specks)
    size_t onPlateau = 0;
    for (int y = b; y < H - b; ++y)
        for (int x = b; x < W - b; ++x) onPlateau += band[static_cast<size_t>(y) * W + x] >= 0;
    out.cover = static_cast<double>(onPlateau) / static_cast<double>(v.size());
    out.relief = out.cover >= o.minCover;
    if (!out.relief) return out;
    std::vector<uint8_t> hasPlateau(out.levels.size(), 0);
    for (size_t i = 0; i < n; ++i)
        if (band[i] >= 0) hasPlateau[static_cast<size_t>(band[i])] = 1;
    for (uint8_t k : hasPlateau) out.plateauLevels += k;
    std::vector<int> plateau = band;
    std::deque<size_t> queue;
    for (size_t i = 0; i < n; ++i)
        if (band[i] >= 0) queue.push_back(i);
    while (!queue.empty()) {
        const size_t i = queue.front();
        queue.pop_front();
        const int x = static_cast<int>(i % W), y = static_cast<int>(i / W);
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
                const int xx = x + dx, yy = y + dy;
                if (xx < 0 || yy < 0 || xx >= W || yy >= H) continue;
                const size_t j = static_cast<size_t>(yy) * W + xx;
                if (plateau[j] >= 0) continue;
                plateau[j] = plateau[i];
                queue.push_back(j);
            }
    }
    out.flattened.assign(n, 0.0f);
    out.ramp.assign(n, 0);
    const int r = std::max(0, o.rampReach);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const size_t i = static_cast<size_t>(y) * W + x;
            if (band[i] >= 0) {
                out.flattened[i] = static_cast<float>(g[i] - out.levels[band[i]]);
                continue;
            }
            bool above = false, below = false;
            for (int yy = std::max(0, y - r); yy <= std::min(H - 1, y + r); ++yy)
                for (int xx = std::max(0, x - r); xx <= std::min(W - 1, x + r); ++xx) {
                    const int k = band[static_cast<size_t>(yy) * W + xx];
                    if (k < 0) continue;
                    above = above || out.levels[k] > g[i];
                    below = below || out.levels[k] < g[i];
                }
            if (above && below) {
                out.ramp[i] = 1;
                continue;
            }
            out.flattened[i] = static_cast<float>(g[i] - out.levels[plateau[i]]);
        }
    return out;
}

}  // namespace sl
