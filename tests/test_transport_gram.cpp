// TransportGram (transport/TransportGram.h): the quadratic forms of T's halves equal the
// unbiased objective's G_u and Σ Ya·Yb computed from the half images, the matrices are exactly
// symmetric and do not depend on the number of threads, the forms over a set of active texels
// equal the whole forms of an E that is zero elsewhere, and the loss through them (whole, on
// columns, Auto's switch) equals the loss through T's products to rounding.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <set>
#include <utility>

#include "TestUtil.h"
#include "app/pipeline/Cache.h"
#include "app/pipeline/HeldOut.h"
#include "app/pipeline/Search.h"
#include "core/Color.h"
#include "core/Rng.h"
#include "io/GramFile.h"
#include "objective/TransportLoss.h"
#include "objective/UnbiasedObjective.h"
#include "render/Render.h"
#include "scene/Scene.h"
#include "transport/TransportColumns.h"
#include "transport/TransportGram.h"
#include "transport/TransportSink.h"

using namespace sl;
using test::maxRelDiff;

namespace {

std::unique_ptr<Scene> smallScene(int res) {
    SceneDesc d = test::bumpyPartDesc(res, res);
    d.material.params.alphaU = 0.15f;
    d.material.params.alphaV = 0.05f;
    const int n = 40;
    return std::make_unique<Scene>(d, n, n, test::bumpyHeightMap(n));
}

TransportMatrix halves(const Scene& s, int channels) {
    RenderOptions o;
    o.spp = 4;
    o.maxDepth = 3;
    o.seed = 9;
    o.sampleSets = 2;
    return precomputeTransport(s, o, channels).matrix;
}

std::vector<double> randomVec(size_t n, uint64_t seed) {
    Pcg32 rng(seed, 3);
    std::vector<double> v(n);
    for (double& x : v) x = rng.nextDouble();
    return v;
}

/// A mask with holes: the object mask with every 7th pixel dropped (pairs at its edges).
std::vector<uint8_t> holedMask(const TransportMatrix& t) {
    std::vector<uint8_t> m = t.objectMask;
    for (size_t p = 0; p < m.size(); p += 7) m[p] = 0;
    return m;
}

}  // namespace

TEST(TransportGram, FormsEqualTheHalfImagesSums) {
    auto s = smallScene(23);
    for (int channels : {1, 3}) {
        TransportMatrix t = halves(*s, channels);
        ASSERT_EQ(t.storage, TransportStorage::Sparse);
        const std::vector<uint8_t> mask = holedMask(t);
        UnbiasedObjective obj(t.width, t.height, mask, ObjectiveOptions{});
        const TransportGram g(t, mask, true);
        ASSERT_EQ(g.cols(), t.cols());
        const size_t n = g.cols();
        // P and Q cover the texels some pixel sees: T's non-empty columns.
        std::vector<uint16_t> seen;
        std::vector<bool> used(n, false);
        for (uint16_t c : t.colIdx) used[c] = true;
        for (size_t c = 0; c < n; ++c)
            if (used[c]) seen.push_back(static_cast<uint16_t>(c));
        ASSERT_TRUE(std::equal(seen.begin(), seen.end(), g.seen().begin(), g.seen().end()));
        ASSERT_LT(seen.size(), n);  // the test covers unseen texels
        const size_t m = seen.size();
        const auto P = g.pairMatrix(), Q = g.productMatrix();
        ASSERT_EQ(P.size(), m * m);
        for (size_t i = 0; i < m; ++i)
            for (size_t j = 0; j < i; ++j) {
                ASSERT_EQ(P[i * m + j], P[j * m + i]);
                ASSERT_EQ(Q[i * m + j], Q[j * m + i]);
            }
        for (uint64_t seed : {1u, 2u, 3u}) {
            const std::vector<double> e = randomVec(n, seed);
            std::vector<double> ya(t.rows()), yb(t.rows());
            t.applyLuminanceHalves(e, ya, yb);
            double R = 0;
            for (size_t p = 0; p < ya.size(); ++p) R += ya[p] * yb[p];
            const double G = obj.energy(ya, yb);
            std::vector<double> pe(n), qe(n);
            EXPECT_NEAR(g.pairForm(e, pe), G, 1e-12 * std::abs(G)) << channels;
            EXPECT_NEAR(g.productForm(e, qe), R, 1e-12 * R) << channels;
            // ∇G = 2·P·E against the products' gradient Tₐᵀ·Lap·T_b·E + T_bᵀ·Lap·Tₐ·E.
            std::vector<double> da(t.rows(), 0.0), db(t.rows(), 0.0), grad(n);
            for (size_t p = 0; p < t.rows(); ++p) {
                if (!mask[p]) continue;
                const size_t w = static_cast<size_t>(t.width), x = p % w, y = p / w;
                for (size_t q : {p + 1, p + w}) {
                    if ((q == p + 1 && x + 1 >= w) || (q == p + w && y + 1 >= size_t(t.height)))
                        continue;
                    if (!mask[q]) continue;
                    da[q] += yb[q] - yb[p];
                    da[p] -= yb[q] - yb[p];
                    db[q] += ya[q] - ya[p];
                    db[p] -= ya[q] - ya[p];
                }
            }
            t.applyTransposeLuminanceHalves(da, db, grad);
            for (double& v : pe) v *= 2;
            EXPECT_LE(maxRelDiff(pe, grad), 1e-12) << channels;
        }
        // Threads do not change a bit.
        t.threads = 1;
        const TransportGram one(t, mask, false, 1);
        EXPECT_FALSE(one.hasProducts());
        EXPECT_EQ(0, std::memcmp(one.pairMatrix().data(), P.data(), m * m * sizeof(double)));
        EXPECT_THROW(one.productForm(randomVec(n, 1), {}), std::logic_error);
    }
}

