#include "optimize/SpecularInit.h"

#include <tbb/combinable.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <string>

#include "core/Error.h"
#include "scene/Scene.h"

namespace sl {

std::vector<double> specularInitialEnvMap(const Scene& scene, int maxDepth, bool rgb) {
    if (maxDepth < 2)
        throw inputError(
            option("init") + " specular",
            "max_depth " + std::to_string(maxDepth) + " lets no camera ray reach the env map",
            "Use render.max_depth >= 2 (2 = one reflection)");
    const Camera& cam = scene.camera;
    const Heightfield& surf = *scene.surface;
    surf.ensureBuilt();
    const EnvMapBasis& basis = scene.basis;
    const size_t texels = static_cast<size_t>(basis.texelCount());
    struct Local {
        std::vector<double> hist;
        size_t cameraHits = 0;
    };
    tbb::combinable<Local> locals([&] { return Local{std::vector<double>(texels, 0.0), 0}; });
    // Rows are summed in fixed per-thread order; the values are integers × bilinear weights, so
    // the sum is exact up to rounding far below the histogram's resolution.
    tbb::parallel_for(0, cam.height(), [&](int y) {
        Local& l = locals.local();
        for (int x = 0; x < cam.width(); ++x) {
            Ray ray = cam.generateRay(x + 0.5, y + 0.5);
            for (int depth = 0;; ++depth) {
                SurfaceHit hit;
                if (!surf.intersect(ray, 0.0f, hit)) {
                    if (depth > 0) {
                        TexelWeights w = basis.weights(ray.direction);
                        for (int k = 0; k < 4; ++k) l.hist[w.index[k]] += w.weight[k];
                    }
                    break;
                }
                if (depth == 0) ++l.cameraHits;
                if (depth + 1 >= maxDepth) break;
                const float cosI = -dot(ray.direction, hit.normal);
                if (cosI <= 0.0f) break;
                ray.origin = offsetRayOrigin(hit.position, hit.normal);
                ray.direction = normalize(ray.direction + hit.normal * (2.0f * cosI));
            }
        }
    });
    std::vector<double> hist(texels, 0.0);
    size_t cameraHits = 0;
    locals.combine_each([&](const Local& l) {
        for (size_t t = 0; t < texels; ++t) hist[t] += l.hist[t];
        cameraHits += l.cameraHits;
    });
    const double mx = *std::max_element(hist.begin(), hist.end());
    if (!(mx > 0.0)) {
        if (cameraHits == 0)
            throw inputError(option("init") + " specular",
                             "no camera ray (pixel centre) hits the part",
                             "Check the scene's camera: it must look at the height map");
        throw inputError(option("init") + " specular",
                         "no camera ray escapes after its reflections (" +
                             std::to_string(cameraHits) + " hit the part)",
                         "Raise render.max_depth, or use another " + option("init"));
    }
    std::vector<double> e(texels * (rgb ? 3 : 1));
    for (size_t t = 0; t < texels; ++t) {
        const double v = hist[t] / mx;
        if (rgb)
            e[3 * t] = e[3 * t + 1] = e[3 * t + 2] = v;
        else
            e[t] = v;
    }
    return e;
}

}  // namespace sl
