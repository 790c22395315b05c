// Noise-aware training (docs/DESIGN.md "Noise is the trap"): how many samples per pixel the
// training estimate of T needs so that the optimum does not fit its noise.
//
// An optimizer that minimizes a loss on one Monte Carlo estimate of T finds the light that is
// best on that estimate: part of its score is the estimate's noise, which an independent
// estimate does not share. The rule measures that directly, on the part and for the objective
// in use:
//
//   1. T (the training estimate, spp n) and V (the validation estimate: the same scene and path
//      length, two sample sets, the seed training seed + kValidationSeedOffset, disjoint from
//      every training seed and from the judge's) are traced (both cached). V starts at
//      validationPilotSpp(n) (n/4, at least kValidationPilotSpp) where its figure does not depend
//      on its spp (validationSppFree) and the rule adapts, else at n; it rises in rounds to the
//      standard error its decisions need: the gap's (step 4) and the answer's
//      (app/pipeline/Answer.h answerDecided: else V is traced again at n);
//   2. the search runs on T as it would anyway; its E* is scored on T and on V;
//   3. the gap (trainingGap) is how much better E* looks on T than on V, relative to V:
//        paper, unbiased (losses, lower is better):  gap = (L_V − L_T) / L_V
//        defects (visibility exp(−L_vis/2), higher is better): gap = (v_T − v_V) / v_V
//      and its standard error SE (trainingGapError) is V's own noise: the wild bootstrap on V's
//      two halves that gives the judge's errors (core/WildBootstrap.h), SE(f_V)/|f_V|, the
//      gap's SE when there is no over-fit (the hypothesis the verdict tests). A gap can be large
//      with no over-fit
//      at all when V's figure of E* is noisy (few defect pixels on a rough part), so the gap
//      is weighed against its SE (gapVerdict, kGapSigmas = 2):
//        over-fit          gap − 2·SE > maxGap: V's noise does not explain it (at 2 SE one-sided
//                          a light whose true gap is maxGap is sent on by V's noise 2.3 % of the
//                          time; 2 rather than 1.64 since 32 replicates know the SE to ±13 %);
//        validation noise  otherwise, while SE > maxGap: V cannot tell a gap of maxGap from 0
//                          (or V's figure of E* is on the objective's floor: its gradient in
//                          the defects below V's noise; at V's most spp that is over-fit);
//        above             otherwise, while gap > maxGap: above the tolerance by less than
//                          V's noise explains (the target is a gap ≤ maxGap, not a gap V's
//                          noise cannot tell from it);
//        within            otherwise: gap ≤ maxGap, measured to SE ≤ maxGap.
//   4. within: n (and the grid) is kept. Validation noise: V, not T, gets more samples — V's
//      spp rises (nextValidationSpp: SE falls as 1/sqrt(spp), so spp·(SE/maxGap)², a power of
//      two, at least 2×, at most maxValidationSpp, the judge's most) and E* is scored again on
//      it, the same T, the same search; at that cap the run says the gap cannot be resolved at
//      this cost and keeps the light (it does not chase V's noise with T's spp or a coarser
//      light); with a given spp V keeps T's (the gap is only measured). The paper
//      objective's eq. 2 is biased by noise (Σ|ΔY| grows with it), so its V keeps T's spp and
//      T's spp rises instead.
//      Above: V first while its noise could hide a gap of twice the tolerance (SE > maxGap/2:
//      V's spp rises until SE ≤ maxGap/2, kAboveErrorShare), else as over-fit: a gap measured
//      above the tolerance is closed by the same remedy (more T, then a coarser light); at the
//      limits the light is kept and the run says its gap is above the tolerance by less than
//      V's noise explains.
//      Over-fit: the part of the gap the noise makes falls as 1/spp (the optimizer's gain on noise
//      is proportional to the noise's variance), so the next n is the smallest power of two ≥ 2n
//      with gap·n/n' ≤ maxGap/2 (half the tolerance, so one more trace usually settles it), at most
//      kMaxSppGrowth·n (a gap far above the tolerance is often a cliff the noise opened — e.g. the
//      defect objective's reference energy pushed below its floor — which closes long before 1/spp
//      predicts) and at most maxSpp; back to 1. The new T is traced anew: extended
//      (app/pipeline/Transport.h transportInDoublings) it would be noisier than a trace of n'
//      (each chunk is stratified on its own; docs/BENCHMARKS.md, issue 31's fourth pass).
//   5. Over-fit at maxSpp (or a given spp): the light's degrees of
//      freedom are the other knob: the search runs again on the same T and V with the light on
//      a coarser grid of nodes (objective/CoarseLight.h), each step √2 fewer nodes per side
//      (nextLightGrid), until the gap is no longer over-fit or the grid has fewer than
//      kCoarsestLightNodes nodes. The optimizer's gain on noise grows with the directions it
//      can combine: on four held-out parts at 512 spp (defects objective) the gap was 17-166 %
//      per texel and 0.1-7 % on 24×12 nodes, at 0.8-0.98 of the per-texel light's visibility
//      by the judge. A search on fewer nodes is also faster (fewer, cheaper evaluations), so
//      a step costs a few seconds and no trace.
//
// Every round (T's spp, the grid, V's spp, both figures, the gap, its SE and the verdict) is
// printed and recorded. A given spp is kept: its gap is still measured, and a gap above
// maxGap is warned about. When maxSpp is reached over-fit, the run says the light is not
// trustworthy on its own and the self-checked answer (app/pipeline/Answer.h) decides against the
// references.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "app/pipeline/Judge.h"
#include "app/pipeline/Transport.h"
#include "objective/CoarseLight.h"
#include "objective/Objective.h"
#include "objective/ObjectiveKind.h"
#include "objective/TransportLoss.h"
#include "objective/UnbiasedObjective.h"

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

