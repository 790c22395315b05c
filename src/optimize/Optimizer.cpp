// The optimizers behind sl::minimize: options validation, dispatch, Adam, and the reports.
//
// Every method minimizes problem.evaluate over the box [lower, upper]^dimension from x (clamped
// to the box first) and returns the point it ends at in x. The history starts with iteration 0
// = the initial point and ends with the returned point, so finalLoss is the loss at the
// returned x. What one "iteration" is, and what `iterations` limits, differs per method:
//
//   adam         Mitsuba 3's Adam (src/python/python/ad/optimizers.py), as the paper used it
//                (lr 0.02, 100 iterations). One iteration = one step:
//                    t += 1;  m = β1·m + (1−β1)·g;  v = β2·v + (1−β2)·g²
//                    lr_t = lr · sqrt(1 − β2^t) / (1 − β1^t)
//                    x ← clamp(x − lr_t · m / (sqrt(v) + ε), lower, upper)
//                Note ε sits beside the *uncorrected* sqrt(v) (Kingma & Ba's "efficient"
//                form), not beside sqrt(v̂) as in PyTorch; with the default ε = 1e-8 the two
//                differ only for tiny gradients. The clamp is the paper's x = min(max(0, x), 1)
//                after every step; like Mitsuba, it does not touch m and v. Arithmetic is in
//                double (Mitsuba's llvm/cuda variants use float32). `iterations` = number of
//                steps; evaluations = iterations + 1 (the gradient at x_0..x_{N−1}, then the
//                loss at the returned x_N). Adam evaluates every point it asks for, even a
//                repeated one, so a stochastic gradient source works with it.
//                Termination: "iteration limit reached".
//
//   lbfgs, mma,  NLopt LD_LBFGS, LD_MMA, LD_CCSAQ with the box as bound constraints; mlsl is
//   ccsaq, mlsl  NLopt G_MLSL_LDS with an LD_LBFGS local optimizer (NloptOptimizer.cpp).
//                NLopt has no iteration count of its own, so one iteration = one evaluation
//                that improves on the best loss so far (history and callback see the best point,
//                and the loss decreases strictly along the history). `iterations` is NLopt's
//                maxeval: at most that many evaluations (line-search trials, MLSL samples and
//                local searches included).
//
//   ceres-lbfgs  ceres::GradientProblemSolver, LBFGS direction, Wolfe line search, on
//                x = lower + (upper − lower)·sin²(z) (CeresOptimizer.cpp). One iteration = one
//                Ceres iteration (an accepted line-search step, usually 1–3 evaluations);
//                `iterations` = max_num_iterations.
//
//   newton-tr    A projected truncated Newton method in a trust region on the problem's exact
//                Hessian products (NewtonOptimizer.cpp, which describes it). One iteration =
//                one accepted step; `iterations` = the most steps. A problem that offers no
//                Hessian products (Problem::hessianProduct) runs NLopt's L-BFGS instead, with
//                maxeval the larger of `iterations` and lbfgs' default budget, and says so in
//                the summary's settings.
//
// relativeFunctionTolerance (0 = off) is NLopt's ftol_rel, Ceres' function_tolerance and
// newton-tr's relative decrease of one step.
// stallEvaluations/stallTolerance (0 = off) stop any method once the best loss has fallen by less
// than the tolerance over that many evaluations (termination "stalled: ..."; not a failure).
// The callback sees every recorded iteration, iteration 0 first; returning false stops the run
// with termination "stopped by callback" and x = the point the callback last saw.
#include "optimize/Optimizer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/Error.h"
#include "optimize/OptimizerDetail.h"

