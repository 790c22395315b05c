#include "app/jobs/OptimizeOptions.h"

#include "app/pipeline/InitialState.h"
#include "optimize/PaperSetup.h"

namespace sl {

namespace {

constexpr OptimizePresetRow kPresets[] = {
    {OptimizePreset::Paper, "paper",
     "the paper's experiment exactly (eq. 2, lambda 30 on mean(E^2), Adam lr 0.02 x 100 from E0 "
     "= 0.5; a fresh estimate of T at the scene's spp every step: 100 estimates)"},
};

}  // namespace

std::span<const OptimizePresetRow> optimizePresetTable() {
    return kPresets;
}

void applyOptimizePreset(OptimizePreset preset, OptimizeJobOptions& o) {
    switch (preset) {
        case OptimizePreset::Paper:  // optimize/PaperSetup.h: one fresh estimate per step
            o.optimizer.method = OptimizerMethod::PaperLoop;
            o.optimizer.iterations = kPaperSetup.steps;
            o.optimizer.learningRate = kPaperSetup.learningRate;
            o.lambdas = {kPaperSetup.lambda};
            o.objective.reg = kPaperSetup.reg;
            o.starts = {parseInitialState(kPaperSetup.startSpec)};
            o.objectiveKind = kPaperSetup.objective;
            o.continuation.clear();
            o.estimates = kPaperExperimentEstimates;
            break;
    }
}

}  // namespace sl
