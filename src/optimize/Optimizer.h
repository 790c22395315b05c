// Optimizers behind one interface: an Options struct in, a Summary out (the shape of Ceres'
// GradientProblemSolver). The problem is box-constrained to [lower, upper] (E in [0, 1]).
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "core/Problem.h"
#include "optimize/Methods.h"

namespace sl {

struct IterationRecord {
    int iteration = 0;    // 0 = the initial point
    int evaluations = 0;  // objective evaluations so far
    double loss = 0;      // at the current iterate
    double seconds = 0;   // wall time since the start of the optimization
};

struct OptimizerOptions {
    OptimizerMethod method = OptimizerMethod::Adam;  // a method minimize() runs (Methods.h)
    int iterations = 100;  // the budget: what one iteration is, per method, in Methods.h
    // Adam (the paper's setting, as Mitsuba 3's optimizer: bias-corrected, x clamped after
    // every step).
    double learningRate = 0.02;
    double beta1 = 0.9, beta2 = 0.999, epsilon = 1e-8;
    // NLopt / Ceres stopping tolerances (0 = off).
    double relativeFunctionTolerance = 0.0;
    /// Any method: stop ("stalled") when the best loss has fallen by less than stallTolerance
    /// over the last stallEvaluations evaluations (0 = off). Unlike a per-step tolerance, one
    /// short step on a plateau does not end the run: only a window without progress does.
    /// Checked at each recorded iteration (NLopt's: each improving evaluation).
    int stallEvaluations = 0;
    double stallTolerance = 0.0;
    // mlsl: seed of NLopt's random numbers (nlopt::srand, a process-wide generator). MLSL
    // samples a Sobol' sequence up to 1111 dimensions, which the seed does not change; above
    // that (a 25×50 map has 1250 texels) NLopt falls back to pseudo-random points, which it does.
    uint64_t seed = 0;
    // mlsl: sample points added per MLSL iteration (NLopt's set_population; 0 = NLopt's
    // default, 4).
    int population = 0;
    /// Called after every iteration (and for the initial point); returning false stops.
    std::function<bool(const IterationRecord&, std::span<const double> x)> callback;
};

struct OptimizerSummary {
    std::string method;  // the method's name (or the name of a set-up that ran it)
    int iterations = 0;
    int evaluations = 0;
    int hessianProducts = 0;  // Problem::hessianProduct calls (newton-tr), each about an evaluation
    double initialLoss = 0, finalLoss = 0;
    double seconds = 0;
    std::string termination;  // why it stopped
    /// True when the method stopped on an internal failure (NLopt failure, Ceres failure, a
    /// roundoff-limited stop before any progress); x is still the best iterate, in bounds.
    bool failed = false;
    size_t dimension = 0;
    double lower = 0, upper = 1;
    std::string settings;  // the method's settings, one line, for fullReport()
    /// history[0] is the initial point, then one record per iteration. The returned x is the
    /// best recorded iterate: the record with iteration returnedIteration (finalLoss its loss),
    /// the last one unless an earlier one was lower (Adam can climb, e.g. at a huge λ).
    std::vector<IterationRecord> history;
    int returnedIteration = 0;
    bool improved() const { return finalLoss < initialLoss; }

    std::string briefReport() const;  // one line
    std::string fullReport() const;   // a short page
};

/// Minimizes problem from x (in/out; clamped to the bounds first). Throws InputError for an
/// unknown method or bad options (naming the option), std::runtime_error naming the method and
/// iteration when the objective returns NaN/Inf; exceptions from the objective propagate.
OptimizerSummary minimize(const Problem& problem, std::vector<double>& x,
                          const OptimizerOptions& options);

}  // namespace sl
