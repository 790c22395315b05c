// The defects objective in JND (objective/JndObjective.h): its exact gradient through T's halves
// against forward-mode autodiff (the Gaussians' adjoint, the band products, the masking, Barten's
// S(L) through the luminance, the soft-min over labels, the exposure band), its value against the
// judge's JND (perception/JndVisibility.h) where the floors are not active, and the eye's
// preference for a brighter part.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <vector>

#include "AutodiffCheck.h"
#include "DefectMeasureParts.h"
#include "TestUtil.h"
#include "core/Error.h"
#include "core/Rng.h"
#include "objective/Autodiff.h"
#include "objective/DefectVisibility.h"
#include "objective/JndObjective.h"
#include "objective/TransportLoss.h"
#include "perception/JndVisibility.h"
#include "scene/Scene.h"
#include "transport/TransportSink.h"

using namespace sl;

TEST(JndObjective, ExactGradientMatchesAutodiff) {
    const TransportMatrix t = test::bumpyHalves(8);
    ObjectiveOptions oo;
    oo.lambda = 3;
    const JndObjective obj(t.width, t.height, t.objectMask, test::twoStripes(t), {}, oo,
                           test::jndOptions(t));
    ASSERT_EQ(obj.labels().size(), 2u);
    Pcg32 rng(11, 3);
    // A mid light, a dark one (the dark floor and the luminance clamp) and a bright one (the
    // band's upper edge, clipping and the white's clamp).
    test::expectMatchesAutodiff(t, obj, rng, {0.5, 0.02, 3.0}, 1e-11, 1e-8);
}

namespace {

/// A 64×64 image pair: a texture everywhere and a bright 4-px scratch band (label 1), with a
/// little independent noise in each estimate.
struct ScratchImages {
    static constexpr int w = 64, h = 64;
    std::vector<uint8_t> part, defects;
    std::vector<double> ya, yb;
    ScratchImages() : part(w * h, 1), defects(w * h, 0), ya(w * h), yb(w * h) {
        Pcg32 rng(5, 9);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const size_t p = static_cast<size_t>(y) * w + x;
                const double texture = 0.02 * std::sin(0.9 * x + 0.4 * y);
                const bool scratch = x >= 30 && x < 34;
                defects[p] = scratch;
                const double base = 0.4 + texture + (scratch ? 0.15 : 0.0);
                ya[p] = base + 0.002 * (rng.nextDouble() - 0.5);
                yb[p] = base + 0.002 * (rng.nextDouble() - 0.5);
            }
    }
};

JndObjectiveOptions scratchOptions() {
    JndObjectiveOptions o;
    o.view.pixelsPerDegree = 38.8;
    o.view.whiteLuminance = 200;
    o.band.whiteMean = 0.8;
    return o;
}

}  // namespace

// With one label whose every band adds contrast above the floor, exp(−L_vis/2) is the judge's
// JND of that label over the defect-free surface (the same bands, products, sensitivity and
// masking), and LossParts::G says the same.
TEST(JndObjective, OneLabelsValueIsTheJudgesJnd) {
    const ScratchImages im;
    const JndObjectiveOptions o = scratchOptions();
    const JndObjective obj(im.w, im.h, im.part, im.defects, {}, ObjectiveOptions{}, o);
    const std::vector<double> e(8, 0.5);
    const LossParts r = obj.evaluate(im.ya, im.yb, e);
    const BandContrast bands(im.w, im.h, im.ya, im.yb, im.part, o.band.whiteMean, o.view);
    const std::vector<uint8_t> clean =
        defectFreeReference(im.w, im.h, im.part, im.defects, kCleanMargin);
    const JndScore judge = bands.score(im.defects, clean);
    ASSERT_GT(judge.jnd, 1.0);
    EXPECT_NEAR(std::exp(-r.lGrad / 2), judge.jnd, 1e-9 * judge.jnd);
    EXPECT_NEAR(r.G, judge.jnd, 1e-9 * judge.jnd);
}

// The ratio is blind to the light's scale; the eye is not: the same pattern at half the
// luminance (both inside the exposure band's reach of the white) is less visible, so the
// objective's L_vis is higher, by exactly what the judge says.
TEST(JndObjective, ABrighterPartIsSeenBetter) {
    const ScratchImages im;
    const JndObjectiveOptions o = scratchOptions();
    const JndObjective obj(im.w, im.h, im.part, im.defects, {}, ObjectiveOptions{}, o);
    std::vector<double> da = im.ya, db = im.yb;
    for (double& v : da) v *= 0.5;
    for (double& v : db) v *= 0.5;
    const std::vector<double> e(8, 0.5);
    const LossParts bright = obj.evaluate(im.ya, im.yb, e), dim = obj.evaluate(da, db, e);
    EXPECT_GT(bright.G, dim.G);
    EXPECT_LT(bright.lGrad, dim.lGrad);
    const BandContrast dimBands(im.w, im.h, da, db, im.part, o.band.whiteMean, o.view);
    const JndScore judge = dimBands.score(
        im.defects, defectFreeReference(im.w, im.h, im.part, im.defects, kCleanMargin));
    EXPECT_NEAR(dim.G, judge.jnd, 1e-9 * judge.jnd);
}

TEST(JndObjective, RegionsWithoutPixelsAreClearErrors) {
    const TransportMatrix t = test::bumpyHalves(2);
    const std::vector<uint8_t> none(t.rows(), 0), all(t.rows(), 1);
    const JndObjectiveOptions o = test::jndOptions(t);
    EXPECT_THROW(JndObjective(t.width, t.height, t.objectMask, none, {}, {}, o), InputError);
    EXPECT_THROW(JndObjective(t.width, t.height, t.objectMask, all, {}, {}, o), InputError);
}

// `optimize --defects-measure jnd` runs the JND objective through the whole job and says so in
// summary.json; it lowers its own loss; a measure outside the table is a usage error naming both.
TEST(JndObjective, OptimizeRunsItAndRecordsTheMeasure) {
    test::TempDir dir("jnd-cli");
    const std::string scene = (dir.path() / "scene.json").string(),
                      truth = (dir.path() / "part-truth.png").string();
    ASSERT_EQ(test::writeScratchedPart(dir.path()), 0);
    const auto out = dir.path() / "out";
    auto r =
        test::runCli("optimize " + scene + " --truth " + truth +
                     " --defects-measure jnd --heldout none --iterations 100 -o " + out.string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const auto summary = nlohmann::json::parse(test::readFile(out / "summary.json"));
    EXPECT_EQ(summary.value("objective", ""), "defects");
    EXPECT_EQ(summary.value("defects_measure", ""), "jnd");
    EXPECT_TRUE(summary.value("improved", false)) << r.output;
    r = test::runCli("optimize " + scene + " --truth " + truth + " --defects-measure eye -o " +
                     (dir.path() / "bad").string());
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("jnd"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("ratio"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir.path() / "bad"));
}
