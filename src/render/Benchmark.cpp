#include "render/Benchmark.h"

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "core/Rng.h"
#include "core/Stopwatch.h"
#include "render/Footprint.h"
#include "render/Render.h"
#include "scene/EnvMapPresets.h"
#include "scene/Scene.h"

namespace sl {

ThroughputRow benchRenderer(const Scene& scene, const RenderOptions& options) {
    EnvMap env = studioEnvMap(scene.basis.width(), scene.basis.height());
    RenderResult r = render(scene, env, options);
    return {"renderer (path tracer + radiance sink)", r.summary.rays, r.summary.seconds};
}

ThroughputRow benchBareEmbree(const Scene& scene, const RenderOptions& opt) {
    const Camera& cam = scene.camera;
    const int W = cam.width(), H = cam.height(), spp = opt.spp;
    RTCScene rs = scene.surface->rtcScene();
    const std::vector<PixelSpan> spans =
        opt.cullBackground ? partFootprint(scene) : std::vector<PixelSpan>(H, PixelSpan{0, W});
    tbb::combinable<uint64_t> rays;
    const Stopwatch clock;
    auto body = [&](const tbb::blocked_range<int>& rowsRange) {
        uint64_t& count = rays.local();
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        for (int y = rowsRange.begin(); y < rowsRange.end(); ++y) {
            const PixelSpan span = spans[static_cast<size_t>(y)];
            for (int x = span.begin; x < span.end; ++x) {
                const auto pixel = static_cast<uint64_t>(y) * W + x;
                for (int s = 0; s < spp; ++s) {
                    Pcg32 rng = sampleRng(opt.seed, pixel, static_cast<uint64_t>(s));
                    const double u1 = rng.nextDouble(), u2 = rng.nextDouble();
                    const auto [ox, oy] = sampleOffset(s, spp, 1, u1, u2);
                    Ray ray = cam.generateRay(x + ox, y + oy);
                    for (int depth = 0; depth < opt.maxDepth; ++depth) {
                        RTCRayHit rh = makeRayHit(ray, 0.0f);
                        rtcIntersect1(rs, &ctx, &rh);
                        ++count;
                        if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID || depth + 1 >= opt.maxDepth)
                            break;
                        Vec3f n = normalize(Vec3f{rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z});
                        if (n.y < 0) n = -n;
                        Vec3f p = ray.origin + ray.direction * rh.ray.tfar;
                        ray.direction = ray.direction - n * (2.0f * dot(ray.direction, n));
                        ray.origin = offsetRayOrigin(p, n);
                    }
                }
            }
        }
    };
    tbb::task_arena arena(opt.threads > 0 ? opt.threads : tbb::task_arena::automatic);
    arena.execute([&] { tbb::parallel_for(tbb::blocked_range<int>(0, H, 1), body); });
    double secs = clock.seconds();
    return {"bare Embree rtcIntersect1 (camera + mirror bounces)", rays.combine(std::plus<>()),
            secs};
}

}  // namespace sl
