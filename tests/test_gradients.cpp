// Gradients: exact (Tᵀ·dL/dY) against autodiff (ceres::Jet) on the same samples, finite
// differences (common random numbers) and SPSA through the black-box renderer against autodiff,
// and the black-box optimizers. Tiny scenes (24×24 px, 4 spp, 40×40 height map) made here.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <numeric>

#include "TestUtil.h"
#include "core/Error.h"
#include "io/SceneFile.h"
#include "objective/Autodiff.h"
#include "objective/TransportLoss.h"
#include "optimize/BlackBox.h"
#include "render/Render.h"
#include "scene/Scene.h"
#include "transport/TransportSink.h"

namespace sl {
namespace {

/// A 40×40 machined-looking patch: scallops along x, a scratch along z, a dent.
std::vector<float> testHeights(int n) {
    std::vector<float> h(static_cast<size_t>(n) * n);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            double v = 0.004 * std::sin(0.9 * i) + 0.002 * std::cos(0.37 * j + 0.2 * i);
            if (std::abs(i - 23) <= 1) v -= 0.006;                                      // a scratch
            v -= 0.01 * std::exp(-((i - 12) * (i - 12) + (j - 27) * (j - 27)) / 18.0);  // a dent
            h[static_cast<size_t>(j) * n + i] = static_cast<float>(v);
        }
    return h;
}

struct Fixture {
    test::TempDir dir{"gradients"};
    std::unique_ptr<Scene> scene;
    RenderOptions render;
    TransportMatrix t;
    std::unique_ptr<ImageObjective> objective;
    std::vector<double> E;

    explicit Fixture(const std::string& material = R"("distribution": "ggx", "alpha": 0.2)") {
        const int n = 40;
        test::writeNpyF32(dir / "h.npy", n, n, testHeights(n));
        const std::string json = R"({"heightmap": {"path": "h.npy", "pixel_pitch": 0.01},
            "material": {"type": "roughconductor", )" +
                                 material + R"(, "material": "Al"},
            "camera": {"width": 24, "height": 24, "fov": 30},
            "render": {"spp": 4, "max_depth": 3, "seed": 7}})";
        scene = loadScene(parseScene(json, dir.path(), "test scene"));
        render = renderOptionsFor(*scene);
        t = precomputeTransport(*scene, render, 1).matrix;
        ObjectiveOptions oo;
        oo.lambda = 30;
        objective = std::make_unique<ImageObjective>(24, 24, t.objectMask, oo);
        // A deterministic, non-constant E in [0.2, 0.8].
        E.resize(t.cols());
        for (size_t i = 0; i < E.size(); ++i)
            E[i] = 0.5 + 0.3 * std::sin(0.731 * static_cast<double>(i) + 0.3);
    }
};

std::vector<double> exactGradient(const Fixture& f, bool fused) {
    TransportLoss tl(f.t, *f.objective, false);
    std::vector<double> g(f.E.size());
    if (fused)
        tl.evaluateFused(f.E, g);
    else
        tl.evaluate(f.E, g);
    return g;
}

TEST(Gradients, ExactEqualsAutodiffOnTheSameSamples) {
    Fixture f;
    ASSERT_GT(f.objective->maskSize(), 100);
    const AutodiffGradient ad = autodiffThroughMatrix(f.t, *f.objective, f.E);
    EXPECT_EQ(ad.passes, (1250 + kAutodiffChunk - 1) / kAutodiffChunk);
    for (bool fused : {false, true}) {
        const std::vector<double> g = exactGradient(f, fused);
        const GradientError e = compareGradients(g, ad.gradient);
        std::printf("exact (%s) vs autodiff through T: rel %.3g, cos %.15f\n",
                    fused ? "fused" : "two-pass", e.relativeL2, e.cosine);
        EXPECT_LE(e.relativeL2, 1e-9) << (fused ? "fused" : "two-pass");
        EXPECT_GT(e.cosine, 1 - 1e-12);
    }
    // The loss values agree too.
    TransportLoss tl(f.t, *f.objective, false);
    EXPECT_NEAR(tl.evaluate(f.E, {}).total, ad.loss, 1e-12 * std::abs(ad.loss));
}

