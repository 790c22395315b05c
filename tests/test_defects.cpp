// The defect-aware objective (objective/DefectObjective.h): its exact gradient through T's
// halves against forward-mode autodiff, the analytic groove case (light across a groove shows it,
// light along it does not), and clear errors for bad masks.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>
#include <vector>

#include "AutodiffCheck.h"
#include "TestUtil.h"
#include "app/pipeline/Truth.h"
#include "core/Error.h"
#include "core/Rng.h"
#include "detect/MarkShapes.h"
#include "io/ImageIO.h"
#include "io/MaskIO.h"
#include "objective/Autodiff.h"
#include "objective/DefectObjective.h"
#include "objective/TransportLoss.h"
#include "optimize/Methods.h"
#include "optimize/Optimizer.h"
#include "scene/EnvMapBasis.h"
#include "scene/Scene.h"
#include "transport/TransportSink.h"

using namespace sl;

namespace {

TransportMatrix halves(const Scene& scene, int spp) {
    RenderOptions o;
    o.spp = spp;
    o.maxDepth = 3;
    o.sampleSets = 2;
    // The thresholds below were measured on this realization of the bsdf sampler (the optimum's
    // across/along ratio is 1.9-2.9 over seeds with either sampler; render/PathTracer.h).
    o.sampling = Sampling::Bsdf;
    return precomputeTransport(scene, o, 1).matrix;
}

/// Mean over the part of T·E: the part's brightness under E.
double partMean(const TransportMatrix& t, const std::vector<double>& e) {
    std::vector<double> y(t.rows());
    t.applyLuminance(e, y);
    double s = 0, n = 0;
    for (size_t p = 0; p < y.size(); ++p)
        if (t.objectMask[p]) s += y[p], n += 1;
    return s / n;
}

/// Mean over the part of T·1: the white-furnace brightness.
double whiteMean(const TransportMatrix& t) {
    return partMean(t, std::vector<double>(t.cols(), 1.0));
}

/// Columns [x0, x1) of the image as the defect region.
std::vector<uint8_t> stripe(const TransportMatrix& t, int x0, int x1) {
    std::vector<uint8_t> m(t.rows(), 0);
    for (int y = 0; y < t.height; ++y)
        for (int x = x0; x < x1; ++x) m[static_cast<size_t>(y) * t.width + x] = 1;
    return m;
}

}  // namespace

TEST(DefectObjective, ExactGradientMatchesAutodiff) {
    SceneDesc d;
    d.heightmap.pitch = 0.05;
    d.camera.origin = {0, 2, 2};
    d.camera.width = d.camera.height = 20;
    d.render.maxDepth = 3;
    const Scene scene(d, 32, 32, test::bumpyHeightMap(32));
    const TransportMatrix t = halves(scene, 8);
    DefectObjectiveOptions dopt;
    dopt.whiteMean = whiteMean(t);
    ObjectiveOptions oo;
    oo.lambda = 3;
    // The default contrast floor, and one so high that L_con is active at every light.
    for (double contrastFloor : {dopt.contrastFloor, 10.0}) {
        SCOPED_TRACE(contrastFloor);
        DefectObjectiveOptions o = dopt;
        o.contrastFloor = contrastFloor;
        const DefectObjective obj(t.width, t.height, t.objectMask, stripe(t, 8, 12), {}, oo, o);
        Pcg32 rng(7, 1);
        // A mid light, a dark one (the band's lower edge is active) and a bright one (clipping).
        test::expectMatchesAutodiff(t, obj, rng, {0.5, 0.02, 3.0}, 1e-12, 1e-9);
    }
}