TEST(TransportGram, AFormsProductIsEachRowsDotInItsFourSumsBitForBit) {
    // The header's order: a row's dot with E over the seen texels in four sums (position mod 4)
    // added as (s0 + s2) + (s1 + s3); G the same dot of E with P·E. Sizes around the products'
    // blocks of four rows, and one above kSerialEntries (rows over threads), on 1 and 2 threads.
    auto dot = [](const double* a, const double* b, size_t n) {
        double s[4] = {0, 0, 0, 0};
        for (size_t k = 0; k < n; ++k) s[k % 4] += a[k] * b[k];
        return (s[0] + s[2]) + (s[1] + s[3]);
    };
    for (const size_t m : {size_t{1}, size_t{3}, size_t{4}, size_t{5}, size_t{7}, size_t{9},
                           size_t{66}, size_t{2051}}) {
        const size_t n = m + 3;  // three texels no pixel sees
        std::vector<uint16_t> seen;
        for (size_t k = 0; k < m; ++k) seen.push_back(static_cast<uint16_t>(k + (k > m / 2) * 3));
        std::vector<double> p = randomVec(m * m, 10 + m);
        for (double& x : p) x -= 0.5;
        const TransportGram g(n, seen, p, {});
        std::vector<double> e = randomVec(n, 20 + m), x(m), ref(m);
        for (size_t k = 0; k < m; ++k) x[k] = e[seen[k]];
        for (size_t k = 0; k < m; ++k) ref[k] = dot(p.data() + k * m, x.data(), m);
        const double G = dot(x.data(), ref.data(), m);
        for (const int threads : {1, 2}) {
            std::vector<double> pe(n, -1.0);
            EXPECT_EQ(g.pairForm(e, pe, threads), G) << m << " texels, " << threads;
            for (size_t k = 0; k < m; ++k) EXPECT_EQ(pe[seen[k]], ref[k]) << m << ", row " << k;
            for (size_t c = 0; c < n; ++c) {
                if (std::find(seen.begin(), seen.end(), c) == seen.end()) {
                    EXPECT_EQ(pe[c], 0.0) << "texel " << c;
                }
            }
        }
    }
}

TEST(TransportGram, FormsOnActiveTexelsEqualTheWholeFormsOfAnEnvMapZeroElsewhere) {
    auto s = smallScene(19);
    const TransportMatrix t = halves(*s, 1);
    const TransportGram g(t, t.objectMask, true);
    const size_t n = g.cols();
    std::vector<uint16_t> active;
    for (size_t c = 3; c < n; c += 5) active.push_back(static_cast<uint16_t>(c));
    std::vector<double> e(n, 0.0);
    const std::vector<double> r = randomVec(n, 4);
    for (uint16_t c : active) e[c] = r[c];
    std::vector<double> pe(n), pa(n, -1.0), qe(n), qa(n, -1.0);
    const double G = g.pairForm(e, pe), Ga = g.pairFormOn(e, active, pa);
    const double R = g.productForm(e, qe), Ra = g.productFormOn(e, active, qa);
    EXPECT_NEAR(Ga, G, 1e-13 * std::abs(G));
    EXPECT_NEAR(Ra, R, 1e-13 * std::abs(R));
    for (uint16_t c : active) {
        EXPECT_NEAR(pa[c], pe[c], 1e-13 * std::abs(G));
        EXPECT_NEAR(qa[c], qe[c], 1e-13 * std::abs(R));
    }
    EXPECT_EQ(pa[0], -1.0);  // only the active texels are written
}

