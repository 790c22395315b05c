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

Thresholds tailThresholds(const std::vector<float>& score, int W, int H, const DefectMapOptions& o,
                          double seed, double grow) {
    if (!(o.seedTail > 0.0)) return {seed, grow};
    std::vector<float> v;
    v.reserve(score.size());
    for (int y = o.border; y < H - o.border; ++y)
        for (int x = o.border; x < W - o.border; ++x)
            v.push_back(score[static_cast<size_t>(y) * W + x]);
    if (v.empty()) return {seed, grow};
    const size_t k = std::min(
        v.size() - 1, static_cast<size_t>(o.seedTailQuantile * static_cast<double>(v.size())));
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
    const double q = static_cast<double>(v[k]);
    const double s = std::max(seed, o.seedTail * q);
    const double g = o.growTail > 0.0 ? std::max(grow, o.growTail * q) : grow * s / seed;
    return {s, std::min(g, s)};
}

}  // namespace sl::defectmap
