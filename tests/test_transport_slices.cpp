// TransportSlices (transport/TransportSlices.h): the slices layout's products equal the CSR
// products of TransportMatrix (T·E exactly, Tᵀ·g to rounding) for every variant (gray and RGB T,
// one plane and halves, each plane, sparse and dense, gray and RGB E, any row range), do not
// depend on the number of threads, and the loss through it (fused or two passes, the paper's
// objective and the noise-unbiased one on the halves) equals the loss through CSR.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "TestUtil.h"
#include "core/Rng.h"
#include "objective/TransportLoss.h"
#include "objective/UnbiasedObjective.h"
#include "render/Render.h"
#include "scene/Scene.h"
#include "transport/TransportSink.h"
#include "transport/TransportSlices.h"

using namespace sl;
using test::maxRelDiff;

namespace {

// 21×21: the width is not a multiple of the 8 lanes, so every image row ends in a short slice.
std::unique_ptr<Scene> smallScene(int res = 21) {
    SceneDesc d = test::bumpyPartDesc(res, res);
    d.material.params.alphaU = 0.15f;  // anisotropic
    d.material.params.alphaV = 0.05f;
    const int n = 40;
    return std::make_unique<Scene>(d, n, n, test::bumpyHeightMap(n));
}

TransportMatrix precompute(const Scene& s, int channels, int sampleSets) {
    RenderOptions o;
    o.spp = 4;
    o.maxDepth = 3;
    o.seed = 5;
    o.sampleSets = sampleSets;
    return precomputeTransport(s, o, channels).matrix;
}

std::vector<double> randomVec(size_t n, uint64_t seed, double shift = 0.0) {
    Pcg32 rng(seed, 7);
    std::vector<double> v(n);
    for (double& x : v) x = rng.nextDouble() - shift;
    return v;
}

size_t countDifferent(std::span<const double> a, std::span<const double> b) {
    size_t n = 0;
    for (size_t i = 0; i < a.size(); ++i) n += a[i] != b[i];
    return n;
}

/// Every product of the slices layout against T's own, for every plane and kind of E.
void expectSameProducts(const TransportMatrix& t, const std::string& what) {
    const TransportSlices b(t);
    EXPECT_GE(b.padding(), 1.0) << what;
    EXPECT_EQ(b.nnz(), t.storage == TransportStorage::Sparse ? t.nnz() : b.nnz()) << what;
    std::vector<int> planes{TransportMatrix::kMeanPlane};
    for (int p = 0; p < t.planes; ++p) planes.push_back(p);
    for (int ech : t.channels == 3 ? std::vector<int>{1, 3} : std::vector<int>{1}) {
        const std::vector<double> e = randomVec(t.cols() * ech, 11 + ech);
        const std::vector<double> g = randomVec(t.rows(), 12, 0.5);  // signs mixed
        for (int plane : planes) {
            const std::string tag =
                what + " E channels " + std::to_string(ech) + " plane " + std::to_string(plane);
            std::vector<double> y1(t.rows()), y2(t.rows()), o1(e.size()), o2(e.size());
            t.applyLuminance(e, y1, plane);
            b.applyLuminance(e, y2, plane);
            EXPECT_GT(*std::max_element(y1.begin(), y1.end()), 0.0) << tag;  // T is not empty
            EXPECT_EQ(countDifferent(y1, y2), 0u) << tag;  // the same sums in the same order
            t.applyTransposeLuminance(g, o1, plane);
            b.applyTransposeLuminance(g, o2, plane);
            EXPECT_LE(maxRelDiff(o2, o1), 1e-13) << tag;
            // Row kernels over a range that starts and ends inside slices.
            const size_t r0 = 5, r1 = t.rows() - 3;
            std::vector<double> yr1(r1 - r0), yr2(r1 - r0);
            t.applyLuminanceRows(e.data(), ech == 3, yr1.data(), r0, r1, plane);
            b.applyLuminanceRows(e.data(), ech == 3, yr2.data(), r0, r1, plane);
            EXPECT_EQ(countDifferent(yr1, yr2), 0u) << tag;
            std::vector<double> or1(e.size(), 0.0), or2(e.size(), 0.0);
            t.accumulateTransposeRows(g.data() + r0, ech == 3, or1.data(), r0, r1, plane);
            b.accumulateTransposeRows(g.data() + r0, ech == 3, or2.data(), r0, r1, plane);
            EXPECT_LE(maxRelDiff(or2, or1), 1e-13) << tag;
        }
        if (t.planes == 2) {
            const std::string tag = what + " halves, E channels " + std::to_string(ech);
            std::vector<double> a1(t.rows()), b1(t.rows()), a2(t.rows()), b2(t.rows());
            t.applyLuminanceHalves(e, a1, b1);
            b.applyLuminanceHalves(e, a2, b2);
            EXPECT_EQ(countDifferent(a1, a2), 0u) << tag;
            EXPECT_EQ(countDifferent(b1, b2), 0u) << tag;
            const std::vector<double> gb = randomVec(t.rows(), 13, 0.5);
            std::vector<double> o1(e.size()), o2(e.size());
            t.applyTransposeLuminanceHalves(g, gb, o1);
            b.applyTransposeLuminanceHalves(g, gb, o2);
            EXPECT_LE(maxRelDiff(o2, o1), 1e-13) << tag;
        }
    }
}

}  // namespace

