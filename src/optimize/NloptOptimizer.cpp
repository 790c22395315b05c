// NLopt methods (NLopt 2.7, C++ API nlopt.hpp), the box [lower, upper] as bound constraints.
//
//   lbfgs   LD_LBFGS   Luksan's limited-memory BFGS with simple bounds (NLopt's default storage).
//   mma     LD_MMA     Svanberg's method of moving asymptotes (unconstrained but for the box).
//   ccsaq   LD_CCSAQ   Svanberg's CCSA with quadratic approximations.
//   mlsl    G_MLSL_LDS multi-level single-linkage: each MLSL iteration adds `population` (0 =
//                      NLopt's 4) sample points (Sobol' up to 1111 dimensions, pseudo-random
//                      above; both deterministic given nlopt::srand(seed), called before every
//                      run) and starts a local search from the promising ones. The local optimizer
//                      is LD_LBFGS with ftol_rel = relativeFunctionTolerance if set, else 1e-8
//                      (a relative loss change of 1e-8 is far below anything visible in the
//                      render), and xtol_rel = 1e-6 — loose enough that a local search ends in tens
//                      of evaluations and leaves budget for other starts, tight enough that the
//                      returned minimum is accurate to ~1e-6. MLSL never converges by itself: it
//                      stops at maxeval = `iterations` (samples + all local-search evaluations),
//                      so give it thousands. NLopt's random generator is process-wide: concurrent
//                      mlsl runs are not deterministic.
//
// Iteration = an evaluation that improves on the best loss so far; the history and the
// callback see the best point, and x returns the best point evaluated (NLopt's own choice for
// these algorithms too). `iterations` = maxeval. relativeFunctionTolerance = ftol_rel (0 = off;
// lbfgs/mma/ccsaq then stop at maxeval or when NLopt's own tests say converged).
//
// Result codes → termination: SUCCESS/FTOL/XTOL/MAXEVAL/MAXTIME/STOPVAL as such; a
// roundoff-limited stop (typical for L-BFGS once the loss no longer changes in double precision)
// after progress is "converged to roundoff" and not a failure, before any progress it is a
// failure (often a gradient that does not match the loss); NLOPT_FAILURE is a failure with
// NLopt's message (Luksan's L-BFGS returns it when its line search finds no decrease: a wrong
// gradient, or a kink such as |ΔI| = 0 in L_grad). Inside MLSL a failed or roundoff-limited
// local search ends the whole MLSL run (NLopt's mlsl.c), so mlsl on a kinked objective may stop
// early: prefer the objective's smooth |x| for lbfgs and mlsl. A forced stop is either our callback
// stop or an exception from the objective (NaN check included), which is rethrown unchanged after
// NLopt has unwound. In every case x is the best point evaluated, which lies in the box.
#include <cmath>
#include <exception>
#include <new>
#include <nlopt.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/Error.h"
#include "optimize/OptimizerDetail.h"

