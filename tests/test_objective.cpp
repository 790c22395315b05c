// Tests of the objective (src/objective/Objective.{h,cpp}): exact values on a hand-computed
// case, the analytic gradient against central differences and against ceres::Jet autodiff,
// the pair mask, the G floor, empty masks, and masks from files.
#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "TestUtil.h"
#include "core/Error.h"
#include "core/Image.h"
#include "io/ImageIO.h"
#include "io/MaskIO.h"
#include "objective/Objective.h"

namespace sl {
namespace {

// A deterministic uniform double in [lo, hi) from a fixed-seed engine (no
// std::uniform_real_distribution, whose output is implementation-defined).
double uniform(std::mt19937_64& rng, double lo, double hi) {
    return lo + (hi - lo) * static_cast<double>(rng() >> 11) * 0x1.0p-53;
}

std::vector<double> randomVec(std::mt19937_64& rng, size_t n, double lo, double hi) {
    std::vector<double> v(n);
    for (double& x : v) x = uniform(rng, lo, hi);
    return v;
}

double norm(const std::vector<double>& v) {
    double s = 0;
    for (double x : v) s += x * x;
    return std::sqrt(s);
}

double relErr(const std::vector<double>& a, const std::vector<double>& b) {
    std::vector<double> d(a.size());
    for (size_t i = 0; i < a.size(); ++i) d[i] = a[i] - b[i];
    return norm(d) / std::max(norm(b), 1e-300);
}

// The 3×3 hand-computed case.
//   Y = 1 2 4      M = 1 1 0
//       0 3 3          1 1 1
//       5 1 2          0 1 1
// Counted pairs (both pixels inside): x: |2−1|, |3−0|, |3−3|, |2−1| = 1, 3, 0, 1;
// y: |0−1|, |3−2|, |1−3|, |2−3| = 1, 1, 2, 1.  G = 10, S = 7, L_grad = 0.7.
// dG/dY = s = [0 0 0; −2 3 1; 0 −2 0] (the pair (4,5) has Δ = 0 and contributes nothing).
const std::vector<double> kY3 = {1, 2, 4, 0, 3, 3, 5, 1, 2};
const std::vector<uint8_t> kM3 = {1, 1, 0, 1, 1, 1, 0, 1, 1};
const std::vector<double> kS3 = {0, 0, 0, -2, 3, 1, 0, -2, 0};

// A random mask with some holes (about 80 % inside), never empty.
std::vector<uint8_t> randomMask(std::mt19937_64& rng, size_t n) {
    std::vector<uint8_t> m(n);
    for (auto& v : m) v = uniform(rng, 0, 1) < 0.8 ? 255 : 0;
    m[0] = 255;
    return m;
}

// Smallest |Δ| over the counted pairs (to pick Y without ties for the non-smooth |x|).
double minAbsDiff(const ImageObjective& obj, const std::vector<double>& Y) {
    double m = std::numeric_limits<double>::infinity();
    detail::forEachMaskedPair(obj.width(), obj.height(), obj.mask().data(),
                              [&](size_t p, size_t q) { m = std::min(m, std::abs(Y[q] - Y[p])); });
    return m;
}

// Gradient of the total loss with respect to Y (for RegTarget::Image) or, with Y fixed, with
// respect to E, by central differences with step h = 1e-6·max(1, |x|).
std::vector<double> centralDiff(const ImageObjective& obj, std::vector<double> Y,
                                std::vector<double> E, bool wrtY) {
    std::vector<double>& x = wrtY ? Y : E;
    std::vector<double> g(x.size());
    for (size_t i = 0; i < x.size(); ++i) {
        const double x0 = x[i];
        const double h = 1e-6 * std::max(1.0, std::abs(x0));
        x[i] = x0 + h;
        const double fp = obj.evaluate(Y, E).total;
        x[i] = x0 - h;
        const double fm = obj.evaluate(Y, E).total;
        x[i] = x0;
        g[i] = (fp - fm) / (2 * h);
    }
    return g;
}

}  // namespace

TEST(Objective, HandComputed3x3) {
    const std::vector<double> E = {0.5, 1.0, 0.0, 2.0};  // ΣE² = 5.25, N = 4
    for (RegTarget reg : {RegTarget::EnvMap, RegTarget::Image}) {
        ObjectiveOptions opt;
        opt.lambda = 2.0;
        opt.reg = reg;
        ImageObjective obj(3, 3, kM3, opt);
        EXPECT_EQ(obj.maskSize(), 7.0);
        std::vector<double> dY(9), dE(4);
        const LossParts r = obj.evaluate(kY3, E, dY, dE);
        EXPECT_EQ(r.S, 7.0);
        EXPECT_EQ(r.G, 10.0);
        EXPECT_DOUBLE_EQ(r.lGrad, 0.7);
        EXPECT_FALSE(r.clamped);
        const double lReg = reg == RegTarget::EnvMap ? 5.25 / 4 : 69.0 / 9;  // ΣY² = 69
        EXPECT_DOUBLE_EQ(r.lReg, lReg);
        EXPECT_DOUBLE_EQ(r.total, 0.7 + 2.0 * lReg);
        for (size_t i = 0; i < 9; ++i) {
            const double expect =
                -7.0 / 100.0 * kS3[i] + (reg == RegTarget::Image ? 2 * 2.0 * kY3[i] / 9 : 0.0);
            EXPECT_NEAR(dY[i], expect, 1e-15) << "pixel " << i;
        }
        for (size_t i = 0; i < 4; ++i) {
            EXPECT_DOUBLE_EQ(dE[i], reg == RegTarget::EnvMap ? 2 * 2.0 * E[i] / 4 : 0.0);
        }
        std::vector<double> s(9);
        EXPECT_EQ(obj.gradientSigns(kY3, s), 10.0);
        for (size_t i = 0; i < 9; ++i) EXPECT_EQ(s[i], kS3[i]) << "pixel " << i;
    }
}

TEST(Objective, HandComputedSmoothAbs) {
    ObjectiveOptions opt;
    opt.smoothAbs = true;
    opt.smoothEps = 0.5;
    ImageObjective obj(3, 3, kM3, opt);
    // |d|_ε = sqrt(d² + 0.25) − 0.5 over the eight counted differences 1,3,0,1,1,1,2,1 (abs).
    auto a = [](double d) { return std::sqrt(d * d + 0.25) - 0.5; };
    const double G = 5 * a(1) + a(3) + a(0) + a(2);
    EXPECT_NEAR(obj.evaluate(kY3, std::vector<double>{1.0}).G, G, 1e-15);
    EXPECT_EQ(a(0), 0.0);
}

TEST(Objective, GradientMatchesCentralDifferences) {
    std::mt19937_64 rng(12345);
    const int W = 7, H = 5;
    const size_t n = W * H, N = 6;
    for (RegTarget reg : {RegTarget::EnvMap, RegTarget::Image}) {
        for (bool smooth : {false, true}) {
            ObjectiveOptions opt;
            opt.lambda = 3.0;
            opt.reg = reg;
            opt.smoothAbs = smooth;
            opt.smoothEps = 0.05;  // large enough that the smooth region is exercised
            ImageObjective obj(W, H, randomMask(rng, n), opt);
            std::vector<double> Y, E = randomVec(rng, N, 0, 1);
            do {  // no ties (|Δ| ≥ 1e-3 ≫ h) so the non-smooth |x| is differentiable at Y
                Y = randomVec(rng, n, 0, 1);
            } while (minAbsDiff(obj, Y) < 1e-3);
            std::vector<double> dY(n), dE(N);
            obj.evaluate(Y, E, dY, dE);

            // d total / dY: only meaningful as a whole for RegTarget::Image; for EnvMap the
            // reg part does not depend on Y, so the same check covers the L_grad part.
            const std::vector<double> fdY = centralDiff(obj, Y, E, true);
            const double eY = relErr(fdY, dY);
            EXPECT_LT(eY, 1e-6) << "dL/dY, reg " << int(reg) << " smooth " << smooth;
            const std::vector<double> fdE = centralDiff(obj, Y, E, false);
            if (reg == RegTarget::EnvMap) {
                EXPECT_LT(relErr(fdE, dE), 1e-6) << "dL/dE, smooth " << smooth;
            } else {
                for (size_t i = 0; i < N; ++i) {
                    EXPECT_EQ(dE[i], 0.0);
                    EXPECT_EQ(fdE[i], 0.0);
                }
            }
            std::printf("[ info ] reg %s smooth %d: rel. error dL/dY %.2e, dL/dE %.2e\n",
                        reg == RegTarget::EnvMap ? "EnvMap" : "Image", int(smooth), eY,
                        reg == RegTarget::EnvMap ? relErr(fdE, dE) : 0.0);
        }
    }
}

TEST(Objective, PairMaskIgnoresBackgroundNextToMask) {
    // 5×4 image, mask = the 3×2 block at x 1..3, y 1..2.
    const int W = 5, H = 4;
    std::vector<uint8_t> mask(W * H, 0);
    for (int y = 1; y <= 2; ++y)
        for (int x = 1; x <= 3; ++x) mask[y * W + x] = 255;
    std::mt19937_64 rng(7);
    std::vector<double> Y = randomVec(rng, W * H, 0, 1);
    ImageObjective obj(W, H, mask, {});
    const std::vector<double> E = {0.5};
    std::vector<double> dY0(W * H);
    const LossParts r0 = obj.evaluate(Y, E, dY0);
    for (size_t i = 0; i < Y.size(); ++i)
        if (!mask[i]) Y[i] = 100.0;  // a bright background all around the part
    std::vector<double> dY1(W * H);
    const LossParts r1 = obj.evaluate(Y, E, dY1);
    EXPECT_EQ(r0.G, r1.G);
    EXPECT_EQ(r0.total, r1.total);
    for (size_t i = 0; i < Y.size(); ++i) {
        EXPECT_EQ(dY0[i], dY1[i]);
        if (!mask[i]) {
            EXPECT_EQ(dY1[i], 0.0) << "background pixel " << i;
        }
    }
    // The paper's first-pixel mask would have counted the right/bottom edges (|Δ| ≈ 100 each).
    EXPECT_LT(r1.G, 20.0);
}

TEST(Objective, InputErrors) {
    EXPECT_THROW(ImageObjective(3, 3, std::vector<uint8_t>(9, 0), {}), InputError);
    try {
        ImageObjective(3, 3, std::vector<uint8_t>(9, 0), {});
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("mask is empty"), std::string::npos) << e.what();
    }
    EXPECT_THROW(ImageObjective(3, 3, std::vector<uint8_t>(8, 1), {}), InputError);
    EXPECT_THROW(ImageObjective(0, 3, {}, {}), InputError);
    ObjectiveOptions bad;
    bad.lambda = -1;
    EXPECT_THROW(ImageObjective(3, 3, kM3, bad), InputError);
    bad = {};
    bad.smoothAbs = true;
    bad.smoothEps = 0;
    EXPECT_THROW(ImageObjective(3, 3, kM3, bad), InputError);

