// An objective on two independent half-sample images Y_a = T_a·E, Y_b = T_b·E of the same
// pixels (the noise-unbiased objectives: objective/UnbiasedObjective.h, DefectObjective.h).
// TransportLoss evaluates any of them through T's halves with the exact gradient
// T_aᵀ·dL/dY_a + T_bᵀ·dL/dY_b + dL/dE.
#pragma once

#include <span>

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
};

}  // namespace sl
