// The noise-unbiased objective (objective `unbiased`; docs/DESIGN.md "Noise is the trap").
//
// Monte Carlo noise raises Σ|ΔY| by itself, so the paper's S/G rewards noise. With two
// independent, unbiased half-sample images Y_a and Y_b of the same pixels (T = (T_a + T_b)/2),
//
//   G_u = Σ_pairs (Y_a,q − Y_a,p)·(Y_b,q − Y_b,p)        (the same pairs as ImageObjective)
//
// has expectation Σ_pairs (Ȳ_q − Ȳ_p)², the noise-free gradient energy. The loss plays the role
// of eq. 2 (more gradient → lower loss) in the same units:
//
//   L_grad,u = sqrt(S / G_u)          the reciprocal root-mean-square luminance gradient
//                                     (eq. 2 is the reciprocal mean absolute gradient, S/G)
//   L_reg    = mean(E²)               (reg envmap), or Σ_p Y_a,p·Y_b,p / (W·H) (reg image:
//                                     the unbiased estimate of Σ Ȳ²/(W·H))
//   Loss     = L_grad,u + λ·L_reg
//
// G_u can be ≤ 0 (noise can make the product of two differences negative; at a few spp on a
// small mask it happens even at E0). Below the floor G_min = 1e-12·S, L_grad continues along
// its tangent at G_min: L_grad = sqrt(S/G_min) − ½·sqrt(S)·G_min^(−3/2)·(G_u − G_min), and
// `clamped` is set. The loss is then finite, C¹ and strictly decreasing in G_u everywhere, so
// an optimizer that starts (or lands) there is pushed back toward positive gradient energy;
// a zero gradient there would leave only the regulariser, which drives E to black. In
// practice G_u is far above the floor as soon as the image has any structure.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "objective/HalfImageObjective.h"
#include "objective/Objective.h"

namespace sl {

class UnbiasedObjective final : public HalfImageObjective {
  public:
    /// Same mask and options rules as ImageObjective (smoothAbs is not used: no |x| here).
    UnbiasedObjective(int width, int height, std::vector<uint8_t> mask, ObjectiveOptions options);

    /// Loss at the half images Ya, Yb (width*height each) and E. Gradients are filled when the
    /// spans are non-empty: dLdYa, dLdYb (width*height), dLdE (E.size()).
    LossParts evaluate(std::span<const double> Ya, std::span<const double> Yb,
                       std::span<const double> E, std::span<double> dLdYa = {},
                       std::span<double> dLdYb = {}, std::span<double> dLdE = {}) const override;
    int imageWidth() const override { return width(); }
    int imageHeight() const override { return height(); }
    /// The loss is sqrt(S/G_u) (or its tangent) + λ·(mean(E²) or R/(W·H)): quadratic in the
    /// halves, so TransportLoss may evaluate it through T's Gram matrices.
    bool quadraticInHalves() const override { return true; }
    std::span<const uint8_t> pairMask() const override { return mask(); }
    bool usesProducts() const override { return options().reg == RegTarget::Image; }
    LossParts fromForms(double G, double R, std::span<const double> E, double& dLdG, double& dLdR,
                        std::span<double> dLdE) const override;
    /// d²L/dG² = ¾·sqrt(S)·G^(−5/2) above the floor, 0 on the tangent below it; the
    /// regulariser's curvature 2λ/texels for mean(E²), 0 for the image's (λ·R/(W·H) is linear
    /// in R).
    void formCurvature(double G, size_t texels, double& d2LdG2,
                       double& regCurvature) const override;

    /// G_u alone (for tests and scoring).
    double energy(std::span<const double> Ya, std::span<const double> Yb) const;
    /// The standard error of G_u from its two halves' own noise, by the delta method on the
    /// halves' product (exact for a bilinear form): with Y_a = μ + n, Y_b = μ + m, every
    /// pixel's noise independent, var n_p = var m_p = σ_p², and G_u = Y_aᵀ·M·Y_b (M the
    /// Laplacian of the counted pairs: M_pp the pixel's pair count, −1 per pair),
    ///   var G_u = Σ_p 2σ_p²·(Mμ)_p²  +  Σ_p M_pp²·σ_p⁴ + 2·Σ_pairs σ_p²·σ_q²,
    /// estimated without the noise's square counting twice: σ_p² by v_p = (Y_a,p − Y_b,p)²/2,
    /// (Mμ)_p² by (M·Y_a)_p·(M·Y_b)_p (independent halves: unbiased), and σ_p⁴ on the diagonal
    /// by v_p² (its own bias against v_p·(M·Y_a)_p·(M·Y_b)_p included: exact for a normal
    /// noise). A wild bootstrap (core/WildBootstrap.h) perturbs the observed, noisy
    /// differences instead of their means, which adds the quadratic part twice more: at a few
    /// spp, where that part dominates, its SE is several times the spread over independent
    /// estimates. 0 for a negative estimate (only possible when noise dominates).
    double energyStandardError(std::span<const double> Ya, std::span<const double> Yb) const;
    /// The standard error of lGrad = sqrt(S/G_u) by energyStandardError (|dL/dG|·SE(G_u)); the
    /// regulariser mean(E²) has none (reg envmap; NaN for reg image or a clamped G_u).
    double lossStandardError(std::span<const double> Ya, std::span<const double> Yb) const;

    int width() const { return base_.width(); }
    int height() const { return base_.height(); }
    const std::vector<uint8_t>& mask() const { return base_.mask(); }
    const ObjectiveOptions& options() const { return base_.options(); }
    double maskSize() const { return base_.maskSize(); }

  private:
    // Eq. 2's objective on the same mask and options: it checks them, holds them, and
    // provides the floor G_min and the env-map regulariser.
    ImageObjective base_;
};

}  // namespace sl
