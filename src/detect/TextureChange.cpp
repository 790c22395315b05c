#include "detect/TextureChange.h"

#include <algorithm>
#include <cmath>

#include "detect/Hysteresis.h"
#include "detect/ImageFilters.h"

namespace sl::defectmap {

ChangeEnergy changeEnergy(std::vector<float>& v, int W, int H, const DefectMapOptions& o,
                          double floorSigma, double ratio, bool lineExcess) {
    ChangeEnergy e;
    e.lineExcess = lineExcess;
    for (float& x : v) x = std::abs(x);
    // on the 2×2-pooled values (window halved): a quarter of the work
    const std::vector<float> pooled = pool2(v.data(), W, H, e.W2, e.H2);
    v = {};
    e.E = separableMedian(pooled, e.W2, e.H2, std::max(3, (o.energyWindow / 2) | 1));
    e.medE = std::max(medianAbs(e.E), floorSigma);
    if (!(e.medE > 0.0)) return e;
    e.base = ratio * e.medE;
    if (!(o.seedTail > 0.0 && o.seedTailWide > 0.0)) return e;
    // the wide changes: regions of E >= base (outside the halved border) of at least
    // seedTailWide tail tiles' cells (tailQuantile's tiles on the pooled map)
    const int W2 = e.W2, H2 = e.H2, b = (o.border + 1) / 2;
    const int w = W2 - 2 * b, h = H2 - 2 * b;
    if (w <= 0 || h <= 0) return e;
    const int nt = std::max(1, std::min({o.seedTailTiles, w, h}));
    const double tile = (static_cast<double>(w) / nt) * (static_cast<double>(h) / nt);
    const auto inside = [&](size_t k) {
        const int x = static_cast<int>(k % static_cast<size_t>(W2));
        const int y = static_cast<int>(k / static_cast<size_t>(W2));
        return x >= b && y >= b && x < W2 - b && y < H2 - b && e.E[k] >= e.base;
    };
    forEachRegion(W2, H2, 1, inside, inside, [&](const std::vector<size_t>& region) {
        if (static_cast<double>(region.size()) < o.seedTailWide * tile) return;
        if (e.wide.empty()) e.wide.assign(e.E.size(), 0);
        for (size_t k : region) e.wide[k] = 1;
    });
    return e;
}

void wideChanges(const std::vector<ChangeEnergy>& energies, int W, int H,
                 std::vector<uint8_t>& pooled, std::vector<uint8_t>& samples) {
    pooled.clear();
    samples.clear();
    for (const ChangeEnergy& e : energies) {
        if (e.wide.empty()) continue;
        if (pooled.empty()) pooled.assign(e.wide.size(), 0);
        for (size_t k = 0; k < pooled.size(); ++k) pooled[k] |= e.wide[k];
    }
    if (pooled.empty()) return;
    const int W2 = energies.front().W2;
    samples.assign(static_cast<size_t>(W) * H, 0);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x)
            samples[static_cast<size_t>(y) * W + x] =
                pooled[static_cast<size_t>(y / 2) * W2 + x / 2];
}

size_t markTextureChange(const ChangeEnergy& e, const std::vector<uint8_t>& wide, int W, int H,
                         const DefectMapOptions& o, std::vector<uint8_t>& map) {
    const size_t n = static_cast<size_t>(W) * H;
    // the distance of a sample to the map's nearest edge (its layer of the border)
    auto layer = [&](int x, int y) {
        return std::min(std::min(x, W - 1 - x), std::min(y, H - 1 - y));
    };
    size_t marked = 0;
    if (!(e.base > 0.0)) return 0;
    const std::vector<float>& E2 = e.E;
    const int W2 = e.W2, H2 = e.H2;
    const double medE = e.medE;
    double base = e.base;  // the threshold on E
    if (o.seedTail > 0.0) {
        // step 7b on E: a texture whose own local amplitude varies much (clusters of a heavy-
        // tailed texture's deepest marks) raises the threshold to seedTail × E's tail, taken
        // per tile (tailQuantile) on the pooled map, its border halved as the map is, the wide
        // changes left out (they are no texture's tail)
        base = std::max(base, o.seedTail * tailQuantile(E2, W2, H2, (o.border + 1) / 2, o,
                                                        wide.empty() ? nullptr : &wide));
    }
    auto cell = [&](int x, int y) { return static_cast<size_t>(y / 2) * W2 + x / 2; };
    auto energy = [&](int x, int y) { return E2[cell(x, y)]; };
    const bool grow = o.energyGrowBorder && o.border > 0;
    // this test's marks: 1 above the (tail-raised) threshold, 2 on a wide change of its own (at
    // the base threshold; grown into the border at it)
    std::vector<uint8_t> own(n, 0);
    for (size_t k = 0; k < n; ++k) {
        const int x = static_cast<int>(k % static_cast<size_t>(W));
        const int y = static_cast<int>(k / static_cast<size_t>(W));
        if (layer(x, y) < o.border) continue;
        if (energy(x, y) >= base)
            own[k] = 1;
        else if (!e.wide.empty() && e.wide[cell(x, y)])
            own[k] = 2;
    }
    if (grow) {
        std::vector<double> rowExcess(H2, 0.0), colExcess(W2, 0.0);
        if (e.lineExcess) {
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
            if (own[k]) return;
            const double E = energy(x, y);
            if (E < e.base + excess) return;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int xx = x + dx, yy = y + dy;
                    if (xx < 0 || yy < 0 || xx >= W || yy >= H || layer(xx, yy) != j + 1) continue;
                    const uint8_t from = own[static_cast<size_t>(yy) * W + xx];
                    if (!from || E < (from == 2 ? e.base : base) + excess) continue;
                    own[k] = from;
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