TEST(TransportGram, TheBuildIsEachEntrysSumOverThePixelsInOrderBitForBit) {
    // P = sym(T_aᵀ·Lap·T_b) and Q = sym(T_aᵀ·T_b), every entry summed over the pixels in
    // ascending order (Lap's row p: its neighbours' rows with −1, then its own with deg(p)),
    // written out densely here: the build (in blocks of rows, a pixel's entries in a block
    // several rows at a time, the rows of Lap·T_b over chunks of pixels, on any number of
    // threads) gives exactly these numbers, so Gram files stored by an earlier build of the
    // same order stay valid under their revision. 40² pixels: more than one chunk of them.
    auto s = smallScene(40);
    for (int channels : {1, 3})
        for (int threads : {1, 3}) {
            const TransportMatrix t = halves(*s, channels);
            const std::vector<uint8_t> mask = holedMask(t);
            const size_t w = static_cast<size_t>(t.width), h = static_cast<size_t>(t.height);
            const size_t n = t.cols(), st = static_cast<size_t>(t.stride());
            // An entry's luminance in a plane, as core/Color.h weighs the channels.
            auto val = [&](uint64_t k, int plane) {
                const float* v = t.values.data() + k * st + size_t(plane * channels);
                if (channels == 1) return double(v[0]);
                return luminance(1.0, 0.0, 0.0) * v[0] + luminance(0.0, 1.0, 0.0) * v[1] +
                       luminance(0.0, 0.0, 1.0) * v[2];
            };
            const TransportGram g(t, mask, true, threads);
            const size_t m = g.seen().size();
            std::vector<int> index(n, -1);
            for (size_t k = 0; k < m; ++k) index[g.seen()[k]] = static_cast<int>(k);
            std::vector<double> P(m * m, 0.0), Q(m * m, 0.0), lap(m), b(m);
            for (size_t p = 0; p < t.rows(); ++p) {
                std::fill(lap.begin(), lap.end(), 0.0);
                std::fill(b.begin(), b.end(), 0.0);
                for (uint64_t k = t.rowPtr[p]; k < t.rowPtr[p + 1]; ++k)
                    b[size_t(index[t.colIdx[k]])] = val(k, 1);
                bool hasLap = false;
                if (mask[p]) {
                    int deg = 0;
                    auto gather = [&](size_t q, double f) {
                        for (uint64_t k = t.rowPtr[q]; k < t.rowPtr[q + 1]; ++k)
                            lap[size_t(index[t.colIdx[k]])] += f * val(k, 1);
                    };
                    const size_t x = p % w, y = p / w;
                    if (x + 1 < w && mask[p + 1]) gather(p + 1, -1.0), ++deg;
                    if (y + 1 < h && mask[p + w]) gather(p + w, -1.0), ++deg;
                    if (x > 0 && mask[p - 1]) gather(p - 1, -1.0), ++deg;
                    if (y > 0 && mask[p - w]) gather(p - w, -1.0), ++deg;
                    if (deg > 0) gather(p, deg), hasLap = true;
                }
                for (uint64_t k = t.rowPtr[p]; k < t.rowPtr[p + 1]; ++k) {
                    const size_t i = size_t(index[t.colIdx[k]]);
                    const double ai = val(k, 0);
                    for (uint64_t l = t.rowPtr[p]; l < t.rowPtr[p + 1]; ++l) {
                        const size_t j = size_t(index[t.colIdx[l]]);
                        Q[i * m + j] += ai * b[j];
                    }
                    if (!hasLap) continue;
                    for (size_t j = 0; j < m; ++j)
                        if (lap[j] != 0.0) P[i * m + j] += ai * lap[j];
                }
            }
            for (std::vector<double>* M : {&P, &Q})
                for (size_t i = 0; i < m; ++i)
                    for (size_t j = i + 1; j < m; ++j) {
                        const double v = 0.5 * ((*M)[i * m + j] + (*M)[j * m + i]);
                        (*M)[i * m + j] = (*M)[j * m + i] = v;
                    }
            size_t differ = 0;
            for (size_t e = 0; e < m * m; ++e)
                differ += (g.pairMatrix()[e] != P[e]) + (g.productMatrix()[e] != Q[e]);
            EXPECT_EQ(differ, 0u) << channels << " channels, threads " << threads << ", " << m
                                  << " seen texels";
            EXPECT_GT(m, 64u);  // more than two blocks of rows
        }
}