// The contrast floor L_con: where the defects' contrast sqrt(g(D))/m is under f_c·c0 the loss
// rises by exactly κ_c·(½·log(g(D)/(f_c·c0·m)²))²; above it nothing changes. The contrast is
// invariant to the light's scale, so one light is scored against floors around its contrast.
TEST(DefectObjective, LowContrastDefectsCostTheFloorsLogSquared) {
    SceneDesc d;
    d.heightmap.pitch = 0.05;
    d.camera.origin = {0, 2, 2};
    d.camera.width = d.camera.height = 20;
    const Scene scene(d, 32, 32, test::bumpyHeightMap(32));
    const TransportMatrix t = halves(scene, 8);
    DefectObjectiveOptions without;
    without.whiteMean = whiteMean(t);
    without.contrastWeight = 0;
    const ObjectiveOptions oo;
    const DefectObjective b(t.width, t.height, t.objectMask, stripe(t, 8, 12), {}, oo, without);
    const TransportLoss lb(t, b, false);
    const std::vector<double> E(t.cols(), 0.5);
    const LossParts base = lb.evaluate(E, {});
    const double m = partMean(t, E);
    ASSERT_GT(base.G, 0.0);
    const double contrast = std::sqrt(base.G) / m;
    for (double f : {0.5, 0.99, 1.5, 4.0}) {  // the floor over the light's contrast
        SCOPED_TRACE(f);
        DefectObjectiveOptions with = without;
        with.contrastWeight = 100;
        with.contrastFloor = f * contrast;
        const DefectObjective a(t.width, t.height, t.objectMask, stripe(t, 8, 12), {}, oo, with);
        const TransportLoss la(t, a, false);
        const double extra = la.evaluate(E, {}).total - base.total;
        const double expected = f > 1 ? 100 * std::pow(std::log(1 / f), 2.0) : 0.0;
        EXPECT_NEAR(extra, expected, 1e-6 * (1 + expected));  // T vs its halves: float sums
    }
}

