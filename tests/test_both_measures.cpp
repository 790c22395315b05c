// The defects objective on both measures (objective/BothMeasuresObjective.h): its exact gradient
// against forward-mode autodiff, its value against the two measures' (a soft maximum of their
// losses less the anchors: between the larger less τ·log 2 and the larger), the anchor light's
// gain of exactly 1, and `optimize --defects-measure both` end to end.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <vector>

#include "AutodiffCheck.h"
#include "DefectMeasureParts.h"
#include "TestUtil.h"
#include "core/Error.h"
#include "core/Rng.h"
#include "objective/BothMeasuresObjective.h"
#include "objective/TransportLoss.h"
#include "scene/Scene.h"
#include "transport/TransportSink.h"

using namespace sl;

namespace {

/// A light brighter towards one side of the grid (a lamp-like anchor).
std::vector<double> sideLight(const TransportMatrix& t) {
    std::vector<double> e(t.cols());
    for (size_t k = 0; k < e.size(); ++k)
        e[k] = 0.1 + 0.9 * static_cast<double>(k % t.envWidth) / t.envWidth;
    return e;
}

}  // namespace

TEST(BothMeasuresObjective, ExactGradientMatchesAutodiff) {
    const TransportMatrix t = test::bumpyHalves(8);
    ObjectiveOptions oo;
    oo.lambda = 3;
    BothMeasuresObjective obj(t.width, t.height, t.objectMask, test::twoStripes(t), {}, oo,
                              test::jndOptions(t));
    obj.setAnchors(measureAnchors(t, obj, sideLight(t), false));
    Pcg32 rng(17, 5);
    // A mid light, a dark one (the floors) and a bright one (the band's upper edge).
    test::expectMatchesAutodiff(t, obj, rng, {0.5, 0.02, 3.0}, 1e-11, 1e-8);
}

// The loss is the soft maximum of the two measures' losses less their anchors: at most the
// larger, at least the larger less τ·log 2; its visibility term at the anchor light is 0 (a gain
// of exactly 1 on both measures), and its gradient weighs the measure that gains less.
TEST(BothMeasuresObjective, IsTheSoftMaximumOfTheTwoGainsOverTheLamp) {
    const TransportMatrix t = test::bumpyHalves(8);
    ObjectiveOptions oo;
    oo.lambda = 3;
    BothMeasuresObjective obj(t.width, t.height, t.objectMask, test::twoStripes(t), {}, oo,
                              test::jndOptions(t));
    const std::vector<double> lamp = sideLight(t);
    const MeasureAnchors a = measureAnchors(t, obj, lamp, false);
    obj.setAnchors(a);
    const TransportLoss both(t, obj, false), jnd(t, obj.jnd(), false), ratio(t, obj.ratio(), false);
    const LossParts atLamp = both.evaluate(lamp, {});
    EXPECT_NEAR(atLamp.lGrad, 0.0, 1e-12);
    EXPECT_NEAR(atLamp.G, 1.0, 1e-12);
    Pcg32 rng(3, 8);
    for (int trial = 0; trial < 4; ++trial) {
        std::vector<double> e(t.cols());
        for (double& v : e) v = 0.1 + rng.nextDouble();
        const double aj = jnd.evaluate(e, {}).total - a.jnd,
                     ar = ratio.evaluate(e, {}).total - a.ratio;
        const double top = std::max(aj, ar), total = both.evaluate(e, {}).total;
        EXPECT_LE(total, top + 1e-12);
        EXPECT_GE(total, top - kLabelSoftMin * std::log(2.0) - 1e-12);
        // The gradient is the two gradients weighted towards the larger loss.
        std::vector<double> g(t.cols()), gj(t.cols()), gr(t.cols());
        both.evaluate(e, g);
        jnd.evaluate(e, gj);
        ratio.evaluate(e, gr);
        const double w = 1 / (1 + std::exp((ar - aj) / kLabelSoftMin));
        for (size_t k = 0; k < g.size(); ++k)
            EXPECT_NEAR(g[k], w * gj[k] + (1 - w) * gr[k],
                        1e-9 * (std::abs(gj[k]) + std::abs(gr[k]) + 1e-12));
    }
    EXPECT_THROW(measureAnchors(t, obj, std::vector<double>{}, false), InputError);
}

// Under a lamp that shows the defects less than 1 JND (the side light dimmed), the JND anchor is
// the visibility term of 1 JND (lGrad = −2·log 1 = 0), so a light's JND gain is counted from the
// threshold of seeing; the ratio's anchor is still the lamp's own (the ratio does not depend on
// the light's scale, the JND does).
TEST(BothMeasuresObjective, TheJndAnchorIsAtLeastOneJnd) {
    const TransportMatrix t = test::bumpyHalves(8);
    ObjectiveOptions oo;
    BothMeasuresObjective obj(t.width, t.height, t.objectMask, test::twoStripes(t), {}, oo,
                              test::jndOptions(t));
    const TransportLoss jnd(t, obj.jnd(), false), ratio(t, obj.ratio(), false);
    std::vector<double> lamp = sideLight(t);
    for (int k = 0; k < 40 && jnd.evaluate(lamp, {}).G >= 0.5 * kGainFloorJnd; ++k)
        for (double& v : lamp) v *= 0.25;
    ASSERT_LT(jnd.evaluate(lamp, {}).G, 0.5 * kGainFloorJnd) << "no dimming hides the stripes";
    const MeasureAnchors a = measureAnchors(t, obj, lamp, false);
    EXPECT_EQ(a.jnd, -2.0 * std::log(kGainFloorJnd));
    EXPECT_EQ(a.ratio, ratio.evaluate(lamp, {}).lGrad);
    // Where the lamp shows them at more than 1 JND its own term is the anchor.
    const std::vector<double> lit = sideLight(t);
    const LossParts litJnd = jnd.evaluate(lit, {});
    if (litJnd.G > kGainFloorJnd) {
        EXPECT_EQ(measureAnchors(t, obj, lit, false).jnd, litJnd.lGrad);
    }
}

TEST(BothMeasuresObjective, OptimizeRunsItOverTheLampAndRecordsTheMeasure) {
    test::TempDir dir("both-cli");
    const std::string scene = (dir.path() / "scene.json").string(),
                      truth = (dir.path() / "part-truth.png").string();
    ASSERT_EQ(test::writeScratchedPart(dir.path()), 0);
    const auto out = dir.path() / "out";
    const auto r =
        test::runCli("optimize " + scene + " --truth " + truth +
                     " --defects-measure both --heldout none --iterations 100 -o " + out.string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const auto summary = nlohmann::json::parse(test::readFile(out / "summary.json"));
    EXPECT_EQ(summary.value("defects_measure", ""), "both");
    EXPECT_TRUE(summary.value("improved", false)) << r.output;
}
