// The defects objective in the eye's units (`--objective defects`, measure `jnd`): make the
// worst defect label's visibility in just-noticeable differences large, as the judge measures it
// (perception/JndVisibility.h, README "Visibility in JND"), on two independent half-sample images,
// while the image stays usefully exposed (the same band and floor as the ratio measure,
// objective/DefectObjective.h).
//
// Regions (image space, within the part mask P): the defect labels D_1..D_K (every label with a
// pixel on the part) and the defect-free reference F (default: DefectObjective's, the part pixels
// farther than kCleanMargin pixels from every defect). With the band products of
// perception/BandFilters.h (c_b,a·c_b,b per pixel, b = 0..kJndBands−1):
//
//   e_b(X)  = mean over X of c_b,a·c_b,b           (noise-unbiased band contrast energy)
//   Δ_kb    = e_b(D_k) − e_b(F)                     (the contrast energy label k adds)
//   L       = white luminance · clamp(m / w, ℓ0, 1)  m the part's mean of Ȳ, w the white furnace's;
//             ℓ0 = kMinJndLuminance / white luminance keeps the eye model in its photopic range
//   S_kb    = Barten's S(u_b, L, X0_k, X0_k),  X0_k = sqrt(|D_k|) / pixels per degree
//   q_k     = Σ_b jndBandFourth(h(Δ_kb), max(e_b(F), 0), S_kb)   = J_k⁴ where every Δ_kb ≥ δ0
//   h(Δ)    = Δ² for Δ ≥ δ0, else its tangent 2δ0·Δ − δ0²: C¹ and increasing, so a light that shows
//             nothing (Δ ≤ 0, noise can make it negative) is still pushed towards one that does;
//             δ0 = kJndEnergyFloor (an RMS band contrast of 1/1000)
//   φ_k     = log q_k for q_k ≥ q0, else its tangent (objective/DefectObjective_impl.h
//             defectLogFloor), q0 = kJndFloor⁴
//   M       = softmin_τ (φ_k / 2) over the labels (τ = kLabelSoftMin, as the ratio measure's; φ/2 =
//             2·log J, the ratio measure's units of 2·log visibility), so exp(M/2) = J with one
//             label
//   Loss    = −M + L_exp + L_dark + λ·mean(E²)   (L_exp, L_dark: DefectObjective.h exposureBand)
//
// LossParts: lGrad = −M (so exp(−lGrad/2) is the worst label's JND, as exp(−lGrad/2) is the ratio
// measure's visibility: the noise rule's gap reads either), G = that JND, S = the texture's band
// contrast RMS (sqrt Σ_b max(e_b(F),0)). Unlike the ratio, JND depends on the light's brightness
// through the eye's sensitivity: a brighter part is seen better, up to the band's upper edge.
//
// evaluate() gives dLoss/dY_a, dLoss/dY_b exactly (the adjoint of every step above; Barten's S(L)
// differentiated with core/Dual.h); value<S>() computes the same loss in any scalar type for the
// autodiff check (objective/Autodiff.h).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "objective/DefectObjective.h"
#include "objective/HalfImageObjective.h"
#include "objective/Objective.h"
#include "perception/BandFilters.h"
#include "perception/ViewingModel.h"

namespace sl {

inline constexpr double kJndFloor = 0.1;         // JND below which φ is linear
inline constexpr double kJndEnergyFloor = 1e-6;  // δ0: band contrast energy (RMS 0.001)
inline constexpr double kMinJndLuminance = 0.1;  // cd/m², the least luminance the model sees

struct JndObjectiveOptions {
    ViewingModel view;            // pixels per degree and the display's white (cd/m²)
    DefectObjectiveOptions band;  // whiteMean (> 0), the exposure band and the dark floor
    /// How the band filters are computed (perception/BandFilters.h): the same operator either
    /// way; Direct is the reference `bench jnd` times Fourier against.
    GaussianMethod gaussians = GaussianMethod::Fourier;
};

class JndObjective final : public HalfImageObjective {
  public:
    /// part, defects (labels, 0: none), reference (empty: the default) as DefectObjective's.
    /// Throws InputError (option 'defects' / 'reference') when no label has a pixel on the part
    /// or no reference pixel is left.
    JndObjective(int width, int height, std::vector<uint8_t> part, std::vector<uint8_t> defects,
                 std::vector<uint8_t> reference, ObjectiveOptions options, JndObjectiveOptions jnd);

    LossParts evaluate(std::span<const double> Ya, std::span<const double> Yb,
                       std::span<const double> E, std::span<double> dLdYa = {},
                       std::span<double> dLdYb = {}, std::span<double> dLdE = {}) const override;
    int imageWidth() const override { return width_; }
    int imageHeight() const override { return height_; }

    /// The same loss in scalar type S (double, ceres::Jet): the autodiff reference.
    template <typename S>
    S value(std::span<const S> Ya, std::span<const S> Yb, std::span<const S> E) const;

    int width() const { return width_; }
    int height() const { return height_; }
    /// The labels scored (values of the defect mask with a pixel on the part), ascending.
    const std::vector<uint8_t>& labels() const { return labels_; }

  private:
    /// The luminance L(m) of the header and dL/dm (0 where clamped).
    template <typename S>
    S luminanceOf(const S& m) const;

    int width_, height_;
    ImageObjective base_;  // the part mask, options, the env-map regulariser
    BandFilterBank bank_;
    JndObjectiveOptions o_;
    std::vector<uint8_t> labels_;
    std::vector<int> labelOf_;         // per pixel: index into labels_ (−1: none or off the part)
    std::vector<uint8_t> reference_;   // 0/1
    std::vector<double> labelPixels_;  // |D_k|
    std::vector<double> labelSizeDeg_;  // X0_k
    double referencePixels_ = 0, partPixels_ = 0;
    std::vector<double> bandFrequency_;  // u_b, cycles/degree
};

}  // namespace sl

#include "objective/JndObjective_impl.h"
