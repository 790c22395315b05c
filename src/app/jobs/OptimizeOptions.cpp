#include "app/jobs/OptimizeOptions.h"

#include "app/pipeline/InitialState.h"

namespace sl {

namespace {

constexpr OptimizePresetRow kPresets[] = {
    {OptimizePreset::Paper, "paper",
     "the paper's experiment exactly (eq. 2, lambda 30, E0 = 0.5, Adam lr 0.02 x 100, a fresh "
     "sample set of the scene's spp every iteration: 100 estimates of T)"},
};

}  // namespace

std::span<const OptimizePresetRow> optimizePresetTable() {
    return kPresets;
}

void applyOptimizePreset(OptimizePreset preset, OptimizeJobOptions& o) {
    switch (preset) {
        case OptimizePreset::Paper:
            o.optimizer.method = OptimizerMethod::PaperLoop;
            o.optimizer.iterations = 100;
            o.optimizer.learningRate = 0.02;
            o.lambdas = {30.0};
            o.objective.reg = RegTarget::EnvMap;
            o.starts = {parseInitialState("const:0.5")};
            o.objectiveKind = ObjectiveKind::Paper;
            o.continuation.clear();
            o.planes = 100;
            break;
    }
}

}  // namespace sl
