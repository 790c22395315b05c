// The optimize job's stages 1–4 (app/jobs/OptimizeJob.h runOptimizeJob calls them in order over
// one Plan, app/jobs/OptimizePlan.h): loading T (training estimates, held-out, validation), the
// runs' inputs (mask, truth, starts) and the comparisons (the user's lamp, the paper's light, the
// regions), then per λ the search, the self-checked answer and the judge's scores. What every λ
// shares is one Inputs; one λ's result is a LambdaResult, which app/jobs/OptimizeOutputs.h writes.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "app/jobs/OptimizePlan.h"
#include "app/pipeline/LossMask.h"
#include "app/pipeline/PartOfTransport.h"
#include "app/pipeline/Search.h"
#include "app/pipeline/Transport.h"
#include "app/pipeline/Truth.h"
#include "app/report/OptimizeFigures.h"
#include "core/Communicator.h"
#include "core/RegionLabel.h"
#include "core/Registry.h"
#include "io/MaskIO.h"
#include "objective/Metrics.h"
#include "objective/ObjectiveKind.h"
#include "perception/ViewingModel.h"
#include "scene/Scene.h"
#include "transport/TransportMatrix.h"

namespace sl::optimizejob {

/// The visibility metrics (objective/Metrics.h) of T's image under e on the loss mask (the
/// stages' E0 and the outputs' E*).
VisibilityMetrics metricsFor(const TransportMatrix& t, const std::vector<double>& image,
                             const std::vector<uint8_t>& mask, const std::vector<double>& e,
                             bool rgb, const std::vector<uint8_t>& truth);
/// The render a person looks at: RGB when T is RGB, else luminance. Over MPI ranks t is this
/// rank's shard (the rows of `shard`) and the image is put together over the ranks.
std::vector<double> renderImage(const TransportMatrix& t, const std::vector<double>& e,
                                const RowShard& shard);

/// What every λ run of the job shares.
struct Inputs {
    const Communicator* ranks = nullptr;  // Plan::ranks
    RowShard shard;                       // the rows of T this rank holds (over MPI ranks)
    std::unique_ptr<Scene> scene;         // loaded once; from T's provenance for a .tm when needed
    /// A .tm's part without its height map (app/pipeline/PartOfTransport.h): set, with the scene
    /// unloaded, when what the run needs of it is cached; kept beside T once the scene is loaded.
    std::optional<PartOfTransport> part;
    ObjectiveKind kind = ObjectiveKind::Unbiased;
    bool onHalves() const { return registryRow(objectiveKindTable(), kind).planes == 2; }
    std::vector<uint8_t> defects, reference;  // the defects objective's regions (image)
    size_t unjudgedRegions = 0;  // auto: the regions the defect map could not judge (Truth.h)
    double unjudgedShare = 0;    // and their share of the height map
    /// The training trace's per-pixel sample multipliers (app/pipeline/TrainingNoise.h
    /// defectSppScale; empty: none), chosen on the first load from the scene and the regions, kept
    /// after.
    std::optional<std::vector<uint8_t>> sppScale;
    std::vector<const TransportMatrix*> set;  // the training estimates of T
    LossMask mask;
    std::vector<uint8_t> truth;                    // the truth mask in the image (metrics), 255/0
    std::vector<std::vector<double>> startValues;  // E0 of every start
    std::vector<double> image0;                    // T·E0 of the first start
    VisibilityMetrics metricsInitial;
    // The comparisons (prepareComparisons): the user's lamp and the paper's light on T, and the
    // regions the judge scores and the report outlines (truth, else defects, else a drawn mask).
    std::string lampName;
    std::vector<double> lampE, paperE;
    std::vector<uint8_t> regionLabels;  // image space, 0 = none
    std::vector<RegionLabel> regionLegend;
    std::vector<uint8_t> regionReference;  // the defect region's reference (empty: the default)
    std::string regionSource;              // where the regions come from ("" = none)
    /// defects, reference, truth, truthLabels, lampName and lampE depend on the scene and the
    /// options, not on T: once set (the first load), a training-noise round that traces T again
    /// keeps them instead of projecting the regions (or computing the defect map) again.
    bool sceneParts = false;
    LabelMask truthLabels;  // the truth projected into the image, its legend (truth given)
    /// The training trace's resolved options and seed (what the validation estimate repeats
    /// with its own seed); unset for a .tm.
    std::optional<PrecomputeOptions> trained;
    uint64_t trainingSeed = 0;
};

/// Stage 1: the scene and the training estimates of T (traced or cached, or the .tm); `spp`:
/// the noise-aware rule's choice (app/pipeline/TrainingNoise.h), over any other (0: none).
void loadTraining(const Plan& p, Inputs& in, OptimizeJobSummary& job, int spp);
/// Stage 2: the independent estimate every result is scored on.
void loadHeldOut(const Plan& p, const Inputs& in, OptimizeJobSummary& job);
/// Stage 2b: the validation estimate (app/pipeline/TrainingNoise.h): the training trace again with
/// its own seed, two sample sets; for a .tm, T's recorded spp and path length on its scene.
void loadValidation(const Plan& p, Inputs& in, OptimizeJobSummary& job);
/// The objective in use through the validation estimate (its figure of E* and the gap's SE).
ObjectiveOnT validationObjective(const Inputs& in, const OptimizeJobSummary& job,
                                 const ObjectiveOptions& oo, bool rgb);
RegionSpec defectRegion(const OptimizeJobOptions& o);
/// Stage 3: the loss mask, the truth, every start's E0 and what E0 shows (the same for every λ).
void prepareRuns(const Plan& p, Inputs& in, OptimizeJobSummary& job);
/// Stage 3b: what E* is compared with (the user's lamp, the paper's light) and the regions the
/// judge scores and the report outlines.
void prepareComparisons(const Plan& p, Inputs& in, const OptimizeJobSummary& job);

inline constexpr const char* kLossCsvHeader =
    "iteration,evaluations,loss,L_grad,L_reg,seconds,heldout_loss,heldout_paper_loss,heldout_U";

/// One λ's optimization: E* and loss.csv's rows.
struct LambdaResult {
    OptimizeRun run;
    std::vector<double> e;  // the answer (app/pipeline/Answer.h): E*, or the reference that beat it
    std::vector<double> optimizedE;  // E* when the answer is a reference (else empty)
    std::vector<std::vector<double>> startResults;  // every start's E (multistart)
    /// The lights the noise rule searched on finer grids at this run's spp before E*'s
    /// (app/pipeline/TrainingNoise.h step 5), named with their grid and gap: the self-check's
    /// fallback.
    std::vector<std::pair<std::string, std::vector<double>>> finer;
    std::vector<std::string> rows;
    LossCurve curve;                        // loss.csv's loss and held-out loss, for the loss plot
    LossParts lampTraining, paperTraining;  // the lamp's and the paper's light on T at λ
};

/// How a person sees the images (the judge's JND): the scene's viewing model, the default one
/// when only T is at hand.
ViewingModel viewingOf(const Inputs& in);
/// The objective's options at λ; the jnd measure sees the image as the judge does (viewingOf).
ObjectiveOptions objectiveAt(const Plan& p, const Inputs& in, double lambda);
/// Stage 4: one λ run (the search on T, or the black box through the renderer), its held-out
/// scores and the judge's.
LambdaResult optimizeLambda(const Plan& p, const Inputs& in, const OptimizeJobSummary& job,
                            double lambda);
/// Stage 4b: the self-checked answer (app/pipeline/Answer.h) on the validation estimate: E*, every
/// other start's result and the references; a reference that wins becomes the answer and E*
/// is kept beside it.
void checkAnswer(const Plan& p, const Inputs& in, const OptimizeJobSummary& job, LambdaResult& r);
/// Stage 4c: the judge's scores (the held-out estimate, at this run's λ) of the answer, the
/// user's lamp, the paper's light and, when a reference is the answer, E*; the warnings.
void judgeRun(const Plan& p, const Inputs& in, OptimizeJobSummary& job, LambdaResult& r);

}  // namespace sl::optimizejob