/// The multipliers by label (index: the label's value; 1 for 0 and for absent labels), the rule
/// above per label: the objective's soft-min over labels follows the label that shows least, and
/// its noise is that label's g(D_k), a mean over its own pairs; a truth's smallest labels (a burr,
/// a dent: tens of pixels) are the noisiest, while a chatter band of thousands of pixels would
/// spend the whole budget at 2x on one factor for all. So the budget goes to the labels in order
/// of size, smallest first, each taking the largest power of two ≤ kDefectSppScale whose extra
/// samples fit in what the smaller ones left. One label: defectSppFactor's factor exactly.
/// labelPixels[v]: the pixels of label v the camera sees of the part (labelPixels[0] unused).
std::array<int, 256> defectSppFactors(const std::array<size_t, 256>& labelPixels,
                                      size_t partPixels);
/// The labels with a pixel in labelPixels (values 1-255), smallest first (ties: by value): the
/// order defectSppFactors spends its budget in.
std::vector<size_t> labelsBySize(const std::array<size_t, 256>& labelPixels);
/// The per-pixel multipliers: `factor` on the nonzero pixels of `defects`, 1 elsewhere; empty
/// when factor is 1 (the plain trace).
std::vector<uint8_t> defectSppScale(const std::vector<uint8_t>& defects, int factor);
/// The same with a factor per label (defectSppFactors); empty when every factor is 1.
std::vector<uint8_t> defectSppScale(const std::vector<uint8_t>& defects,
                                    const std::array<int, 256>& factors);

/// The validation estimate's seed: the training seed plus this ("valid"). It is not in any
/// training seed range a user can reach with --estimates (< 2^20) and not the judge's seed.
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

/// How many of its standard errors a gap may exceed maxGap by before it counts as over-fit
/// (header, step 3).
inline constexpr double kGapSigmas = 2.0;

/// The image pixels at which the rule's spp caps (TrainingNoiseOptions::maxSpp and
/// maxValidationSpp) hold as written: 256². The caps are a budget of samples, not of samples per
/// pixel: an image with fewer pixels may trace proportionally more spp for what a 256² trace
/// costs (a 128² part 4×), since there the over-fit the rule measures and V's noise are the
/// same per pixel while a trace is a quarter of the cost (on rough 128² parts the defects'
/// figure on V at 1024 spp kept a standard error of 3–31 %, so the gap could not be resolved). A
/// larger image keeps the caps in spp.
inline constexpr size_t kSppCapPixels = 256 * 256;
/// The most the caps are scaled by (a 128² image's factor): below 128² an image is a preview,
/// and its traces at 16× the spp would take longer than the 256² run they stand in for.
inline constexpr int kMaxSppCapScale = 4;
/// `spp` scaled to an image of `pixels` pixels by the rule above: spp times the largest power of
/// two ≤ kSppCapPixels / pixels, at least 1, at most kMaxSppCapScale.
int sppCapForImage(int spp, size_t pixels);

