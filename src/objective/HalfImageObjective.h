// An objective on two independent half-sample images Y_a = T_a·E, Y_b = T_b·E of the same
// pixels (the noise-unbiased objectives: objective/UnbiasedObjective.h, DefectObjective.h).
// TransportLoss evaluates any of them through T's halves with the exact gradient
// T_aᵀ·dL/dY_a + T_bᵀ·dL/dY_b + dL/dE.
#pragma once

#include <cstdint>
#include <span>
#include <stdexcept>

#include "objective/Objective.h"

namespace sl {

class HalfImageObjective {
  public:
    virtual ~HalfImageObjective() = default;
    /// Loss at the half images (width*height each) and E; fills the gradients when the spans
    /// are non-empty (dLdYa, dLdYb: width*height; dLdE: E.size()).
    virtual LossParts evaluate(std::span<const double> Ya, std::span<const double> Yb,
                               std::span<const double> E, std::span<double> dLdYa = {},
                               std::span<double> dLdYb = {}, std::span<double> dLdE = {}) const = 0;
    virtual int imageWidth() const = 0;
    virtual int imageHeight() const = 0;

    /// Whether the loss depends on the halves only through the two quadratic forms
    ///   G = Σ_pairs (Ya_q − Ya_p)·(Yb_q − Yb_p)   (right and down neighbours, both in pairMask())
    ///   R = Σ_p Ya_p·Yb_p                         (every pixel; read only when usesProducts())
    /// and E: then TransportLoss may evaluate it through T's Gram matrices
    /// (transport/TransportGram.h) with fromForms. The defaults say it does not.
    virtual bool quadraticInHalves() const { return false; }
    virtual std::span<const uint8_t> pairMask() const { return {}; }
    virtual bool usesProducts() const { return false; }
    /// The loss from G, R and E, as evaluate() forms it from the halves; dLdG, dLdR receive
    /// dLoss/dG and dLoss/dR, dLdE (when non-empty) the loss's direct dLoss/dE.
    virtual LossParts fromForms(double G, double R, std::span<const double> E, double& dLdG,
                                double& dLdR, std::span<double> dLdE) const {
        (void)G, (void)R, (void)E, (void)dLdG, (void)dLdR, (void)dLdE;
        throw std::logic_error("HalfImageObjective::fromForms: the loss is not quadratic");
    }
    /// fromForms' second derivatives, for Hessian products through the Gram: d²L/dG² at G into
    /// d2LdG2 (L is linear in R: dLdR is its whole part), and the direct d²L/dE² as a multiple
    /// of the identity into regCurvature (for `texels` values of E).
    virtual void formCurvature(double G, size_t texels, double& d2LdG2,
                               double& regCurvature) const {
        (void)G, (void)texels, (void)d2LdG2, (void)regCurvature;
        throw std::logic_error("HalfImageObjective::formCurvature: the loss is not quadratic");
    }
};

}  // namespace sl
