// ceres-lbfgs: ceres::GradientProblemSolver (Ceres 2.1), LBFGS direction, Wolfe line search.
// The only translation unit that includes Ceres headers (they compile slowly).
//
// Bounds. Ceres' GradientProblem has no bound constraints, so the box is removed by a change of
// variables, per coordinate, with w = upper − lower:
//
//     x = lower + w·sin²(z)        dx/dz = w·sin(2z)        z₀ = asin(sqrt((x₀ − lower)/w))
//
// x stays in [lower, upper] for every z (the result is also clamped against rounding), reaches
// both bounds exactly, and is smooth; near a bound x − lower = w·z² (or upper − x = w·(π/2−z)²),
// so a solution on a bound is an ordinary quadratic minimum in z. The weakness: dx/dz = 0 at
// the bounds, so a texel that starts exactly at lower or upper has a zero z-gradient and could
// never move. The start is therefore nudged inside: (x₀ − lower)/w is clamped to
// [kNudge, 1 − kNudge], kNudge = 1e-6, i.e. x moves by at most 1e-6·w (invisible in a light
// map; it makes the start's z-gradient 2·sqrt(kNudge)·w·∂f/∂x ≈ 2e-3·w·∂f/∂x). The initial
// point recorded as iteration 0 is this nudged start. Periodicity in z is harmless: every z maps
// into the box. A texel whose optimum is on a bound gets there only as z → 0 (x − lower = w·z²,
// typically ~1e-10 when Ceres stops), so count "texels at 0" with a threshold, not with ==.
//
// Iterations: one Ceres iteration (an accepted line-search step) = one history entry; Ceres
// calls IterationCallbacks for iteration 0 and after every step except the one that meets a
// convergence test, which minimize() then records itself. `iterations` = max_num_iterations;
// relativeFunctionTolerance = function_tolerance (0 = off); gradient_tolerance (1e-10 on
// max|∂f/∂z|) and parameter_tolerance (1e-8, relative step in z) are Ceres' defaults. Termination:
// CONVERGENCE / NO_CONVERGENCE with Ceres' message; FAILURE (typically "line search failed" once
// the loss stops changing in double precision) after progress is not a failure, before any progress
// it is. Exceptions from the objective (the NaN check included) stop the solver (the callback
// aborts it) and are rethrown unchanged.
#include <ceres/first_order_function.h>
#include <ceres/gradient_problem.h>
#include <ceres/gradient_problem_solver.h>
#include <ceres/iteration_callback.h>

#include <cmath>
#include <exception>
#include <string>
#include <vector>

#include "optimize/OptimizerDetail.h"

namespace sl::detail {

namespace {

constexpr double kNudge = 1e-6;

struct Box {
    double lower = 0, width = 1;

    void toX(const double* z, std::vector<double>& x) const {
        for (size_t i = 0; i < x.size(); ++i) {
            const double s = std::sin(z[i]);
            x[i] = clampTo(lower + width * (s * s), lower, lower + width);
        }
    }
};

struct Shared {
    Run* run = nullptr;
    Box box;
    std::exception_ptr error;
    bool stoppedByCallback = false;
};

class BoxedFunction : public ceres::FirstOrderFunction {
  public:
    BoxedFunction(Shared& shared, size_t n) : shared_(shared), x_(n), gx_(n) {}

    bool Evaluate(const double* z, double* cost, double* gradient) const override {
        if (shared_.error) return false;  // the callback aborts at the end of this iteration
        shared_.box.toX(z, x_);
        try {
            *cost = shared_.run->evaluate(
                x_, gradient ? std::span<double>(gx_) : std::span<double>(), true);
        } catch (...) {
            shared_.error = std::current_exception();
            return false;
        }
        if (gradient)
            for (size_t i = 0; i < x_.size(); ++i)
                gradient[i] = gx_[i] * shared_.box.width * std::sin(2.0 * z[i]);
        return true;
    }

    int NumParameters() const override { return static_cast<int>(x_.size()); }

