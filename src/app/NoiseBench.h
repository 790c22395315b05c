// `scratchlight bench noise`: speed against quality of the two objectives as the sample count
// of T grows. For each spp, T is traced once with two sample sets (the paper objective uses
// T = (T_a + T_b)/2, the unbiased one the halves), E* is optimized with each objective (Adam,
// the paper's settings), and every E* is scored on ONE shared independent high-spp estimate:
// with its own objective and with the paper's eq. 2 (the common yardstick).
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace sl {

struct NoiseBenchOptions {
    std::filesystem::path scene;
    int resolution = 256;
    std::vector<int> spps{4, 16, 64, 256, 1024};
    int heldOutSpp = 4096;
    int iterations = 100;
    int threads = 0;
    std::function<void(const std::string&)> log;
};

struct NoiseBenchRow {
    int spp = 0;
    std::string objective;         // paper | unbiased
    double precomputeSeconds = 0;  // tracing + building T (shared by both objectives)
    double optimizeSeconds = 0;
    double trainLoss = 0;     // final loss on the training T, own objective
    double heldOutLoss = 0;   // E* scored with its own objective on the shared estimate
    double heldOutPaper = 0;  // E* scored with eq. 2 on the shared estimate
    double seconds() const { return precomputeSeconds + optimizeSeconds; }
};

struct NoiseBenchResult {
    std::vector<NoiseBenchRow> rows;
    double heldOutSeconds = 0;
    int heldOutSpp = 0;
};

NoiseBenchResult runNoiseBench(const NoiseBenchOptions& options);

}  // namespace sl
