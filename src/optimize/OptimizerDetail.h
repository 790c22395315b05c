// Private to src/optimize: the bookkeeping every method shares (evaluation counting, the NaN/Inf
// check, a small cache of recent evaluations, the iteration history and the user's callback),
// and the entry points of the methods that live in their own translation units.
#pragma once

#include <array>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/Stopwatch.h"
#include "core/Text.h"
#include "optimize/Optimizer.h"

namespace sl::detail {

/// One optimization run.
///
/// evaluate() is the only way a method reaches the objective: it counts calls and throws a
/// std::runtime_error naming the method, the evaluation and the iteration when the loss or the
/// gradient is not finite. It remembers the last few points; with reuse = true a point that was
/// just evaluated is served from them (NLopt's first call at x0, MMA's repeated points, Ceres'
/// accepted step looked up in the callback). NLopt and Ceres assume a deterministic objective
/// anyway (their line searches compare losses); Adam never reuses, so it works with a
/// stochastic gradient. A cache hit is not counted: `evaluations` counts Problem::evaluate calls.
///
/// record() appends the next IterationRecord (0 for the first call) and calls the user's
/// callback; its result says whether to go on.
class Run {
  public:
    Run(const Problem& problem, const OptimizerOptions& options);

    const Problem& problem() const { return problem_; }
    const OptimizerOptions& options() const { return options_; }
    size_t dimension() const { return problem_.dimension; }

    /// f(x), and its gradient into grad when grad is non-empty (grad.size() == dimension).
    double evaluate(std::span<const double> x, std::span<double> grad, bool reuse);

    /// Appends iteration lastIteration()+1 (0 first) with this loss at x; calls the callback.
    /// Returns false when the callback asks to stop.
    bool record(double loss, std::span<const double> x);

    /// Makes history.back() describe x (recording it, evaluated with reuse, if it is not the
    /// last recorded point; the callback's answer is then ignored), then returns the best
    /// recorded iterate in x when one was lower than the last, and fills the summary's totals.
    void finish(std::vector<double>& x);

    /// After a NonFinite stop: x = the best recorded iterate, the summary says why it stopped.
    /// Rethrows when nothing finite was recorded (the start itself is not finite).
    void finishAfterNonFinite(const struct NonFinite& stop, std::vector<double>& x);

    int evaluations() const { return evaluations_; }
    int lastIteration() const {
        return summary.history.empty() ? -1 : summary.history.back().iteration;
    }
    double seconds() const;
    bool progressed() const;  // a recorded loss below the initial one
    /// record() stopped the run: the best loss fell by less than options().stallTolerance over
    /// the last options().stallEvaluations evaluations.
    bool stalled() const { return stalled_; }

    OptimizerSummary summary;

  private:
    struct CacheEntry {
        std::vector<double> x, grad;
        double loss = 0;
        bool hasGrad = false;
        bool valid = false;
    };
    bool stalled_ = false;

    const Problem& problem_;
    const OptimizerOptions& options_;
    Stopwatch clock_;
    int evaluations_ = 0;
    std::array<CacheEntry, 4> cache_;
    size_t cacheNext_ = 0;
    std::vector<double> lastRecordedX_;
    double bestLoss_ = 0;
    int bestIteration_ = -1;
    std::vector<double> bestX_;
};

/// Thrown by Run::evaluate when the objective returns a non-finite loss or gradient; minimize()
/// catches it and returns the best finite iterate (a std::runtime_error for callers of the
/// methods that do not).
struct NonFinite : std::runtime_error {
    using std::runtime_error::runtime_error;
};

/// Clamps v to [lo, hi].
inline double clampTo(double v, double lo, double hi) {
    return v < lo ? lo : (v > hi ? hi : v);
}

// The methods. Each starts from x (clamped, validated; nothing recorded yet), records the
// initial point and every iteration through run, leaves the returned point in x and sets
// run.summary.termination / failed / settings. Run::finish() is called by minimize().
void minimizeNlopt(Run& run, std::vector<double>& x);     // NloptOptimizer.cpp
void minimizeCeres(Run& run, std::vector<double>& x);     // CeresOptimizer.cpp
void minimizeNewtonTr(Run& run, std::vector<double>& x);  // NewtonOptimizer.cpp

}  // namespace sl::detail