  private:
    Shared& shared_;
    mutable std::vector<double> x_, gx_;
};

class Callback : public ceres::IterationCallback {
  public:
    Callback(Shared& shared, const std::vector<double>& z) : shared_(shared), z_(z), x_(z.size()) {}

    ceres::CallbackReturnType operator()(const ceres::IterationSummary& it) override {
        if (shared_.error) return ceres::SOLVER_ABORT;
        if (it.iteration == 0) return ceres::SOLVER_CONTINUE;  // recorded before Solve()
        // update_state_every_iteration: z_ holds the current iterate.
        shared_.box.toX(z_.data(), x_);
        try {
            // The accepted point was just evaluated, so this is a cache hit.
            const double loss = shared_.run->evaluate(x_, {}, true);
            if (!shared_.run->record(loss, x_)) {
                shared_.stoppedByCallback = true;
                return ceres::SOLVER_TERMINATE_SUCCESSFULLY;
            }
        } catch (...) {
            shared_.error = std::current_exception();
            return ceres::SOLVER_ABORT;
        }
        return ceres::SOLVER_CONTINUE;
    }

  private:
    Shared& shared_;
    const std::vector<double>& z_;
    std::vector<double> x_;
};

}  // namespace

void minimizeCeres(Run& run, std::vector<double>& x) {
    const OptimizerOptions& o = run.options();
    const size_t n = x.size();
    OptimizerSummary& s = run.summary;

    Shared shared;
    shared.run = &run;
    shared.box.lower = run.problem().lower;
    shared.box.width = run.problem().upper - run.problem().lower;

    std::vector<double> z(n);
    for (size_t i = 0; i < n; ++i) {
        const double t = clampTo((x[i] - shared.box.lower) / shared.box.width, kNudge, 1 - kNudge);
        z[i] = std::asin(std::sqrt(t));
    }
    shared.box.toX(z.data(), x);  // the nudged start, exactly as Ceres' first evaluation sees it

    s.settings =
        "Ceres GradientProblemSolver, LBFGS (rank 20), Wolfe line search; "
        "x = lower + w sin^2(z), start nudged by <= 1e-6 w; max_num_iterations = " +
        std::to_string(o.iterations) + ", function_tolerance " +
        formatNumber(o.relativeFunctionTolerance);

    {
        std::vector<double> g(n);
        if (!run.record(run.evaluate(x, g, false), x)) {
            s.termination = "stopped by callback";
            return;
        }
    }

    ceres::GradientProblemSolver::Options options;
    options.line_search_direction_type = ceres::LBFGS;
    options.line_search_type = ceres::WOLFE;
    options.max_num_iterations = o.iterations;
    options.function_tolerance = o.relativeFunctionTolerance;
    options.logging_type = ceres::SILENT;
    options.minimizer_progress_to_stdout = false;
    options.update_state_every_iteration = true;
    Callback callback(shared, z);
    options.callbacks.push_back(&callback);

    ceres::GradientProblem problem(new BoxedFunction(shared, n));  // takes ownership
    ceres::GradientProblemSolver::Summary summary;
    ceres::Solve(options, problem, z.data(), &summary);

    if (shared.error) std::rethrow_exception(shared.error);
    shared.box.toX(z.data(), x);
    switch (summary.termination_type) {
        case ceres::CONVERGENCE:
            s.termination = "converged: " + summary.message;
            break;
        case ceres::NO_CONVERGENCE:
            s.termination = "iteration limit: " + summary.message;
            break;
        case ceres::USER_SUCCESS:
            s.termination = "stopped by callback";
            break;
        default:
            if (shared.stoppedByCallback) {
                s.termination = "stopped by callback";
            } else if (run.progressed()) {
                s.termination = "converged to roundoff (Ceres: " + summary.message + ")";
            } else {
                s.termination = "Ceres failure: " + summary.message;
                s.failed = true;
            }
    }
}

}  // namespace sl::detail