    ImageObjective obj(3, 3, kM3, {});
    const std::vector<double> E = {0.1, 0.2};
    EXPECT_THROW(obj.evaluate(std::vector<double>(8, 0.0), E), std::invalid_argument);
    EXPECT_THROW(obj.evaluate(kY3, std::vector<double>{}), std::invalid_argument);
    std::vector<double> dY(5);
    EXPECT_THROW(obj.evaluate(kY3, E, dY), std::invalid_argument);
    std::vector<double> Ynan = kY3;
    Ynan[4] = std::nan("");
    try {
        obj.evaluate(Ynan, E);
        ADD_FAILURE() << "NaN in Y accepted";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("Y[4]"), std::string::npos) << e.what();
    }
    const std::vector<double> Enan = {0.1, std::numeric_limits<double>::quiet_NaN()};
    try {
        obj.evaluate(kY3, Enan);
        ADD_FAILURE() << "NaN in E accepted";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("E[1]"), std::string::npos) << e.what();
    }
    EXPECT_THROW(obj.value<double>(Ynan, E), std::invalid_argument);
    std::vector<double> s(9);
    EXPECT_THROW(obj.gradientSigns(Ynan, s), std::invalid_argument);
    // Overflow is not returned silently either.
    std::vector<double> Ybig = kY3;
    Ybig[0] = 1e300;
    ObjectiveOptions img;
    img.reg = RegTarget::Image;
    EXPECT_THROW(ImageObjective(3, 3, kM3, img).evaluate(Ybig, E), std::range_error);
}

