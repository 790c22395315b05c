#include "detect/Hysteresis.h"

#include <algorithm>

namespace sl::defectmap {

size_t hysteresis(const std::vector<float>& score, int W, int H, double seed, double grow,
                  int minRegion, std::vector<uint8_t>& map) {
    size_t marked = 0;
    forEachRegion(
        W, H, 1, [&](size_t k) { return score[k] >= seed; },
        [&](size_t k) { return score[k] >= grow; },
        [&](const std::vector<size_t>& region) {
            if (region.size() < static_cast<size_t>(minRegion)) return;
            for (size_t k : region) map[k] = 255;
            marked += region.size();
        });
    return marked;
}

double tailQuantile(const std::vector<float>& score, int W, int H, int border,
                    const DefectMapOptions& o, const std::vector<uint8_t>* skip) {
    const int x0 = border, x1 = W - border, y0 = border, y1 = H - border;
    if (x1 <= x0 || y1 <= y0) return 0.0;
    const int n = std::max(1, std::min({o.seedTailTiles, x1 - x0, y1 - y0}));
    std::vector<double> tileQ;
    tileQ.reserve(static_cast<size_t>(n) * n);
    std::vector<float> v;
    for (int ty = 0; ty < n; ++ty)
        for (int tx = 0; tx < n; ++tx) {
            const int ya = y0 + (y1 - y0) * ty / n, yb = y0 + (y1 - y0) * (ty + 1) / n;
            const int xa = x0 + (x1 - x0) * tx / n, xb = x0 + (x1 - x0) * (tx + 1) / n;
            v.clear();
            for (int y = ya; y < yb; ++y)
                for (int x = xa; x < xb; ++x) {
                    const size_t k = static_cast<size_t>(y) * W + x;
                    if (!skip || !(*skip)[k]) v.push_back(score[k]);
                }
            const size_t all = static_cast<size_t>(yb - ya) * static_cast<size_t>(xb - xa);
            if (v.empty() || 2 * v.size() < all) continue;
            const size_t k =
                std::min(v.size() - 1,
                         static_cast<size_t>(o.seedTailQuantile * static_cast<double>(v.size())));
            std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
            tileQ.push_back(static_cast<double>(v[k]));
        }
    if (tileQ.empty()) return 0.0;
    // the median over tiles (the lower middle one of an even count)
    const size_t m = (tileQ.size() - 1) / 2;
    std::nth_element(tileQ.begin(), tileQ.begin() + static_cast<std::ptrdiff_t>(m), tileQ.end());
    return tileQ[m];
}

Thresholds tailThresholds(const std::vector<float>& score, int W, int H, const DefectMapOptions& o,
                          double seed, double grow, const std::vector<uint8_t>* skip) {
    if (!(o.seedTail > 0.0)) return {seed, grow};
    const double q = tailQuantile(score, W, H, o.border, o, skip);
    const double s = std::max(seed, o.seedTail * q);
    const double g = o.growTail > 0.0 ? std::max(grow, o.growTail * q) : grow * s / seed;
    return {s, std::min(g, s)};
}

}  // namespace sl::defectmap
