// The exact gradient of a half-image objective through T's halves against forward-mode autodiff
// (objective/Autodiff.h), at random lights: the defects objective's two measures share it.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <initializer_list>
#include <vector>

#include "core/Rng.h"
#include "objective/Autodiff.h"
#include "objective/TransportLoss.h"

namespace sl::test {

/// At lights with texels in [0.2, 1]·scale (drawn from rng), for each scale: the loss to
/// lossTol and the gradient to gradTol (relative L2) of autodiffThroughHalves.
template <class HalfObjective>
void expectMatchesAutodiff(const TransportMatrix& t, const HalfObjective& obj, Pcg32& rng,
                           std::initializer_list<double> scales, double lossTol, double gradTol) {
    const TransportLoss loss(t, obj, false);
    for (double scale : scales) {
        SCOPED_TRACE(scale);
        std::vector<double> e(t.cols());
        for (double& v : e) v = scale * (0.2 + 0.8 * rng.nextDouble());
        std::vector<double> grad(t.cols());
        const LossParts p = loss.evaluate(e, grad);
        const AutodiffGradient ad = autodiffThroughHalves(t, obj, e);
        EXPECT_NEAR(p.total, ad.loss, lossTol * std::abs(ad.loss));
        EXPECT_LT(compareGradients(grad, ad.gradient).relativeL2, gradTol);
    }
}

}  // namespace sl::test