TEST(Gradients, ExactMatchesAutodiffThroughTheRecordedPathsToFloatRounding) {
    Fixture f;
    TraceSummary summary;
    const PathRecording rec = recordPaths(*f.scene, f.render, &summary);
    EXPECT_EQ(summary.objectMask, f.t.objectMask);  // same samples, same mask
    EXPECT_GT(rec.pathCount(), 300u);
    const AutodiffGradient ad = autodiffThroughPaths(rec, *f.objective, f.E);
    const GradientError e = compareGradients(exactGradient(f, true), ad.gradient);
    std::printf("exact (float T) vs autodiff through the paths (double): rel %.3g, cos %.12f\n",
                e.relativeL2, e.cosine);
    EXPECT_LE(e.relativeL2, 1e-5);
    EXPECT_GT(e.relativeL2, 0.0);  // T is float32: not bit-identical, which is the point
    // The templated chain in double is the render: the black box's loss agrees to float
    // rounding of its image.
    const double chain = lossThroughPaths<double>(rec, *f.objective, f.E);
    const RenderLoss box(*f.scene, f.render, *f.objective);
    const double black = box.evaluate(f.E, f.render.seed).total;
    EXPECT_NEAR(black, chain, 1e-5 * chain);
    EXPECT_NEAR(ad.loss, chain, 1e-12 * chain);
    EXPECT_EQ(objectMaskFor(*f.scene, f.render), f.t.objectMask);
}

TEST(Gradients, CentralFiniteDifferencesConvergeToAutodiffUntilRounding) {
    Fixture f;
    const PathRecording rec = recordPaths(*f.scene, f.render);
    const AutodiffGradient ad = autodiffThroughPaths(rec, *f.objective, f.E);
    // The 48 texels with the largest |gradient| (plenty of signal), to keep the test fast.
    std::vector<uint32_t> idx(ad.gradient.size());
    std::iota(idx.begin(), idx.end(), 0u);
    std::partial_sort(idx.begin(), idx.begin() + 48, idx.end(), [&](uint32_t a, uint32_t b) {
        return std::abs(ad.gradient[a]) > std::abs(ad.gradient[b]);
    });
    idx.resize(48);
    std::sort(idx.begin(), idx.end());
    std::vector<double> ref(idx.size());
    for (size_t k = 0; k < idx.size(); ++k) ref[k] = ad.gradient[idx[k]];

    const RenderLoss box(*f.scene, f.render, *f.objective);
    auto errorAt = [&](double h, bool crn) {
        FdOptions o;
        o.h = h;
        o.commonRandomNumbers = crn;
        o.texels = idx;
        const GradientEstimate g = finiteDifferenceGradient(box, f.E, o);
        std::vector<double> sub(idx.size());
        for (size_t k = 0; k < idx.size(); ++k) sub[k] = g.gradient[idx[k]];
        EXPECT_EQ(g.evaluations, 1 + 2 * static_cast<int>(idx.size()));
        return compareGradients(sub, ref).relativeL2;
    };
    const std::vector<double> hs{1e-1, 1e-2, 1e-3, 1e-7};
    std::vector<double> err;
    for (double h : hs) {
        err.push_back(errorAt(h, true));
        std::printf("central FD, CRN, h %.0e: relative error %.3g\n", h, err.back());
    }
    // The trend: the error shrinks with h (truncation and kinks) ...
    EXPECT_LT(err[1], err[0]);
    EXPECT_LT(err[2], err[1]);
    EXPECT_LT(err[2], 1e-2);  // a good match at h = 1e-3
    // ... until float rounding of the env map and the image takes over.
    EXPECT_GT(err[3], err[2]);
    // With fresh seeds, Monte Carlo noise dominates: much worse than CRN at the same h.
    const double fresh = errorAt(1e-2, false);
    std::printf("central FD, fresh seeds, h 1e-2: relative error %.3g\n", fresh);
    EXPECT_GT(fresh, 10 * err[1]);
}

