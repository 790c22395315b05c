// Noise-aware training (docs/DESIGN.md "Noise is the trap"): how many samples per pixel the
// training estimate of T needs so that the optimum does not fit its noise.
//
// An optimizer that minimizes a loss on one Monte Carlo estimate of T finds the light that is
// best on that estimate: part of its score is the estimate's noise, which an independent
// estimate does not share. The rule measures that directly, on the part and for the objective
// in use:
//
//   1. T (the training estimate, spp n) and V (the validation estimate: the same scene, spp and
//      path length, two sample sets, the seed training seed + kValidationSeedOffset, disjoint
//      from every training seed and from the judge's) are traced (both cached);
//   2. the search runs on T as it would anyway; its E* is scored on T and on V;
//   3. the gap (trainingGap) is how much better E* looks on T than on V, relative to V:
//        paper, unbiased (losses, lower is better):  gap = (L_V − L_T) / L_V
//        defects (visibility exp(−L_vis/2), higher is better): gap = (v_T − v_V) / v_V
//   4. gap ≤ maxGap: n is kept. Otherwise, the part of the gap the noise makes falls as 1/spp
//      (the optimizer's gain on noise is proportional to the noise's variance), so the next n is
//      the smallest power of two ≥ 2n with gap·n/n' ≤ maxGap/2 (half the tolerance, so one more
//      trace usually settles it), at most kMaxSppGrowth·n (a gap far above the tolerance is
//      often a cliff the noise opened — e.g. the defect objective's reference energy pushed
//      below its floor — which closes long before 1/spp predicts) and at most maxSpp; back to 1.
//   5. At maxSpp (or a given spp) with the gap still above maxGap, the light's degrees of
//      freedom are the other knob: the search runs again on the same T and V with the light on
//      a coarser grid of nodes (objective/CoarseLight.h), each step √2 fewer nodes per side
//      (nextLightGrid), until the gap is within maxGap or the grid has fewer than
//      kCoarsestLightNodes nodes. The optimizer's gain on noise grows with the directions it
//      can combine: on four held-out parts at 512 spp (defects objective) the gap was 17-166 %
//      per texel and 0.1-7 % on 24×12 nodes, at 0.8-0.98 of the per-texel light's visibility
//      by the judge. A search on fewer nodes is also faster (fewer, cheaper evaluations), so
//      a step costs a few seconds and no trace.
//
// A given spp is kept: its gap is still measured, and a gap above maxGap is warned about. When
// maxSpp is reached above maxGap, the run says the light is not trustworthy on its own and the
// self-checked answer (app/Answer.h) decides against the references.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "app/Judge.h"
#include "app/Transport.h"
#include "objective/CoarseLight.h"
#include "objective/Objective.h"
#include "objective/ObjectiveKind.h"

