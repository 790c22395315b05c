// `scratchlight bench targets`: issue 32's wall-clock targets, one row each, measured in one
// run so that the ratios share the machine's load. On the bundled part (or a scene) at N², S spp
// with halves, after one untimed run that fills the cache (T, its validation estimate, the
// paper's light, the specular start, the judge's estimate):
//   - re-optimize: optimize on the cached T at another lambda L, no held-out (target 0.2 s),
//   - the same with the default held-out estimate, the judge's (target 0.2 s),
//   - the first answer from the scene: optimize the scene at N², S spp, no held-out, its cache
//     folder emptied before each run so that T is traced (target 1 s),
//   - lamps on T, K = 3 (target 1 s).
// Each is run `repeats` times, interleaved, in this process (no process start-up: ~0.03 s),
// as the command runs it (the job with the command's defaults, figures and report included).
// A row: the median wall seconds and its ratio to the target, the median CPU seconds and the
// load beside it, and where the time went: the trace's seconds (from the scene), the optimizer's
// (or the lamp fit's) seconds, its evaluations and ms per evaluation, and the rest (loading, the
// comparison lights, the self-check, renders, figures, report).
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace sl {

struct TargetsBenchOptions {
    std::filesystem::path scene;  // empty: the bundled part
    int size = 256;
    int spp = 16;
    int repeats = 3;
    double lambda = 10;
    int lampCount = 3;
    std::filesystem::path workDir = "out/bench-targets";
    std::function<void(const std::string&)> log;
};

struct TargetsBenchRow {
    std::string target;        // what is timed, as the command a user types
    double targetSeconds = 0;  // issue 32's bound
    double seconds = 0;        // median wall seconds of the whole job
    double secondsMin = 0, secondsMax = 0;
    double optimizerSeconds = 0;  // median: the optimizer (optimize) or the fits K = 1..K (lamps)
    double evaluations = 0;       // median: loss-and-gradient evaluations in it
    double secondsTarget = 0;     // lamps: optimizing E* first (median; 0 for optimize)
    double secondsTrace = 0;      // from the scene: its estimates of T (load, trace, write)
    /// Median CPU seconds of the job (all threads, and the plot script it waits for): on a
    /// shared machine the wall time is mostly the scheduler's, the CPU time the work's.
    double cpuSeconds = 0;
    double loadAverage = 0;  // the 1-minute load average when the row's last run ended
    double msPerEvaluation() const {
        return evaluations > 0 ? 1e3 * optimizerSeconds / evaluations : 0;
    }
    double rest() const { return seconds - optimizerSeconds - secondsTarget - secondsTrace; }
    double ratio() const { return targetSeconds > 0 ? seconds / targetSeconds : 0; }
};

struct TargetsBenchResult {
    TargetsBenchOptions options;
    double precomputeSeconds = 0;  // tracing T (halves), not part of any row
    std::vector<TargetsBenchRow> rows;
    std::string table() const;
    std::string csv() const;
};

TargetsBenchResult runTargetsBench(const TargetsBenchOptions& options);

}  // namespace sl
