// Hard cases (README "Limits"): each gives finite results or a clear error, never a silent NaN,
// a hang or a crash. Small scenes, so the whole suite takes a few seconds.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <vector>

#include "TestUtil.h"
#include "app/jobs/OptimizeJob.h"
#include "app/pipeline/InitialState.h"
#include "core/Error.h"
#include "detect/ScratchMap.h"
#include "io/TransportFile.h"
#include "objective/Metrics.h"
#include "objective/Objective.h"
#include "objective/TransportLoss.h"
#include "objective/UnbiasedObjective.h"
#include "optimize/BlackBox.h"
#include "optimize/Optimizer.h"
#include "render/Render.h"
#include "scene/Scene.h"
#include "transport/TransportSink.h"

using namespace sl;

namespace {

/// A 16×16-pixel view that the 32×32-sample part (1.55 mm) fills.
SceneDesc smallDesc(int res = 16) {
    SceneDesc d;
    d.heightmap.pitch = 0.05;
    d.camera.origin = {0, 2, 2};
    d.material.params.alphaU = d.material.params.alphaV = 0.1f;
    d.camera.width = d.camera.height = res;
    d.render.maxDepth = 3;
    return d;
}

std::unique_ptr<Scene> sceneOf(std::vector<float> h, int n, const SceneDesc& d = smallDesc()) {
    return std::make_unique<Scene>(d, n, n, std::move(h));
}

RenderOptions opts(int spp = 4, int sets = 1) {
    RenderOptions o;
    o.spp = spp;
    o.maxDepth = 3;
    o.sampleSets = sets;
    return o;
}

bool allFinite(std::span<const double> v) {
    for (double x : v)
        if (!std::isfinite(x)) return false;
    return true;
}

/// T·E equals the render under E (gray), and both are finite.
void expectRenderMatchesTransport(const Scene& scene, double e, size_t minPartPixels = 20) {
    const RenderOptions o = opts();
    const TransportMatrix t = precomputeTransport(scene, o, 1).matrix;
    size_t part = 0;
    for (uint8_t m : t.objectMask) part += m != 0;
    EXPECT_GE(part, minPartPixels) << "the camera does not see the part";
    std::vector<double> E(t.cols(), e), Y(t.rows());
    t.applyLuminance(E, Y);
    ASSERT_TRUE(allFinite(Y));
    const RenderResult r =
        render(scene, EnvMap::constant(t.envWidth, t.envHeight, static_cast<float>(e)), o);
    for (size_t p = 0; p < Y.size(); ++p) {
        const float* c = &r.image.data[p * static_cast<size_t>(r.image.channels)];
        ASSERT_TRUE(std::isfinite(c[0]));
        EXPECT_NEAR(Y[p], 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2], 1e-5) << p;
    }
}

/// A separable box-constrained quadratic with its minimum at m (inside or outside [0, 1]).
Problem quadratic(std::vector<double> m) {
    Problem p;
    p.dimension = m.size();
    p.evaluate = [m](std::span<const double> x, std::span<double> g) {
        double f = 0;
        for (size_t i = 0; i < x.size(); ++i) {
            f += (x[i] - m[i]) * (x[i] - m[i]);
            if (!g.empty()) g[i] = 2 * (x[i] - m[i]);
        }
        return f;
    };
    return p;
}

}  // namespace