// Labels (issue 31 item 4): with two defect labels L_vis is ψ(g(R)) minus the soft-min of the
// labels' φ (objective/DefectObjective.h), to the last digit, with an exact gradient; and the
// rule holds: one label made 8x as salient while the other all but vanishes lowers the pooled
// objective (one region) but raises the labelled one.
TEST(DefectObjective, TheWorstLabelCountsSoftlyAndIsNotBoughtByAnother) {
    const int W = 16, H = 16;
    const std::vector<uint8_t> part(W * H, 1);
    std::vector<uint8_t> labelled(W * H, 0), pooled(W * H, 0), reference(W * H, 0);
    for (int y = 0; y < H; ++y) {
        for (int x : {2, 3}) labelled[y * W + x] = 1, pooled[y * W + x] = 1;
        for (int x : {10, 11}) labelled[y * W + x] = 2, pooled[y * W + x] = 1;
        for (int x : {6, 7}) reference[y * W + x] = 1;
    }
    DefectObjectiveOptions dopt;
    dopt.whiteMean = 1;
    ObjectiveOptions oo;
    oo.lambda = 0;
    const DefectObjective byLabel(W, H, part, labelled, reference, oo, dopt);
    const DefectObjective asOne(W, H, part, pooled, reference, oo, dopt);
    ASSERT_EQ(byLabel.labels(), (std::vector<uint8_t>{1, 2}));
    // Rows alternate by c inside each stripe (vertical pairs differ by c, horizontal by 0).
    auto image = [&](double c1, double c2) {
        std::vector<double> y(W * H);
        for (int r = 0; r < H; ++r)
            for (int x = 0; x < W; ++x) {
                const double c = labelled[r * W + x] == 1   ? c1
                                 : labelled[r * W + x] == 2 ? c2
                                                            : 0.01;
                y[r * W + x] = 0.5 + c * (r % 2);
            }
        return y;
    };
    const std::vector<double> E(8, 0.5);
    // g of a 2-column stripe of 16 rows: 30 vertical pairs of c², 16 horizontal of 0.
    auto g = [](double c) { return 30.0 / 46.0 * c * c; };
    const double tau = kLabelSoftMin;
    for (auto [c1, c2] : {std::pair{0.05, 0.05}, std::pair{0.4, 0.002}, std::pair{0.2, 0.03}}) {
        SCOPED_TRACE(c1);
        const std::vector<double> y = image(c1, c2);
        const double phi1 = std::log(g(c1)), phi2 = std::log(g(c2));
        const double M = -tau * std::log(0.5 * (std::exp(-phi1 / tau) + std::exp(-phi2 / tau)));
        const LossParts p = byLabel.evaluate(y, y, E);
        EXPECT_NEAR(p.lGrad, std::log(g(0.01)) - M, 1e-12 * std::abs(p.lGrad));
        EXPECT_LE(M, 0.5 * (phi1 + phi2) + 1e-12);  // between the worst label and the mean
        EXPECT_GE(M, std::min(phi1, phi2) - 1e-12);
    }
    const double before = byLabel.evaluate(image(0.05, 0.05), image(0.05, 0.05), E).total;
    const double after = byLabel.evaluate(image(0.4, 0.002), image(0.4, 0.002), E).total;
    const double pooledBefore = asOne.evaluate(image(0.05, 0.05), image(0.05, 0.05), E).total;
    const double pooledAfter = asOne.evaluate(image(0.4, 0.002), image(0.4, 0.002), E).total;
    EXPECT_LT(pooledAfter, pooledBefore);  // one region: the vanished label is not seen
    EXPECT_GT(after, before + 1.0);        // by label: it is
    // One label: the soft-min is φ itself (the pooled objective as it was).
    EXPECT_NEAR(asOne.evaluate(image(0.05, 0.05), image(0.05, 0.05), E).lGrad,
                std::log(g(0.01)) - std::log(g(0.05)), 1e-12);

    // The exact gradient through T's halves against autodiff, two labels on a rendered part.
    SceneDesc d;
    d.heightmap.pitch = 0.05;
    d.camera.origin = {0, 2, 2};
    d.camera.width = d.camera.height = 20;
    d.render.maxDepth = 3;
    const Scene scene(d, 32, 32, test::bumpyHeightMap(32));
    const TransportMatrix t = halves(scene, 8);
    DefectObjectiveOptions tdopt;
    tdopt.whiteMean = whiteMean(t);
    std::vector<uint8_t> two = stripe(t, 4, 7);
    const std::vector<uint8_t> second = stripe(t, 12, 15);
    for (size_t q = 0; q < two.size(); ++q)
        if (second[q]) two[q] = 7;
    ObjectiveOptions to;
    to.lambda = 3;
    const DefectObjective obj(t.width, t.height, t.objectMask, two, {}, to, tdopt);
    ASSERT_EQ(obj.labels().size(), 2u);
    Pcg32 rng(11, 1);
    test::expectMatchesAutodiff(t, obj, rng, {0.5, 0.05}, 1e-12, 1e-9);
}

// The dark floor L_dark (objective/DefectObjective.h): below darkFloor (2·kMinVisibleBrightness)
// of the white furnace the loss rises by exactly κ_f·log(m/(f·w))², without bound as the part goes
// black; above it nothing changes.
TEST(DefectObjective, ADarkPartCostsTheFloorsLogSquared) {
    SceneDesc d;
    d.heightmap.pitch = 0.05;
    d.camera.origin = {0, 2, 2};
    d.camera.width = d.camera.height = 20;
    const Scene scene(d, 32, 32, test::bumpyHeightMap(32));
    const TransportMatrix t = halves(scene, 8);
    DefectObjectiveOptions with;
    with.whiteMean = whiteMean(t);
    DefectObjectiveOptions without = with;
    without.darkWeight = 0;
    const ObjectiveOptions oo;
    const DefectObjective a(t.width, t.height, t.objectMask, stripe(t, 8, 12), {}, oo, with);
    const DefectObjective b(t.width, t.height, t.objectMask, stripe(t, 8, 12), {}, oo, without);
    const TransportLoss la(t, a, false), lb(t, b, false);
    double last = 0;
    for (double level : {0.5, 0.12, 0.08, 0.02, 0.001}) {
        SCOPED_TRACE(level);
        const std::vector<double> E(t.cols(), level);  // the part's mean is level·w
        const double m = partMean(t, E);
        const double floor = with.darkFloor * with.whiteMean;
        const double expected =
            m < floor ? with.darkWeight * std::pow(std::log(m / floor), 2.0) : 0.0;
        const double extra = la.evaluate(E, {}).total - lb.evaluate(E, {}).total;
        EXPECT_NEAR(extra, expected, 1e-6 * (1 + expected));  // T vs its halves: float sums
        EXPECT_GE(extra, last - 1e-12);                       // darker costs more
        last = extra;
    }
    EXPECT_GT(last, 100.0);  // 1/100 of the floor: κ_f·log(100)² ≈ 2120
}

