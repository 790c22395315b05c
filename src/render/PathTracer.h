// PathTracer: camera rays with a box pixel filter and stratified jitter, Embree closest hits,
// BSDF sampling (and, with Sampling::Mis, env-map sampling) at each conductor interaction, and
// escaped paths handed to a PathSink.
//
// CONVENTION (path length): `maxDepth` as in Mitsuba 3's `path` integrator: 1 = only what the
// camera sees directly (the env map is hidden, so nothing), 2 = one reflection, 3 = up to two.
// Pixels whose camera ray misses the part are background: 0, as Mitsuba's hide_emitters.
// No Russian roulette (Mitsuba's starts at depth 5; scenes here stay below).
// CONVENTION (seeding): sample s of pixel p draws everything from sampleRng(seed, p, s)
// (core/Rng.h), so the result does not depend on the number of threads. Per vertex it draws the
// BSDF's three numbers, then (Sampling::Mis only) the emitter's two, so `bsdf` traces exactly as
// before the other samplers existed.
//
// CONVENTION (direction sampling; RenderOptions::sampling, the rows of scene/RenderDesc.h).
// The env map's radiance is L(ω) = Σ_t E_t b_t(ω), b_t the bilinear weight of texel t
// (EnvMapBasis::weights). At a vertex with throughput β and view direction wi, the reflected
// direct light is ∫ f(wi,ω) cos θ_ω V(ω) L(ω) dω (V: 1 if the ray toward ω leaves the height
// field), so every sink needs, per texel t, an unbiased estimate of β ∫ f cos V b_t dω; a sink
// only ever receives EscapedPaths (weight a, direction ω) and adds a·b_t(ω) to texel t (times
// E_t for an image), which keeps T·E == render(E) exact for one sample set.
//   bsdf: ω_B ~ p_B (the BSDF's sample()), β ← β f cos / p_B; a ray that escapes yields
//         (β, ω_B).
//   stratified: as bsdf, but the pixel's samples are spread jointly over the camera offset and
//         the first two bounces: sample k of a sample set takes point k of the 6-dimensional
//         Sobol' sequence (render/Sobol.h; dims 0-1 the film offset, jittered below 2^-32;
//         dims 2-3 and 4-5 the BSDF's 2D numbers at bounces 0 and 1, on nextFloat's 2^-24
//         grid), XOR-ed with six random 32-bit masks per pixel and set drawn from
//         sampleRng(seed, pixel, ~(2^32 + set)) (a random digital shift); deeper bounces jitter
//         within stratum π_d(k) of strataFor's grid, π_d a random permutation per pixel, set
//         and bounce from sampleRng(seed, pixel, ~(2d + set)). A uniform mask makes each
//         shifted point uniform on the grid, and the permutation makes π_d(k) uniform over the
//         strata, both independent of sample k's own stream, so every sample keeps exactly
//         bsdf's distribution (unbiased, each set on its own) while the pixel's samples form a
//         digital net; T·E == render(E) holds as for every sampler (one set of samples, any sink).
//   mis:  at each vertex whose BSDF is not a Dirac lobe and which may still scatter
//         (depth + 1 < maxDepth, Mitsuba's emitter-sampling condition), also
//         (a) ω_L ~ p_L (scene/EnvSampler.h, a proper solid-angle density); if f cos(ω_L) > 0 and
//             Embree's occlusion query finds nothing along ω_L: yields (β f cos w_L / p_L, ω_L);
//         (b) the BSDF ray as above, but its escape yields (β w_B, ω_B);
//         with the power heuristic w_L = p_L²/(p_L² + p_B²) at ω_L and w_B = p_B²/(p_B² + p_L²)
//         at ω_B (w_B = 1 after a Dirac vertex, where (a) is skipped).
//   Unbiased per texel: E[(a)] + E[direct part of (b)] = ∫ f cos V b_t (w_L·1[p_L>0] +
//   w_B·1[p_B>0]) dω = ∫ f cos V b_t dω, because w_L + w_B = 1 where both densities are
//   positive, w_B = 1 where p_L = 0 and w_L = 1 where p_B = 0 (f cos = 0 where neither is). No
//   weight depends on E, so each column of T is an unbiased estimate of its own texel's
//   integral and T is linear in E; the guide of p_L (RenderOptions::guide) changes only the
//   variance and is part of the sample set (precompute and render must use the same one for
//   T·E == render(E)). Indirect light (a BSDF ray that hits the surface) continues as in bsdf.
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
/// spp and seed would trace differently (2: watertight intersection; 3: the transport sink sums
/// a texel's paths in path order, which changes T in the last bit of some floats).
/// Sampling is recorded beside it in the fingerprint: `bsdf` traces as revision 2 did (but for
/// revision 3's order of sums).
inline constexpr int kTracerRevision = 3;

/// The largest per-pixel sample multiplier (RenderOptions::sppScale).
inline constexpr int kMaxSppScale = 64;

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
    /// The pixels traced: empty, every pixel (of the rows above); otherwise width·height flags,
    /// and pixels flagged 0 are not traced, as rows outside the range (no paths, objectMask 0).
    /// Only what a region needs (a loss mask), or a sparse lattice for a quick measurement.
    std::vector<uint8_t> pixels;
    /// Per-pixel sample multiplier: empty, every pixel takes spp samples; otherwise width·height
    /// factors in [1, kMaxSppScale] (0 reads as 1), and pixel p takes spp·sppScale[p] samples,
    /// in sets of spp·sppScale[p]/sampleSets (each sample still depends only on (seed, pixel,
    /// sample), so shards and threads change nothing). Every pixel stays an unbiased
    /// estimate, so T·E still equals a render; only the noise differs: samples where an
    /// estimator needs them (a small region whose statistic would be noisy), not everywhere.
    std::vector<uint8_t> sppScale;
    /// Skip the pixels outside the part's footprint (render/Footprint.h): they see only the
    /// hidden background, so the image and T are the same; off only to check exactly that.
    bool cullBackground = true;
    Sampling sampling = RenderDesc{}.sampling;  // see CONVENTION (direction sampling) above
    /// Mis only: per-texel guide of the env-map sampling density (scene/EnvSampler.h), e.g. an
    /// E; empty: 1 everywhere (by solid angle).
    std::vector<float> guide;
    std::function<void(double)> progress;  // fraction done, called from any thread, serialised
    /// An interrupt request (core/Interrupt.h) stops the trace at the next pixel by throwing
    /// Interrupted. Off for the renders inside a black-box optimizer step: the optimizer stops
    /// at its next iteration instead, keeping its best iterate.
    bool interruptible = true;
};

struct TraceSummary {
    int width = 0, height = 0, spp = 0;
    uint64_t cameraRays = 0;  // primary rays
    uint64_t rays = 0;        // all closest-hit queries (camera + bounces)
    uint64_t shadowRays = 0;  // occlusion queries (Sampling::Mis)
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

/// Film offset in [0,1)² of the sample in stratum (k mod nx, k div nx) of nx × ny, jittered by
/// two uniform numbers (u1, u2).
inline std::pair<double, double> stratumOffset(int k, int nx, int ny, double u1, double u2) {
    return {(k % nx + u1) / nx, (k / nx + u2) / ny};
}

/// Film offset in [0,1)² of sample s of a pixel: stratum (k mod nx, k div nx) of the sample's
/// set (k = index within the set) jittered by two uniform numbers (u1, u2).
std::pair<double, double> sampleOffset(int s, int spp, int sampleSets, double u1, double u2);

}  // namespace sl