TEST(Objective, FlatImageIsClampedAndStationary) {
    for (bool smooth : {false, true}) {
        ObjectiveOptions opt;
        opt.smoothAbs = smooth;
        ImageObjective obj(3, 3, kM3, opt);
        for (double c : {0.0, 0.37}) {  // E = 0 (Y = 0) and a constant image
            const std::vector<double> Y(9, c), E(4, c);
            std::vector<double> dY(9, 1.0), dE(4, 1.0);
            const LossParts r = obj.evaluate(Y, E, dY, dE);
            EXPECT_TRUE(r.clamped);
            EXPECT_EQ(r.G, 0.0);
            EXPECT_TRUE(std::isfinite(r.total));
            EXPECT_DOUBLE_EQ(r.lGrad, 7.0 / (1e-12 * 7.0));
            for (double g : dY) EXPECT_EQ(g, 0.0);  // L_grad's gradient is 0 when clamped
            for (size_t i = 0; i < 4; ++i) EXPECT_DOUBLE_EQ(dE[i], 2 * opt.lambda * c / 4);
            EXPECT_DOUBLE_EQ(obj.value<double>(Y, E), r.total);
            EXPECT_EQ(obj.lGradScale(r.G), 0.0);
        }
    }
    // Just above the floor: not clamped.
    ImageObjective obj(2, 1, {1, 1}, {});
    const std::vector<double> Y = {0.0, 2.5e-12}, E = {1.0};
    const LossParts r = obj.evaluate(Y, E);
    EXPECT_FALSE(r.clamped);
    EXPECT_DOUBLE_EQ(r.lGrad, 2.0 / 2.5e-12);
}

