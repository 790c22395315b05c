// The judge (README "The judge"): scores env maps on an estimate that no optimizer saw.
//
// The estimate is a transport matrix of the scene traced with the judge's own seed and two
// independent sample sets (T_a, T_b), cached on disk by fingerprint, so judging ten lights costs
// one trace; its spp is what the scores need (judgeInRounds: from kJudgePilotSpp (32) until every
// score's standard error is <= 1 %, at most 1024), each round extending the last one's estimate
// by as many samples again (app/pipeline/Transport.h transportInDoublings), not tracing anew.
// Per light E:
//   eq2        the paper's eq. 2 (S/G + λ·mean(E²)) on the mean image Ȳ = (T_a + T_b)/2 · E
//   unbiased   U = sqrt(S / Σ_pairs ΔY_a·ΔY_b) + λ·mean(E²)  (objective/UnbiasedObjective.h)
//   mean_E     mean texel value;  sparsity: fraction of texel values < kDarkTexel
//   visibility with a truth label mask (height-map space, projected through each pixel's centre
//              ray): per region, the noise-unbiased RMS gradient inside it over that of the
//              defect-free surface, and its Weber contrast (objective/DefectVisibility.h);
//              with a viewing model, its JND: how many times its threshold a person sees it
//              (perception/JndVisibility.h)
// Both losses use the part mask (pixels whose every judge sample hit the part); lower is
// better for both.
//
// CONVENTION (judge seed): the judge traces with kJudgeSeed. Optimizations trace with the
// scene's render.seed (default 0, a small user-chosen number); a training seed equal to the
// judge's is refused, so the judge's samples are disjoint from every optimization's.
#pragma once

#include <cstdint>
#include <deque>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "app/pipeline/Transport.h"
#include "io/MaskIO.h"
#include "objective/DefectVisibility.h"
#include "objective/Objective.h"