namespace sl {

namespace detail {

Run::Run(const Problem& problem, const OptimizerOptions& options)
    : problem_(problem), options_(options) {
    summary.method = methodName(options.method);
    summary.dimension = problem.dimension;
    summary.lower = problem.lower;
    summary.upper = problem.upper;
}

double Run::seconds() const {
    return clock_.seconds();
}

bool Run::progressed() const {
    const auto& h = summary.history;
    return h.size() > 1 &&
           std::any_of(h.begin() + 1, h.end(), [&](const auto& r) { return r.loss < h[0].loss; });
}

double Run::evaluate(std::span<const double> x, std::span<double> grad, bool reuse) {
    const bool wantGrad = !grad.empty();
    for (const CacheEntry& c : cache_) {
        if (!reuse) break;
        if (!c.valid || (wantGrad && !c.hasGrad) || !std::equal(x.begin(), x.end(), c.x.begin()))
            continue;
        if (wantGrad) std::copy(c.grad.begin(), c.grad.end(), grad.begin());
        return c.loss;
    }

    const double loss = problem_.evaluate(x, grad);
    ++evaluations_;

    auto fail = [&](const std::string& what) {
        throw NonFinite("minimize (method '" + summary.method + "'): the objective " + what +
                        " at evaluation " + std::to_string(evaluations_) + ", iteration " +
                        std::to_string(lastIteration() + 1) +
                        "; stopping (no NaN leaves the optimizer)");
    };
    if (!std::isfinite(loss)) fail("returned a non-finite loss (" + formatNumber(loss) + ")");
    for (size_t i = 0; i < grad.size(); ++i)
        if (!std::isfinite(grad[i]))
            fail("returned a non-finite gradient (grad[" + std::to_string(i) +
                 "] = " + formatNumber(grad[i]) + ")");

    CacheEntry& c = cache_[cacheNext_];
    cacheNext_ = (cacheNext_ + 1) % cache_.size();
    c.x.assign(x.begin(), x.end());
    c.hasGrad = wantGrad;
    if (wantGrad) c.grad.assign(grad.begin(), grad.end());
    c.loss = loss;
    c.valid = true;
    return loss;
}

bool Run::record(double loss, std::span<const double> x) {
    IterationRecord r;
    r.iteration = lastIteration() + 1;
    r.evaluations = evaluations_;
    r.loss = loss;
    r.seconds = seconds();
    summary.history.push_back(r);
    lastRecordedX_.assign(x.begin(), x.end());
    if (bestIteration_ < 0 || loss < bestLoss_) {
        bestLoss_ = loss;
        bestIteration_ = r.iteration;
        bestX_.assign(x.begin(), x.end());
    }
    if (options_.stallEvaluations > 0 && evaluations_ >= options_.stallEvaluations) {
        // The best loss recorded by evaluation (now − window), against the best now.
        double before = std::numeric_limits<double>::infinity();
        for (const IterationRecord& h : summary.history)
            if (h.evaluations <= evaluations_ - options_.stallEvaluations)
                before = std::min(before, h.loss);
        if (std::isfinite(before) && before - bestLoss_ < options_.stallTolerance) {
            stalled_ = true;
            return false;
        }
    }
    return !options_.callback || options_.callback(r, x);
}

void Run::finish(std::vector<double>& x) {
    if (summary.history.empty() || !std::equal(x.begin(), x.end(), lastRecordedX_.begin()))
        record(evaluate(x, {}, true), x);
    const auto& h = summary.history;
    summary.iterations = h.back().iteration;
    summary.evaluations = evaluations_;
    summary.initialLoss = h.front().loss;
    summary.finalLoss = h.back().loss;
    summary.returnedIteration = h.back().iteration;
    if (bestLoss_ < h.back().loss) {
        x = bestX_;
        summary.finalLoss = bestLoss_;
        summary.returnedIteration = bestIteration_;
        summary.termination += "; returned iteration " + std::to_string(bestIteration_) +
                               ", the lowest loss seen (the last was " +
                               formatNumber(h.back().loss) + ")";
    }
    summary.seconds = seconds();
}

void Run::finishAfterNonFinite(const NonFinite& stop, std::vector<double>& x) {
    if (bestIteration_ < 0) throw std::runtime_error(stop.what());
    x = bestX_;
    const auto& h = summary.history;
    summary.iterations = h.back().iteration;
    summary.evaluations = evaluations_;
    summary.initialLoss = h.front().loss;
    summary.finalLoss = bestLoss_;
    summary.returnedIteration = bestIteration_;
    summary.failed = true;
    summary.termination = std::string(stop.what()) + "; returned iteration " +
                          std::to_string(bestIteration_) + ", the best finite iterate";
    summary.seconds = seconds();
}

}  // namespace detail

namespace {

void validate(const Problem& problem, const std::vector<double>& x, const OptimizerOptions& o) {
    const OptimizerMethodRow& row = methodRow(o.method);
    if (row.gradient != GradientSource::Exact || row.runs != o.method) {
        std::string list;
        for (const std::string& m : optimizerMethods()) list += (list.empty() ? "" : ", ") + m;
        throw inputError("optimizer method",
                         std::string("'") + row.name + "' is not a method minimize() runs",
                         "use one of: " + list);
    }
    auto bad = [](const std::string& field, const std::string& problemText,
                  const std::string& fix) { return inputError(field, problemText, fix); };
    if (o.iterations < 1)
        throw bad(option("iterations"), "is " + std::to_string(o.iterations), "use a count >= 1");
    if (!(o.learningRate > 0) || !std::isfinite(o.learningRate))
        throw bad(option("learning-rate"), "is " + formatNumber(o.learningRate),
                  "use a finite value > 0 (the paper: 0.02)");
    if (!(o.beta1 >= 0 && o.beta1 < 1))
        throw bad(option("beta1"), "is " + formatNumber(o.beta1),
                  "use 0 <= beta1 < 1 (default 0.9)");
    if (!(o.beta2 >= 0 && o.beta2 < 1))
        throw bad(option("beta2"), "is " + formatNumber(o.beta2),
                  "use 0 <= beta2 < 1 (default 0.999)");
    if (!(o.epsilon > 0) || !std::isfinite(o.epsilon))
        throw bad(option("epsilon"), "is " + formatNumber(o.epsilon),
                  "use a finite value > 0 (default 1e-8)");
    if (!(o.relativeFunctionTolerance >= 0) || !std::isfinite(o.relativeFunctionTolerance))
        throw bad(option("relative-function-tolerance"),
                  "is " + formatNumber(o.relativeFunctionTolerance), "use a value >= 0 (0 = off)");
    if (o.stallEvaluations < 0)
        throw bad(option("stall-evaluations"), "is " + std::to_string(o.stallEvaluations),
                  "use a count >= 0 (0 = off)");
    if (!(o.stallTolerance >= 0) || !std::isfinite(o.stallTolerance))
        throw bad(option("stall-tolerance"), "is " + formatNumber(o.stallTolerance),
                  "use a finite value >= 0");
    if (o.population < 0)
        throw bad(option("population"), "is " + std::to_string(o.population),
                  "use a count >= 0 (0 = NLopt's default)");
    if (!std::isfinite(problem.lower) || !std::isfinite(problem.upper) ||
        !(problem.lower < problem.upper))
        throw bad("optimizer bounds",
                  "[" + formatNumber(problem.lower) + ", " + formatNumber(problem.upper) +
                      "] is not a box",
                  "use finite lower < upper (the env map: [0, 1])");
    if (problem.dimension == 0)
        throw bad("optimizer problem", "dimension is 0", "give the number of unknowns");
    if (problem.dimension > static_cast<size_t>(1) << 30)
        throw bad("optimizer problem",
                  "dimension " + std::to_string(problem.dimension) + " is too large",
                  "use at most 2^30 unknowns");
    if (x.size() != problem.dimension)
        throw bad("optimizer start point",
                  "x has " + std::to_string(x.size()) + " values, the problem " +
                      std::to_string(problem.dimension),
                  "pass one value per unknown");
    if (!problem.evaluate)
        throw bad("optimizer problem", "has no objective", "set Problem::evaluate");
    for (size_t i = 0; i < x.size(); ++i)
        if (!std::isfinite(x[i]))
            throw bad("optimizer start point",
                      "x[" + std::to_string(i) + "] is " + formatNumber(x[i]),
                      "start from finite values");
}

void minimizeAdam(detail::Run& run, std::vector<double>& x) {
    const OptimizerOptions& o = run.options();
    const double lo = run.problem().lower, hi = run.problem().upper;
    const size_t n = x.size();
    run.summary.settings = "lr " + formatNumber(o.learningRate) + ", beta1 " +
                           formatNumber(o.beta1) + ", beta2 " + formatNumber(o.beta2) +
                           ", epsilon " + formatNumber(o.epsilon) + ", x clamped after every step";
    std::vector<double> g(n), m(n, 0.0), v(n, 0.0);
    for (int t = 1; t <= o.iterations; ++t) {
        const double loss = run.evaluate(x, g, false);  // at x_{t-1}
        if (!run.record(loss, x)) {
            run.summary.termination = "stopped by callback";
            return;
        }
        const double lrT =
            o.learningRate * std::sqrt(1.0 - std::pow(o.beta2, t)) / (1.0 - std::pow(o.beta1, t));
        for (size_t i = 0; i < n; ++i) {
            m[i] = o.beta1 * m[i] + (1.0 - o.beta1) * g[i];
            v[i] = o.beta2 * v[i] + (1.0 - o.beta2) * g[i] * g[i];
            x[i] = detail::clampTo(x[i] - lrT * m[i] / (std::sqrt(v[i]) + o.epsilon), lo, hi);
        }
    }
    // The loss at the returned point x_N: iteration N (the callback's answer no longer matters).
    run.record(run.evaluate(x, {}, false), x);
    run.summary.termination = "iteration limit reached (" + std::to_string(o.iterations) + ")";
}

// The summary of L-BFGS run for newton-tr on a problem without Hessian products.
void noteNoHessian(OptimizerSummary& s, const OptimizerOptions& asked) {
    s.method = methodName(asked.method);
    s.settings = "the problem offers no Hessian products: NLopt's L-BFGS ran (" + s.settings + ")";
}

std::string fixed(double v, int decimals) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
    return buf;
}

std::string sci(double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.6e", v);
    return buf;
}

}  // namespace

