#include "app/pipeline/AutoDepth.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/Color.h"
#include "render/Render.h"
#include "scene/Scene.h"

namespace sl {

namespace {

std::string percent(double share) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.3g %%", 100.0 * share);
    return buf;
}

}  // namespace

DepthChoice chooseMaxDepth(const std::vector<double>& energy, double threshold) {
    DepthChoice c;
    const int last = static_cast<int>(energy.size()) - 1;
    for (int d = 2; d < last; ++d) {
        const double next = energy[static_cast<size_t>(d) + 1];
        const double added = next > 0 ? (next - energy[static_cast<size_t>(d)]) / next : 0;
        if (added < threshold) {
            c.maxDepth = d;
            c.reason = "bounce " + std::to_string(d) + " (max_depth " + std::to_string(d + 1) +
                       ") would add " + percent(added) + " of the image, less than " +
                       percent(threshold);
            return c;
        }
    }
    c.maxDepth = std::max(2, last);
    c.reason = "every measured bounce adds at least " + percent(threshold) +
               " of the image; the longest measured path length";
    return c;
}

double whiteEnergy(const Scene& scene, RenderOptions ro, int depth, TraceSummary* summary) {
    const EnvMap white = EnvMap::constant(scene.basis.width(), scene.basis.height(), 1.0f);
    ro.maxDepth = depth;
    const RenderResult rr = render(scene, white, ro);
    double e = 0;
    for (size_t p = 0; p < rr.image.pixelCount(); ++p)
        e += luminance<double>(rr.image.data[3 * p], rr.image.data[3 * p + 1],
                               rr.image.data[3 * p + 2]);
    if (summary) *summary = rr.summary;
    return e;
}

std::vector<uint8_t> pixelLattice(int width, int height, int count) {
    const double area = static_cast<double>(width) * height;
    const int k = std::max(1, static_cast<int>(std::sqrt(area / std::max(1, count))));
    std::vector<uint8_t> flags(static_cast<size_t>(width) * height, 0);
    for (int y = k / 2; y < height; y += k)
        for (int x = k / 2; x < width; x += k) flags[static_cast<size_t>(y) * width + x] = 1;
    return flags;
}

DepthChoice autoMaxDepth(const Scene& scene, const AutoDepthOptions& o) {
    RenderOptions ro = renderOptionsFor(scene);
    ro.spp = o.spp;
    ro.threads = o.threads;
    ro.pixels = pixelLattice(scene.camera.width(), scene.camera.height(), o.pixels);
    const auto traced = std::count(ro.pixels.begin(), ro.pixels.end(), 1);
    std::vector<double> energy{0.0};
    double seconds = 0;
    auto withReason = [&](DepthChoice c) {
        char buf[128];
        std::snprintf(buf, sizeof buf,
                      " (measured under a white light at %d spp on %lld pixels in %.2f s)", o.spp,
                      static_cast<long long>(traced), seconds);
        c.reason += buf;
        return c;
    };
    for (int depth = 1; depth <= o.limit; ++depth) {
        TraceSummary s;
        energy.push_back(whiteEnergy(scene, ro, depth, &s));
        seconds += s.seconds;
        if (depth >= 3) {
            DepthChoice c = chooseMaxDepth(energy, o.threshold);
            if (c.maxDepth < depth || depth == o.limit) return withReason(c);
        }
    }
    return withReason(chooseMaxDepth(energy, o.threshold));
}

}  // namespace sl