namespace sl {

struct Scene;
struct EnvMap;
class UnbiasedObjective;
class BandFilterBank;

inline constexpr uint64_t kJudgeSeed = 0x6A75646765ULL << 24;  // "judge"
/// The most samples the judge's rounds trace (and the spp of `--heldout-spp`'s old default).
inline constexpr int kJudgeDefaultSpp = 1024;
/// The judge's first round (README "The judge"): rounds start here and stop when every score a
/// person reads has a relative standard error of at most kJudgeMaxError (or at the cap). 64
/// was tried before with U's SE from the wild bootstrap (docs/BENCHMARKS.md, issue 31's third
/// pass): on a held-out 512² part the paper's light's U had a bootstrap SE of 7.4 % at 64 spp
/// against 1.4 % at 128 (the bootstrap over-states the SE of a product of two noisy halves at
/// low spp), so the rounds went to 1024 spp instead of 512. U's SE is now the delta method's
/// (scoreWithErrors), and a round extends the estimate before it (transportInDoublings), so
/// starting at 64 never traces more than starting at 128 did. 32 since issue 31's eighth pass,
/// a trace of its own: the rounds after it extend the 64-spp estimate (kJudgeDoublingBase), so
/// every estimate from 64 spp on is the one it was before, and a part whose scores need more
/// than 32 traces 32 spp more than it did.
inline constexpr int kJudgePilotSpp = 32;
/// The judge's estimates from here on are extensions of this one (transportInDoublings' base).
inline constexpr int kJudgeDoublingBase = 64;
/// Below this spp the wild bootstrap under-states eq. 2's SE: on the test part at 32 spp it
/// was 0.55× its spread over 16 independent judge seeds (within ±45 % of it from 64 spp on;
/// tests/test_judge_rounds.cpp StandardErrorHoldsAtThePilotSpp, now at 32). scoreWithErrors
/// multiplies the bootstrap's SEs of eq. 2 and of the regions (their visibility, contrast and
/// JND, not measured at 32) by kJudgeLowSppInflation on an estimate below it, so what is
/// printed and what the rounds stop on is not less than the spread: a 32-spp round stops only
/// where eq. 2's bootstrap SE is within half the target. U's delta-method SE (0.78× its spread
/// at 32 spp) and the brightness's bootstrap SE (1.4×) are kept.
inline constexpr int kJudgeBootstrapFullSpp = 64;
inline constexpr double kJudgeLowSppInflation = 2.0;
inline constexpr double kJudgeMaxError = 0.01;
/// Replicates of the standard-error estimate (Judge::scoreWithErrors): the SE itself is then
/// known to about 1/sqrt(2·(R − 1)) = 13 % of its value.
inline constexpr int kJudgeReplicates = 32;
inline constexpr double kDarkTexel = 1e-3;

struct JudgeOptions {
    /// Samples per pixel of the estimate (both halves together); 0: in rounds from
    /// kJudgePilotSpp until the scores' standard errors are small (judgeInRounds), at most
    /// kJudgeDefaultSpp.
    int spp = 0;
    uint64_t seed = kJudgeSeed;      // the judge's seed (a second judge uses another)
    std::optional<int> maxDepth;     // default: the scene's render.max_depth
    ObjectiveOptions objective;      // λ and the regulariser of eq. 2 and U (λ = 30)
    bool rgb = false;                // RGB T: RGB env maps are scored in colour
    std::filesystem::path truth;     // label mask in height-map space (optional)
    std::filesystem::path cacheDir;  // where the estimate is cached ("" = not stored)
    int threads = 0;
    /// How a person sees the image: with it, each region's visibility in JND too
    /// (perception/JndVisibility.h). Judge(scene, ...) takes the scene's when unset.
    std::optional<ViewingModel> viewing;
};

/// The scene's viewing model (its "viewing" block, perception/ViewingModel.h), one pixel of
/// its camera spanning Camera::mmPerPixel of the part.
ViewingModel viewingFor(const Scene& scene);

struct JudgeScore {
    std::string name;
    LossParts eq2, unbiased;
    double meanE = 0, sparsity = 0;
    /// Mean luminance over the part relative to the white furnace (E = 1): 1 = as bright as a
    /// white sky can make it (a well-exposed inspection image sits between 0.05 and 0.8).
    double brightness = 0;
    std::vector<RegionVisibility> visibility;  // one per truth region (empty without truth)
    int spp = 0;                               // of the estimate it was scored on
    /// Standard errors of the scores above (Judge::scoreWithErrors), when estimated.
    struct Errors {
        int replicates = 0;
        double eq2 = 0, unbiased = 0, brightness = 0;
        double combinedVisibility = 0;  // of combinedVisibility(visibility) (NaN without one)
        std::vector<double> visibility, contrast;  // per region, in visibility's order
        /// With a viewing model: each region's JND, and the least visible kind's JND
        /// (leastVisibleJnd: the figure the answer is chosen on; NaN without one).
        std::vector<double> jnd;
        double leastVisibleJnd = std::numeric_limits<double>::quiet_NaN();
    };
    std::optional<Errors> se;
};

/// The score a person reads whose standard error is the largest relative to its size:
/// SE / max(|score|, floor), the floor being the score's scale near zero (a score near 0 is
/// held to an absolute SE of floor·kJudgeMaxError instead of an ever smaller relative one):
/// eq. 2 and U 1e-3, brightness 0.05 (below it a light is not eligible as an answer), each
/// region's visibility and the combined visibility 0.1, contrast 0.01 (about the least the eye
/// sees), the least visible kind's JND (the answer's figure) 1 (the threshold: below it the SE
/// is held to kJudgeMaxError of one JND). NaN scores are skipped. relative 0 without errors.
struct WorstError {
    double relative = 0;
    std::string score;  // e.g. "lamp: visibility scratch"
    /// The SE over what the stopping rule allows it (worstError): <= 1 is met. worstRelativeError
    /// leaves it at relative / kJudgeMaxError.
    double excess = 0;
    /// The allowance was the gap to the answer's score, not the score's own target (a reference).
    bool byGap = false;
};
WorstError worstRelativeError(const JudgeScore& score);

/// A reference light (optimize's lamp, paper's light, E* beside a reference answer) is read
/// only against the answer: "31 % lower than under your lamp", "2.3× the lamp's JND". Its
/// score's standard error is enough when it is within kJudgeMaxError of the score (as the
/// answer's) or within kJudgeGapShare of its gap to the answer's same score (the comparison is
/// then decided, 10 standard errors apart, and its size known to a tenth), but never above
/// kJudgeReferenceMaxError of the score (the cap: a reference printed to ±20 % is not read).
/// A reference's comparison that is not decided at kJudgeReferenceMaxSpp (128)
/// does not trace further by itself (the answer's own scores still may, to kJudgeDefaultSpp):
/// on a near-flat part the paper's light's U kept a 5.4 % SE at 1024 spp, 2 SE from the
/// answer's, and 60 % of the judge's seconds went to it. The run then says so (describe).
inline constexpr double kJudgeGapShare = 0.1;
inline constexpr double kJudgeReferenceMaxError = 0.2;
inline constexpr int kJudgeReferenceMaxSpp = 128;

/// The stopping rule's worst score of `score`: each score's SE over what it is allowed,
/// target·max(|value|, floor) (worstRelativeError's floors), and for a reference (`answer`
/// given: the light it is compared with) max(that, gapShare·|value − answer's value|), at most
/// referenceCap·max(|value|, floor). The worst by excess; its relative SE beside it.
WorstError worstError(const JudgeScore& score, double target = kJudgeMaxError,
                      const JudgeScore* answer = nullptr, double gapShare = kJudgeGapShare,
                      double referenceCap = kJudgeReferenceMaxError);

/// The spp of the judge's next round: the standard error falls as 1/sqrt(spp), so
/// spp·(worst/target)², to a power of two, at least twice spp and at most cap; 0 when the
/// worst relative error is within target or spp is at the cap.
int nextJudgeSpp(int spp, double worstRelative, int cap, double target = kJudgeMaxError);

class Judge {
  public:
    /// Traces (or reads from options.cacheDir) the judge's estimate of `scene`, and projects
    /// options.truth into the image. Throws InputError for a mismatched truth mask.
    Judge(const Scene& scene, const JudgeOptions& options);
    ~Judge();
    Judge(const Judge&) = delete;
    Judge& operator=(const Judge&) = delete;
    /// A judge on a given two-plane estimate that outlives it (optimize's held-out estimate,
    /// tests). `labels`: image-space labels (width*height) or empty; `reference`: where the
    /// defect-free surface of the visibility may lie (width*height, nonzero) or empty (the part).
    Judge(const TransportSource& estimate, const JudgeOptions& options,
          std::vector<uint8_t> labels = {}, std::vector<RegionLabel> legend = {},
          std::vector<uint8_t> reference = {});

