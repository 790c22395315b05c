// The noise-unbiased objective (`--objective unbiased`; DESIGN.md "Noise is the trap").
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
//   L_reg    = mean(E²)               (--reg envmap), or Σ_p Y_a,p·Y_b,p / (W·H) (--reg image:
//                                     the unbiased estimate of Σ Ȳ²/(W·H))
//   Loss     = L_grad,u + λ·L_reg
//
// G_u can be ≤ 0 (noise can make the product of two differences negative). Below the floor
// G_min = 1e-12·S the loss is sqrt(S/G_min), its L_grad gradient is 0 and `clamped` is set —
// the same defined behaviour as ImageObjective's G → 0. In practice G_u is far above the floor
// as soon as the image has any structure.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "objective/Objective.h"

namespace sl {

class UnbiasedObjective {
  public:
    /// Same mask and options rules as ImageObjective (smoothAbs is not used: no |x| here).
    UnbiasedObjective(int width, int height, std::vector<uint8_t> mask, ObjectiveOptions options);

    /// Loss at the half images Ya, Yb (width*height each) and E. Gradients are filled when the
    /// spans are non-empty: dLdYa, dLdYb (width*height), dLdE (E.size()).
    LossParts evaluate(std::span<const double> Ya, std::span<const double> Yb,
                       std::span<const double> E, std::span<double> dLdYa = {},
                       std::span<double> dLdYb = {}, std::span<double> dLdE = {}) const;

    /// G_u alone (for tests and scoring).
    double energy(std::span<const double> Ya, std::span<const double> Yb) const;

    int width() const { return width_; }
    int height() const { return height_; }
    const std::vector<uint8_t>& mask() const { return mask_; }
    const ObjectiveOptions& options() const { return opt_; }
    double maskSize() const { return S_; }

  private:
    int width_, height_;
    std::vector<uint8_t> mask_;
    ObjectiveOptions opt_;
    double S_ = 0;
};

}  // namespace sl