OptimizerSummary minimize(const Problem& problem, std::vector<double>& x,
                          const OptimizerOptions& options) {
    validate(problem, x, options);
    for (double& xi : x) xi = detail::clampTo(xi, problem.lower, problem.upper);

    // newton-tr on a problem without Hessian products: L-BFGS, said in the settings.
    OptimizerOptions lbfgs;
    const bool noHessian = options.method == OptimizerMethod::NewtonTr && !problem.hessianProduct;
    if (noHessian) {
        lbfgs = options;
        lbfgs.method = OptimizerMethod::Lbfgs;
        lbfgs.iterations =
            std::max(options.iterations, methodRow(OptimizerMethod::Lbfgs).defaultBudget);
    }
    detail::Run run(problem, noHessian ? lbfgs : options);
    try {
        switch (run.options().method) {
            case OptimizerMethod::Adam:
                minimizeAdam(run, x);
                break;
            case OptimizerMethod::CeresLbfgs:
                detail::minimizeCeres(run, x);
                break;
            case OptimizerMethod::Lbfgs:
            case OptimizerMethod::Mma:
            case OptimizerMethod::Ccsaq:
            case OptimizerMethod::Mlsl:
            case OptimizerMethod::Tnewton:
                detail::minimizeNlopt(run, x);
                break;
            case OptimizerMethod::NewtonTr:
                detail::minimizeNewtonTr(run, x);
                break;
            case OptimizerMethod::FdAdam:
            case OptimizerMethod::Spsa:
            case OptimizerMethod::PaperLoop:
                break;  // refused by validate()
        }
    } catch (const detail::NonFinite& stop) {
        run.finishAfterNonFinite(stop, x);
        if (noHessian) noteNoHessian(run.summary, options);
        return run.summary;
    }
    if (noHessian) noteNoHessian(run.summary, options);
    run.finish(x);
    if (run.stalled())
        run.summary.termination = "stalled: the loss fell less than " +
                                  formatNumber(options.stallTolerance) + " over the last " +
                                  std::to_string(options.stallEvaluations) + " evaluations";
    return run.summary;
}

