#include "objective/ImageSpace.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "core/Error.h"
#include "scene/Scene.h"

namespace sl {

size_t PrimaryHits::hitCount() const {
    return static_cast<size_t>(
        std::count_if(sample.begin(), sample.end(), [](int64_t s) { return s >= 0; }));
}

PrimaryHits tracePrimaryHits(const Scene& scene, int threads) {
    const Camera& cam = scene.camera;
    const Heightfield& surf = *scene.surface;
    surf.ensureBuilt();
    PrimaryHits r;
    r.width = cam.width();
    r.height = cam.height();
    r.mapWidth = surf.width();
    r.mapHeight = surf.height();
    r.sample.assign(static_cast<size_t>(r.width) * r.height, -1);
    const double p = surf.pitch();
    const double ci = 0.5 * (r.mapWidth - 1), cj = 0.5 * (r.mapHeight - 1);
    auto body = [&](int y) {
        for (int x = 0; x < r.width; ++x) {
            Ray ray = cam.generateRay(x + 0.5, y + 0.5);
            SurfaceHit hit;
            if (!surf.intersect(ray, 0.0f, hit)) continue;
            auto i = static_cast<int64_t>(std::lround(hit.position.x / p + ci));
            auto j = static_cast<int64_t>(std::lround(hit.position.z / p + cj));
            i = std::clamp<int64_t>(i, 0, r.mapWidth - 1);
            j = std::clamp<int64_t>(j, 0, r.mapHeight - 1);
            r.sample[static_cast<size_t>(y) * r.width + x] = j * r.mapWidth + i;
        }
    };
    tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
    arena.execute([&] { tbb::parallel_for(0, r.height, body); });
    return r;
}

std::vector<uint8_t> projectToImage(const PrimaryHits& hits, std::span<const uint8_t> mapMask) {
    std::vector<uint8_t> out = projectLabelsToImage(hits, mapMask);
    for (uint8_t& v : out) v = v != 0 ? 255 : 0;
    return out;
}

std::vector<uint8_t> projectLabelsToImage(const PrimaryHits& hits,
                                          std::span<const uint8_t> mapLabels) {
    const size_t n = static_cast<size_t>(hits.mapWidth) * hits.mapHeight;
    if (mapLabels.size() != n)
        throw inputError("height-map mask",
                         "has " + std::to_string(mapLabels.size()) + " samples, the height map " +
                             std::to_string(hits.mapWidth) + "x" + std::to_string(hits.mapHeight),
                         "Give a mask of the height map's size (as gen-surface's -truth.png)");
    std::vector<uint8_t> out(hits.sample.size(), 0);
    for (size_t k = 0; k < out.size(); ++k) {
        int64_t s = hits.sample[k];
        if (s >= 0) out[k] = mapLabels[static_cast<size_t>(s)];
    }
    return out;
}

std::vector<uint8_t> scratchMaskImage(const Scene& scene, const ScratchMapOptions& options,
                                      int threads) {
    ScratchMap m = computeScratchMap(scene.heights, scene.mapWidth, scene.mapHeight, options);
    return projectToImage(tracePrimaryHits(scene, threads), m.map);
}

}  // namespace sl
