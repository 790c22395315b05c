// A box-constrained first-order function: what a loss offers and an optimizer consumes, known
// to neither side's internals (the shape of Ceres' FirstOrderFunction plus its bounds). Losses
// (objective/) build one; optimizers (optimize/) minimize one; neither includes the other.
#pragma once

#include <cstddef>
#include <functional>
#include <span>

namespace sl {

/// f(x, grad): the objective at x; fills grad (same size as x) when grad is non-empty.
/// x stays in the box [lower, upper]^dimension.
struct Problem {
    size_t dimension = 0;
    std::function<double(std::span<const double> x, std::span<double> grad)> evaluate;
    double lower = 0.0, upper = 1.0;
    /// Optional second-order information: Hv = ∇²f(x)·v (each the size of x), exact, for the
    /// methods that read it (optimize/Methods.h `newton-tr`). Empty when the problem offers
    /// none (a loss through T's Gram offers it: objective/TransportLoss.h hessianProduct).
    std::function<void(std::span<const double> x, std::span<const double> v, std::span<double> Hv)>
        hessianProduct;
};

}  // namespace sl