TEST(TransportSlices, ProductsEqualTheCsrProductsForEveryVariant) {
    auto s = smallScene();
    for (int channels : {1, 3}) {
        for (int sets : {1, 2}) {
            TransportMatrix t = precompute(*s, channels, sets);
            ASSERT_EQ(t.planes, sets);
            t.toSparse();
            const std::string what =
                std::to_string(channels) + " channel(s), " + std::to_string(sets) + " plane(s)";
            expectSameProducts(t, what + ", sparse");
            t.toDense();
            expectSameProducts(t, what + ", dense");
        }
    }
}

TEST(TransportSlices, StoresEveryNonZeroAndIgnoresTheThreadCount) {
    auto s = smallScene();
    TransportMatrix t = precompute(*s, 1, 1);
    t.toSparse();
    const TransportSlices b(t);
    EXPECT_EQ(b.nnz(), t.nnz());
    EXPECT_EQ(b.rows(), t.rows());
    EXPECT_EQ(b.cols(), t.cols());
    // Every non-zero once, padded to the longest row of each slice of 8.
    EXPECT_GE(b.slots(), t.nnz());
    EXPECT_LE(b.slots(), TransportSlices::kLanes * t.nnz());
    EXPECT_EQ(b.slots() % TransportSlices::kLanes, 0u);
    const std::vector<double> g = randomVec(t.rows(), 3, 0.5);
    std::vector<double> o1(t.cols()), o2(t.cols());
    b.applyTransposeLuminance(g, o1, TransportMatrix::kMeanPlane, 1);
    b.applyTransposeLuminance(g, o2, TransportMatrix::kMeanPlane, 2);
    EXPECT_EQ(0, std::memcmp(o1.data(), o2.data(), o1.size() * sizeof(double)));
    // A wrong E is refused as by TransportMatrix.
    std::vector<double> y(t.rows()), rgb(3 * t.cols());
    EXPECT_THROW(b.applyLuminance(rgb, y), std::invalid_argument);
    EXPECT_THROW(b.applyLuminance(std::vector<double>(t.cols()), y, 1), std::invalid_argument);
}

