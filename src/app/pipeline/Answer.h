// The self-checked answer: which light `optimize` returns.
//
// The optimized light is best on its training estimate by construction, so the training
// estimate cannot say whether it is better than a plain lamp. Every candidate — the optimized
// light of every start, the user's lamp (or the studio preset), a uniform dome (const 0.5) and
// the paper's light — is scored on the validation estimate (app/pipeline/TrainingNoise.h:
// independent of the training estimate and of the judge's), by the figure the answer line reports
// (answerMerit: the JND of the least visible defect kind when defect regions and a viewing
// model are known, else the defects' combined visibility ratio, else the judge's U). A candidate
// whose image is darker than minBrightness of the white furnace, or (chosen by the visibility
// ratio) whose defects' gradient is below minContrast of the image's brightness (a uniform dome
// makes both gradients tiny and their ratio noise; JND needs no such floor: it is contrast over
// the eye's threshold already), is not eligible unless none is. The best eligible candidate is the
// answer; when it is a reference, the run says so first and the optimized light is kept beside it.
// The judge's estimate then reports on the answer, so the selection does not bias the figures a
// person reads.
//
// Finer lights (CandidateKind::Finer): the lights the noise rule searched on a finer grid at the
// same spp before it settled on E*'s (app/pipeline/TrainingNoise.h step 5). Their training figures
// fit the estimate's noise, so they are not the answer while E* or a start passes the checks; when
// none does (e.g. E*'s defects' gradient just under minContrast), the best of them on the
// validation estimate competes with the references, since an independent estimate still says
// fairly which shows the defects better.
#pragma once

#include <cstddef>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "app/pipeline/Judge.h"
#include "objective/BothMeasuresObjective.h"
#include "objective/DefectObjective.h"

namespace sl {

/// What the answer is judged on: the value, its direction and its name.
struct AnswerMerit {
    double value = 0;
    bool higherIsBetter = false;
    std::string what;  // "JND", "defect visibility", "U" or "gain over <lamp>"
    /// The defects' combined visibility ratio, beside the JND (NaN without defect regions).
    double visibility = std::numeric_limits<double>::quiet_NaN();
    /// With JND: all kinds pooled (combinedJnd), the tie-break; and the least visible kind.
    double pooled = std::numeric_limits<double>::quiet_NaN();
    std::string leastVisible;
    /// With a gain merit (AnswerOptions::gainOver): the least visible kind's JND, the value's
    /// numerator beside the visibility ratio's.
    double jnd = std::numeric_limits<double>::quiet_NaN();
};
/// The figure the judge (and the answer line) reports first, of a judge's score: with defect
/// regions in view, the JND of the least visible defect kind (objective/DefectVisibility.h
/// leastVisibleJnd, what the defects objective maximizes) when the judge has a viewing model
/// (`inJnd`), else their combined visibility ratio (combinedVisibility); without, U. The kind
/// depends on the judge alone, so every candidate of one choice is compared on the same figure
/// (a light whose figure cannot be formed, e.g. a ratio of two vanishing gradients, gets NaN).
AnswerMerit answerMerit(const JudgeScore& score, bool inJnd);
/// a better than b by their merit (the same `what`; NaN is never better); equal values are
/// decided by the pooled JND.
bool betterMerit(const AnswerMerit& a, const AnswerMerit& b);

/// Where a candidate comes from.
enum class CandidateKind { Optimized, Start, Finer, Reference };
/// summary.json's name of a kind: "optimized" (E* and the starts), "finer", "reference".
const char* candidateKindName(CandidateKind kind);
struct AnswerCandidate {
    std::string name;  // "optimized", "start specular", "lamp", "uniform-0.5", "paper"
    CandidateKind kind = CandidateKind::Reference;
    std::vector<double> e;
};

struct AnswerOptions {
    double minBrightness = kMinVisibleBrightness;  // of the white furnace's mean over the part
    /// Chosen by the visibility ratio: the least combined contrast (RMS gradient in the regions
    /// over the mean brightness; the eye needs about 0.01), below which the ratio is noise.
    double minContrast = kMinDefectContrast;
    /// With the defects objective's `both` measure (objective/BothMeasuresObjective.h): the name
    /// of the candidate (the user's lamp) over which every candidate's merit is a gain, the
    /// smaller of its JND's and its visibility ratio's over that candidate's, as the objective
    /// raises (so a light is chosen over the lamp only when it shows the defects more by both).
    /// Empty, or without JND: answerMerit's figure.
    std::string gainOver;
    /// The least JND the gains are counted from (objective/BothMeasuresObjective.h's anchor):
    /// under a lamp that shows the defects less, a gain over it is a gain over this.
    double gainFloorJnd = kGainFloorJnd;
};

struct ScoredCandidate {
    AnswerCandidate candidate;
    JudgeScore score;  // on the validation estimate
    AnswerMerit merit;
    bool eligible = true;
    std::string why;  // why not eligible
};

struct AnswerChoice {
    std::vector<ScoredCandidate> scored;  // in the order given
    size_t chosen = 0;                    // index into scored
    size_t optimized = 0;                 // the best optimized candidate (kind Optimized/Start)
    bool referenceWon() const { return scored[chosen].candidate.kind == CandidateKind::Reference; }
    const ScoredCandidate& answer() const { return scored[chosen]; }
    /// One line: what was chosen and why (the figures on the validation estimate).
    std::string reason;
    double seconds = 0;     // scoring the candidates on the validation estimate (JND included)
    int validationSpp = 0;  // the validation estimate's spp (0: not recorded)
};

/// How many standard errors of the difference of two merits on the validation estimate the
/// answer must win by for its choice to stand on V's first spp (answerDecided).
inline constexpr double kAnswerMarginSigmas = 3.0;
/// Whether the choice would stand on another estimate: the answer's merit and the best eligible
/// merit of the other side (the references when an optimized light won, the optimized lights
/// when a reference did) differ by more than kAnswerMarginSigmas·√2·relativeSe of the larger
/// (relativeSe: the validation estimate's relative standard error of a merit, e.g. the noise
/// rule's gap SE). True when there is no other side to lose to. NaN relativeSe: not decided.
bool answerDecided(const AnswerChoice& choice, double relativeSe);

/// summary.json's `answer`: the light chosen, its kind, the merit, the reason, the seconds the
/// scoring took and every candidate (name, kind, merit, visibility ratio, brightness, eligible,
/// why), scored on the validation estimate.
nlohmann::ordered_json answerJson(const AnswerChoice& choice);

/// Scores every candidate on `validation` and picks the answer (header). At least one
/// candidate of kind Optimized is required.
AnswerChoice chooseAnswer(const Judge& validation, std::vector<AnswerCandidate> candidates,
                          const AnswerOptions& options = {});

}  // namespace sl
