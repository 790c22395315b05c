#include "render/PathTracer.h"

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <tuple>

#include "core/Interrupt.h"
#include "core/Rng.h"
#include "core/Stopwatch.h"
#include "render/Footprint.h"
#include "render/Sobol.h"
#include "scene/EnvSampler.h"
#include "scene/Scene.h"

namespace sl {

std::pair<int, int> strataFor(int spp) {
    int nx = static_cast<int>(std::sqrt(static_cast<double>(spp)));
    while (nx > 1 && spp % nx != 0) --nx;
    return {nx, spp / nx};
}

std::pair<double, double> sampleOffset(int s, int spp, int sampleSets, double u1, double u2) {
    const int perSet = spp / sampleSets;
    const auto [nx, ny] = strataFor(perSet);
    return stratumOffset(s % perSet, nx, ny, u1, u2);
}

namespace {

struct Counters {
    uint64_t rays = 0, camera = 0, escaped = 0, shadow = 0;
};

constexpr float kBelowOne = 0x1.fffffep-1f;          // the largest float < 1
constexpr double kBelowOneD = 0x1.fffffffffffffp-1;  // the largest double < 1

/// Stratified sampling's permutations (see trace()): for each bounce from 2 on and each set, a
/// Fisher-Yates shuffle of the set's strata drawn from the pixel's own stream
/// sampleRng(seed, pixel, ~(bounce·2 + set)) (sample indices never come near those).
void permuteStrata(uint64_t seed, uint32_t pixel, int spp, int sampleSets, int bounces,
                   std::vector<int>& strata) {
    const int perSet = spp / sampleSets;
    for (int d = 2; d < bounces; ++d) {  // bounces 0 and 1 take Sobol' points
        for (int set = 0; set < sampleSets; ++set) {
            Pcg32 rng = sampleRng(seed, pixel, ~static_cast<uint64_t>(d * 2 + set));
            int* p =
                strata.data() + static_cast<size_t>(d) * spp + static_cast<size_t>(set) * perSet;
            for (int i = 0; i < perSet; ++i) p[i] = i;
            for (int i = perSet - 1; i > 0; --i)
                std::swap(p[i], p[std::min(i, static_cast<int>(rng.nextDouble() * (i + 1)))]);
        }
    }
}

/// Mitsuba's power heuristic (its mis_weight), 0 when both densities are 0.
inline float powerHeuristic(float pdfA, float pdfB) {
    const float a = pdfA * pdfA, b = pdfB * pdfB;
    return a + b > 0.0f ? a / (a + b) : 0.0f;
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
    surf.ensureBuilt();
    const ConductorBsdf& bsdf = scene_.bsdf;
    const int W = cam.width(), H = cam.height(), baseSpp = opt.spp;
    const bool mis = opt.sampling == Sampling::Mis;
    const bool stratified = opt.sampling == Sampling::Stratified;
    if (!opt.sppScale.empty() && opt.sppScale.size() != static_cast<size_t>(W) * H)
        throw std::invalid_argument("PathTracer: the spp multipliers do not match the image");
    int maxScale = 1;
    for (uint8_t f : opt.sppScale) maxScale = std::max(maxScale, static_cast<int>(f));
    if (maxScale > kMaxSppScale)
        throw std::invalid_argument("PathTracer: an spp multiplier is above kMaxSppScale");
    // A pixel's sampling constants, per multiplier (index: the multiplier).
    struct PixelSampling {
        int spp = 0, perSet = 0, strataX = 1, strataY = 1;
        float invSpp = 0, strataXf = 1, strataYf = 1;
    };
    std::vector<PixelSampling> samplings(static_cast<size_t>(maxScale) + 1);
    for (int f = 1; f <= maxScale; ++f) {
        PixelSampling& ps = samplings[static_cast<size_t>(f)];
        ps.spp = baseSpp * f;
        ps.perSet = ps.spp / opt.sampleSets;
        ps.invSpp = 1.0f / static_cast<float>(ps.spp);
        const auto [nx, ny] = strataFor(ps.perSet);
        ps.strataX = nx;
        ps.strataY = ny;
        ps.strataXf = static_cast<float>(nx);
        ps.strataYf = static_cast<float>(ny);
    }
    const int bounces = std::max(0, opt.maxDepth - 1);  // vertices that sample a direction
    std::optional<EnvSampler> emitter;
    if (mis) emitter.emplace(scene_.basis, opt.guide);

    TraceSummary sum;
    sum.width = W;
    sum.height = H;
    sum.spp = baseSpp;
    sum.objectMask.assign(static_cast<size_t>(W) * H, 0);
    sum.coverage.assign(static_cast<size_t>(W) * H, 0.0f);

    tbb::combinable<Counters> counters;
    std::atomic<int> rowsDone{0};
    std::mutex progressMutex;
    const Stopwatch clock;

    // Stratified: per pixel and sample set, the random digital shifts (XOR masks) of the six
    // Sobol' dimensions (camera x, y; the BSDF's two numbers at bounces 0 and 1).
    using Shifts = std::array<std::array<uint32_t, 6>, 2>;
    auto shiftsFor = [&](uint32_t pixel) {
        Shifts sh{};
        for (int set = 0; set < opt.sampleSets; ++set) {
            Pcg32 r =
                sampleRng(opt.seed, pixel, ~((uint64_t{1} << 32) + static_cast<uint64_t>(set)));
            for (uint32_t& m : sh[static_cast<size_t>(set)]) m = r.nextU32();
        }
        return sh;
    };

    // Rows are traced in order, each thread a run of neighbouring rows, so consecutive rays
    // meet the same part of Embree's tree and the sink's rows are neighbours in memory (a
    // stride order that mixed far rows cost ~4 % of the footprint's rays/s, docs/BENCHMARKS.md).
    // The progress counts the rows' samples, not the rows: rows that miss the part cost
    // nothing, so the fraction done grows linearly in time and the ETA holds. Each pixel's
    // samples depend only on (seed, pixel, sample), so the order changes no result.
    const int rowBegin = opt.rowBegin, rowEnd = opt.rowEnd > 0 ? opt.rowEnd : H;
    if (rowBegin < 0 || rowEnd > H || rowBegin >= rowEnd)
        throw std::invalid_argument("PathTracer: the row range is not within the image");
    if (!opt.pixels.empty() && opt.pixels.size() != static_cast<size_t>(W) * H)
        throw std::invalid_argument("PathTracer: the pixel flags do not match the image");
    const std::vector<PixelSpan> spans =
        opt.cullBackground ? partFootprint(scene_) : std::vector<PixelSpan>(H, PixelSpan{0, W});
    const int traced = rowEnd - rowBegin;
    std::vector<uint64_t> rowSamples(static_cast<size_t>(traced), 0);
    uint64_t totalSamples = 0;
    if (opt.progress) {
        for (int y = rowBegin; y < rowEnd; ++y) {
            const PixelSpan span = spans[static_cast<size_t>(y)];
            uint64_t n = 0;
            for (int x = span.begin; x < span.end; ++x) {
                const size_t pixel = static_cast<size_t>(y) * W + x;
                if (!opt.pixels.empty() && opt.pixels[pixel] == 0) continue;
                n += opt.sppScale.empty() ? 1 : std::max<uint64_t>(1, opt.sppScale[pixel]);
            }
            rowSamples[static_cast<size_t>(y - rowBegin)] = n;
            totalSamples += n;
        }
    }
    std::atomic<uint64_t> samplesDone{0};
    auto body = [&](const tbb::blocked_range<int>& rows) {
        std::vector<EscapedPath> paths;
        paths.reserve(static_cast<size_t>(baseSpp));
        // Stratified: strata[depth·spp + s] is the stratum of sample s's 2D BSDF numbers at that
        // bounce; per set, a uniformly random permutation of its perSet strata.
        std::vector<int> strata(stratified ? static_cast<size_t>(bounces) * baseSpp * maxScale : 0);
        Counters& c = counters.local();
        for (int k = rows.begin(); k < rows.end(); ++k) {
            const int y = rowBegin + k;
            const PixelSpan span = spans[static_cast<size_t>(y)];
            for (int x = span.begin; x < span.end; ++x) {
                // Ctrl-C: stop here, keep nothing. Per pixel, not per row: a row at the judge's
                // spp can take minutes (one relaxed atomic load per pixel).
                if (opt.interruptible) throwIfInterrupted();
                const uint32_t pixel = static_cast<uint32_t>(y * W + x);
                if (!opt.pixels.empty() && opt.pixels[pixel] == 0) continue;
                const PixelSampling& ps =
                    samplings[opt.sppScale.empty() ? 1 : std::max<size_t>(1, opt.sppScale[pixel])];
                const int spp = ps.spp, perSet = ps.perSet, strataX = ps.strataX,
                          strataY = ps.strataY;
                const float invSpp = ps.invSpp, strataXf = ps.strataXf, strataYf = ps.strataYf;
                paths.clear();
                uint32_t hits = 0;
                Shifts shifts{};
                if (stratified) {
                    permuteStrata(opt.seed, pixel, spp, opt.sampleSets, bounces, strata);
                    shifts = shiftsFor(pixel);
                }
                for (int s = 0; s < spp; ++s) {
                    Pcg32 rng = sampleRng(opt.seed, pixel, static_cast<uint64_t>(s));
                    const double u1 = rng.nextDouble(), u2 = rng.nextDouble();
                    const auto set = static_cast<uint32_t>(s / perSet);
                    const auto kInSet = static_cast<uint32_t>(s % perSet);
                    const auto& shift = shifts[set];
                    double ox, oy;
                    if (stratified) {  // Sobol' point kInSet, shifted, jittered below 2^-32
                        ox = std::min(
                            (static_cast<double>(sobol(kInSet, 0) ^ shift[0]) + u1) * 0x1p-32,
                            kBelowOneD);
                        oy = std::min(
                            (static_cast<double>(sobol(kInSet, 1) ^ shift[1]) + u2) * 0x1p-32,
                            kBelowOneD);
                    } else {
                        std::tie(ox, oy) =
                            stratumOffset(static_cast<int>(kInSet), strataX, strataY, u1, u2);
                    }
                    Ray ray = cam.generateRay(x + ox, y + oy);
                    Rgb throughput{1.0f};
                    float bsdfPdf = 0.0f;   // density of the last BSDF direction (mis)
                    bool bsdfDelta = true;  // ... or a Dirac lobe (no emitter sampling there)
                    ++c.camera;
                    for (int depth = 0;; ++depth) {
                        SurfaceHit hit;
                        ++c.rays;
                        if (!surf.intersect(ray, 0.0f, hit)) {
                            if (depth > 0) {
                                float w = 1.0f;
                                if (mis && !bsdfDelta)
                                    w = powerHeuristic(bsdfPdf, emitter->pdf(ray.direction));
                                if (w > 0.0f)
                                    paths.push_back(
                                        {throughput * (w * invSpp), ray.direction, set});
                            }
                            break;
                        }
                        if (depth == 0) ++hits;
                        if (depth + 1 >= opt.maxDepth) break;
                        Frame frame = shadingFrame(hit.normal);
                        Vec3f wi = frame.toLocal(-ray.direction);
                        const float b1 = rng.nextFloat();
                        float b2 = rng.nextFloat(), b3 = rng.nextFloat();
                        if (stratified && depth < 2) {
                            const int dim = 2 + 2 * depth;
                            b2 = static_cast<float>((sobol(kInSet, dim) ^ shift[dim]) >> 8) *
                                 0x1p-24f;
                            b3 =
                                static_cast<float>((sobol(kInSet, dim + 1) ^ shift[dim + 1]) >> 8) *
                                0x1p-24f;
                        } else if (stratified) {
                            const int st = strata[static_cast<size_t>(depth) * spp + s];
                            b2 = std::min((static_cast<float>(st % strataX) + b2) / strataXf,
                                          kBelowOne);
                            b3 = std::min((static_cast<float>(st / strataX) + b3) / strataYf,
                                          kBelowOne);
                        }
                        const Vec3f origin = offsetRayOrigin(hit.position, hit.normal);
                        if (mis && !bsdf.params().smooth) {
                            // Emitter sampling: see CONVENTION (direction sampling), (a).
                            const float e1 = rng.nextFloat(), e2 = rng.nextFloat();
                            const EnvSampler::Sample es = emitter->sample(e1, e2);
                            const Vec3f wo = frame.toLocal(es.direction);
                            if (es.pdf > 0.0f && wo.z > 0.0f) {
                                const Rgb f = bsdf.eval(wi, wo);
                                if (maxComponent(f) > 0.0f) {
                                    ++c.shadow;
                                    if (!surf.occluded(Ray{origin, es.direction}, 0.0f)) {
                                        const float w = powerHeuristic(es.pdf, bsdf.pdf(wi, wo));
                                        paths.push_back({throughput * f * (w / es.pdf * invSpp),
                                                         es.direction, set});
                                    }
                                }
                            }
                        }
                        BsdfSample bs = bsdf.sample(wi, b1, b2, b3);
                        if (!bs.valid) break;
                        throughput *= bs.weight;
                        if (maxComponent(throughput) <= 0.0f) break;
                        bsdfPdf = bs.pdf;
                        bsdfDelta = bs.delta;
                        ray.origin = origin;
                        ray.direction = normalize(frame.toWorld(bs.wo));
                    }
                }
                c.escaped += paths.size();
                sum.coverage[pixel] = static_cast<float>(hits) * invSpp;
                sum.objectMask[pixel] = hits == static_cast<uint32_t>(spp) ? 1 : 0;
                sink.consume(PixelPaths{pixel, hits, paths});
            }
            const int done = ++rowsDone;
            const uint64_t samples = samplesDone += rowSamples[static_cast<size_t>(k)];
            if (opt.progress) {
                std::unique_lock lock(progressMutex, std::try_to_lock);
                if (lock.owns_lock() || done == traced)
                    opt.progress(done == traced || totalSamples == 0
                                     ? static_cast<double>(done) / traced
                                     : static_cast<double>(samples) /
                                           static_cast<double>(totalSamples));
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
        sum.shadowRays += c.shadow;
    });
    return sum;
}

}  // namespace sl
