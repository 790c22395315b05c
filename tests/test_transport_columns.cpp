// TransportColumns (transport/TransportColumns.h): products over a few active texels equal
// TransportMatrix's full products for an E that is zero elsewhere, for every plane, gray and
// RGB T, sparse and dense storage; and the loss through them equals the loss through T.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "TestUtil.h"
#include "objective/TransportLoss.h"
#include "objective/UnbiasedObjective.h"
#include "scene/Scene.h"
#include "transport/TransportColumns.h"
#include "transport/TransportSink.h"

namespace {

using namespace sl;

TransportMatrix tracedT(bool rgb, int sampleSets) {
    const int n = 32;
    Scene scene(test::bumpyPartDesc(16, 16), n, n, test::bumpyHeightMap(n));
    RenderOptions ro;
    ro.spp = 8;
    ro.maxDepth = 3;
    ro.sampleSets = sampleSets;
    return precomputeTransport(scene, ro, rgb ? 3 : 1).matrix;
}

/// Every third texel that T has entries in, and E non-zero on them only.
struct ActiveE {
    std::vector<uint16_t> active;
    std::vector<double> E;
};
ActiveE activeE(const TransportColumns& c, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> U(0.1, 1.0);
    ActiveE a;
    a.E.assign(c.cols(), 0.0);
    for (size_t t = 0; t < c.cols(); t += 3)
        if (c.columnEntries(t) > 0) {
            a.active.push_back(static_cast<uint16_t>(t));
            a.E[t] = U(rng);
        }
    return a;
}

void expectClose(const std::vector<double>& a, const std::vector<double>& b, const char* what) {
    ASSERT_EQ(a.size(), b.size());
    double scale = 0;
    for (double v : b) scale = std::max(scale, std::abs(v));
    ASSERT_GT(scale, 0.0) << what;
    for (size_t i = 0; i < a.size(); ++i) EXPECT_NEAR(a[i], b[i], 1e-6 * scale) << what << " " << i;
}

void checkProducts(TransportMatrix t) {
    const TransportColumns c(t);
    if (t.storage == TransportStorage::Sparse) {
        EXPECT_EQ(c.nnz(), t.nnz());
    } else {  // dense T stores its zeros; the columns keep the non-zero entries only
        EXPECT_LT(c.nnz(), t.nnz());
        EXPECT_GT(c.nnz(), 0u);
    }
    const ActiveE a = activeE(c, 3);
    ASSERT_GT(a.active.size(), 10u);
    std::mt19937 rng(5);
    std::normal_distribution<double> N;
    std::vector<double> g(t.rows());
    for (double& v : g) v = N(rng);
    std::vector<int> planes{TransportMatrix::kMeanPlane};
    if (t.planes == 2) planes = {0, 1, TransportMatrix::kMeanPlane};
    for (int p : planes) {
        std::vector<double> y(t.rows()), yc(t.rows());
        t.applyLuminance(a.E, y, p);
        c.apply(a.E, a.active, yc, p);
        expectClose(yc, y, "T·E");
        std::vector<double> out(t.cols()), outc(t.cols(), -7.0);
        t.applyTransposeLuminance(g, out, p);
        c.transpose(g, a.active, outc, p);
        std::vector<double> want(t.cols(), -7.0);  // untouched outside the active texels
        for (uint16_t k : a.active) want[k] = out[k];
        expectClose(outc, want, "Tᵀ·g");
        // Every column at once, split over threads: T's product, the same for any threads.
        std::vector<double> all1(t.cols()), all2(t.cols());
        c.transposeAll(g, all1, p, 1);
        c.transposeAll(g, all2, p, 2);
        expectClose(all1, out, "Tᵀ·g over every column");
        EXPECT_EQ(all1, all2);
    }
    if (t.planes == 2) {
        std::vector<double> ya(t.rows()), yb(t.rows()), yca(t.rows()), ycb(t.rows());
        t.applyLuminanceHalves(a.E, ya, yb);
        c.applyHalves(a.E, a.active, yca, ycb);
        expectClose(yca, ya, "T_a·E");
        expectClose(ycb, yb, "T_b·E");
        std::vector<double> g2(t.rows());
        for (double& v : g2) v = N(rng);
        std::vector<double> out(t.cols()), outc(t.cols(), 0.0);
        t.applyTransposeLuminanceHalves(g, g2, out);
        c.transposeHalves(g, g2, a.active, outc);
        std::vector<double> want(t.cols(), 0.0);
        for (uint16_t k : a.active) want[k] = out[k];
        expectClose(outc, want, "T_aᵀ·ga + T_bᵀ·gb");
        std::vector<double> all1(t.cols()), all2(t.cols());
        c.transposeHalvesAll(g, g2, all1, 1);
        c.transposeHalvesAll(g, g2, all2, 2);
        expectClose(all1, out, "T_aᵀ·ga + T_bᵀ·gb over every column");
        EXPECT_EQ(all1, all2);
    }
}

TEST(TransportColumns, ProductsMatchTheFullProductsGraySparse) {
    checkProducts(tracedT(false, 2));
}

TEST(TransportColumns, ProductsMatchTheFullProductsOnePlaneDense) {
    TransportMatrix t = tracedT(false, 1);
    t.toDense();
    checkProducts(t);
}

TEST(TransportColumns, ProductsMatchTheFullProductsRgb) {
    checkProducts(tracedT(true, 2));
}

TEST(TransportColumns, LossOnColumnsEqualsTheLossThroughT) {
    const TransportMatrix t = tracedT(false, 2);
    const TransportColumns c(t);
    ObjectiveOptions oo;
    oo.lambda = 0.5;
    UnbiasedObjective obj(t.width, t.height, t.objectMask, oo);
    TransportLoss loss(t, obj, false);
    const ActiveE a = activeE(c, 9);
    std::vector<double> g(loss.dimension()), gc(loss.dimension());
    const double v = loss.evaluate(a.E, g).total;
    const double vc = loss.evaluateOnColumns(c, a.E, a.active, gc).total;
    EXPECT_NEAR(vc, v, 1e-9 * std::abs(v));
    std::vector<double> want(g.size()), got(g.size());
    for (uint16_t k : a.active) {
        want[k] = g[k];
        got[k] = gc[k];
    }
    expectClose(got, want, "gradient on the active texels");
}

TEST(TransportColumns, RefusesColumnsOfAnotherMatrixAndBadTexels) {
    const TransportMatrix t = tracedT(false, 2), one = tracedT(false, 1);
    const TransportColumns c(t), c1(one);
    ObjectiveOptions oo;
    UnbiasedObjective obj(t.width, t.height, t.objectMask, oo);
    TransportLoss loss(t, obj, false);
    std::vector<double> E(t.cols(), 0.0);
    const std::vector<uint16_t> active{0, 1};
    EXPECT_THROW(loss.evaluateOnColumns(c1, E, active, {}), std::invalid_argument);
    const std::vector<uint16_t> bad{static_cast<uint16_t>(t.cols())};
    std::vector<double> y(t.rows());
    EXPECT_THROW(c.apply(E, bad, y), std::invalid_argument);
    EXPECT_THROW(c1.applyHalves(E, active, y, y), std::invalid_argument);
}

}  // namespace