namespace sl::detail {

namespace {

struct Context {
    Run* run = nullptr;
    nlopt::opt* opt = nullptr;
    double bestLoss = 0;
    std::vector<double> bestX;
    bool stoppedByCallback = false;
    std::exception_ptr error;
    int requests = 0;  // calls from NLopt (maxeval counts these, cache hits included)
};

// The nlopt_func NLopt calls. Must not throw: errors are stored and NLopt is asked to stop.
double objective(unsigned n, const double* x, double* grad, void* data) {
    Context& c = *static_cast<Context*>(data);
    if (c.error || c.stoppedByCallback) {  // a local search that has not seen the stop yet
        c.opt->force_stop();
        if (grad)
            for (unsigned i = 0; i < n; ++i) grad[i] = 0;
        return HUGE_VAL;
    }
    try {
        ++c.requests;
        std::span<const double> xs(x, n);
        const double f =
            c.run->evaluate(xs, grad ? std::span<double>(grad, n) : std::span<double>(), true);
        if (f < c.bestLoss) {
            c.bestLoss = f;
            c.bestX.assign(x, x + n);
            if (!c.run->record(f, xs)) {
                c.stoppedByCallback = true;
                c.opt->force_stop();
            }
        }
        return f;
    } catch (...) {
        c.error = std::current_exception();
        c.opt->force_stop();
        if (grad)
            for (unsigned i = 0; i < n; ++i) grad[i] = 0;
        return HUGE_VAL;
    }
}

std::string resultText(nlopt::result r, const OptimizerOptions& o) {
    switch (r) {
        case nlopt::SUCCESS:
            return "converged (NLopt success)";
        case nlopt::STOPVAL_REACHED:
            return "stop value reached";
        case nlopt::FTOL_REACHED:
            return "relative function tolerance reached (" +
                   formatNumber(o.relativeFunctionTolerance) + ")";
        case nlopt::XTOL_REACHED:
            return "x tolerance reached (x stopped changing)";
        case nlopt::MAXEVAL_REACHED:
            return "evaluation limit reached (maxeval = iterations = " +
                   std::to_string(o.iterations) + ")";
        case nlopt::MAXTIME_REACHED:
            return "time limit reached";
        default:
            return "NLopt result " + std::to_string(static_cast<int>(r));
    }
}

}  // namespace

void minimizeNlopt(Run& run, std::vector<double>& x) {
    const OptimizerOptions& o = run.options();
    const unsigned n = static_cast<unsigned>(run.dimension());
    OptimizerSummary& s = run.summary;

    const bool mlsl = o.method == OptimizerMethod::Mlsl;
    nlopt::algorithm algorithm = nlopt::LD_LBFGS;
    switch (o.method) {
        case OptimizerMethod::Mma:
            algorithm = nlopt::LD_MMA;
            break;
        case OptimizerMethod::Ccsaq:
            algorithm = nlopt::LD_CCSAQ;
            break;
        case OptimizerMethod::Mlsl:
            algorithm = nlopt::G_MLSL_LDS;
            break;
        case OptimizerMethod::Tnewton:
            algorithm = nlopt::LD_TNEWTON_PRECOND_RESTART;
            break;
        default:  // lbfgs (minimize() sends only NLopt's methods here)
            break;
    }

    nlopt::opt opt(algorithm, n);
    opt.set_lower_bounds(run.problem().lower);
    opt.set_upper_bounds(run.problem().upper);
    opt.set_maxeval(o.iterations);
    s.settings = std::string("NLopt ") + opt.get_algorithm_name() +
                 "; maxeval = iterations = " + std::to_string(o.iterations);
    if (mlsl) {
        nlopt::opt local(nlopt::LD_LBFGS, n);
        const double localFtol =
            o.relativeFunctionTolerance > 0 ? o.relativeFunctionTolerance : 1e-8;
        local.set_ftol_rel(localFtol);
        local.set_xtol_rel(1e-6);
        opt.set_local_optimizer(local);
        if (o.population > 0) opt.set_population(static_cast<unsigned>(o.population));
        s.settings += "; local LD_LBFGS ftol_rel " + formatNumber(localFtol) +
                      ", xtol_rel 1e-06; population " +
                      (o.population > 0 ? std::to_string(o.population) : std::string("4")) +
                      "; seed " + std::to_string(o.seed);
    } else {
        opt.set_ftol_rel(o.relativeFunctionTolerance);
        s.settings += "; ftol_rel " + formatNumber(o.relativeFunctionTolerance);
    }
    nlopt::srand(static_cast<unsigned long>(o.seed));

    // The initial point: iteration 0. NLopt's own first evaluation at x then hits the cache.
    Context c;
    c.run = &run;
    c.opt = &opt;
    {
        std::vector<double> g(n);
        c.bestLoss = run.evaluate(x, g, false);
        c.bestX = x;
        if (!run.record(c.bestLoss, x)) {
            s.termination = "stopped by callback";
            return;
        }
    }
    opt.set_min_objective(objective, &c);

    std::vector<double> xs = x;
    double fx = 0;
    std::string outcome;
    const int evaluationsBefore = run.evaluations() - 1;  // NLopt's first request is x0's
    try {
        const nlopt::result r = opt.optimize(xs, fx);
        outcome = resultText(r, o);
        const int repeats = c.requests - (run.evaluations() - evaluationsBefore);
        if (r == nlopt::MAXEVAL_REACHED && repeats > 0)
            outcome += "; " + std::to_string(repeats) +
                       " of NLopt's requests repeated an evaluated point (not re-evaluated)";
    } catch (const nlopt::roundoff_limited&) {
        if (run.progressed())
            outcome = mlsl ? "a local search hit roundoff, which ends MLSL (not an error)"
                           : "converged to roundoff (NLopt roundoff-limited after progress)";
        else {
            outcome = "roundoff-limited before any progress (does the gradient match the loss?)";
            s.failed = true;
        }
    } catch (const nlopt::forced_stop&) {
        if (!c.error && !c.stoppedByCallback) {
            outcome = "forced stop";
            s.failed = true;
        }
    } catch (const std::bad_alloc&) {
        throw;
    } catch (const std::invalid_argument& e) {
        if (!c.error && !c.stoppedByCallback)
            throw std::runtime_error("minimize (method '" + s.method +
                                     "'): NLopt rejected its arguments: " + e.what());
    } catch (const std::runtime_error& e) {  // NLOPT_FAILURE
        if (!c.error && !c.stoppedByCallback) {
            const std::string what = e.what();
            outcome = "NLopt failure";
            if (what != "nlopt failure") outcome += ": " + what;
            if (o.method == OptimizerMethod::Lbfgs || mlsl)
                outcome += std::string(mlsl ? " in a local L-BFGS search (ends MLSL)" : "") +
                           "; L-BFGS found no decrease along its direction: the loss is flat "
                           "to its precision there (near an optimum; the best point is kept), "
                           "a kink (eq. 2 and U: try their smooth |x|, " +
                           option("smooth-abs") + "), or a gradient that does not match the loss";
            s.failed = true;
        }
    }
    // Our own stop reasons win over whatever code NLopt returned on the way out (a local
    // search inside MLSL may report roundoff or failure after being stopped).
    if (c.error) std::rethrow_exception(c.error);
    s.termination = c.stoppedByCallback ? "stopped by callback" : outcome;
    s.failed = s.failed && !c.stoppedByCallback;
    x = c.bestX;
}

}  // namespace sl::detail