TEST(TransportGram, RefusesWhatItCannotRepresent) {
    auto s = smallScene(12);
    TransportMatrix t = halves(*s, 1);
    EXPECT_THROW(TransportGram(t, std::vector<uint8_t>(3, 1), false), std::invalid_argument);
    RenderOptions o;
    o.spp = 2;
    o.maxDepth = 2;
    const TransportMatrix one = precomputeTransport(*s, o, 1).matrix;
    EXPECT_THROW(TransportGram(one, one.objectMask, false), std::invalid_argument);
    t.toDense();
    EXPECT_THROW(TransportGram(t, t.objectMask, false), std::invalid_argument);
}

TEST(TransportGram, BuildWorkCountsTheBuildsMultiplyAdds) {
    auto s = smallScene(15);
    const TransportMatrix t = halves(*s, 1);
    const std::vector<uint8_t> none(t.rows(), 0);
    EXPECT_EQ(TransportGram::buildWork(t, none, false), 0.0);
    double squares = 0;
    for (size_t p = 0; p < t.rows(); ++p) {
        const double k = static_cast<double>(t.rowPtr[p + 1] - t.rowPtr[p]);
        squares += k * k;
    }
    EXPECT_EQ(TransportGram::buildWork(t, none, true), squares);
    // With pairs: Σ_p k_p·|L_p|, L_p row p of Lap·T_b (the texels of p and of its masked
    // neighbours, each once), over the masked pixels with a masked neighbour; below the
    // neighbours' rows added one by one (Σ_p k_p·(k_p + Σ_q k_q)).
    for (const std::vector<uint8_t>& mask : {t.objectMask, holedMask(t)}) {
        double merged = 0, oneByOne = 0;
        const size_t w = static_cast<size_t>(t.width);
        for (size_t p = 0; p < t.rows(); ++p) {
            const double kp = static_cast<double>(t.rowPtr[p + 1] - t.rowPtr[p]);
            if (!mask[p] || kp == 0) continue;
            std::set<uint16_t> texels;
            double around = 0;
            int deg = 0;
            const size_t x = p % w, y = p / w;
            for (auto [ok, q] :
                 {std::pair{x + 1 < w, p + 1}, std::pair{y + 1 < size_t(t.height), p + w},
                  std::pair{x > 0, p - 1}, std::pair{y > 0, p - w}}) {
                if (!ok || !mask[q]) continue;
                ++deg;
                around += static_cast<double>(t.rowPtr[q + 1] - t.rowPtr[q]);
                texels.insert(t.colIdx.begin() + long(t.rowPtr[q]),
                              t.colIdx.begin() + long(t.rowPtr[q + 1]));
            }
            if (deg == 0) continue;
            texels.insert(t.colIdx.begin() + long(t.rowPtr[p]),
                          t.colIdx.begin() + long(t.rowPtr[p + 1]));
            merged += kp * static_cast<double>(texels.size());
            oneByOne += kp * (kp + around);
        }
        EXPECT_EQ(TransportGram::buildWork(t, mask, false), merged);
        EXPECT_EQ(TransportGram::buildWork(t, mask, true), merged + squares);
        EXPECT_LT(merged, oneByOne);
        std::printf("[ measured ] build work %.4g, neighbours' rows one by one %.4g (%.2fx)\n",
                    merged, oneByOne, oneByOne / merged);
    }
}

