// What the `optimize` job (app/jobs/OptimizeJob.h) takes and gives, as Ceres's Solver::Options
// and Solver::Summary: OptimizeJobOptions in (and the presets, settings fixed together), an
// OptimizeJobSummary out with one OptimizeRun per λ. The stages that turn one into the other:
// app/jobs/OptimizePlan.h (the options resolved), app/jobs/OptimizeStages.h (T, the
// comparisons, the search, the answer and the judge), app/jobs/OptimizeOutputs.h (OUTDIR).
#pragma once

#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "app/host/ExternalRenderer.h"
#include "app/pipeline/Answer.h"
#include "app/pipeline/Cache.h"
#include "app/pipeline/Defaults.h"
#include "app/pipeline/HeldOut.h"
#include "app/pipeline/InitialState.h"
#include "app/pipeline/Judge.h"
#include "app/pipeline/LossMask.h"
#include "app/pipeline/TrainingNoise.h"
#include "app/pipeline/Transport.h"
#include "app/pipeline/Truth.h"
#include "core/Communicator.h"
#include "detect/ScratchMap.h"
#include "objective/Objective.h"
#include "objective/ObjectiveKind.h"
#include "optimize/BlackBox.h"
#include "optimize/Optimizer.h"

namespace sl {

struct OptimizeJobOptions {
    std::filesystem::path input;              // scene (.json) or transport matrix (.tm)
    std::vector<std::string> sceneOverrides;  // -D key=value on the scene (io/SceneFile.h)
    std::filesystem::path outDir = "out/optimize";
    std::vector<double> lambdas{optimizeDefaults().lambda};
    ObjectiveOptions objective;  // lambda is taken from `lambdas`
    /// unset: the default (app/pipeline/Defaults.h defaultObjective).
    std::optional<ObjectiveKind> objectiveKind;
    /// The starts (several: multistart, the lowest training loss wins); empty: the defaults'
    /// (paper-loop: the paper's const:0.5).
    std::vector<InitialState> starts;
    LossMaskSpec mask;            // the loss's region (app/pipeline/LossMask.h)
    ScratchMapOptions scratch;    // for the scratch mask
    std::filesystem::path truth;  // ground-truth defect mask in height-map space (metrics)
    /// The user's current lamp, the report's "before": a light spec (io/EnvMapIO.h
    /// lightFromSpec: a file, const:V or a preset; empty: the "studio" preset), scored beside
    /// E* and the paper's light.
    std::string compare;
    bool figures = true;  // the report's figures (app/report/OptimizeFigures.h)
    /// The defects objective's regions in height-map space (app/pipeline/Truth.h RegionSpec): the
    /// defects (empty: `truth`, else auto: the defect map of the scene's height map) and the
    /// defect-free reference (empty: the part away from the defects; auto: the part the defect
    /// map leaves unmarked, outside the defects).
    /// Region A against region B (e.g. the chatter half against the clean half) is the same
    /// objective with A as `defects` and B as `reference`.
    RegionSpec defects, reference;
    std::string commandLine;  // how the run was asked for: recorded in summary.json, not parsed
    /// Ctrl-C: write the best E so far (marked "interrupted") instead of leaving OUTDIR as it was.
    bool keepInterrupted = false;
    bool rgb = false;
    HeldOutSource heldOut;  // default: the judge's estimate traced from the scene (cached)
    /// 0: the judge's rounds (app/pipeline/Judge.h judgeInRounds: from kJudgePilotSpp until the
    /// judged scores' standard errors are <= 1 %, at most kJudgeDefaultSpp); else that spp.
    int heldOutSpp = 0;
    int heldOutEvery = 50;  // held-out column of loss.csv every N iterations
    /// method: any row of optimize/Methods.h; iterations: 0 = the method's default budget.
    OptimizerOptions optimizer = optimizeJobOptimizerOptions();
    BlackBoxOptions blackBox;  // fd-adam / spsa: gradients through the renderer
    /// The renderer fd-adam / spsa render through (app/host/ExternalRenderer.h); the training T,
    /// the held-out scores and the judge stay our tracer's.
    RendererKind renderer = RendererKind::Builtin;
    ExternalRendererOptions external;  // povray / command
    PrecomputeOptions precompute;      // used when input is a scene
    /// Noise-aware training (app/pipeline/TrainingNoise.h): without a given spp (precompute.spp
    /// unset, or precompute.autoSpp) the training spp is raised until E*'s train/validation gap is
    /// within precompute.sppTolerance; with a given spp the gap is measured and warned about. Off
    /// for the paper's loop (the paper's experiment), black-box optimizers and MPI ranks.
    /// The most training spp the rule traces; 0: TrainingNoiseOptions' maxSpp scaled to the image
    /// (app/pipeline/TrainingNoise.h sppCapForImage: 512 at 256² and above, 2048 at 128²).
    int noiseMaxSpp = 0;
    /// The defects objective's defect pixels take this many times the training spp (and the
    /// validation estimate's); 0: the rule of app/pipeline/TrainingNoise.h (defectSppFactors, per
    /// label), 1: off.
    int defectSppScale = 0;
    /// The self-checked answer (app/pipeline/Answer.h): the light returned is the best of E*, every
    /// start's result and the references on the validation estimate. False: E* is returned.
    bool selfCheck = true;
    /// Trace only the loss mask's pixels (a file or the scratch map; not `object`): the loss
    /// and E* are the same as with the whole image, for the rays of the region only. The
    /// renders from T are then dark outside the mask (the judge still traces the whole part).
    bool traceMaskOnly = false;
    CacheLocation cache;  // where traced matrices are kept (app/pipeline/Cache.h)
    // The search (app/pipeline/Search.h). estimates: independent estimates of T cycled per step (0:
    // the method's default); continuation: λ factors before λ.
    int estimates = 0;
    std::vector<double> continuation;
    /// The grid the light is searched on (objective/CoarseLight.h). Unset: the noise rule's
    /// (app/pipeline/TrainingNoise.h: one value per texel, coarser while the gap stays large at the
    /// most spp; per texel for a given T, .tm or .shards); set: that grid, the gap only
    /// measured.
    std::optional<LightGrid> lightGrid;
    /// MPI ranks (docs/CLUSTER.md): with more than one, `input` is a .shards list naming one
    /// shard per rank, each rank holds only its own (app/pipeline/Transport.h readShardOfRank),
    /// every rank runs the same optimization in step and rank 0 alone writes OUTDIR. Null: one
    /// process. What needs the whole T in one place is refused (held-out estimates, the
    /// defects objective, black-box optimizers, several estimates of T).
    const Communicator* ranks = nullptr;
};

/// Presets: settings fixed together, one table. "paper": the paper's experiment exactly (eq. 2,
/// λ 30 on mean(E²), E0 = 0.5, Adam lr 0.02 × 100, a fresh sample set of the scene's spp every
/// iteration: 100 estimates of T).
enum class OptimizePreset { Paper };
struct OptimizePresetRow {
    OptimizePreset value;
    const char* name;
    const char* help;
};
std::span<const OptimizePresetRow> optimizePresetTable();
void applyOptimizePreset(OptimizePreset preset, OptimizeJobOptions& options);

struct OptimizeRun {
    double lambda = 0;
    std::filesystem::path dir;
    OptimizerSummary optimizer;
    LossParts initial, final;
    std::string objective;  // what initial, final and heldFinal.own are (ObjectiveKind's name)
    std::optional<HeldOutScore> heldInitial, heldFinal;
    double secondsHeldOutScoring = 0;  // inside the optimizer's time (callback)
    std::string start;                 // the start that won (multistart)
    std::vector<std::pair<std::string, double>> startLosses;
    std::optional<JudgeScore> judged;  // the judge's scores of E* (with the held-out estimate)
    /// ... and of the user's lamp and of the paper's light (eq. 2, Adam from E0 = 0.5 on the
    /// same T), on the same estimate at the same λ.
    std::optional<JudgeScore> judgedLamp, judgedPaper;
    /// The optimized light's judge scores when the answer is a reference (else `judged` is it).
    std::optional<JudgeScore> judgedOptimized;
    /// The judge's rounds for these scores (app/pipeline/Judge.h judgeInRounds): the spp their
    /// standard errors asked for; the held-out curve before the last round is on the first round's
    /// estimate (heldCurveSpp), the held-out figures of the start and of E* on the last.
    JudgedRounds judgeRounds;
    int heldCurveSpp = 0;
    /// E*'s figure (app/pipeline/TrainingNoise.h trainingFigure) on the training and the validation
    /// estimate, and the rule's rounds (the first λ only; later λs keep its spp).
    std::optional<LossParts> validationFinal;
    TrainingNoiseSummary noise;
    /// The self-check (app/pipeline/Answer.h): absent without a validation estimate.
    std::optional<AnswerChoice> answer;
    /// The training loss: the objective the optimizer minimized, through what (our T, or the
    /// renderer of a black-box optimizer: then initial/final hold only its totals).
    std::string lossThrough = "T";
    /// What to know before trusting E*: a failed optimizer, no improvement on the start, an
    /// all-black light, an image without contrast (also in summary.json and the log).
    std::vector<std::string> warnings;
    /// Stopped by an interrupt request (core/Interrupt.h): E* is the best iterate so far.
    bool interrupted = false;
    /// Over MPI ranks: this rank's seconds inside the collectives during the optimization
    /// (part of optimizer.seconds).
    double secondsCollectives = 0;
    /// Where the job's seconds went (`bench jnd`), over every round of the noise rule: tracing
    /// or reading T and the validation estimate, the searches (with their held-out curves), and
    /// the judge (its first estimate, and its rounds scoring the answer); the seconds are the
    /// job's up to this λ.
    double secondsTrace = 0, secondsSearch = 0, secondsJudge = 0;
};

struct OptimizeJobSummary {
    TransportSource transport;
    std::vector<TransportSource> extraEstimates;  // estimates 1..estimates−1 of T
    std::optional<TransportSource> heldOut;       // the judge's estimate
    std::optional<TransportSource>
        validation;  // the validation estimate (app/pipeline/TrainingNoise.h)
    size_t maskPixels = 0;
    std::vector<OptimizeRun> runs;
    bool interrupted = false;  // a run was interrupted; the λs after it were not run
};

}  // namespace sl
