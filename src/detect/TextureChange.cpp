#include "detect/TextureChange.h"

#include <algorithm>
#include <cmath>

#include "detect/Hysteresis.h"
#include "detect/ImageFilters.h"

namespace sl::defectmap {

size_t markTextureChange(std::vector<float>& v, int W, int H, const DefectMapOptions& o,
                         double floorSigma, double ratio, bool lineExcess,
                         std::vector<uint8_t>& map) {
    const size_t n = static_cast<size_t>(W) * H;
    // the distance of a sample to the map's nearest edge (its layer of the border)
    auto layer = [&](int x, int y) {
        return std::min(std::min(x, W - 1 - x), std::min(y, H - 1 - y));
    };
    size_t marked = 0;
    for (float& x : v) x = std::abs(x);
    // on the 2×2-pooled values (window halved): a quarter of the work
    int W2 = 0, H2 = 0;
    const std::vector<float> pooled = pool2(v.data(), W, H, W2, H2);
    v = {};
    const std::vector<float> E2 =
        separableMedian(pooled, W2, H2, std::max(3, (o.energyWindow / 2) | 1));
    const double medE = std::max(medianAbs(E2), floorSigma);
    if (!(medE > 0.0)) return 0;
    double base = ratio * medE;  // the threshold on E
    if (o.seedTail > 0.0) {
        // step 7b on E: a texture whose own local amplitude varies much (clusters of a heavy-
        // tailed texture's deepest marks) raises the threshold to seedTail × E's tail, taken
        // per tile (tailQuantile) on the pooled map, its border halved as the map is
        base = std::max(base, o.seedTail * tailQuantile(E2, W2, H2, (o.border + 1) / 2, o));
    }
    auto energy = [&](int x, int y) { return E2[static_cast<size_t>(y / 2) * W2 + x / 2]; };
    const bool grow = o.energyGrowBorder && o.border > 0;
    std::vector<uint8_t> own(n, 0);  // this test's marks
    for (size_t k = 0; k < n; ++k) {
        const int x = static_cast<int>(k % static_cast<size_t>(W));
        const int y = static_cast<int>(k / static_cast<size_t>(W));
        if (layer(x, y) >= o.border && energy(x, y) >= base) own[k] = 1;
    }
    if (grow) {
        std::vector<double> rowExcess(H2, 0.0), colExcess(W2, 0.0);
        if (lineExcess) {
            std::vector<float> line;
            for (int py = 0; py < H2; ++py)
                if (2 * py < o.border || 2 * py + 1 >= H - o.border) {
                    line.assign(E2.begin() + static_cast<size_t>(py) * W2,
                                E2.begin() + static_cast<size_t>(py + 1) * W2);
                    rowExcess[py] = std::max(0.0, medianAbs(line) - medE);
                }
            line.resize(H2);
            for (int px = 0; px < W2; ++px)
                if (2 * px < o.border || 2 * px + 1 >= W - o.border) {
                    for (int py = 0; py < H2; ++py)
                        line[py] = E2[static_cast<size_t>(py) * W2 + px];
                    colExcess[px] = std::max(0.0, medianAbs(line) - medE);
                }
        }
        // grow outward, layer by layer: a sample at distance j from the edge joins when
        // its E passes and an 8-neighbour at distance j + 1 is marked by this test
        auto visit = [&](int x, int y, int j) {
            const size_t k = static_cast<size_t>(y) * W + x;
            double excess = 0.0;
            if (y < o.border || y >= H - o.border) excess = rowExcess[y / 2];
            if (x < o.border || x >= W - o.border) excess = std::max(excess, colExcess[x / 2]);
            const double threshold = base + excess;
            if (own[k] || energy(x, y) < threshold) return;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int xx = x + dx, yy = y + dy;
                    if (xx < 0 || yy < 0 || xx >= W || yy >= H || layer(xx, yy) != j + 1 ||
                        !own[static_cast<size_t>(yy) * W + xx])
                        continue;
                    own[k] = 1;
                    return;
                }
        };
        for (int j = o.border - 1; j >= 0; --j) {
            if (2 * j + 1 >= W || 2 * j + 1 >= H) continue;  // no sample at distance j
            for (int x = j; x < W - j; ++x) {
                visit(x, j, j);
                visit(x, H - 1 - j, j);
            }
            for (int y = j + 1; y < H - 1 - j; ++y) {
                visit(j, y, j);
                visit(W - 1 - j, y, j);
            }
        }
    }
    for (size_t k = 0; k < n; ++k)
        if (own[k]) {
            if (!map[k]) ++marked;
            map[k] = 255;
        }
    return marked;
}

}  // namespace sl::defectmap