struct TrainingNoiseOptions {
    /// Measure the gap and raise spp until it is within maxGap (false: keep the given spp and
    /// only warn).
    bool adapt = true;
    /// Coarsen the light's grid (step 5) when the spp cannot be raised and the gap is large
    /// (false: the grid given is kept).
    bool adaptGrid = true;
    double maxGap = 0.05;
    /// Half the judge's default spp (app/pipeline/Judge.h): T and V together never trace more
    /// samples than the judge's estimate does, so the rule at most about doubles a run's tracing.
    int maxSpp = kJudgeDefaultSpp / 2;
    /// The most spp V is traced at when its own noise hides the gap (step 4): the judge's most,
    /// so V never needs more samples than an estimate the judge itself trusts.
    int maxValidationSpp = kJudgeDefaultSpp;
    /// These options with both caps scaled to an image of `pixels` pixels (sppCapForImage);
    /// `keepMaxSpp`: a maxSpp the user gave is kept as given.
    TrainingNoiseOptions forImage(size_t pixels, bool keepMaxSpp) const;
};

/// The validation estimate V for a training trace of `scene` made with `training` (its spp,
/// path length, pixels and channels, already resolved) and seed `trainingSeed`: the same trace
/// with two sample sets and the seed trainingSeed + kValidationSeedOffset, cached in cacheDir
/// like transportForScene.
/// `spp` > 0 traces V at that spp instead of the training trace's (step 4).
TransportSource validationEstimate(const Scene& scene, const PrecomputeOptions& training,
                                   uint64_t trainingSeed, const std::filesystem::path& cacheDir,
                                   int spp = 0);
/// The options validationEstimate traces V with (its spp, seed and sample sets set from the
/// training trace's), for finding V in the cache without the scene (app/pipeline/Transport.h
/// cachedTransport).
PrecomputeOptions validationOptions(const PrecomputeOptions& training, uint64_t trainingSeed,
                                    int spp = 0);

/// V's least first round (header, step 1): at 16 spp V's figure of E* has a standard error of
/// ~0.2 % on a 512² part without defects (the gap's tolerance is 5 %).
inline constexpr int kValidationPilotSpp = 16;
/// V's first spp for a training T at `trainingSpp` (header, step 1): a quarter of it, even, at
/// least kValidationPilotSpp, at most trainingSpp.
int validationPilotSpp(int trainingSpp);

/// The verdict on a round's gap weighed against its standard error (header, step 3).
enum class GapVerdict { Within, OverFit, ValidationNoise, Above };
/// "within", "over-fit", "validation noise", "above".
const char* gapVerdictName(GapVerdict verdict);
/// Over-fit when gap − kGapSigmas·se > maxGap; else validation noise when se > maxGap; else
/// above when gap > maxGap; else within. An unknown SE (NaN: V's figure of E* is on the objective's
/// floor, or the bootstrap could not form it in half its replicates) is validation noise while V
/// can take more samples
/// (`validationAtMost` false) and over-fit once it cannot: V's most samples do not see what T
/// shows.
GapVerdict gapVerdict(double gap, double se, double maxGap, bool validationAtMost);

/// One training trace of the rule: its spp, E*'s figure on T and on V, the gap, the seconds
/// the round cost (traces, the search and the scoring).
struct TrainingNoiseRound {
    int spp = 0;
    LightGrid grid;                       // the grid E* was searched on
    double training = 0, validation = 0;  // trainingFigure of E* on T and on V
    double gap = 0;
    double seconds = 0;
    int validationSpp = 0;       // V's spp (0: T's)
    double gapError = 0;         // the gap's standard error, from V's noise (trainingGapError)
    double secondsGapError = 0;  // computing gapError (part of `seconds`)
    GapVerdict verdict = GapVerdict::Within;
    std::string decision;  // what the rule did next: "kept", "T at 128 spp", "V at 1024 spp", ...
};