TEST(Objective, AbsSubgradientAtZeroIsZero) {
    // Y with exact ties inside the mask: the tied pairs contribute nothing to s = dG/dY.
    ImageObjective obj(3, 1, {1, 1, 1}, {});
    std::vector<double> s(3);
    EXPECT_DOUBLE_EQ(obj.gradientSigns(std::vector<double>{0.5, 0.5, 0.9}, s), 0.4);
    EXPECT_EQ(s[0], 0.0);   // pair (0,1): Δ = 0
    EXPECT_EQ(s[1], -1.0);  // pair (1,2): Δ > 0
    EXPECT_EQ(s[2], 1.0);
    // The same through Jet autodiff: the derivative of |Δ| at Δ = 0 is 0.
    using J = ceres::Jet<double, 3>;
    const std::vector<J> Yj = {J(0.5, 0), J(0.5, 1), J(0.9, 2)};
    ObjectiveOptions noReg;
    noReg.lambda = 0;
    const J v = ImageObjective(3, 1, {1, 1, 1}, noReg).value<J>(Yj, std::vector<J>{J(0.0)});
    const double k = -3.0 / (0.4 * 0.4);  // −S/G²
    EXPECT_NEAR(v.v[0], k * 0.0, 1e-12);
    EXPECT_NEAR(v.v[1], k * -1.0, 1e-12);
    EXPECT_NEAR(v.v[2], k * 1.0, 1e-12);
}

TEST(Objective, ValueDoubleEqualsEvaluate) {
    std::mt19937_64 rng(99);
    const int W = 9, H = 6;
    for (RegTarget reg : {RegTarget::EnvMap, RegTarget::Image}) {
        for (bool smooth : {false, true}) {
            ObjectiveOptions opt;
            opt.reg = reg;
            opt.smoothAbs = smooth;
            ImageObjective obj(W, H, randomMask(rng, W * H), opt);
            const std::vector<double> Y = randomVec(rng, W * H, 0, 2);
            const std::vector<double> E = randomVec(rng, 10, 0, 1);
            const double total = obj.evaluate(Y, E).total;
            const double v = obj.value<double>(Y, E);
            EXPECT_LE(std::abs(v - total), 1e-12 * std::abs(total));
        }
    }
}

TEST(Objective, JetDerivativesMatchAnalyticGradient) {
    // Y = A·e and E = B·e for a random 4-vector e: d total/de = Aᵀ·dLdY + Bᵀ·dLdE.
    constexpr int K = 4;
    using J = ceres::Jet<double, K>;
    std::mt19937_64 rng(2024);
    const int W = 8, H = 6;
    const size_t n = W * H, N = 5;
    for (RegTarget reg : {RegTarget::EnvMap, RegTarget::Image}) {
        for (bool smooth : {false, true}) {
            ObjectiveOptions opt;
            opt.reg = reg;
            opt.smoothAbs = smooth;
            opt.smoothEps = 0.02;
            ImageObjective obj(W, H, randomMask(rng, n), opt);
            const std::vector<double> e = randomVec(rng, K, 0.2, 1.0);
            std::vector<double> A, B, Y(n), E(N);
            do {
                A = randomVec(rng, n * K, 0, 1);
                for (size_t p = 0; p < n; ++p) {
                    Y[p] = 0;
                    for (int k = 0; k < K; ++k) Y[p] += A[p * K + k] * e[k];
                }
            } while (minAbsDiff(obj, Y) < 1e-6);  // no ties
            B = randomVec(rng, N * K, 0, 1);
            for (size_t i = 0; i < N; ++i) {
                E[i] = 0;
                for (int k = 0; k < K; ++k) E[i] += B[i * K + k] * e[k];
            }
            std::vector<double> dY(n), dE(N);
            obj.evaluate(Y, E, dY, dE);
            std::vector<double> analytic(K, 0.0);
            for (int k = 0; k < K; ++k) {
                for (size_t p = 0; p < n; ++p) analytic[k] += A[p * K + k] * dY[p];
                for (size_t i = 0; i < N; ++i) analytic[k] += B[i * K + k] * dE[i];
            }

            std::vector<J> ej(K), Yj(n, J(0.0)), Ej(N, J(0.0));
            for (int k = 0; k < K; ++k) ej[k] = J(e[k], k);
            for (size_t p = 0; p < n; ++p)
                for (int k = 0; k < K; ++k) Yj[p] += A[p * K + k] * ej[k];
            for (size_t i = 0; i < N; ++i)
                for (int k = 0; k < K; ++k) Ej[i] += B[i * K + k] * ej[k];
            const J v = obj.value<J>(Yj, Ej);
            const std::vector<double> jet(v.v.data(), v.v.data() + K);
            EXPECT_LE(std::abs(v.a - obj.evaluate(Y, E).total), 1e-12 * std::abs(v.a));
            const double err = relErr(jet, analytic);
            EXPECT_LT(err, 1e-9) << "reg " << int(reg) << " smooth " << smooth;
            std::printf("[ info ] Jet vs analytic, reg %s smooth %d: rel. error %.2e\n",
                        reg == RegTarget::EnvMap ? "EnvMap" : "Image", int(smooth), err);
        }
    }
}

