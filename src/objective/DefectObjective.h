// The defect-aware objective (objective `defects`): make the defects' image gradient large
// relative to the defect-free surface's, on two independent half-sample images (as the unbiased
// objective), while the image stays usefully exposed.
//
// Regions (image space, all within the part mask P): D, the defect pixels, each with its label
// (the mask's value: a truth's labels, or one label for a plain mask); R, the reference
// (default: the part pixels farther than kCleanMargin pixels from every defect pixel, the judge's
// "defect-free surface"; objective/DefectVisibility.h). Pairs are right and lower neighbours with
// both pixels in the region. With Y_a, Y_b the half images and Ȳ = (Y_a + Y_b)/2:
//
//   g(X)  = Σ_{pairs p,q ⊂ X} (Y_a,q − Y_a,p)(Y_b,q − Y_b,p) / #pairs(X)
//           unbiased for the mean squared noise-free gradient in X (the judge's g²)
//   L_vis = ψ(g(R)) − M,  M = φ(g(D)) with one label: −log(visibility²) above the floor
//   With labels D_1..D_K (pairs with both pixels in one label; labels without a pair are not
//   measured): the defects are the worst label's, softly,
//   M     = softmin_τ φ(g(D_k)) = −τ·log( (1/K)·Σ_k exp(−φ(g(D_k))/τ) ),  τ = kLabelSoftMin
//           between min_k φ_k and their mean, equal to φ when all labels are alike; its
//           gradient weighs label k by w_k = exp(−φ_k/τ)/Σ_j exp(−φ_j/τ), so the optimizer works
//           on the label that shows least and cannot buy one label's visibility with another's
//           disappearance (a pooled g(D) would: one bright scratch outweighs a dent gone dark)
//   φ(g)  = log g for g ≥ g0, else its tangent log g0 + (g − g0)/g0: finite, C¹ and increasing
//           for any g (a noisy g can be ≤ 0), so a light that hides the defects is pushed back
//   ψ(g)  = log max(g, g0): flat below the floor, so noise that makes the reference's estimate
//           negative earns nothing (a tangent there would reward it without bound)
//   g0    = 1e-6·w² (an rms gradient of 1/1000 of the white-furnace brightness w, below
//           anything visible)
//   m     = mean Ȳ over P;  w = the white-furnace mean (mean over P of T·1, given)
//   L_exp = κ·[ (max(0, lo·w − m)/w)² + (max(0, m − hi·w)/w)² + mean_P max(0, Ȳ − 1)² ]
//           keeps the mean brightness within [lo, hi] of the furnace value and off clipping
//   L_dark = κ_f·log(max(m, 1e-12·w)/(f·w))² where m < f·w, else 0: a floor the band's soft
//           pull cannot be traded against (a dark-field light can buy more visibility than
//           L_exp costs and leave the part at 1/600 of white); f is twice the answer's
//           brightness floor (app/pipeline/Answer.h), so E* stays a light a person can see
//   L_con = κ_c·(½·log(max(g(D), g0)/(f_c·c0·m)²))² where g(D) < (f_c·c0·m)², else 0: the
//           defects' contrast sqrt(g(D))/m (their rms gradient over the part's brightness, the
//           judge's contrast) kept above f_c = 2 times c0 = kMinDefectContrast, the answer's
//           eligibility: a light can buy visibility by flattening the reference until the
//           defects' own gradient is under what any eye sees, and the check then refuses it
//   Loss  = L_vis + L_exp + L_dark + L_con + λ·mean(E²)
//
// L_vis is invariant to scaling E; L_exp and λ fix the scale (with λ > 0 the optimum sits near
// the band's lower edge). The gradient dLoss/dY_a, dLoss/dY_b is exact; value<S>() computes the
// same loss in any scalar type for the autodiff check (objective/Autodiff.h).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "core/Communicator.h"
#include "objective/HalfImageObjective.h"
#include "objective/Objective.h"
#include "transport/TransportMatrix.h"