TEST(Gradients, SpsaIsUnbiased) {
    Fixture f;
    const PathRecording rec = recordPaths(*f.scene, f.render);
    const AutodiffGradient ad = autodiffThroughPaths(rec, *f.objective, f.E);
    const RenderLoss box(*f.scene, f.render, *f.objective);
    const size_t n = f.E.size();
    const int m = 1200;  // estimates (2 renders each), in batches
    Pcg32 rng(42, 1);
    std::vector<double> sum(n, 0.0), sum2(n, 0.0), est;
    for (int b = 0; b < m / 100; ++b) {
        spsaGradient(box, f.E, 2e-3, 100, rng, true, static_cast<uint64_t>(b), 0, &est);
        for (int k = 0; k < 100; ++k)
            for (size_t i = 0; i < n; ++i) {
                const double v = est[static_cast<size_t>(k) * n + i];
                sum[i] += v;
                sum2[i] += v * v;
            }
    }
    // z_i = (mean_i − g_i) / (s_i / √m): for an unbiased estimator, approximately N(0, 1).
    double chi2 = 0, maxZ = 0;
    for (size_t i = 0; i < n; ++i) {
        const double mean = sum[i] / m;
        const double var = (sum2[i] - m * mean * mean) / (m - 1);
        const double z = (mean - ad.gradient[i]) / std::sqrt(var / m);
        chi2 += z * z;
        maxZ = std::max(maxZ, std::abs(z));
    }
    chi2 /= static_cast<double>(n);
    std::printf("SPSA, %d estimates: mean z^2 = %.3f (1 if unbiased), max |z| = %.2f\n", m, chi2,
                maxZ);
    // E[z²] = 1 (sd of the mean of 1250 ≈ 0.04); a bias of a tenth of the standard error
    // per texel would add 0.01, a bias of 1/3 would add 0.11.
    EXPECT_LT(chi2, 1.15);
    EXPECT_GT(chi2, 0.85);
    EXPECT_LT(maxZ, 5.0);
}

TEST(Gradients, BlackBoxOptimizersDecreaseTheLoss) {
    Fixture f;
    const RenderLoss box(*f.scene, f.render, *f.objective);
    for (const std::string method : {"spsa", "fd-adam"}) {
        std::vector<double> E(f.E.size(), 0.5);
        OptimizerOptions o;
        o.method = parseOptimizerMethod(method);
        o.iterations = method == "spsa" ? 40 : 3;
        int calls = 0;
        o.callback = [&](const IterationRecord& r, std::span<const double> x) {
            EXPECT_EQ(r.iteration, calls);
            for (double v : x) EXPECT_TRUE(v >= 0 && v <= 1);
            ++calls;
            return true;
        };
        BlackBoxOptions bb;
        bb.fd.h = 1e-3;
        const OptimizerSummary s = minimizeBlackBox(box, E, o, bb);
        std::printf("%s\n", s.briefReport().c_str());
        EXPECT_EQ(s.method, method);
        EXPECT_EQ(s.iterations, o.iterations);
        EXPECT_EQ(static_cast<int>(s.history.size()), o.iterations + 1);
        EXPECT_LT(s.finalLoss, s.initialLoss);
        EXPECT_NEAR(s.finalLoss, box.evaluate(E, f.render.seed).total, 1e-12 * s.finalLoss);
        EXPECT_GT(s.evaluations, o.iterations);
    }
    std::vector<double> E(f.E.size(), 0.5);
    OptimizerOptions bad;
    bad.method = OptimizerMethod::Adam;
    EXPECT_THROW(minimizeBlackBox(box, E, bad, {}), InputError);
}

}  // namespace
}  // namespace sl