/// What the rule did.
struct TrainingNoiseSummary {
    std::vector<TrainingNoiseRound> rounds;
    bool adapted = false;      // the rule chose spp (false: a given spp was kept)
    bool gridAdapted = false;  // the rule may coarsen the light (false: a given grid was kept)
    bool met = false;          // the last round's verdict is within (step 3)
    /// The last round's verdict is validation noise at V's most spp: the gap cannot be
    /// resolved at this cost (the light is kept, not chased).
    bool unresolved = false;
    double maxGap = 0.05;
    /// Seconds spent beyond the last round (the earlier rounds' traces and searches): what the
    /// rule added to a run that would have used the last round's spp from the start.
    double secondsAdded = 0;
    std::string reason;  // one line for the log and summary.json
    int spp() const { return rounds.empty() ? 0 : rounds.back().spp; }
    LightGrid grid() const { return rounds.empty() ? LightGrid{} : rounds.back().grid; }
    double gap() const { return rounds.empty() ? 0.0 : rounds.back().gap; }
    double gapError() const { return rounds.empty() ? 0.0 : rounds.back().gapError; }
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

/// The standard error of E*'s gap (header, step 3) under the hypothesis the verdict tests (no
/// over-fit: E*'s figure on T is one more estimate of its figure on V): the standard error of
/// E*'s figure on V relative to that figure, SE(f_V)/|f_V|, the gap's at gap 0 by the delta
/// method. (The gap's own spread at a large gap is (1 + gap) times this: a light that shows
/// the defects nothing has a near-zero f_V whose relative noise is large, and that spread would
/// excuse the very over-fit the rule is there to catch.) `onValidation` is the objective in use
/// through V (two planes), E is E*; SE(f_V) is the wild bootstrap of V's half images
/// (core/WildBootstrap.h) with `replicates` replicates. NaN when E*'s loss on V is clamped (a
/// label's gradient, or G, below the objective's floor: V shows the defects no gradient, so its
/// figure is the floor's, not a noisy measure), f_V is 0, or fewer than half the replicates
/// give a finite figure. `unbiased` (the unbiased objective of `onValidation`, kind Unbiased):
/// SE(f_V) by the delta method on V's halves (objective/UnbiasedObjective.h lossStandardError)
/// instead, which the bootstrap over-states at a few spp (on a held-out 512² part at 16 spp:
/// 10 % against 0.25 % at 128).
double trainingGapError(ObjectiveKind kind, const TransportLoss& onValidation,
                        std::span<const double> E, uint64_t seed, int replicates = kJudgeReplicates,
                        const UnbiasedObjective* unbiased = nullptr);

/// Whether V may be traced at more spp than T (step 4): its figure's expectation does not
/// depend on the spp (U and the defects' visibility are noise-unbiased; eq. 2 is not).
bool validationSppFree(ObjectiveKind kind);
/// V's next spp after a round whose gap's standard error is `se` with V at `spp` (step 4):
/// nextJudgeSpp's rule with target maxGap and cap maxValidationSpp; nullopt at the cap.
std::optional<int> nextValidationSpp(int spp, double se, const TrainingNoiseOptions& options);

/// The share of maxGap V's standard error must come down to before a gap above the tolerance
/// is closed with T's spp (step 4, "above"): at SE ≤ maxGap/2 V's noise cannot hide a gap of
/// twice the tolerance.
inline constexpr double kAboveErrorShare = 0.5;

/// What the rule does after a round (step 4): V at nextValidation spp (the same T and E*),
/// else T at nextTraining spp, else the light on `coarser`, else the light is kept.
struct GapDecision {
    int nextValidation = 0;
    int nextTraining = 0;
    std::optional<LightGrid> coarser;
    /// The light is kept within what V's noise explains at V's most spp (validation noise or
    /// above at the limits): the gap is not resolved at this cost.
    bool unresolved = false;
    std::string describe() const;  // "V at 1024 spp", "T at 128 spp", "a coarser light, …", "kept…"
    GapVerdict verdict = GapVerdict::Within;
};
/// The verdict on `round` (its spp, grid, V's spp, gap and SE; its own verdict is not read) and
/// what follows it, for objective `kind` on an envWidth × envHeight env map.
GapDecision decideAfterRound(const TrainingNoiseRound& round, ObjectiveKind kind,
                             const TrainingNoiseOptions& options, int envWidth, int envHeight);

/// The next spp after a round at `spp` with `gap` (header, step 4); nullopt when spp is already
/// at options.maxSpp.
std::optional<int> nextTrainingSpp(int spp, double gap, const TrainingNoiseOptions& options);

/// The summary's reason line: the rounds' spp, grids and gaps and the choice (the seconds the
/// rule added are TrainingNoiseSummary::secondsAdded, printed beside it).
std::string describeTrainingNoise(const TrainingNoiseSummary& summary);

}  // namespace sl