// E = 0: the image is black, G = 0 (eq. 2 would be infinite: it is clamped at its floor, with
// a zero gradient) and the unbiased loss is finite; every optimizer returns finite values, and
// `optimize` refuses such a start with a message (app/jobs/OptimizeStages.cpp prepareRuns).
TEST(HardCases, AllBlackStart) {
    auto scene = sceneOf(test::bumpyHeightMap(32), 32);
    const TransportMatrix t = precomputeTransport(*scene, opts(8, 2), 1).matrix;
    ImageObjective paper(t.width, t.height, t.objectMask, {});
    UnbiasedObjective unb(t.width, t.height, t.objectMask, {});
    const std::vector<double> zero(t.cols(), 0.0);
    for (bool unbiased : {false, true}) {
        const TransportLoss loss =
            unbiased ? TransportLoss(t, unb, false) : TransportLoss(t, paper, false);
        std::vector<double> g(t.cols());
        const LossParts p = loss.evaluate(zero, g);
        EXPECT_TRUE(std::isfinite(p.total)) << p.total;
        EXPECT_TRUE(p.clamped);
        EXPECT_TRUE(allFinite(g));
        for (const std::string& m : optimizerMethods()) {
            std::vector<double> e = zero;
            OptimizerOptions o;
            o.method = parseOptimizerMethod(m);
            o.iterations = 50;
            const OptimizerSummary s = minimize(loss.problem(), e, o);
            EXPECT_TRUE(std::isfinite(s.finalLoss)) << m;
            EXPECT_TRUE(allFinite(e)) << m;
            EXPECT_LE(s.finalLoss, s.initialLoss) << m;
        }
    }
    // The job refuses the start, naming the option.
    test::TempDir dir("hard-black");
    writeTransportFile(dir.path() / "g.tm", t, transportProvenance(*scene, opts(8, 2), 1));
    OptimizeJobOptions o;
    o.input = dir.path() / "g.tm";
    o.outDir = dir.path() / "out";
    o.heldOut.mode = HeldOutMode::None;
    o.starts = {parseInitialState("const:0")};
    try {
        runOptimizeJob(o);
        ADD_FAILURE() << "an all-black start was accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find(option("init")), std::string::npos) << e.what();
    }
    EXPECT_FALSE(std::filesystem::exists(o.outDir));
}

// An empty mask and a mask outside the part are refused; a mask of the whole part works.
TEST(HardCases, Masks) {
    auto scene = sceneOf(test::bumpyHeightMap(32), 32);
    const TransportMatrix t = precomputeTransport(*scene, opts(), 1).matrix;
    const std::vector<uint8_t> empty(t.rows(), 0);
    EXPECT_THROW(ImageObjective(t.width, t.height, empty, {}), InputError);
    std::vector<uint8_t> outside(t.rows());
    for (size_t p = 0; p < t.rows(); ++p) outside[p] = t.objectMask[p] ? 0 : 1;
    EXPECT_THROW(ImageObjective(t.width, t.height, intersectMasks(t.objectMask, outside), {}),
                 InputError);
    const ImageObjective whole(t.width, t.height, t.objectMask, {});
    const TransportLoss loss(t, whole, false);
    std::vector<double> g(t.cols());
    EXPECT_TRUE(std::isfinite(loss.evaluate(std::vector<double>(t.cols(), 0.5), g).total));
    EXPECT_TRUE(allFinite(g));
}

// A flat perfect mirror under a light just above 1: every part pixel is clipped (no contrast).
// The loss and its gradient are finite, the metrics say the image is clipped everywhere.
TEST(HardCases, FullyClippedImage) {
    SceneDesc d = smallDesc();
    d.material.params.ior = ComplexIor{Rgb{0.0f}, Rgb{1.0f}};  // F = 1
    d.material.params.smooth = true;
    auto scene = sceneOf(std::vector<float>(32 * 32, 0.0f), 32, d);
    const TransportMatrix t = precomputeTransport(*scene, opts(), 1).matrix;
    const std::vector<double> one(t.cols(), 1.01);
    std::vector<double> Y(t.rows());
    t.applyLuminance(one, Y);
    const ImageObjective obj(t.width, t.height, t.objectMask, {});
    std::vector<double> dY(t.rows());
    const LossParts p = obj.evaluate(Y, one, dY);
    EXPECT_TRUE(std::isfinite(p.total));
    EXPECT_LT(p.G, 1e-5 * p.S);  // float32 T: differences of ~1e-7, no contrast
    EXPECT_TRUE(allFinite(dY));
    MetricsInput in;
    in.width = t.width;
    in.height = t.height;
    in.image = Y;
    in.objectMask = t.objectMask;
    in.lossMask = t.objectMask;
    in.envmap = one;
    EXPECT_GT(computeVisibilityMetrics(in).clippedFraction, 0.999);
}

// Roughness at the ends of its range: a near-mirror (α = 1e-4) and α = 1.
TEST(HardCases, RoughnessExtremes) {
    for (float alpha : {1e-4f, 1.0f}) {
        SCOPED_TRACE(alpha);
        SceneDesc d = smallDesc();
        d.material.params.alphaU = d.material.params.alphaV = alpha;
        expectRenderMatchesTransport(*sceneOf(test::bumpyHeightMap(32), 32, d), 0.5);
    }
}

