// The optimizer methods: one table (core/Registry.h), the only list of them. Each row says
// what the method is, where its gradient comes from, what one unit of its budget is and the
// budget it gets when none is given. `minimize()` (Optimizer.h) runs the exact-gradient methods,
// `minimizeBlackBox()` (BlackBox.h) the ones through the renderer; `paper-loop` is Adam on a
// loss that cycles through independent estimates of T (the optimize job sets it up).
//
// Adding a method (docs/DESIGN.md "Add an optimizer"): its enum value here, one row in
// Methods.cpp's table, and its code where the compiler's -Wswitch points (Optimizer.cpp's
// dispatch: a method of its own in its own file, declared in OptimizerDetail.h, as
// NewtonOptimizer.cpp; NloptOptimizer.cpp's switch for an NLopt algorithm).
#pragma once

#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace sl {

enum class OptimizerMethod {
    Adam,
    Lbfgs,
    Mma,
    Ccsaq,
    Mlsl,
    CeresLbfgs,
    FdAdam,
    Spsa,
    PaperLoop,
    Tnewton,
    NewtonTr
};

/// Where a method's gradient comes from.
enum class GradientSource {
    Exact,    // the problem's own gradient (through T: exact for the sampled estimate)
    Renderer  // estimated from renders of the scene (a black box): finite differences, SPSA
};

/// What the budget ("iterations") counts.
enum class BudgetUnit { Steps, Evaluations };

struct OptimizerMethodRow {
    OptimizerMethod value;
    const char* name;
    const char* help;
    GradientSource gradient;
    const char* iteration;  // what one unit of the budget ("iterations") is
    BudgetUnit budget;      // ... counted in the summary's iterations or evaluations
    int defaultBudget;      // iterations when none is given
    OptimizerMethod runs;   // the method that does the work (paper-loop: adam)
    int defaultEstimates;   // independent estimates of T cycled per step when none is given
};

std::span<const OptimizerMethodRow> optimizerMethodTable();
const OptimizerMethodRow& methodRow(OptimizerMethod method);
inline const char* methodName(OptimizerMethod method) {
    return methodRow(method).name;
}
/// The method named `name`; InputError naming `where` and listing every name otherwise.
OptimizerMethod parseOptimizerMethod(std::string_view name,
                                     const std::string& where = "optimizer method");

/// Names of the methods minimize() runs itself (exact gradient, no set-up of their own).
std::vector<std::string> optimizerMethods();
/// Names of the methods minimizeBlackBox() runs (gradients through the renderer).
std::vector<std::string> blackBoxMethods();

}  // namespace sl
