// PathTracer: camera rays with a box pixel filter and stratified jitter, Embree closest hits,
// BSDF sampling at each conductor interaction, and escaped paths handed to a PathSink.
//
// CONVENTION (path length): `maxDepth` as in Mitsuba 3's `path` integrator: 1 = only what the
// camera sees directly (the env map is hidden, so nothing), 2 = one reflection, 3 = up to two.
// Pixels whose camera ray misses the part are background: 0, as Mitsuba's hide_emitters.
// No Russian roulette (Mitsuba's starts at depth 5; scenes here stay below).
// CONVENTION (seeding): sample s of pixel p draws everything from sampleRng(seed, p, s)
// (core/Rng.h), so the result does not depend on the number of threads.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "render/PathSink.h"
#include "scene/RenderDesc.h"

namespace sl {

struct Scene;

/// Revision of what the tracer computes for given inputs. Transport-matrix fingerprints include
/// it, so cached matrices from an older tracer are recomputed. Bump it whenever the same scene,
/// spp and seed would trace differently (2: watertight intersection).
inline constexpr int kTracerRevision = 2;

struct RenderOptions {
    // Defaults: the scene file's render section (scene/RenderDesc.h), defined there once.
    int spp = RenderDesc{}.spp;
    int maxDepth = RenderDesc{}.maxDepth;
    uint64_t seed = RenderDesc{}.seed;
    int threads = 0;  // 0: all cores
    /// 1, or 2: the spp samples form two independent sample sets of spp/2 (samples
    /// [0, spp/2) and [spp/2, spp)), each stratified over the whole pixel on its own, so that
    /// either half alone is an unbiased estimate (used for the noise-unbiased objective).
    int sampleSets = 1;
    /// The image rows traced: [rowBegin, rowEnd) (rowEnd 0: to the last row). Rows outside are
    /// not traced (no paths, objectMask 0): a shard of T (`precompute --rows`). Each pixel's
    /// samples depend only on (seed, pixel, sample), so shards put together are the whole trace.
    int rowBegin = 0, rowEnd = 0;
    std::function<void(double)> progress;  // fraction done, called from any thread, serialised
    /// An interrupt request (core/Interrupt.h) stops the trace at the next row by throwing
    /// Interrupted. Off for the renders inside a black-box optimizer step: the optimizer stops
    /// at its next iteration instead, keeping its best iterate.
    bool interruptible = true;
};

struct TraceSummary {
    int width = 0, height = 0, spp = 0;
    uint64_t cameraRays = 0;  // primary rays
    uint64_t rays = 0;        // all closest-hit queries (camera + bounces)
    uint64_t escapedPaths = 0;
    double seconds = 0;
    std::vector<uint8_t> objectMask;  // 1 where every camera sample of the pixel hit the part
    std::vector<float> coverage;      // fraction of camera samples that hit the part

    double raysPerSecond() const { return seconds > 0 ? static_cast<double>(rays) / seconds : 0; }
};

class PathTracer {
  public:
    explicit PathTracer(const Scene& scene) : scene_(scene) {}
    TraceSummary trace(const RenderOptions& options, PathSink& sink) const;

  private:
    const Scene& scene_;
};

/// Stratification of spp camera samples: nx × ny strata with nx the largest divisor <= sqrt(spp).
std::pair<int, int> strataFor(int spp);

/// Film offset in [0,1)² of sample s of a pixel: stratum (k mod nx, k div nx) of the sample's
/// set (k = index within the set) jittered by two uniform numbers (u1, u2).
std::pair<double, double> sampleOffset(int s, int spp, int sampleSets, double u1, double u2);

}  // namespace sl
