// The optimize job's stage 0 (app/jobs/OptimizeJob.h): its options with every default resolved
// from the tables and checked, the Plan every later stage reads (app/jobs/OptimizeStages.h,
// app/jobs/OptimizeOutputs.h).
#pragma once

#include <filesystem>

#include "app/jobs/OptimizeOptions.h"
#include "app/pipeline/TrainingNoise.h"
#include "core/Communicator.h"
#include "optimize/Methods.h"
#include "optimize/Optimizer.h"

namespace sl::optimizejob {

/// Stage 0: the options with every default filled in (budget, starts, estimates) and checked; a
/// method that stands for a set-up (paper-loop) expanded into it.
struct Plan {
    OptimizeJobOptions o;
    OptimizerMethod requested = OptimizerMethod::Lbfgs;  // the name the results carry
    bool blackBox = false;                               // gradients through the renderer
    bool tmInput = false;
    /// Noise-aware training (app/pipeline/TrainingNoise.h): `validate` traces the validation
    /// estimate (the gap and the self-check need it); `noise.adapt` raises the training spp.
    bool validate = false;
    TrainingNoiseOptions noise;
    /// V's spp when its own noise hides the gap (app/pipeline/TrainingNoise.h step 4; 0: T's).
    int validationSpp = 0;
    /// The defect pixels of the defects objective take more samples (app/pipeline/TrainingNoise.h
    /// defectSppScale); not for black boxes (their renders take one spp) nor shards.
    bool superSampleDefects = false;
    /// The optimizer as asked for, before its default budget was filled in: a search resolves
    /// it for its objective (app/pipeline/Defaults.h resolveOptimizer: the default budget's
    /// stall stop; a given budget runs to its end).
    OptimizerOptions requestedOptimizer;
    const Communicator* ranks = nullptr;  // MPI ranks holding shards of T (null: one process)
    bool writes() const { return !ranks || ranks->root(); }  // this process writes OUTDIR
    std::filesystem::path cacheDir;
    std::filesystem::path writeDir;  // where OUTDIR is staged (io/StagedDirectory.h)
    /// Where a path under OUTDIR is written while staged.
    std::filesystem::path staged(const std::filesystem::path& underOutDir) const {
        return (writeDir / underOutDir.lexically_relative(o.outDir)).lexically_normal();
    }
};

Plan plan(const OptimizeJobOptions& options);

}  // namespace sl::optimizejob