TEST(Objective, GradientSignsConsistentWithEvaluate) {
    std::mt19937_64 rng(5);
    const int W = 10, H = 7;
    for (bool smooth : {false, true}) {
        ObjectiveOptions opt;  // RegTarget::EnvMap: dLdY is the L_grad part only
        opt.smoothAbs = smooth;
        opt.smoothEps = 0.01;
        ImageObjective obj(W, H, randomMask(rng, W * H), opt);
        const std::vector<double> Y = randomVec(rng, W * H, 0, 1), E = {0.3, 0.4};
        std::vector<double> dY(W * H), s(W * H);
        const LossParts r = obj.evaluate(Y, E, dY);
        const double G = obj.gradientSigns(Y, s);
        EXPECT_EQ(G, r.G);
        const double k = -r.S / (G * G);
        EXPECT_EQ(obj.lGradScale(G), k);
        EXPECT_EQ(obj.lGrad(G), r.lGrad);
        for (size_t i = 0; i < s.size(); ++i) EXPECT_EQ(dY[i], k * s[i]) << "pixel " << i;
    }
}

TEST(Objective, LoadImageMaskFromPng) {
    test::TempDir dir("objective");
    const int W = 6, H = 4;
    std::vector<uint8_t> mask(W * H, 0);
    for (int y = 1; y < 3; ++y)
        for (int x = 2; x < 5; ++x) mask[y * W + x] = 255;
    mask[0] = 200;  // ≥ 128 in a linear-tagged mask PNG: inside

    const auto maskPng = dir / "mask.png";
    writeMaskPng(maskPng, mask, W, H);
    const std::vector<uint8_t> m = loadImageMask(maskPng, W, H);
    ASSERT_EQ(m.size(), mask.size());
    for (size_t i = 0; i < m.size(); ++i) EXPECT_EQ(m[i], mask[i] ? 255 : 0) << "pixel " << i;

    // An sRGB preview PNG (3 channels): linear 1.0 = white is inside, 0.2 (sRGB 124) is not.
    Image img(W, H, 3, 0.2f);
    for (int c = 0; c < 3; ++c) img.at(1, 2, c) = 1.0f;
    const auto rgbPng = dir / "rgb.png";
    writePng(rgbPng, img);
    const std::vector<uint8_t> m2 = loadImageMask(rgbPng, W, H);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x)
            EXPECT_EQ(m2[y * W + x], (x == 1 && y == 2) ? 255 : 0) << x << "," << y;

    try {
        loadImageMask(maskPng, W + 1, H);
        ADD_FAILURE() << "wrong size accepted";
    } catch (const InputError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("mask.png"), std::string::npos) << msg;
        EXPECT_NE(msg.find("6x4"), std::string::npos) << msg;
        EXPECT_NE(msg.find("7x4"), std::string::npos) << msg;
    }
    writeMaskPng(dir / "empty.png", std::vector<uint8_t>(W * H, 0), W, H);
    EXPECT_THROW(loadImageMask(dir / "empty.png", W, H), InputError);

    const std::vector<uint8_t> both = intersectMasks(m, m2);
    for (uint8_t b : both) EXPECT_EQ(b, 0);  // (1,2) is outside the first mask
    const std::vector<uint8_t> self = intersectMasks(m, m);
    EXPECT_EQ(self, m);
    EXPECT_THROW(intersectMasks(m, std::vector<uint8_t>(3, 1)), InputError);
}

}  // namespace sl