namespace sl {

/// Region supersampling (docs/DESIGN.md "Noise is the trap"): the defects objective's g(D) is
/// a mean over the few pixel pairs of the defect region (often 1-5 % of the part), so at any spp
/// its noise dwarfs the reference's (thousands of pairs) and it is what the optimum fits. The
/// defect pixels take kDefectSppScale times the spp (a per-pixel multiplier of the trace,
/// RenderOptions::sppScale), or the largest power of two below it whose extra samples stay
/// within kDefectSppBudget of the part's: the noise of g(D) falls by that factor for a fraction
/// of the cost of raising spp everywhere.
inline constexpr int kDefectSppScale = 32;
inline constexpr double kDefectSppBudget = 0.5;

/// The multiplier of the defect pixels by the rule above (1 when none is affordable):
/// `defectPixels` of the `partPixels` the camera sees of the part.
int defectSppFactor(size_t defectPixels, size_t partPixels);
/// The per-pixel multipliers: `factor` on the nonzero pixels of `defects`, 1 elsewhere; empty
/// when factor is 1 (the plain trace).
std::vector<uint8_t> defectSppScale(const std::vector<uint8_t>& defects, int factor);

/// The validation estimate's seed: the training seed plus this ("valid"). It is not in any
/// training seed range a user can reach with --planes (< 2^20) and not the judge's seed.
inline constexpr uint64_t kValidationSeedOffset = 0x76616C6964ULL << 20;

/// The most one round multiplies the training spp by. 8: with the defect pixels supersampled
/// the defects objective's gap at 64 spp still predicts thousands of spp, and every round is
/// traced and searched from scratch (the last round's T and E* do not depend on the rounds
/// before it), so a 64 → 256 → 512 ladder spent a third of its time on the 256 round.
inline constexpr int kMaxSppGrowth = 8;

/// The coarsest light grid the rule tries (step 5): below this many nodes a light cannot aim
/// at a lay direction any more (a 9×4 grid's nodes are 40° apart in azimuth).
inline constexpr int kCoarsestLightNodes = 32;

/// The next coarser grid of step 5 after `grid` on an envWidth × envHeight env map: each side
/// divided by √2 (rounded, the height at least 2); nullopt below kCoarsestLightNodes nodes.
std::optional<LightGrid> nextLightGrid(const LightGrid& grid, int envWidth, int envHeight);

struct TrainingNoiseOptions {
    /// Measure the gap and raise spp until it is within maxGap (false: keep the given spp and
    /// only warn).
    bool adapt = true;
    /// Coarsen the light's grid (step 5) when the spp cannot be raised and the gap is large
    /// (false: the grid given is kept).
    bool adaptGrid = true;
    double maxGap = 0.05;
    /// Half the judge's default spp (app/Judge.h): T and V together never trace more samples
    /// than the judge's estimate does, so the rule at most about doubles a run's tracing.
    int maxSpp = kJudgeDefaultSpp / 2;
};

/// The validation estimate V for a training trace of `scene` made with `training` (its spp,
/// path length, pixels and channels, already resolved) and seed `trainingSeed`: the same trace
/// with two sample sets and the seed trainingSeed + kValidationSeedOffset, cached in cacheDir
/// like transportForScene.
TransportSource validationEstimate(const Scene& scene, const PrecomputeOptions& training,
                                   uint64_t trainingSeed, const std::filesystem::path& cacheDir);

/// One training trace of the rule: its spp, E*'s figure on T and on V, the gap, the seconds
/// the round cost (traces, the search and the scoring).
struct TrainingNoiseRound {
    int spp = 0;
    LightGrid grid;                       // the grid E* was searched on
    double training = 0, validation = 0;  // trainingFigure of E* on T and on V
    double gap = 0;
    double seconds = 0;
};

/// What the rule did.
struct TrainingNoiseSummary {
    std::vector<TrainingNoiseRound> rounds;
    bool adapted = false;      // the rule chose spp (false: a given spp was kept)
    bool gridAdapted = false;  // the rule may coarsen the light (false: a given grid was kept)
    bool met = false;          // the last round's gap ≤ maxGap
    double maxGap = 0.05;
    /// Seconds spent beyond the last round (the earlier rounds' traces and searches): what the
    /// rule added to a run that would have used the last round's spp from the start.
    double secondsAdded = 0;
    std::string reason;  // one line for the log and summary.json
    int spp() const { return rounds.empty() ? 0 : rounds.back().spp; }
    LightGrid grid() const { return rounds.empty() ? LightGrid{} : rounds.back().grid; }
    double gap() const { return rounds.empty() ? 0.0 : rounds.back().gap; }
};

/// The figure of the objective the gap is measured on: the loss for paper and unbiased (lower
/// is better), the defects' visibility exp(−L_vis/2) for defects (higher is better; L_vis =
/// lGrad of the defects objective's LossParts, −log(g(D)/g(R)) with its floors, so this is
/// sqrt(g(D)/g(R)) where both are above the floor).
double trainingFigure(ObjectiveKind kind, const LossParts& parts);
bool figureHigherIsBetter(ObjectiveKind kind);
/// How much better E* looks on its training estimate than on the validation estimate, as a
/// fraction of the validation figure (header, step 3); ≤ 0 when it looks no better. +inf when
/// the validation figure is 0 and the training one is not.
double trainingGap(ObjectiveKind kind, double training, double validation);

/// The next spp after a round at `spp` with `gap` (header, step 4); nullopt when spp is already
/// at options.maxSpp.
std::optional<int> nextTrainingSpp(int spp, double gap, const TrainingNoiseOptions& options);

/// The summary's reason line: the rounds' spp, grids and gaps and the choice (the seconds the
/// rule added are TrainingNoiseSummary::secondsAdded, printed beside it).
std::string describeTrainingNoise(const TrainingNoiseSummary& summary);

}  // namespace sl
