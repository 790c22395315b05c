// `scratchlight bench noise`: speed against quality of the two objectives as the sample count
// of T grows. For each spp and each training seed, T is traced once with two sample sets (the
// paper objective uses T = (T_a + T_b)/2, the unbiased one the halves), E* is optimized with
// each objective and each optimizer, and every E* is scored on ONE shared independent high-spp
// estimate: with its own objective and with the paper's eq. 2 (the common yardstick).
//
// Two optimizer budgets answer two questions: Adam with the paper's 100 steps (what a fixed,
// short budget gets from a noisy T) and L-BFGS run to convergence (which optimum the objective
// itself defines at that spp). Several seeds give a median and a spread per (spp, objective,
// optimizer): the training noise differs per seed, the held-out estimate is shared.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "optimize/Methods.h"

namespace sl {

struct NoiseBenchOptimizer {
    OptimizerMethod method = OptimizerMethod::Adam;  // a method minimize() runs on T
    int budget = 100;                                // OptimizerOptions::iterations
};

/// Parses "adam:100,lbfgs:2000" (the budget is optional: the method's default budget).
/// Throws InputError naming option 'optimizers'.
std::vector<NoiseBenchOptimizer> parseNoiseBenchOptimizers(const std::string& spec);

struct NoiseBenchOptions {
    std::filesystem::path scene;
    std::vector<std::string> sceneOverrides;  // -D key=value on the scene (io/SceneFile.h)
    int resolution = 256;
    std::vector<int> spps{4, 16, 64, 256, 1024};
    int heldOutSpp = 4096;
    int seeds = 3;  // training seeds: render.seed + 0 … seeds − 1
    std::vector<NoiseBenchOptimizer> optimizers{{OptimizerMethod::Adam, 100},
                                                {OptimizerMethod::Lbfgs, 2000}};
    int threads = 0;
    std::function<void(const std::string&)> log;
};

struct NoiseBenchRow {
    int spp = 0;
    uint64_t seed = 0;
    std::string objective;  // paper | unbiased
    std::string optimizer;  // method name
    int iterations = 0;
    bool converged = false;        // stopped before its budget (NLopt/Ceres convergence)
    double precomputeSeconds = 0;  // tracing + building T (shared by objectives and optimizers)
    double optimizeSeconds = 0;
    double trainLoss = 0;     // final loss on the training T, own objective
    double heldOutLoss = 0;   // E* scored with its own objective on the shared estimate
    double heldOutPaper = 0;  // E* scored with eq. 2 on the shared estimate
    double seconds() const { return precomputeSeconds + optimizeSeconds; }
};

/// Median over seeds of one (spp, objective, optimizer) group.
struct NoiseBenchGroup {
    int spp = 0;
    std::string objective, optimizer;
    int runs = 0, converged = 0;
    double seconds = 0, trainLoss = 0, heldOutLoss = 0, heldOutPaper = 0;  // medians
    double trainGap = 0;  // median of (train − held-out)/held-out
    /// Held-out loss (own objective) against the same objective and optimizer at the largest
    /// spp: median over seeds and the min/max over seeds, each relative to that median.
    double relToTop = 0, relToTopMin = 0, relToTopMax = 0;
};

struct NoiseBenchResult {
    std::vector<NoiseBenchRow> rows;
    std::vector<NoiseBenchGroup> groups;
    double heldOutSeconds = 0;
    int heldOutSpp = 0;
};

NoiseBenchResult runNoiseBench(const NoiseBenchOptions& options);

/// Groups rows by (spp, objective, optimizer) with medians over seeds (exposed for tests).
std::vector<NoiseBenchGroup> summarizeNoiseBench(const std::vector<NoiseBenchRow>& rows);

}  // namespace sl