    /// Scores E (gray: one value per texel; RGB: three, needs options.rgb).
    JudgeScore score(std::span<const double> E, const std::string& name = {}) const;
    /// score() with the standard error of every score (JudgeScore::se), by a wild bootstrap on
    /// the two halves: pixels' samples are independent, and d_p = Y_a,p − Y_b,p has mean 0
    /// and variance 2·var(Y_a,p), so each of `replicates` replicates perturbs the halves by
    /// ±d_p/√2 with independent signs per pixel and half (a fixed seed: the same E gives the
    /// same errors) — the same light's white-furnace image with the same signs — and scores
    /// them again (U's SE is the delta method's on the halves' product instead,
    /// objective/UnbiasedObjective.h lossStandardError, which the bootstrap over-states at a few
    /// spp; each region's JND too, with a viewing model: its band contrasts are formed
    /// anew per replicate on one bank of band filters, the dearest part; the replicates run on
    /// every core, core/WildBootstrap.h); the SE is the replicates' spread (1.4826 × their
    /// median absolute deviation,
    /// a standard deviation robust to a replicate whose denominator nearly vanished; to first
    /// order the delta
    /// method's, without the scores' derivatives). It falls as 1/sqrt(spp).
    JudgeScore scoreWithErrors(std::span<const double> E, const std::string& name = {},
                               int replicates = kJudgeReplicates) const;
    /// The mean luminance image (T_a + T_b)/2 · E.
    std::vector<double> meanImage(std::span<const double> E) const;
    /// E for an env map on the judge's grid: gray maps as they are; RGB maps in colour with an
    /// RGB judge, else by their luminance (exact for a gray conductor).
    std::vector<double> envVector(const EnvMap& env) const;

    const TransportSource& estimate() const { return *estimate_; }
    const std::vector<uint8_t>& partMask() const { return estimate_->file.matrix.objectMask; }
    const std::vector<uint8_t>& labels() const { return labels_; }
    const std::vector<RegionLabel>& legend() const { return legend_; }
    const JudgeOptions& options() const { return options_; }

  private:
    std::optional<TransportSource> owned_;
    const TransportSource* estimate_ = nullptr;
    JudgeOptions options_;
    std::vector<uint8_t> labels_;
    std::vector<RegionLabel> legend_;
    std::vector<uint8_t> reference_;
    std::unique_ptr<ImageObjective> eq2_;          // eq. 2 on the part mask, built once
    std::unique_ptr<UnbiasedObjective> unbiased_;  // U on the part mask, built once
    // The white furnace's mean image and halves (E all 1 of the scored light's size): the same
    // for every light scored, so rendered once per judge and size (whiteImages).
    struct White {
        size_t size = 0;
        std::vector<double> mean, a, b;
    };
    mutable std::mutex whiteMutex_;
    mutable std::deque<White> white_;  // a deque: a White handed out stays where it is