// Cameras that see the part edge-on, or from below: finite renders; a camera that sees none of
// the part is refused by `optimize` with a message naming the scene's camera.
TEST(HardCases, GrazingAndBelowCameras) {
    SceneDesc d = smallDesc();
    d.camera.origin = {-3, 0.15, 0.01};  // edge-on, 3° above the plane, a narrow view
    d.camera.fovDeg = 3;
    expectRenderMatchesTransport(*sceneOf(test::bumpyHeightMap(32), 32, d), 0.5, 1);
    d.camera.fovDeg = 35;
    d.camera.origin = {0, -3, 0.01};  // under the part, looking up
    expectRenderMatchesTransport(*sceneOf(test::bumpyHeightMap(32), 32, d), 0.5);
    d.camera.origin = {0, 2, 2};
    d.camera.target = {200, 40, 40};  // looking away
    auto away = sceneOf(test::bumpyHeightMap(32), 32, d);
    const TransportMatrix t = precomputeTransport(*away, opts(), 1).matrix;
    test::TempDir dir("hard-away");
    writeTransportFile(dir.path() / "g.tm", t, transportProvenance(*away, opts(), 1));
    OptimizeJobOptions o;
    o.input = dir.path() / "g.tm";
    o.outDir = dir.path() / "out";
    o.heldOut.mode = HeldOutMode::None;
    o.starts = {parseInitialState("const:0.5")};
    try {
        runOptimizeJob(o);
        ADD_FAILURE() << "a camera that sees nothing was accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("camera"), std::string::npos) << e.what();
    }
}

// Flat maps, huge height ranges and steep walls, the smallest maps, holes.
TEST(HardCases, HeightMaps) {
    const int n = 32;
    expectRenderMatchesTransport(*sceneOf(std::vector<float>(n * n, 0.02f), n), 0.5);  // flat
    std::vector<float> cliff(n * n);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) cliff[static_cast<size_t>(j * n + i)] = i < n / 2 ? 0 : 0.5f;
    expectRenderMatchesTransport(*sceneOf(cliff, n), 0.5);  // a wall 10 samples high in one step
    std::vector<float> spikes = test::bumpyHeightMap(n);    // ±2 mm spikes, 40× the pitch
    for (size_t k = 0; k < spikes.size(); k += 7) spikes[k] = (k % 2 ? 2.0f : -2.0f);
    expectRenderMatchesTransport(*sceneOf(spikes, n), 0.5, 1);
    // A flat map has no scratches: an empty scratch map, not an error.
    const ScratchMap flat = computeScratchMap(std::vector<float>(n * n, 2.0f), n, n, {});
    for (uint8_t v : flat.map) EXPECT_EQ(v, 0);

    EXPECT_THROW(sceneOf({0.0f}, 1), InputError);  // 1×1: no surface
    expectRenderMatchesTransport(*sceneOf({0.0f, 0.01f, 0.02f, 0.0f}, 2), 0.5, 0);  // 2×2
    std::vector<float> holes = test::bumpyHeightMap(n);
    holes[100] = std::numeric_limits<float>::quiet_NaN();
    try {
        sceneOf(holes, n);
        ADD_FAILURE() << "a NaN hole was accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("row 3, column 4"), std::string::npos) << e.what();
    }
}

// T with all-zero rows (background pixels) and all-zero columns (texels no path reaches): the
// loss gradient is finite, and exactly the regulariser's on the unreached texels.
TEST(HardCases, TransportWithZeroRowsAndColumns) {
    SceneDesc d = smallDesc();
    d.material.params.smooth = true;
    auto scene = sceneOf(test::bumpyHeightMap(32), 32, d);
    const TransportMatrix t = precomputeTransport(*scene, opts(), 1).matrix;
    std::vector<int> used(t.cols(), 0);
    {
        std::vector<double> Y(t.rows(), 1.0), back(t.cols());
        t.applyTransposeLuminance(Y, back);
        for (size_t c = 0; c < t.cols(); ++c) used[c] = back[c] != 0;
    }
    size_t zeroCols = 0;
    for (int u : used) zeroCols += u == 0;
    ASSERT_GT(zeroCols, 0u);
    const ImageObjective obj(t.width, t.height, t.objectMask, {});
    const TransportLoss loss(t, obj, false);
    std::vector<double> E(t.cols(), 0.4), g(t.cols());
    loss.evaluate(E, g);
    ASSERT_TRUE(allFinite(g));
    const double reg = 2 * obj.options().lambda * 0.4 / static_cast<double>(t.cols());
    for (size_t c = 0; c < t.cols(); ++c) {
        if (!used[c]) {
            EXPECT_NEAR(g[c], reg, 1e-12 * reg) << c;
        }
    }
}

