// The judge (README "The judge"): scores env maps on an estimate that no optimizer saw.
//
// The estimate is a transport matrix of the scene traced with the judge's own seed at high spp
// (default 1024) and two independent sample sets (T_a, T_b), cached on disk by fingerprint, so
// judging ten lights costs one trace. Per light E:
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
#include <filesystem>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "app/Transport.h"
#include "io/MaskIO.h"
#include "objective/DefectVisibility.h"
#include "objective/Objective.h"

namespace sl {

struct Scene;
struct EnvMap;
class UnbiasedObjective;

inline constexpr uint64_t kJudgeSeed = 0x6A75646765ULL << 24;  // "judge"
inline constexpr int kJudgeDefaultSpp = 1024;
inline constexpr double kDarkTexel = 1e-3;

struct JudgeOptions {
    int spp = kJudgeDefaultSpp;      // samples per pixel of the estimate (both halves together)
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
};

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

    void buildObjectives();
};

/// The judge's estimate for a scene (cached by fingerprint in cacheDir, traced otherwise).
TransportSource judgeEstimate(const Scene& scene, const JudgeOptions& options);

/// The viewing model as JSON: pixels_per_degree, white_cd_m2, text (ViewingModel::describe).
nlohmann::ordered_json viewingJson(const ViewingModel& view);

/// The score as JSON: name, eq2, unbiased, mean_E, sparsity, visibility (per region: name,
/// value, pixels, visibility, rms_gradient, clean_rms_gradient, weber, jnd, jnd_frequency_cpd,
/// mask_contrast, luminance_cd_m2), eq2_parts, unbiased_parts.
nlohmann::ordered_json toJson(const JudgeScore& score);

/// A fixed-width table of scores, one row per light (for the terminal); the regions' columns
/// worst first (by the first light's visibility, ascending).
std::string formatJudgeTable(const std::vector<JudgeScore>& scores);

}  // namespace sl