// Where the build does not pay at once (gramPays), Auto builds it once the evaluations through
// the products have cost what it will: buildWork <= kGramWorkPerEvaluation·nnz·evaluations,
// exactly from the first evaluation count that reaches it.
TEST(TransportGram, TheBuildIsRepaidAfterTheEvaluationsItCosts) {
    auto s = smallScene(15);
    const TransportMatrix t = halves(*s, 1);
    UnbiasedObjective obj(t.width, t.height, t.objectMask, ObjectiveOptions{});
    const TransportLoss loss(t, obj, false);
    const double work = TransportGram::buildWork(t, obj.pairMask(), obj.usesProducts());
    const double each = TransportLoss::kGramWorkPerEvaluation * static_cast<double>(t.nnz());
    const int k = static_cast<int>(std::ceil(work / each));
    ASSERT_GT(k, 1);
    EXPECT_FALSE(loss.gramRepaid(k - 1));
    EXPECT_TRUE(loss.gramRepaid(k));
    EXPECT_TRUE(loss.gramRepaid(10 * k));
    EXPECT_FALSE(loss.gramRepaid(0));
    // The paper's objective: never.
    ImageObjective paper(t.width, t.height, t.objectMask, ObjectiveOptions{});
    EXPECT_FALSE(TransportLoss(t, paper, false).gramRepaid(1 << 30));
}

TEST(TransportGram, LossThroughTheGramEqualsTheLossThroughTheProducts) {
    auto s = smallScene(21);
    for (int channels : {1, 3}) {
        const TransportMatrix t = halves(*s, channels);
        for (RegTarget reg : {RegTarget::EnvMap, RegTarget::Image}) {
            ObjectiveOptions oo;
            oo.reg = reg;
            oo.lambda = 3;
            UnbiasedObjective obj(t.width, t.height, t.objectMask, oo);
            TransportLoss csr(t, obj, false), gram(t, obj, false);
            csr.setLayout(TransportLayout::Csr);
            gram.setLayout(TransportLayout::Gram);
            ASSERT_TRUE(gram.gramEligible());
            const std::string tag =
                "channels " + std::to_string(channels) + " reg " + std::to_string(int(reg));
            const std::vector<double> e = randomVec(csr.dimension(), 7);
            std::vector<double> g0(e.size()), g1(e.size());
            const LossParts a = csr.evaluateFused(e, g0), b = gram.evaluateFused(e, g1);
            EXPECT_NEAR(a.total, b.total, 1e-12 * a.total) << tag;
            EXPECT_NEAR(a.G, b.G, 1e-12 * std::abs(a.G)) << tag;
            EXPECT_LE(maxRelDiff(g1, g0), 1e-11) << tag;
            EXPECT_NEAR(gram.evaluate(e, {}).total, a.total, 1e-12 * a.total) << tag;
            // On columns (the lamp fit's products): the active texels' gradient, and only the
            // regulariser's elsewhere, as the column products give them.
            const TransportColumns cols(t);
            std::vector<uint16_t> active;
            std::vector<double> ez(e.size(), 0.0);
            for (size_t c = 0; c < e.size(); c += 3) {
                active.push_back(static_cast<uint16_t>(c));
                ez[c] = e[c];
            }
            std::vector<double> c0(e.size()), c1(e.size());
            const LossParts ca = csr.evaluateOnColumns(cols, ez, active, c0);
            const LossParts cb = gram.evaluateOnColumns(cols, ez, active, c1);
            EXPECT_NEAR(ca.total, cb.total, 1e-12 * ca.total) << tag;
            EXPECT_LE(maxRelDiff(c1, c0), 1e-11) << tag;
        }
    }
}

TEST(TransportGram, TheHessianProductIsTheGradientsDerivative) {
    auto s = smallScene(21);
    const TransportMatrix t = halves(*s, 1);
    for (RegTarget reg : {RegTarget::EnvMap, RegTarget::Image}) {
        ObjectiveOptions oo;
        oo.reg = reg;
        oo.lambda = 3;
        UnbiasedObjective obj(t.width, t.height, t.objectMask, oo);
        TransportLoss loss(t, obj, false);
        ASSERT_TRUE(loss.offersHessian());
        const Problem p = loss.problem();
        ASSERT_TRUE(static_cast<bool>(p.hessianProduct));
        const size_t n = loss.dimension();
        std::vector<double> e = randomVec(n, 11), v = randomVec(n, 12);
        for (double& x : e) x = 0.2 + 0.6 * x;
        for (double& x : v) x -= 0.5;
        // Central differences of the exact gradient along v: H·v to O(h²).
        const double h = 1e-5;
        std::vector<double> ep(e), em(e), gp(n), gm(n), fd(n);
        for (size_t i = 0; i < n; ++i) {
            ep[i] += h * v[i];
            em[i] -= h * v[i];
        }
        p.evaluate(ep, gp);
        p.evaluate(em, gm);
        for (size_t i = 0; i < n; ++i) fd[i] = (gp[i] - gm[i]) / (2 * h);
        std::vector<double> hvFresh(n), hvAfter(n), g(n);
        p.hessianProduct(e, v, hvFresh);  // P·E computed for it
        p.evaluate(e, g);
        p.hessianProduct(e, v, hvAfter);  // P·E the evaluation's
        double scale = 0, err = 0;
        for (size_t i = 0; i < n; ++i) {
            scale = std::max(scale, std::abs(fd[i]));
            err = std::max(err, std::abs(hvFresh[i] - fd[i]));
        }
        EXPECT_LT(err, 1e-6 * scale) << "reg " << int(reg);
        EXPECT_EQ(hvFresh, hvAfter);  // the same bits either way
    }
    // An objective that is not quadratic in the halves offers none.
    ImageObjective paper(t.width, t.height, t.objectMask, ObjectiveOptions{});
    TransportLoss image(t, paper, false);
    EXPECT_FALSE(image.offersHessian());
    EXPECT_FALSE(static_cast<bool>(image.problem().hessianProduct));
}

