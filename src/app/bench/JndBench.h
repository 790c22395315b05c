// `scratchlight bench jnd`: what the defects objective's JND measure costs, in one run so that
// the ratios share the machine's load.
//   - One evaluation (loss and gradient through T's halves, as the optimizer calls it) of the
//     JND objective on the bundled part at each size, its band filters computed directly and
//     through the Fourier domain (perception/BandFilters.h GaussianMethod: the same operator),
//     interleaved; beside them the ratio measure's evaluation; and how far the two JND
//     evaluations' losses and gradients differ (rounding only).
//   - The whole `optimize --truth` default on the bundled part at one size from an empty cache,
//     `--defects-measure jnd` and `ratio` interleaved, with where the time went: tracing T and
//     the validation estimate V, the searches, the gap's standard error, the self-check, the
//     judge (its estimate and scoring) and the rest, the CPU seconds beside the wall seconds (on
//     a machine shared with other jobs the wall time is mostly the others'); and the judge's JND
//     of the answer.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace sl {

struct JndBenchOptions {
    std::vector<int> sizes{128, 256, 512};  // image N×N of the evaluation rows
    int evaluationSpp = 4;                  // T's spp (two halves) for the evaluation rows
    int evaluations = 5;                    // timed evaluations per size and method (median)
    int optimizeSize = 256;                 // image N×N of the optimize rows (0: none)
    int repeats = 2;                        // interleaved optimize runs per measure
    std::filesystem::path workDir = "out/bench-jnd";
};

struct JndEvaluationRow {
    int size = 0;
    double secondsDirect = 0, secondsFourier = 0, secondsRatio = 0;  // medians
    double lossDifference = 0;      // |loss_Fourier − loss_direct| / |loss_direct|
    double gradientDifference = 0;  // max |dL/dY| difference / max |dL/dY|
    double speedup() const { return secondsFourier > 0 ? secondsDirect / secondsFourier : 0; }
};

/// One optimize run's phases (seconds).
struct JndOptimizeSample {
    double seconds = 0;
    double cpuSeconds = 0;  // the process's user + system CPU seconds in it (every thread)
    double trace = 0;       // T (every round) and V
    double search = 0;      // the searches of every round (the last one's held-out curve in it)
    double gapError = 0;    // the gap's standard errors (the wild bootstrap on V)
    double answer = 0;      // the self-check on V
    double judge = 0;       // the judge's estimate and its scoring rounds
    double rest = 0;        // loading, comparisons, figures, report, ...
    int spp = 0;            // the training spp the rule kept
    int rounds = 0;         // the noise rule's rounds
    double jnd = 0;         // the judge's JND of the answer's light (worst label)
    double lampJnd = 0;     // ... of the studio lamp
};

struct JndOptimizeRow {
    std::string measure;  // "jnd", "ratio"
    std::vector<JndOptimizeSample> samples;
    JndOptimizeSample median() const;  // per column
};

struct JndBenchResult {
    JndBenchOptions options;
    std::vector<JndEvaluationRow> evaluations;
    std::vector<JndOptimizeRow> optimize;
    std::string table() const;
    std::string csv() const;
};

JndBenchResult runJndBench(const JndBenchOptions& options);

}  // namespace sl