TEST(TransportSlices, LossThroughSlicesEqualsTheLossThroughCsr) {
    auto s = smallScene(19);
    const TransportMatrix t3 = precompute(*s, 3, 1);
    for (RegTarget reg : {RegTarget::EnvMap, RegTarget::Image}) {
        for (bool smooth : {false, true}) {
            for (bool rgb : {false, true}) {
                ObjectiveOptions oo;
                oo.reg = reg;
                oo.smoothAbs = smooth;
                oo.smoothEps = 1e-3;
                TransportMatrix t = t3;
                ImageObjective obj(t.width, t.height, t.objectMask, oo);
                TransportLoss csr(t, obj, rgb), blk(t, obj, rgb);
                csr.setLayout(TransportLayout::Csr);
                blk.setLayout(TransportLayout::Slices);
                const std::vector<double> e = randomVec(csr.dimension(), 4);
                std::vector<double> g0(e.size()), g1(e.size()), g2(e.size()), g3(e.size());
                const LossParts a = csr.evaluate(e, g0);  // the reference: two passes on CSR
                const LossParts b = blk.evaluate(e, g1);
                t.threads = 1;
                const LossParts c = blk.evaluateFused(e, g2);
                t.threads = 2;
                blk.evaluateFused(e, g3);
                const std::string tag = "reg " + std::to_string(int(reg)) + " smooth " +
                                        std::to_string(smooth) + " rgb " + std::to_string(rgb);
                EXPECT_EQ(a.total, b.total) << tag;  // Y is exact, so is the loss
                EXPECT_NEAR(a.total, c.total, 1e-12 * std::abs(a.total)) << tag;
                EXPECT_NEAR(a.G, c.G, 1e-12 * a.G) << tag;
                EXPECT_EQ(a.clamped, c.clamped) << tag;
                EXPECT_LE(maxRelDiff(g1, g0), 1e-12) << tag;
                EXPECT_LE(maxRelDiff(g2, g0), 1e-11) << tag;
                EXPECT_EQ(0, std::memcmp(g2.data(), g3.data(), g2.size() * sizeof(double))) << tag;
                // The value without a gradient, and a copy of the loss sharing the layout.
                const TransportLoss copy = blk;
                EXPECT_EQ(&copy.slices(), &blk.slices());
                EXPECT_EQ(copy.evaluate(e, {}).total, a.total) << tag;
            }
        }
    }
}

TEST(TransportSlices, UnbiasedLossOnTheHalvesEqualsTheLossThroughCsr) {
    auto s = smallScene(19);
    for (int channels : {1, 3}) {
        const TransportMatrix t = precompute(*s, channels, 2);
        UnbiasedObjective obj(t.width, t.height, t.objectMask, ObjectiveOptions{});
        TransportLoss csr(t, obj, false), blk(t, obj, false);
        csr.setLayout(TransportLayout::Csr);
        blk.setLayout(TransportLayout::Slices);
        const std::vector<double> e = randomVec(csr.dimension(), 8);
        std::vector<double> g0(e.size()), g1(e.size());
        const LossParts a = csr.evaluateFused(e, g0), b = blk.evaluateFused(e, g1);
        EXPECT_EQ(a.total, b.total) << channels;
        EXPECT_LE(maxRelDiff(g1, g0), 1e-12) << channels;
    }
}

TEST(TransportSlices, FusedLossRefusesANonFiniteEnvMap) {
    auto s = smallScene(16);
    const TransportMatrix t = precompute(*s, 1, 1);
    ImageObjective obj(t.width, t.height, t.objectMask, ObjectiveOptions{});
    TransportLoss loss(t, obj, false);
    std::vector<double> e = randomVec(loss.dimension(), 2), g(e.size());
    e[3] = std::nan("");
    EXPECT_THROW(loss.evaluateFused(e, g), std::invalid_argument);
}

TEST(TransportSlices, AutoLayoutReadsCsrFirstThenTheSlices) {
    auto s = smallScene(48);  // enough entries per texel that the two orders round apart
    const TransportMatrix t = precompute(*s, 3, 1);
    ImageObjective obj(t.width, t.height, t.objectMask, ObjectiveOptions{});
    TransportLoss csr(t, obj, true), sl(t, obj, true), aut(t, obj, true);
    csr.setLayout(TransportLayout::Csr);
    sl.setLayout(TransportLayout::Slices);
    EXPECT_EQ(aut.layout(), TransportLayout::Auto);  // the default
    const std::vector<double> e = randomVec(aut.dimension(), 6);
    std::vector<double> gc(e.size()), gs(e.size()), ga(e.size());
    csr.evaluateFused(e, gc);
    sl.evaluateFused(e, gs);
    ASSERT_NE(0, std::memcmp(gc.data(), gs.data(), gc.size() * sizeof(double)))
        << "the layouts' gradients round alike here: this test cannot tell them apart";
    for (int i = 0; i < kAutoSlicesAfter + 2; ++i) {
        aut.evaluateFused(e, ga);
        const std::vector<double>& want = i < kAutoSlicesAfter ? gc : gs;
        EXPECT_EQ(0, std::memcmp(ga.data(), want.data(), ga.size() * sizeof(double))) << i;
    }
}