TEST(TransportGram, AutoSwitchesToTheGramWhenItPays) {
    auto s = smallScene(21);
    const TransportMatrix t = halves(*s, 1);
    UnbiasedObjective obj(t.width, t.height, t.objectMask, ObjectiveOptions{});
    TransportLoss aut(t, obj, false), gram(t, obj, false), csr(t, obj, false);
    gram.setLayout(TransportLayout::Gram);
    csr.setLayout(TransportLayout::Csr);
    ASSERT_TRUE(aut.gramPays());  // a small T: its build costs a few evaluations
    const std::vector<double> e = randomVec(aut.dimension(), 5);
    std::vector<double> ga(e.size()), gg(e.size()), gc(e.size());
    gram.evaluateFused(e, gg);
    csr.evaluateFused(e, gc);
    ASSERT_NE(0, std::memcmp(gg.data(), gc.data(), gg.size() * sizeof(double)))
        << "the Gram's and the products' gradients round alike: this test cannot tell them apart";
    for (int i = 0; i < kAutoSlicesAfter + 2; ++i) {
        aut.evaluateFused(e, ga);
        if (i >= kAutoSlicesAfter)
            EXPECT_EQ(0, std::memcmp(ga.data(), gg.data(), ga.size() * sizeof(double))) << i;
        else
            EXPECT_NE(0, std::memcmp(ga.data(), gg.data(), ga.size() * sizeof(double))) << i;
    }
    // The paper's objective (not quadratic) never uses it.
    ImageObjective paper(t.width, t.height, t.objectMask, ObjectiveOptions{});
    const TransportLoss p(t, paper, false);
    EXPECT_FALSE(p.gramEligible());
    EXPECT_THROW(p.gram(), std::logic_error);
}

TEST(TransportGram, TheHeldOutScorerReadsTsArraysAndBuildsNoGram) {
    // optimize's held-out curve asks the scorer for one value every heldOutEvery iterations;
    // Auto would build the held-out T's Gram at its 17th (a 512² part: seconds of CPU for the
    // few scores after it). Its scores stay those of T's own arrays, bit for bit, however many.
    auto s = smallScene(21);
    const TransportMatrix t = halves(*s, 1);
    UnbiasedObjective obj(t.width, t.height, t.objectMask, ObjectiveOptions{});
    const TransportLoss aut(t, obj, false);
    ASSERT_TRUE(aut.gramPays());  // Auto would build it
    TransportLoss csr(t, obj, false);
    csr.setLayout(TransportLayout::Csr);
    const HeldOutScorer scorer(t, t.objectMask, ObjectiveOptions{}, ObjectiveKind::Unbiased, false);
    EXPECT_EQ(scorer.unbiasedLoss().layout(), TransportLayout::Csr);
    for (int i = 0; i < kAutoSlicesAfter + 4; ++i) {
        const std::vector<double> e = randomVec(csr.dimension(), 11 + static_cast<uint64_t>(i));
        const HeldOutScore h = scorer.score(e);
        EXPECT_EQ(h.unbiased.total, csr.evaluate(e, {}).total) << i;
        EXPECT_EQ(h.own.total, h.unbiased.total) << i;
    }
    EXPECT_EQ(scorer.unbiasedLoss().gramIfBuilt(), nullptr);
}

