// `scratchlight bench sampling`: noise per ray of the path tracer's direction sampling
// (render/PathTracer.h, CONVENTION (direction sampling)). For each part (the scene as given, and
// the same scene with other roughnesses, e.g. a mirror-like α = 0.02), a converged reference is
// rendered with kReferenceSampling as two independent halves (its own noise is measured from
// their difference), then each sampler of the table renders at each spp with another seed; the
// table gives the relative RMSE of the luminance against the reference over the part, the
// relative difference of the means, seconds and rays/s, all in the same run, and each sampler's
// ratios to `bsdf`.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "scene/RenderDesc.h"

namespace sl {

/// The sampler of the reference (the least noisy per ray in this bench's own measurements; every
/// sampler is unbiased, and the mean-difference column would show it if one were not).
inline constexpr Sampling kReferenceSampling = Sampling::Stratified;

struct SamplingBenchOptions {
    std::filesystem::path scene;              // empty: the bundled default scene (app/host/Plot.h)
    std::vector<std::string> sceneOverrides;  // -D key=value on the scene (io/SceneFile.h)
    /// Parts: 0 = the scene's own material; a value > 0 = the scene with material.alpha set.
    std::vector<double> alphas{0.0, 0.02};
    std::string envmap = "studio";  // a light spec (io/EnvMapIO.h lightFromSpec)
    int resolution = 128;           // image N×N
    std::vector<int> spps{64, 1024};
    int referenceSpp = 16384;  // two halves of referenceSpp/2, each its own seed
    int threads = 0;
    std::function<void(const std::string&)> log;
};

struct SamplingBenchRow {
    std::string part;  // "scene" or "alpha=0.02"
    Sampling sampling = Sampling::Bsdf;
    int spp = 0;
    double seconds = 0;
    uint64_t rays = 0, shadowRays = 0;
    double relRmse = 0;      // RMSE(Y − Y_ref) / mean(Y_ref) over the reference's object mask
    double relRmseNet = 0;   // the same with the reference's own noise removed (in quadrature)
    double relMeanDiff = 0;  // (mean Y − mean Y_ref) / mean Y_ref
    double raysPerSecond() const {
        return seconds > 0 ? static_cast<double>(rays + shadowRays) / seconds : 0;
    }
};

struct SamplingBenchPart {
    std::string part;
    double alpha = 0;           // the part's material.alpha (alpha_u)
    double referenceNoise = 0;  // relative RMSE of the reference: RMSE(A − B)/2 / mean
    double referenceSeconds = 0;
    size_t pixels = 0;  // pixels in the reference's object mask
};

struct SamplingBenchResult {
    SamplingBenchOptions options;
    std::vector<SamplingBenchPart> parts;
    std::vector<SamplingBenchRow> rows;
    /// The row of (part, sampling, spp), or nullptr.
    const SamplingBenchRow* find(const std::string& part, Sampling s, int spp) const;
    std::string csv() const;
};

/// Runs the benchmark. Throws InputError for a bad scene or option.
SamplingBenchResult runSamplingBench(const SamplingBenchOptions& options);

/// Relative RMSE of luminance images a against ref over mask (1 = inside), and the relative
/// difference of their means (exposed for tests).
struct RelativeError {
    double rmse = 0, meanDiff = 0, refMean = 0;
};
RelativeError relativeError(const std::vector<float>& rgbA, const std::vector<float>& rgbRef,
                            const std::vector<uint8_t>& mask);

}  // namespace sl
