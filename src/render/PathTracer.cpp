#include "render/PathTracer.h"

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>
#include <numeric>
#include <stdexcept>

#include "core/Interrupt.h"
#include "core/Rng.h"
#include "core/Stopwatch.h"
#include "scene/Scene.h"

namespace sl {

std::pair<int, int> strataFor(int spp) {
    int nx = static_cast<int>(std::sqrt(static_cast<double>(spp)));
    while (nx > 1 && spp % nx != 0) --nx;
    return {nx, spp / nx};
}

std::pair<double, double> sampleOffset(int s, int spp, int sampleSets, double u1, double u2) {
    const int perSet = spp / sampleSets, k = s % perSet;
    const auto [nx, ny] = strataFor(perSet);
    return {(k % nx + u1) / nx, (k / nx + u2) / ny};
}

namespace {

struct Counters {
    uint64_t rays = 0, camera = 0, escaped = 0;
};

/// The row stride of trace()'s schedule: the integer nearest 0.618·H that is coprime to H.
int rowStride(int H) {
    int s = std::max(1, static_cast<int>(std::lround(0.6180339887 * H)));
    while (std::gcd(s, H) != 1) ++s;
    return s;
}

}  // namespace

TraceSummary PathTracer::trace(const RenderOptions& opt, PathSink& sink) const {
    if (opt.spp < 1) throw std::invalid_argument("render.spp must be >= 1");
    if (opt.maxDepth < 1) throw std::invalid_argument("render.max_depth must be >= 1");
    if (opt.sampleSets != 1 && opt.sampleSets != 2)
        throw std::invalid_argument("RenderOptions::sampleSets must be 1 or 2");
    if (opt.spp % opt.sampleSets != 0)
        throw std::invalid_argument("two sample sets need an even spp");
    const Camera& cam = scene_.camera;
    const Heightfield& surf = *scene_.surface;
    const ConductorBsdf& bsdf = scene_.bsdf;
    const int W = cam.width(), H = cam.height(), spp = opt.spp;
    const int perSet = spp / opt.sampleSets;
    const float invSpp = 1.0f / static_cast<float>(spp);

    TraceSummary sum;
    sum.width = W;
    sum.height = H;
    sum.spp = spp;
    sum.objectMask.assign(static_cast<size_t>(W) * H, 0);
    sum.coverage.assign(static_cast<size_t>(W) * H, 0.0f);

    tbb::combinable<Counters> counters;
    std::atomic<int> rowsDone{0};
    std::mutex progressMutex;
    const Stopwatch clock;

    // Rows are traced in a stride order (row k is y = k·stride mod H, stride coprime to H, near
    // 0.618·H), so every stretch of the schedule mixes rows that see the part with rows that
    // do not: the rows done grow linearly in time and the progress' ETA holds. Each pixel's
    // samples depend only on (seed, pixel, sample), so the order changes no result.
    const int rowBegin = opt.rowBegin, rowEnd = opt.rowEnd > 0 ? opt.rowEnd : H;
    if (rowBegin < 0 || rowEnd > H || rowBegin >= rowEnd)
        throw std::invalid_argument("PathTracer: the row range is not within the image");
    const int traced = rowEnd - rowBegin;
    const int stride = rowStride(traced);
    auto body = [&](const tbb::blocked_range<int>& rows) {
        std::vector<EscapedPath> paths;
        paths.reserve(static_cast<size_t>(spp));
        Counters& c = counters.local();
        for (int k = rows.begin(); k < rows.end(); ++k) {
            const int y = rowBegin + static_cast<int>((static_cast<int64_t>(k) * stride) % traced);
            if (opt.interruptible) throwIfInterrupted();  // Ctrl-C: stop here, keep nothing
            for (int x = 0; x < W; ++x) {
                const uint32_t pixel = static_cast<uint32_t>(y * W + x);
                paths.clear();
                uint32_t hits = 0;
                for (int s = 0; s < spp; ++s) {
                    Pcg32 rng = sampleRng(opt.seed, pixel, static_cast<uint64_t>(s));
                    const double u1 = rng.nextDouble(), u2 = rng.nextDouble();
                    const auto [ox, oy] = sampleOffset(s, spp, opt.sampleSets, u1, u2);
                    Ray ray = cam.generateRay(x + ox, y + oy);
                    const auto set = static_cast<uint32_t>(s / perSet);
                    Rgb throughput{1.0f};
                    ++c.camera;
                    for (int depth = 0;; ++depth) {
                        SurfaceHit hit;
                        ++c.rays;
                        if (!surf.intersect(ray, 0.0f, hit)) {
                            if (depth > 0)
                                paths.push_back({throughput * invSpp, ray.direction, set});
                            break;
                        }
                        if (depth == 0) ++hits;
                        if (depth + 1 >= opt.maxDepth) break;
                        Frame frame = shadingFrame(hit.normal);
                        Vec3f wi = frame.toLocal(-ray.direction);
                        const float b1 = rng.nextFloat(), b2 = rng.nextFloat(),
                                    b3 = rng.nextFloat();
                        BsdfSample bs = bsdf.sample(wi, b1, b2, b3);
                        if (!bs.valid) break;
                        throughput *= bs.weight;
                        if (maxComponent(throughput) <= 0.0f) break;
                        ray.origin = offsetRayOrigin(hit.position, hit.normal);
                        ray.direction = normalize(frame.toWorld(bs.wo));
                    }
                }
                c.escaped += paths.size();
                sum.coverage[pixel] = static_cast<float>(hits) * invSpp;
                sum.objectMask[pixel] = hits == static_cast<uint32_t>(spp) ? 1 : 0;
                sink.consume(PixelPaths{pixel, hits, paths});
            }
            int done = ++rowsDone;
            if (opt.progress) {
                std::unique_lock lock(progressMutex, std::try_to_lock);
                if (lock.owns_lock() || done == traced)
                    opt.progress(static_cast<double>(done) / traced);
            }
        }
    };

    int threads = opt.threads > 0 ? opt.threads : tbb::task_arena::automatic;
    tbb::task_arena arena(threads);
    arena.execute([&] { tbb::parallel_for(tbb::blocked_range<int>(0, traced, 1), body); });

    sum.seconds = clock.seconds();
    counters.combine_each([&](const Counters& c) {
        sum.rays += c.rays;
        sum.cameraRays += c.camera;
        sum.escapedPaths += c.escaped;
    });
    return sum;
}

}  // namespace sl
