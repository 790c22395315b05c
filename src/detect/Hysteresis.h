// The defect map's regions and thresholds (detect/DefectMap.h, method auto, steps 6 and 7b):
// connected regions grown from seeds, hysteresis on a score, thresholds raised to the texture's
// own tail.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "detect/DefectMap.h"

namespace sl::defectmap {

/// The connected regions of a W×H map: each starts at a sample `seed` accepts (in row-major
/// order) and takes every sample `grow` accepts within `reach` samples (a (2·reach+1)² box) of
/// one it holds; `region` gets each one's samples in the order they were reached. A sample
/// belongs to one region at most.
template <class Seed, class Grow, class Region>
void forEachRegion(int W, int H, int reach, Seed seed, Grow grow, Region region) {
    const size_t n = static_cast<size_t>(W) * H;
    std::vector<uint8_t> seen(n, 0);
    std::vector<size_t> stack, samples;
    for (size_t k0 = 0; k0 < n; ++k0) {
        if (seen[k0] || !seed(k0)) continue;
        samples.clear();
        stack.assign(1, k0);
        seen[k0] = 1;
        while (!stack.empty()) {
            const size_t k = stack.back();
            stack.pop_back();
            samples.push_back(k);
            const int x = static_cast<int>(k % static_cast<size_t>(W));
            const int y = static_cast<int>(k / static_cast<size_t>(W));
            for (int dy = -reach; dy <= reach; ++dy)
                for (int dx = -reach; dx <= reach; ++dx) {
                    const int xx = x + dx, yy = y + dy;
                    if (xx < 0 || yy < 0 || xx >= W || yy >= H) continue;
                    const size_t q = static_cast<size_t>(yy) * W + xx;
                    if (seen[q] || !grow(q)) continue;
                    seen[q] = 1;
                    stack.push_back(q);
                }
        }
        region(samples);
    }
}

/// Step 6: hysteresis on the score, regions below minRegion dropped. Sets map to 255.
size_t hysteresis(const std::vector<float>& score, int W, int H, double seed, double grow,
                  int minRegion, std::vector<uint8_t>& map);

/// Step 7b's q: the samples outside `border` (samples at each edge) cut into seedTailTiles ×
/// seedTailTiles tiles, the seedTailQuantile quantile of `score` in each, and the median of those
/// (the lower middle one of an even count). A texture's tail is everywhere, so every tile has it; a
/// defect, even one that covers more than 1 − seedTailQuantile of the map, is in few tiles and
/// moves the median little. seedTailTiles = 1 is the quantile over the whole map. With `skip`
/// (W×H, nonzero: left out; step 8's wide texture changes), the skipped samples are left out of
/// every tile and a tile with fewer than half of its samples left is left out; no tile left: 0.
double tailQuantile(const std::vector<float>& score, int W, int H, int border,
                    const DefectMapOptions& o, const std::vector<uint8_t>* skip = nullptr);

/// Step 7b: the seed and grow thresholds from the texture's own tail. q = tailQuantile; the seed
/// is max(seed, seedTail·q), the grow threshold max(grow, growTail·q) with growTail > 0, else
/// grow scaled by the seed's factor; never above the seed. `skip` as for tailQuantile.
struct Thresholds {
    double seed, grow;
};

Thresholds tailThresholds(const std::vector<float>& score, int W, int H, const DefectMapOptions& o,
                          double seed, double grow, const std::vector<uint8_t>* skip = nullptr);

}  // namespace sl::defectmap