namespace sl {

/// The least mean brightness over the part, as a fraction of the white furnace's, of a light a
/// person can see the part under: the defects objective's floor (L_dark) and the self-checked
/// answer's eligibility (app/pipeline/Answer.h).
inline constexpr double kMinVisibleBrightness = 0.05;
/// The least combined contrast of the defects (rms gradient in their regions over the part's
/// mean brightness; the eye needs about 0.01) at which a visibility ratio means something: the
/// defects objective's contrast floor (L_con, at twice this) and the answer's eligibility.
inline constexpr double kMinDefectContrast = 0.01;

/// τ of the soft-min over labels, in units of log g (= 2·log visibility): labels whose
/// visibility differs by a factor 2 get weights in the ratio exp(2·log 2/τ) = 16.
inline constexpr double kLabelSoftMin = 0.5;

struct DefectObjectiveOptions {
    double whiteMean = 0;          // mean over the part of T·1 (the white furnace), > 0
    double low = 0.2, high = 0.8;  // the brightness band, as fractions of whiteMean
    double exposureWeight = 10;    // κ
    /// f, a fraction of whiteMean (0: no floor): twice the answer's eligibility, since the
    /// optimum settles just under a soft floor and another estimate must still see it above.
    double darkFloor = 2 * kMinVisibleBrightness;
    double darkWeight = 100;  // κ_f
    /// f_c·c0 of L_con (0: no floor): twice the answer's contrast eligibility, as darkFloor.
    double contrastFloor = 2 * kMinDefectContrast;
    double contrastWeight = 100;  // κ_c
};

class DefectObjective final : public HalfImageObjective {
  public:
    /// part: the loss mask (nonzero inside); defects: the label on defect pixels (0: none);
    /// reference: the defect-free region (empty: the default above). All width*height. Throws
    /// InputError when a region has no pixel pair or a size is wrong (naming option 'defects' /
    /// 'reference').
    DefectObjective(int width, int height, std::vector<uint8_t> part, std::vector<uint8_t> defects,
                    std::vector<uint8_t> reference, ObjectiveOptions options,
                    DefectObjectiveOptions defect);

    /// Loss at the half images and E; fills the gradients when the spans are non-empty.
    /// LossParts: lGrad = L_vis, lReg = mean(E²), G = g(D) over every label's pairs, S = g(R),
    /// clamped when some label's g is below the floor (it shows nothing); total includes L_exp.
    LossParts evaluate(std::span<const double> Ya, std::span<const double> Yb,
                       std::span<const double> E, std::span<double> dLdYa = {},
                       std::span<double> dLdYb = {}, std::span<double> dLdE = {}) const override;
    int imageWidth() const override { return width(); }
    int imageHeight() const override { return height(); }

    /// The same loss in scalar type S (double, ceres::Jet): the autodiff reference.
    template <typename S>
    S value(std::span<const S> Ya, std::span<const S> Yb, std::span<const S> E) const;

    int width() const { return base_.width(); }
    int height() const { return base_.height(); }
    const std::vector<uint8_t>& mask() const { return base_.mask(); }
    const std::vector<uint8_t>& defects() const { return defects_; }
    /// The measured labels (values of the defect mask with a pixel pair), ascending.
    const std::vector<uint8_t>& labels() const { return labels_; }
    const std::vector<uint8_t>& reference() const { return reference_; }
    const ObjectiveOptions& options() const { return base_.options(); }

    /// g0 of the header: 1e-6·whiteMean².
    double floor() const { return 1e-6 * d_.whiteMean * d_.whiteMean; }

  private:
    ImageObjective base_;  // the part mask, options, the env-map regulariser
    std::vector<uint8_t> defects_, reference_;
    std::vector<uint8_t> labels_;        // measured labels
    std::array<int, 256> labelIndex_{};  // value → index in labels_ (−1: not measured)
    std::vector<double> pairsK_;         // pixel pairs of each label
    double pairsD_ = 0, pairsR_ = 0, partPixels_ = 0;
    /// Calls f(k, p, q) for every pair of defect pixels p, q with one measured label k.
    template <typename F>
    void forEachLabelPair(F&& f) const;
    DefectObjectiveOptions d_;
};

/// The defect-free reference of DefectObjective.h's default: the part pixels farther than
/// `margin` pixels (Chebyshev) from every defect pixel.
std::vector<uint8_t> defectFreeReference(int width, int height, const std::vector<uint8_t>& part,
                                         const std::vector<uint8_t>& defects, int margin);

/// The region the defects objective (either measure) compares the defects with: `reference` on
/// the part and off the defects, or, when empty, defectFreeReference at 2 px (kCleanMargin).
/// `defects` holds the labels on the part only.
std::vector<uint8_t> referenceRegion(int width, int height, const std::vector<uint8_t>& part,
                                     const std::vector<uint8_t>& defects,
                                     const std::vector<uint8_t>& reference);

/// The white-furnace brightness w: the mean over `mask` of the luminance of T·1 (E = 1). With
/// `shard` distributed (core/Communicator.h), t holds this rank's rows and the image is put
/// together over the ranks first, so every rank gets the whole image's w.
double whiteFurnaceMean(const TransportMatrix& t, const std::vector<uint8_t>& mask,
                        const RowShard& shard = {});

}  // namespace sl

#include "objective/DefectObjective_impl.h"
