// Gradient checks and the speed-against-error benchmark (`scratchlight gradcheck`,
// `scratchlight bench gradients`).
//
// Both load a scene (small: e.g. 32×32 to 64×64 pixels, a few spp; overrides below), trace it
// once into T and once into a PathRecording (same spp, seed, depth: the same samples), build the
// objective on T's object mask and take the reference gradient by autodiff through the recorded
// paths (objective/Autodiff.h) at E0. Every method is then measured against that reference:
//
//   exact             Tᵀ·dL/dY (TransportLoss::evaluateFused), the precompute amortised
//   exact+precompute  the same plus the time to trace T (a single gradient from scratch)
//   autodiff          the reference itself (ceres::Jet through the paths; error 0 by definition)
//   autodiff-T        ceres::Jet through T (T's float entries): equals exact to <= 1e-9
//   fd, fd-forward    central / forward finite differences through the black-box renderer with
//                     common random numbers (optimize/BlackBox.h), step h
//   fd-fresh          central finite differences with fresh seeds in every render
//   spsa              SPSA with q averaged estimates (common random numbers), perturbation c
//
// Seconds per gradient are medians over `repeats` runs, measured side by side in one process;
// the errors of the random methods (fd-fresh, spsa) are medians over the same runs (each run
// draws new perturbations / seeds).
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "app/pipeline/InitialState.h"
#include "objective/Objective.h"
#include "optimize/BlackBox.h"

namespace sl {

/// What the scene is rendered with (overrides of the scene file) and where the gradient is taken.
struct GradientSetup {
    std::filesystem::path scene;
    std::vector<std::string> sceneOverrides;  // -D key=value on the scene (io/SceneFile.h)
    std::optional<int> width, height;         // camera.width/height overrides
    std::optional<int> spp, maxDepth;
    std::optional<uint64_t> seed;
    int threads = 0;  // 0: all cores
    ObjectiveOptions objective;
    InitialState init;  // E0 (const:0.5), as optimize's option 'init'
};

struct GradCheckOptions {
    GradientSetup setup;
    std::vector<std::string> methods{"exact", "autodiff", "fd", "spsa"};
    FdOptions fd;      // h, threads (central/CRN set per method)
    SpsaOptions spsa;  // c, q, seed, threads
    int repeats = 3;
};

/// The method names gradcheck accepts.
std::vector<std::string> gradCheckMethods();

struct GradCheckRow {
    std::string method;
    std::string settings;  // e.g. "h=0.001, CRN"
    double parameter = 0;  // h (fd*), q (spsa), 0 otherwise
    bool crn = true;       // common random numbers (black-box methods)
    double seconds = 0;    // per gradient (median)
    long renders = 0;      // renders per gradient (black-box methods)
    double relativeError = 0;  // ‖g − g_ref‖ / ‖g_ref‖ (median over repeats for random methods)
    double cosine = 1;
    int repeats = 0;
};

struct GradCheckReport {
    std::string scene;
    int width = 0, height = 0, spp = 0, maxDepth = 0, texels = 0;
    uint64_t seed = 0;
    size_t maskPixels = 0, nnz = 0, paths = 0;
    double loss = 0;                  // at E0
    double secondsPrecompute = 0;     // trace into T (median)
    double exactVsAutodiffT = 0;      // relative L2 error, same float T: <= 1e-9
    double exactVsAutodiffPaths = 0;  // float T against the double paths: ~1e-7
    std::vector<GradCheckRow> rows;

    std::string table() const;  // one row per method
    std::string json() const;
};

/// Runs the check. Throws InputError for a bad scene, method name or option.
GradCheckReport runGradCheck(const GradCheckOptions& options);

struct BenchGradientsOptions {
    GradientSetup setup;
    std::vector<double> fdSteps{1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6};  // central, CRN
    std::vector<double> fdFreshSteps{1e-1, 1e-2, 1e-3};               // central, fresh seeds
    std::vector<int> spsaQ{1, 4, 16, 64, 256};
    std::vector<double> spsaC{0.02, 0.002};  // perturbation sizes of the q sweep
    SpsaOptions spsa;  // seed, and the optimizer's gains (its c for the optimizations)
    int repeats = 3;
    // Whole optimizations from E0 with each method (loss against wall-clock seconds).
    bool optimizations = true;
    int iterations = 100;       // Adam-type methods (exact, autodiff, fd-adam)
    int spsaIterations = 2000;  // SPSA
    double budgetSeconds = 60;  // per optimization
    double learningRate = 0.02;
    std::filesystem::path outDir = "out/bench-gradients";
};

struct BenchTracePoint {
    std::string method;
    int iteration = 0;
    double seconds = 0;  // wall clock, excluding the loss evaluations made for the plot
    double loss = 0;  // noise-free loss of the iterate: T·E (= the black box with the base seed)
    long renders = 0;
};

struct BenchGradientsReport {
    GradCheckReport gradients;
    std::vector<BenchTracePoint> trace;
    std::filesystem::path gradientsCsv, optimizationCsv;
};

/// Runs the benchmark and writes outDir/gradients.csv (one row per method/setting) and
/// outDir/optimization.csv (method, iteration, seconds, loss, renders), atomically.
BenchGradientsReport runBenchGradients(const BenchGradientsOptions& options);

}  // namespace sl
