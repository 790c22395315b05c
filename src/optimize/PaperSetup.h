// The paper's set-up (Motegi et al., docs/DESIGN.md "The optimize report"), written once: eq. 2
// at λ 30 on mean(E²), Mitsuba 3's Adam at lr 0.02 for 100 steps from E0 = 0.5. Three uses derive
// from it and differ only in the estimates of T the steps read, named here:
//   - the paper's experiment, `optimize --preset paper` (app/jobs/OptimizeOptions.cpp
//     applyOptimizePreset): a fresh estimate of T at the scene's spp every step, so
//     kPaperExperimentEstimates (= the steps) estimates;
//   - the `paper-loop` optimizer (optimize/Methods.cpp, the race's baseline in app/bench/Race.cpp):
//     the same loop cycled over kPaperLoopEstimates estimates (`--estimates` changes it; the race
//     traces each at 16 spp);
//   - the paper's light, optimize's comparison (app/jobs/OptimizeStages.cpp paperLight, through the
//     preset): the same steps on one estimate, the training T itself, kept in the cache by T's
//     fingerprint.
// The objective's own default λ (objective/Objective.h ObjectiveOptions) and optimize's
// (app/pipeline/Defaults.h OptimizeDefaults) are the paper's too (tests/test_defaults.cpp checks).
#pragma once

#include <string>

#include "objective/Objective.h"
#include "objective/ObjectiveKind.h"

namespace sl {

struct PaperSetup {
    ObjectiveKind objective = ObjectiveKind::Paper;  // eq. 2
    double lambda = 30.0;                            // the regulariser's weight
    RegTarget reg = RegTarget::EnvMap;               // on mean(E²)
    double learningRate = 0.02;  // Mitsuba 3's Adam (optimize/Optimizer.h), clamped to [0, 1]
    int steps = 100;
    double start = 0.5;                   // E0, a constant light
    const char* startSpec = "const:0.5";  // ... as app/pipeline/InitialState.h names it
};
inline constexpr PaperSetup kPaperSetup{};

/// The paper's experiment: one fresh estimate of T per step.
inline constexpr int kPaperExperimentEstimates = kPaperSetup.steps;
/// paper-loop: the loop cycled over this many estimates (a cost compromise: 8 traces, not 100).
inline constexpr int kPaperLoopEstimates = 8;

/// "eq. 2, lambda 30 on mean(E^2), Adam lr 0.02 x 100 from E0 = 0.5": the set-up in words, as the
/// summary and the help text say it.
std::string paperSetupText();

}  // namespace sl