TEST(TransportGram, LossesOnTheSameTAndMaskShareOneGram) {
    // Built once for every loss on the same T and pair mask alive in the process (a lamps run's
    // E* search and its fit), not for another mask nor another T.
    auto s = smallScene(17);
    const TransportMatrix t = halves(*s, 1), other = halves(*s, 1);
    const std::vector<uint8_t> holed = holedMask(t);
    UnbiasedObjective a(t.width, t.height, t.objectMask, ObjectiveOptions{});
    UnbiasedObjective b(t.width, t.height, t.objectMask, ObjectiveOptions{});
    UnbiasedObjective c(t.width, t.height, holed, ObjectiveOptions{});
    const TransportLoss la(t, a, false), lb(t, b, false), lc(t, c, false), lo(other, a, false);
    EXPECT_EQ(&la.gram(), &lb.gram());  // two objectives with the same mask
    EXPECT_NE(&la.gram(), &lc.gram());  // another mask
    EXPECT_NE(&la.gram(), &lo.gram());  // another T
    // The shared one gives the same forms as a Gram of its own.
    const TransportGram own(t, t.objectMask, a.usesProducts());
    const std::vector<double> E = randomVec(t.cols(), 5);
    EXPECT_EQ(lb.gram().pairForm(E, {}), own.pairForm(E, {}));
    EXPECT_TRUE(std::equal(lb.gram().pairMatrix().begin(), lb.gram().pairMatrix().end(),
                           own.pairMatrix().begin(), own.pairMatrix().end()));
}

TEST(TransportGram, AGramFileReadsBackBitForBitUnderItsKeyOnly) {
    // io/GramFile.h: the stored matrices are the built ones, bit for bit; another key, another
    // texel count, a damaged or cut file read as nothing.
    auto s = smallScene(17);
    const TransportMatrix t = halves(*s, 1);
    const TransportGram built(t, holedMask(t), true);
    test::TempDir dir("gramfile");
    const std::filesystem::path file = dir.path() / "g.gram";
    const std::string key(32, 'a'), other(32, 'b');
    writeGramFile(file, key, built);
    EXPECT_EQ(peekGramFile(file), key);
    const auto read = readGramFile(file, key, t.cols());
    ASSERT_TRUE(read.has_value());
    EXPECT_TRUE(std::equal(read->seen().begin(), read->seen().end(), built.seen().begin(),
                           built.seen().end()));
    ASSERT_EQ(read->pairMatrix().size(), built.pairMatrix().size());
    EXPECT_EQ(0, std::memcmp(read->pairMatrix().data(), built.pairMatrix().data(),
                             built.pairMatrix().size_bytes()));
    EXPECT_EQ(0, std::memcmp(read->productMatrix().data(), built.productMatrix().data(),
                             built.productMatrix().size_bytes()));
    const std::vector<double> E = randomVec(t.cols(), 8);
    EXPECT_EQ(read->pairForm(E, {}), built.pairForm(E, {}));
    EXPECT_EQ(read->productForm(E, {}), built.productForm(E, {}));
    EXPECT_FALSE(readGramFile(file, other, t.cols()));
    EXPECT_FALSE(readGramFile(file, key, t.cols() + 1));
    EXPECT_FALSE(readGramFile(dir.path() / "none.gram", key, t.cols()));
    // One flipped byte in P, then the file cut short.
    std::string bytes;
    {
        std::ifstream in(file, std::ios::binary);
        bytes.assign(std::istreambuf_iterator<char>(in), {});
    }
    auto rewrite = [&](const std::string& b) {
        std::ofstream out(file, std::ios::binary | std::ios::trunc);
        out.write(b.data(), static_cast<std::streamsize>(b.size()));
    };
    std::string damaged = bytes;
    damaged[bytes.size() / 2] ^= 0x10;
    rewrite(damaged);
    EXPECT_FALSE(readGramFile(file, key, t.cols()));
    rewrite(bytes.substr(0, bytes.size() - 9));
    EXPECT_FALSE(readGramFile(file, key, t.cols()));
    rewrite("not a gram file at all, just text of some length");
    EXPECT_EQ(peekGramFile(file), "");
}