std::string OptimizerSummary::briefReport() const {
    return method + ": " + std::to_string(iterations) + " iterations, " +
           std::to_string(evaluations) + " evaluations, " +
           (hessianProducts > 0 ? std::to_string(hessianProducts) + " Hessian products, " : "") +
           "loss " + sci(initialLoss) + " -> " + sci(finalLoss) + ", " + fixed(seconds, 3) +
           " s, " + (failed ? "FAILED: " : "") + termination;
}

std::string OptimizerSummary::fullReport() const {
    // Written through a stream: GCC 12 misreads "literal" + std::string chains under
    // -Wrestrict at -O2 (GCC bug 105329).
    std::ostringstream s;
    auto line = [&s](const std::string& key, const std::string& value) {
        s << std::left << std::setw(26) << key << value << "\n";
    };
    s << "Solver Summary (scratchlight)\n\n";
    line("Method", method);
    if (!settings.empty()) line("Settings", settings);
    line("Parameters", std::to_string(dimension));
    std::ostringstream bounds;
    bounds << '[' << formatNumber(lower) << ", " << formatNumber(upper) << ']';
    line("Bounds", bounds.str());
    s << "\nLoss\n";
    line("  Initial", sci(initialLoss));
    line("  Final", sci(finalLoss));
    const double change = finalLoss - initialLoss;
    std::ostringstream ch;
    ch << sci(change);
    if (initialLoss != 0) ch << " (" << fixed(100.0 * change / std::abs(initialLoss), 2) << "%)";
    line("  Change", ch.str());
    s << "\n";
    line("Iterations", std::to_string(iterations));
    line("Evaluations", std::to_string(evaluations));
    if (hessianProducts > 0) line("Hessian products", std::to_string(hessianProducts));
    line("Time (s)", fixed(seconds, 4));
    if (evaluations > 0) line("  per evaluation (ms)", fixed(1e3 * seconds / evaluations, 4));
    s << "\n";
    line("Termination", std::string(failed ? "FAILED: " : "") + termination);
    return s.str();
}

}  // namespace sl