// A V-groove along z on a gently textured plane, seen from straight above: a light from the
// side (across the groove, elevation twice the wall slope) lights one wall and not the other;
// the same light turned to come along the groove lights neither. The objective prefers the
// first by a wide margin.
TEST(DefectObjective, LightAcrossAGrooveBeatsLightAlongIt) {
    const int n = 96;
    const double pitch = 0.0125, halfWidth = 0.1, depth = 0.03;  // walls at atan(0.3) = 16.7°
    std::vector<float> h(static_cast<size_t>(n) * n);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const double x = (i - 0.5 * (n - 1)) * pitch, z = (j - 0.5 * (n - 1)) * pitch;
            const double groove =
                std::abs(x) < halfWidth ? -depth * (1 - std::abs(x) / halfWidth) : 0.0;
            const double texture = 0.002 * std::sin(2 * std::numbers::pi * x / 0.15) *
                                   std::sin(2 * std::numbers::pi * z / 0.15);
            h[static_cast<size_t>(j) * n + i] = static_cast<float>(groove + texture);
        }
    SceneDesc d;
    d.heightmap.pitch = pitch;
    d.material.params.alphaU = d.material.params.alphaV = 0.15f;
    d.camera.type = CameraDesc::Type::Orthographic;
    d.camera.origin = {0, 20, 0};
    d.camera.target = {0, 0, 0};
    d.camera.up = {0, 0, -1};
    d.camera.widthMm = 1.0;
    d.camera.width = d.camera.height = 40;
    d.render.maxDepth = 2;
    const Scene scene(d, n, n, h);
    const TransportMatrix t = halves(scene, 32);
    // The defect region: the columns over the groove (|x| < halfWidth).
    std::vector<uint8_t> groove(t.rows(), 0);
    for (int y = 0; y < t.height; ++y)
        for (int x = 0; x < t.width; ++x) {
            const double wx = ((x + 0.5) / t.width - 0.5) * 1.0;
            if (std::abs(wx) < 0.8 * halfWidth) groove[static_cast<size_t>(y) * t.width + x] = 1;
        }
    DefectObjectiveOptions dopt;
    dopt.whiteMean = whiteMean(t);
    ObjectiveOptions oo;
    oo.lambda = 0;
    const DefectObjective obj(t.width, t.height, t.objectMask, groove, {}, oo, dopt);
    const TransportLoss loss(t, obj, false);
    // A small lamp at 33° from the zenith (rows 4–5 of 25), azimuth +x (column 12: u = 0.25)
    // or −z (column 0/49: u ≈ 0), as env-map texels (scene/EnvMapBasis.h).
    auto lamp = [&](int col) {
        std::vector<double> E(t.cols(), 0.0);
        for (int row = 4; row <= 5; ++row)
            for (int dc = -1; dc <= 1; ++dc)
                E[static_cast<size_t>(row) * t.envWidth + (col + dc + t.envWidth) % t.envWidth] =
                    1.0;
        return E;
    };
    const LossParts across = loss.evaluate(lamp(12), {}), along = loss.evaluate(lamp(0), {});
    std::printf("L_vis across %.3f (g_D %.3g, g_R %.3g), along %.3f (g_D %.3g, g_R %.3g)\n",
                across.lGrad, across.G, across.S, along.lGrad, along.G, along.S);
    EXPECT_FALSE(across.clamped);
    // L_vis = −log(visibility²): across must show the groove e times more (in g) at least.
    EXPECT_LT(across.lGrad, along.lGrad - 1.0)
        << "across " << across.lGrad << " along " << along.lGrad;

    // The optimum, not just the comparison: L-BFGS from uniform light (with a little λ so the
    // scale is fixed) puts the light across the groove: what E has above its median, on texels
    // whose horizontal direction is nearer ±x (across) than ±z (along), each weighted by its
    // horizontal component (the zenith is neither), is over twice the rest (2.85x here).
    ObjectiveOptions oo2;
    oo2.lambda = 1;
    const DefectObjective obj2(t.width, t.height, t.objectMask, groove, {}, oo2, dopt);
    const TransportLoss loss2(t, obj2, false);
    std::vector<double> E(t.cols(), 0.5);
    OptimizerOptions opt;
    opt.method = OptimizerMethod::Lbfgs;
    opt.iterations = 300;
    const OptimizerSummary sum = minimize(loss2.problem(), E, opt);
    const LossParts best = loss2.evaluate(E, {});
    EXPECT_LT(best.lGrad, across.lGrad + 0.5) << sum.termination;
    const EnvMapBasis basis(t.envWidth, t.envHeight);
    std::vector<double> sorted(E);
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    const double floorE = sorted[sorted.size() / 2];  // the light is what stands above the median
    double acrossWeight = 0, alongWeight = 0;
    for (int row = 0; row < t.envHeight; ++row)
        for (int col = 0; col < t.envWidth; ++col) {
            const Vec3d dir = basis.texelDirection(row, col);
            if (dir.y <= 0) continue;  // below the horizon: no path from the camera reaches it
            const double e =
                std::max(0.0, E[static_cast<size_t>(row) * t.envWidth + col] - floorE) *
                std::sqrt(dir.x * dir.x + dir.z * dir.z);
            (std::abs(dir.x) > std::abs(dir.z) ? acrossWeight : alongWeight) += e;
        }
    std::printf("optimum: L_vis %.3f; light across %.3f, along %.3f\n", best.lGrad, acrossWeight,
                alongWeight);
    EXPECT_GT(acrossWeight, 2.0 * alongWeight);
}