// λ = 0 drives the light up (the paper: E → 1), a huge λ drives it to 0.
TEST(HardCases, LambdaExtremes) {
    auto scene = sceneOf(test::bumpyHeightMap(32), 32);
    const TransportMatrix t = precomputeTransport(*scene, opts(8), 1).matrix;
    auto solve = [&](double lambda) {
        ObjectiveOptions oo;
        oo.lambda = lambda;
        const ImageObjective obj(t.width, t.height, t.objectMask, oo);
        const TransportLoss loss(t, obj, false);
        std::vector<double> e(t.cols(), 0.5);
        OptimizerOptions o;
        o.method = OptimizerMethod::Lbfgs;
        o.iterations = 500;
        const OptimizerSummary s = minimize(loss.problem(), e, o);
        EXPECT_TRUE(std::isfinite(s.finalLoss));
        EXPECT_LE(s.finalLoss, s.initialLoss);
        return e;
    };
    // eq. 2 grows like 1/E as E → 0, so E* falls like λ^(−1/3): ×1e6 in λ, ÷100 in E.
    const std::vector<double> mid = solve(1e6), big = solve(1e12);
    const double maxBig = *std::max_element(big.begin(), big.end());
    EXPECT_LT(maxBig, 2e-3);
    EXPECT_LT(maxBig, 0.05 * *std::max_element(mid.begin(), mid.end()));
    // λ = 0: eq. 2 is invariant to scaling E, so a maximum of E at 1 costs nothing; the loss
    // gradient pushes the texels that shape the image to a bound.
    const std::vector<double> free = solve(0.0);
    EXPECT_GT(*std::max_element(free.begin(), free.end()), 0.99);
}

// Finite differences at the bounds of E stay inside [0, 1] and give finite gradients.
TEST(HardCases, FiniteDifferencesAtTheBounds) {
    SceneDesc d = smallDesc(8);
    auto scene = sceneOf(test::bumpyHeightMap(16), 16, d);
    ImageObjective obj(8, 8, std::vector<uint8_t>(64, 1), {});
    const RenderLoss box(*scene, opts(2), obj);
    for (double e : {0.0, 1.0}) {
        FdOptions fd;
        fd.h = 0.05;
        const GradientEstimate g =
            finiteDifferenceGradient(box, std::vector<double>(box.dimension(), e), fd);
        EXPECT_TRUE(std::isfinite(g.loss)) << e;
        EXPECT_TRUE(allFinite(g.gradient)) << e;
    }
}

// Sums over 5000×5000 pixels: G accumulates in double. Summing the same 25 million |Δ| = 0.1 in
// float would be off by more than 10 %; in double it is exact to 1e-9.
TEST(HardCases, SumsOver25MillionPixels) {
    const int W = 5000, H = 5000;
    std::vector<double> Y(static_cast<size_t>(W) * H);
    for (size_t k = 0; k < Y.size(); ++k) Y[k] = (k % W) % 2 ? 0.1 : 0.0;
    const ImageObjective obj(W, H, std::vector<uint8_t>(Y.size(), 1), {});
    const double exact = static_cast<double>(H) * (W - 1) * 0.1;  // horizontal pairs only
    const LossParts p = obj.evaluate(Y, std::vector<double>{0.5});
    EXPECT_NEAR(p.G, exact, 1e-9 * exact);
    float naive = 0;
    for (size_t i = 0; i < static_cast<size_t>(H) * (W - 1); ++i) naive += 0.1f;
    EXPECT_GT(std::abs(naive - exact) / exact, 0.1);  // why double matters
}

// Every optimizer started at a bound (all 0, all 1) with minima inside, on and outside the box.
TEST(HardCases, EveryOptimizerStartedAtABound) {
    const Problem p = quadratic({0.3, -0.5, 1.5, 0.0, 1.0});
    for (const std::string& m : optimizerMethods())
        for (double start : {0.0, 1.0}) {
            SCOPED_TRACE(m + " from " + std::to_string(start));
            std::vector<double> x(p.dimension, start);
            OptimizerOptions o;
            o.method = parseOptimizerMethod(m);
            o.iterations = 300;
            o.learningRate = 0.01;
            const OptimizerSummary s = minimize(p, x, o);
            EXPECT_TRUE(std::isfinite(s.finalLoss));
            EXPECT_LT(s.finalLoss, s.initialLoss);
            for (double v : x) {
                EXPECT_GE(v, 0.0);
                EXPECT_LE(v, 1.0);
            }
        }
}