    void buildObjectives();
    /// The white furnace's images for an E of `size` values (rendered on first use).
    const White& whiteImages(size_t size, bool halves) const;
    /// The scores from the light's half images and the white furnace's (means: (a + b)/2
    /// unless given); `bank`: the JND's band filters on the part, built once (null: per call).
    JudgeScore scoreImages(std::span<const double> E, std::span<const double> ya,
                           std::span<const double> yb, std::span<const double> y,
                           std::span<const double> wa, std::span<const double> wb,
                           std::span<const double> w, bool withJnd = true,
                           const BandFilterBank* bank = nullptr) const;
};

/// The judge in rounds (JudgeOptions::spp 0): scores `lights` (name, E) with their errors on
/// judgeAt(spp) from `spp` on; while a score's relative error exceeds `target` and spp is below
/// `cap`, asks judgeAt(nextJudgeSpp(...)) and scores again. judgeAt returns a judge on the
/// estimate at that spp, which must outlive the next call. The scores are those of the last
/// round (so the same seed gives the same numbers); with a fixed spp, spp == cap: one round.
struct JudgeRound {
    int spp = 0;
    WorstError worst;  // over every light (by excess)
    /// With references (JudgeStopRule::againstFirst): the answer's worst and the references'.
    WorstError answer, references;
};
struct JudgedRounds {
    std::vector<JudgeScore> scores;  // in the lights' order, of the last round
    std::vector<JudgeRound> rounds;
    bool met = false;           // every error within what the rule allows
    bool againstFirst = false;  // the rule's references (JudgeStopRule::againstFirst)
    double gapShare = kJudgeGapShare;
    int referenceMaxSpp = 0;
    int spp() const { return rounds.empty() ? 0 : rounds.back().spp; }
    /// "128 spp: SE <= 1 % (worst 0.62 %, lamp: U)" or "... at the cap 1024 spp: worst ...";
    /// with references, what they were held to.
    std::string describe(double target = kJudgeMaxError) const;
};
/// With againstFirst (optimize: its answer first, then the lights it is compared with) the
/// others are references (worstError's rule with the first light's scores); else every light's
/// every score is held to target.
struct JudgeStopRule {
    double target = kJudgeMaxError;
    bool againstFirst = false;
    double gapShare = kJudgeGapShare;
    double referenceCap = kJudgeReferenceMaxError;
    int referenceMaxSpp = kJudgeReferenceMaxSpp;  // the references' rounds stop here
};
JudgedRounds judgeInRounds(const std::function<const Judge&(int spp)>& judgeAt,
                           const std::vector<std::pair<std::string, std::vector<double>>>& lights,
                           int spp, int cap, const JudgeStopRule& rule);
JudgedRounds judgeInRounds(const std::function<const Judge&(int spp)>& judgeAt,
                           const std::vector<std::pair<std::string, std::vector<double>>>& lights,
                           int spp, int cap, double target = kJudgeMaxError);

/// The judge's estimate for a scene (cached by fingerprint in cacheDir, traced otherwise), at
/// options.spp (0: kJudgeDefaultSpp).
TransportSource judgeEstimate(const Scene& scene, const JudgeOptions& options);

/// The viewing model as JSON: pixels_per_degree, white_cd_m2, text (ViewingModel::describe).
nlohmann::ordered_json viewingJson(const ViewingModel& view);

/// The score as JSON: name, eq2, unbiased, mean_E, sparsity, visibility (per region: name,
/// value, pixels, visibility, rms_gradient, clean_rms_gradient, weber, jnd, jnd_frequency_cpd,
/// mask_contrast, luminance_cd_m2), eq2_parts, unbiased_parts, spp, and with errors `se` (eq2,
/// unbiased, brightness, combined_visibility, least_visible_jnd, visibility, contrast and jnd
/// per region, replicates).
nlohmann::ordered_json toJson(const JudgeScore& score);

/// The judge's rounds as JSON: [{spp, worst_relative_se, worst_score}, ...].
nlohmann::ordered_json roundsJson(const JudgedRounds& rounds);

/// A fixed-width table of scores, one row per light (for the terminal); the regions' columns
/// worst first (by the first light's visibility, ascending). With errors, the standard error
/// relative to each score is printed beside it ("±0.4%").
std::string formatJudgeTable(const std::vector<JudgeScore>& scores);

}  // namespace sl