TEST(TransportGram, ACachedGramIsStoredOnceAndReadByTheNextLossBitForBit) {
    // app/pipeline/Cache.h cachedGram: the first loss builds and stores T's Gram, a loss of a
    // later run (none alive in between) reads it; both evaluate to the same bits; the cache
    // lists, trims and clears the file with the matrices.
    auto s = smallScene(17);
    const TransportMatrix t = halves(*s, 1);
    UnbiasedObjective obj(t.width, t.height, t.objectMask, ObjectiveOptions{});
    test::TempDir dir("gramcache");
    const std::string fp = "0123456789abcdef0123456789abcdef";
    const std::vector<double> e = randomVec(t.cols(), 6);
    std::vector<double> g0(e.size()), g1(e.size());
    double l0 = 0, l1 = 0;
    {
        TransportLoss first(t, obj, false);
        first.setLayout(TransportLayout::Gram);
        ASSERT_TRUE(first.gramPays());
        const auto held = cachedGram(dir.path(), fp, first);
        ASSERT_TRUE(held);
        EXPECT_EQ(held.get(), &first.gram());
        l0 = first.evaluate(e, g0).total;
    }
    const CacheContents listed = cacheContents(dir.path());
    EXPECT_EQ(listed.grams, 1u);
    EXPECT_NE(describeCache(listed).find("1 Gram matrix"), std::string::npos);
    {
        TransportLoss second(t, obj, false);
        second.setLayout(TransportLayout::Gram);
        EXPECT_FALSE(second.gramIfBuilt());
        const auto held = cachedGram(dir.path(), fp, second);
        ASSERT_TRUE(held);
        EXPECT_EQ(held.get(), &second.gram());
        EXPECT_FALSE(second.adoptGram(held));  // it has one already
        l1 = second.evaluate(e, g1).total;
    }
    EXPECT_EQ(l0, l1);
    EXPECT_EQ(0, std::memcmp(g0.data(), g1.data(), g0.size() * sizeof(double)));
    // Another fingerprint or pair mask is another key.
    UnbiasedObjective holed(t.width, t.height, holedMask(t), ObjectiveOptions{});
    const TransportLoss third(t, holed, false);
    EXPECT_NE(third.gramKey(fp), TransportLoss(t, obj, false).gramKey(fp));
    EXPECT_NE(TransportLoss(t, obj, false).gramKey(fp),
              TransportLoss(t, obj, false).gramKey(std::string(32, 'f')));
    // No folder or no fingerprint: nothing kept.
    EXPECT_FALSE(cachedGram({}, fp, third));
    EXPECT_FALSE(cachedGram(dir.path(), "", third));
    EXPECT_EQ(clearCache(dir.path()).grams, 1u);
    EXPECT_EQ(cacheContents(dir.path()).grams, 0u);
}

TEST(TransportGram, ASearchStoresTheGramAndTheNextSearchReadsItForTheSameLight) {
    // app/pipeline/Search.h: a search given the cache folder and T's fingerprint builds the
    // Gram before its first evaluation and stores it; the next search reads it and finds the
    // same E* bit for bit; a search without the cache reads the products for its first
    // evaluations (Auto) and finds it to rounding.
    auto s = smallScene(19);
    const TransportMatrix t = halves(*s, 1);
    test::TempDir dir("gramsearch");
    SearchInputs in;
    in.set = {&t};
    in.mask = t.objectMask;
    in.objective.lambda = 3;
    SearchOptions so;
    so.objective = ObjectiveKind::Unbiased;
    so.optimizer.method = OptimizerMethod::Lbfgs;
    so.optimizer.iterations = 300;
    const SearchResult plain = search(in, so);
    EXPECT_EQ(cacheContents(dir.path()).grams, 0u);
    in.gramCache = dir.path();
    in.fingerprint = "00112233445566778899aabbccddeeff";
    const SearchResult cold = search(in, so);
    EXPECT_EQ(cacheContents(dir.path()).grams, 1u);
    const SearchResult warm = search(in, so);
    EXPECT_EQ(cacheContents(dir.path()).grams, 1u);
    ASSERT_EQ(cold.e.size(), warm.e.size());
    EXPECT_EQ(0, std::memcmp(cold.e.data(), warm.e.data(), cold.e.size() * sizeof(double)));
    EXPECT_EQ(cold.optimizer.evaluations, warm.optimizer.evaluations);
    EXPECT_GT(cold.optimizer.evaluations, kAutoSlicesAfter);
    EXPECT_NEAR(cold.training.total, plain.training.total, 1e-9 * std::abs(plain.training.total));
    EXPECT_LE(maxRelDiff(cold.e, plain.e), 1e-4);
}