TEST(DefectObjective, BadMasksGetClearErrors) {
    const int W = 8, H = 8;
    const std::vector<uint8_t> part(W * H, 1);
    DefectObjectiveOptions dopt;
    dopt.whiteMean = 1;
    auto expectError = [&](const std::string& what, std::vector<uint8_t> defects,
                           std::vector<uint8_t> reference) {
        try {
            DefectObjective(W, H, part, std::move(defects), std::move(reference), {}, dopt);
            ADD_FAILURE() << what << " accepted";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
        }
    };
    expectError(option("defects"), std::vector<uint8_t>(W * H, 0), {});    // empty
    expectError(option("reference"), std::vector<uint8_t>(W * H, 1), {});  // all defect
    expectError(option("defects"), std::vector<uint8_t>(10, 1), {});       // wrong size
    std::vector<uint8_t> some(W * H, 0);
    some[9] = some[10] = 1;
    expectError(option("reference"), some, std::vector<uint8_t>(3, 1));  // wrong size
    DefectObjective ok(W, H, part, some, {}, {}, dopt);
    EXPECT_EQ(ok.defects()[9], 1);
}

// `optimize --objective defects` on a generated part: trains on the truth mask, reports the
// objective; without a defect mask it finds one (auto); a bad region is refused.
TEST(DefectObjective, OptimizeRunsItOnAGeneratedPart) {
    test::TempDir dir("defects-cli");
    const std::string part = (dir.path() / "part.exr").string(),
                      scene = (dir.path() / "scene.json").string(),
                      truth = (dir.path() / "part-truth.png").string();
    ASSERT_EQ(test::runCli("gen-surface -o " + part +
                           " --width 160 --height 160 --scratches 3 "
                           "--chatter-start 0.5 --scene " +
                           scene + " --image-size 40 --spp 8 --max-depth 3")
                  .exitCode,
              0);
    const auto out = dir.path() / "out";
    auto r = test::runCli("optimize " + scene + " --objective defects --truth " + truth +
                          " --heldout none --iterations 200 -o " + out.string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    std::ifstream in(out / "summary.json");
    std::stringstream ss;
    ss << in.rdbuf();
    EXPECT_NE(ss.str().find("\"objective\": \"defects\""), std::string::npos);
    // Every summary says which build wrote it, how it was asked for and when.
    const auto summary = nlohmann::json::parse(ss.str());
    EXPECT_FALSE(summary["scratchlight"]["version"].get<std::string>().empty());
    EXPECT_FALSE(summary["scratchlight"]["commit"].get<std::string>().empty());
    EXPECT_NE(summary["scratchlight"]["command"].get<std::string>().find("--objective defects"),
              std::string::npos);
    EXPECT_EQ(summary["scratchlight"]["date"].get<std::string>().size(), 20u);
    // regions.png: the render with the defect region's boundary in red.
    const Image regions = readImage(out / "regions.png");
    ASSERT_EQ(regions.channels, 3);
    int red = 0;
    for (size_t q = 0; q < regions.pixelCount(); ++q)
        red += regions.data[3 * q] > 0.99f && regions.data[3 * q + 1] < 0.01f;
    EXPECT_GT(red, 0);
    // Naming the defects (a truth) without an objective gives the defects objective (the
    // default measured by scripts/eval-defects); without them, the noise-unbiased one.
    r = test::runCli("optimize " + scene + " --truth " + truth +
                     " --heldout none --iterations 20 -o " + (dir.path() / "byDefault").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_EQ(nlohmann::json::parse(test::readFile(dir.path() / "byDefault" / "summary.json"))
                  .value("objective", ""),
              "defects");
    r = test::runCli("optimize " + scene + " --heldout none --iterations 20 -o " +
                     (dir.path() / "plain").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_EQ(nlohmann::json::parse(test::readFile(dir.path() / "plain" / "summary.json"))
                  .value("objective", ""),
              "unbiased");
    // Without a mask or a truth: the defect map found without labels (auto).
    r = test::runCli("optimize " + scene +
                     " --objective defects --heldout none --iterations 50 -o " +
                     (dir.path() / "out2").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    std::ifstream in2(dir.path() / "out2" / "summary.json");
    std::stringstream ss2;
    ss2 << in2.rdbuf();
    EXPECT_NE(ss2.str().find("\"defects\": \"auto\""), std::string::npos) << ss2.str();
    // auto's regions are the map's marks labelled by shape (detect/MarkShapes.h): the
    // scratches are lines, and nothing else is written
    {
        const Image labels = readImage(dir.path() / "out2" / "regions-defects.png");
        size_t lines = 0, other = 0;
        for (size_t q = 0; q < labels.pixelCount(); ++q) {
            const long v = std::lround(labels.data[q * labels.channels] * 255.0f);
            lines += v == kMarkLine;
            other += v != 0 && !isMarkShapeLabel(static_cast<uint8_t>(v));
        }
        EXPECT_GT(lines, 0u);
        EXPECT_EQ(other, 0u);
    }
    // A label the truth does not have: an error naming the file, exit 1.
    r = test::runCli("optimize " + scene + " --objective defects --heldout none --defects " +
                     truth + ":nosuchkind -o " + (dir.path() / "out3").string());
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.output.find("part-truth.png"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir.path() / "out3"));
    // A clean part: the defect map marks nothing, and auto says so.
    const std::string clean = (dir.path() / "clean.exr").string(),
                      cleanScene = (dir.path() / "clean.json").string();
    ASSERT_EQ(test::runCli("gen-surface -o " + clean +
                           " --width 160 --height 160 --scratches 0 --gouges 0 --chatter 0 "
                           "--no-pocket --scene " +
                           cleanScene + " --image-size 40 --spp 4 --max-depth 3")
                  .exitCode,
              0);
    r = test::runCli("optimize " + cleanScene + " --objective defects --heldout none -o " +
                     (dir.path() / "out4").string());
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.output.find("--defects auto: the defect map"), std::string::npos) << r.output;
}

// Regions by label (the region-comparison mode): "FILE:LABEL,..." picks the listed labels of a
// truth file by name or value; "none"/0 is the unlabelled surface; other paths stay whole.
TEST(RegionSpec, PicksLabelsOfATruthFile) {
    EXPECT_EQ(parseRegionSpec("m.png", "defects").labels.size(), 0u);
    EXPECT_EQ(parseRegionSpec("dir:with:colons/m.png", "defects").file, "dir:with:colons/m.png");
    const RegionSpec r = parseRegionSpec("a/t.png:chatter,255", "defects");
    EXPECT_EQ(r.file, "a/t.png");
    ASSERT_EQ(r.labels.size(), 2u);
    EXPECT_EQ(r.labels[0], "chatter");
    EXPECT_EQ(r.text(), "a/t.png:chatter,255");
    EXPECT_THROW(parseRegionSpec("t.png:chatter,", "defects"), InputError);
    EXPECT_TRUE(parseRegionSpec("auto", "defects").automatic);
    EXPECT_EQ(parseRegionSpec("auto", "defects").text(), "auto");
    EXPECT_FALSE(parseRegionSpec("auto.png", "defects").automatic);

    test::TempDir dir("regions");
    const std::string part = (dir.path() / "p.exr").string();
    ASSERT_EQ(test::runCli("gen-surface -o " + part + " --width 64 --height 48 --scratches 2 " +
                           "--gouges 0 --chatter-start 0.5")
                  .exitCode,
              0);
    const std::string truth = (dir.path() / "p-truth.png").string();
    const LabelMask m = readLabelMask(truth, 64, 48);
    size_t chatter = 0, none = 0, scratch = 0;
    for (uint8_t v : m.labels) {
        chatter += v == 128;
        none += v == 0;
        scratch += v == 255;
    }
    ASSERT_GT(chatter, 0u);
    ASSERT_GT(scratch, 0u);
    auto count = [](const std::vector<uint8_t>& x) {
        size_t n = 0;
        for (uint8_t v : x) n += v != 0;
        return n;
    };
    // The labels keep their values (the defects objective scores each); "none" is 255.
    {
        const auto both =
            regionInHeightMap(parseRegionSpec(truth + ":chatter,defect", "d"), 64, 48);
        for (size_t q = 0; q < both.size(); ++q)
            ASSERT_EQ(both[q], m.labels[q] == 128 || m.labels[q] == 255 ? m.labels[q] : 0) << q;
        const auto clean = regionInHeightMap(parseRegionSpec(truth + ":none", "d"), 64, 48);
        for (size_t q = 0; q < clean.size(); ++q) ASSERT_EQ(clean[q], m.labels[q] ? 0 : 255) << q;
    }
    EXPECT_EQ(count(regionInHeightMap(parseRegionSpec(truth + ":chatter", "d"), 64, 48)), chatter);
    EXPECT_EQ(count(regionInHeightMap(parseRegionSpec(truth + ":128", "d"), 64, 48)), chatter);
    EXPECT_EQ(count(regionInHeightMap(parseRegionSpec(truth + ":none", "d"), 64, 48)), none);
    EXPECT_EQ(count(regionInHeightMap(parseRegionSpec(truth + ":chatter,defect", "d"), 64, 48)),
              chatter + scratch);
    try {
        regionInHeightMap(parseRegionSpec(truth + ":bogus", "d"), 64, 48);
        ADD_FAILURE() << "an unknown label was accepted";
    } catch (const InputError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("p-truth.png"), std::string::npos) << msg;
        EXPECT_NE(msg.find("chatter (128)"), std::string::npos) << msg;
    }
}
