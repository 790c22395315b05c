#include "optimize/Methods.h"

#include "core/Registry.h"
#include "optimize/PaperSetup.h"

namespace sl {

namespace {

using M = OptimizerMethod;
using G = GradientSource;
constexpr BudgetUnit kSteps = BudgetUnit::Steps, kEvals = BudgetUnit::Evaluations;

// clang-format off
constexpr OptimizerMethodRow kMethods[] = {
    {M::Adam, "adam", "Adam as Mitsuba 3 runs it (the paper: lr 0.02, 100 steps)",
     G::Exact, "one step (one gradient evaluation)", kSteps, kPaperSetup.steps, M::Adam, 1},
    {M::Lbfgs, "lbfgs", "NLopt's L-BFGS with the [0, 1] box as bounds",
     G::Exact, "one evaluation (NLopt's maxeval)", kEvals, 2000, M::Lbfgs, 1},
    {M::Mma, "mma", "NLopt's method of moving asymptotes",
     G::Exact, "one evaluation (NLopt's maxeval)", kEvals, 2000, M::Mma, 1},
    {M::Ccsaq, "ccsaq", "NLopt's CCSA with quadratic approximations",
     G::Exact, "one evaluation (NLopt's maxeval)", kEvals, 2000, M::Ccsaq, 1},
    {M::Mlsl, "mlsl", "NLopt's multi-level single-linkage global search, L-BFGS locally",
     G::Exact, "one evaluation (NLopt's maxeval, samples and local searches included)", kEvals, 2000,
     M::Mlsl, 1},
    {M::CeresLbfgs, "ceres-lbfgs", "Ceres' L-BFGS with a Wolfe line search (box by x = sin²z)",
     G::Exact, "one accepted line-search step", kSteps, 2000, M::CeresLbfgs, 1},
    {M::FdAdam, "fd-adam", "Adam on finite-difference gradients through the renderer",
     G::Renderer, "one step (2N+1 renders central, N+1 forward)", kSteps, 100, M::FdAdam, 1},
    {M::Spsa, "spsa", "projected SPSA through the renderer",
     G::Renderer, "one step (2q renders)", kSteps, 100, M::Spsa, 1},
    {M::PaperLoop, "paper-loop",
     "the paper's loop on T: eq. 2, Adam from 0.5, a fresh estimate of T every step",
     G::Exact, "one Adam step on the next estimate of T", kSteps, kPaperSetup.steps, M::Adam,
     kPaperLoopEstimates},
    {M::Tnewton, "tnewton", "NLopt's preconditioned truncated Newton with restarts",
     G::Exact, "one evaluation (NLopt's maxeval)", kEvals, 2000, M::Tnewton, 1},
    {M::NewtonTr, "newton-tr",
     "projected truncated Newton in a trust region on the problem's exact Hessian products "
     "(the unbiased objective through T's Gram); NLopt's L-BFGS where it offers none",
     G::Exact, "one accepted step (one or more evaluations and Hessian products)", kSteps, 500,
     M::NewtonTr, 1},
};
// clang-format on

}  // namespace

std::span<const OptimizerMethodRow> optimizerMethodTable() {
    return kMethods;
}

const OptimizerMethodRow& methodRow(OptimizerMethod method) {
    return registryRow(optimizerMethodTable(), method);
}

OptimizerMethod parseOptimizerMethod(std::string_view name, const std::string& where) {
    return parseRegistryName(optimizerMethodTable(), name, where).value;
}

std::vector<std::string> optimizerMethods() {
    std::vector<std::string> names;
    for (const OptimizerMethodRow& r : optimizerMethodTable())
        if (r.gradient == GradientSource::Exact && r.runs == r.value) names.push_back(r.name);
    return names;
}

std::vector<std::string> blackBoxMethods() {
    std::vector<std::string> names;
    for (const OptimizerMethodRow& r : optimizerMethodTable())
        if (r.gradient == GradientSource::Renderer) names.push_back(r.name);
    return names;
}

}  // namespace sl
