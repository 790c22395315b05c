// The `optimize` job: T (traced or cached, or read from a .tm), the objective on a mask, one
// optimization per λ, and the outputs a person looks at.
//
// OUTDIR (or OUTDIR/lambda-<λ>/ per λ of a sweep) holds:
//   envmap.exr   the optimized E on the env-map grid (data)      envmap.png  enlarged preview
//   render.exr   T·E* (luminance, or RGB with an RGB T)          render.png  its sRGB preview
//   initial.png  T·E0 under the initial env map
//   loss.csv     iteration, evaluations, loss, L_grad, L_reg, seconds
//   summary.json optimizer, lambda, iterations, initial/final loss and parts, timings, T's facts
// A sweep also writes OUTDIR/sweep.csv (one row per λ).
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "app/Transport.h"
#include "objective/Objective.h"
#include "optimize/Optimizer.h"

namespace sl {

struct OptimizeJobOptions {
    std::filesystem::path input;  // scene (.json) or transport matrix (.tm)
    std::filesystem::path outDir = "out/optimize";
    std::vector<double> lambdas{30.0};
    ObjectiveOptions objective;  // lambda is taken from `lambdas`
    std::string init = "const:0.5";
    std::string mask;  // "" = object mask; a PNG/EXR file in image space
    bool rgb = false;
    OptimizerOptions optimizer;
    PrecomputeOptions precompute;  // used when input is a scene
};

struct OptimizeRun {
    double lambda = 0;
    std::filesystem::path dir;
    OptimizerSummary optimizer;
    LossParts initial, final;
};

struct OptimizeJobSummary {
    TransportSource transport;
    size_t maskPixels = 0;
    std::vector<OptimizeRun> runs;
};

OptimizeJobSummary runOptimizeJob(const OptimizeJobOptions& options);

/// Writes `image` (width×height, 1 or 3 channels, double) as EXR + PNG preview.
void writeRender(const std::filesystem::path& exr, const std::vector<double>& image, int width,
                 int height, int channels);

}  // namespace sl
