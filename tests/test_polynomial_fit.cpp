// core/PolynomialFit.h: the least-squares polynomial surface that levelling, the selfsim map and
// insert-defects share. Exact polynomials are reproduced to the samples' float rounding (also on
// a large grid at a high degree, with a large offset: the conditioning), the residual of any
// map is orthogonal to every term, masked samples are left out, and maps one or two samples
// wide fit the surface their samples determine.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "core/PolynomialFit.h"
#include "core/Rng.h"

namespace sl {
namespace {

/// A polynomial of total degree `n` in pixel coordinates scaled by the grid (x = i/w, y = j/h),
/// fixed coefficients of alternating sign times `amp`, plus `offset`; stored as float.
std::vector<float> exactPolynomial(size_t w, size_t h, int n, double offset, double amp) {
    const auto np = static_cast<size_t>(n) + 1;
    std::vector<double> xp(w * np), yp(h * np);  // powers 0..n of each column's x, row's y
    for (size_t i = 0; i < w; ++i)
        for (size_t a = 0; a < np; ++a)
            xp[i * np + a] = std::pow(static_cast<double>(i) / static_cast<double>(w), a);
    for (size_t j = 0; j < h; ++j)
        for (size_t b = 0; b < np; ++b)
            yp[j * np + b] = std::pow(static_cast<double>(j) / static_cast<double>(h), b);
    std::vector<float> z(w * h);
    for (size_t j = 0; j < h; ++j)
        for (size_t i = 0; i < w; ++i) {
            double v = offset;
            for (int tot = 0; tot <= n; ++tot)
                for (int a = 0; a <= tot; ++a)
                    v += amp * (1.0 + 0.37 * a - 0.21 * (tot - a)) *
                         xp[i * np + static_cast<size_t>(a)] *
                         yp[j * np + static_cast<size_t>(tot - a)] * ((a + tot) % 2 ? -1.0 : 1.0);
            z[j * w + i] = static_cast<float>(v);
        }
    return z;
}

/// max |z − surface| over all samples.
double maxResidual(const std::vector<float>& z, const PolynomialSurface& s) {
    double worst = 0.0;
    std::vector<double> f;
    for (size_t j = 0; j < s.height; ++j) {
        s.row(j, f);
        for (size_t i = 0; i < s.width; ++i)
            worst = std::max(worst, std::abs(static_cast<double>(z[j * s.width + i]) - f[i]));
    }
    return worst;
}

double maxAbs(const std::vector<float>& z) {
    double m = 0.0;
    for (float v : z) m = std::max(m, std::abs(static_cast<double>(v)));
    return m;
}

TEST(PolynomialFit, ReproducesAnExactPolynomialOfItsDegree) {
    for (int n : {0, 1, 2, 3, 5}) {
        const std::vector<float> z = exactPolynomial(37, 23, n, 0.25, 0.01);
        const auto s = fitPolynomialSurface(z, 37, 23, n);
        ASSERT_TRUE(s) << "degree " << n;
        EXPECT_EQ(s->terms.size(), static_cast<size_t>((n + 1) * (n + 2) / 2));
        // only the samples' own float rounding is left
        EXPECT_LE(maxResidual(z, *s), 2.0 * maxAbs(z) * std::numeric_limits<float>::epsilon())
            << "degree " << n;
    }
}

TEST(PolynomialFit, TheResidualIsOrthogonalToEveryTerm) {
    const size_t w = 41, h = 29;
    Pcg32 rng(7, 1);
    std::vector<float> z(w * h);
    for (float& v : z) v = static_cast<float>(rng.nextDouble() - 0.5);
    const auto s = fitPolynomialSurface(z, w, h, 3);
    ASSERT_TRUE(s);
    const size_t np = 4;
    std::vector<double> f;
    for (size_t t = 0; t < s->terms.size(); ++t) {
        double dot = 0.0, norm = 0.0;
        for (size_t j = 0; j < h; ++j) {
            s->row(j, f);
            for (size_t i = 0; i < w; ++i) {
                const double basis = s->pu[i * np + static_cast<size_t>(s->terms[t][0])] *
                                     s->pv[j * np + static_cast<size_t>(s->terms[t][1])];
                dot += (z[j * w + i] - f[i]) * basis;
                norm += basis * basis;
            }
        }
        EXPECT_NEAR(dot / std::sqrt(norm), 0.0, 1e-12) << "term " << t;
    }
}

TEST(PolynomialFit, LeavesOutMaskedSamples) {
    const size_t w = 30, h = 20;
    std::vector<float> z = exactPolynomial(w, h, 2, 0.0, 1.0);
    std::vector<uint8_t> invalid(w * h, 0);
    for (size_t k = 0; k < z.size(); k += 3) {
        invalid[k] = 1;
        z[k] = 1e6f;  // a spike the fit must not see
    }
    const auto s = fitPolynomialSurface(z, w, h, 2, invalid);
    ASSERT_TRUE(s);
    const std::vector<float> clean = exactPolynomial(w, h, 2, 0.0, 1.0);
    EXPECT_LE(maxResidual(clean, *s), 4.0 * maxAbs(clean) * std::numeric_limits<float>::epsilon());
    // every sample masked: nothing determines the fit
    EXPECT_FALSE(fitPolynomialSurface(z, w, h, 1, std::vector<uint8_t>(w * h, 1)));
    // all valid samples on one column: a plane is not determined
    std::vector<uint8_t> column(w * h, 1);
    for (size_t j = 0; j < h; ++j) column[j * w + 4] = 0;
    EXPECT_FALSE(fitPolynomialSurface(z, w, h, 1, column));
}

TEST(PolynomialFit, StaysExactOnALargeGridAtAHighDegree) {
    // In monomials of pixel coordinates the normal equations' entries would span from the
    // sample count to ~1024^20 (1e60) at degree 10; the Legendre basis on [−1, 1] keeps the fit
    // to the samples' rounding, under a large offset too (heights far from 0).
    const size_t w = 1024, h = 768;
    const std::vector<float> z = exactPolynomial(w, h, 10, 100.0, 0.5);
    const auto s = fitPolynomialSurface(z, w, h, 10);
    ASSERT_TRUE(s);
    EXPECT_LE(maxResidual(z, *s), 2.0 * maxAbs(z) * std::numeric_limits<float>::epsilon());
}

TEST(PolynomialFit, NarrowMapsFitWhatTheirSamplesDetermine) {
    // One sample wide: the quadratic in v alone; two wide: linear in u times quadratic in v.
    for (size_t w : {1u, 2u}) {
        const size_t h = 17;
        std::vector<float> z(w * h);
        for (size_t j = 0; j < h; ++j)
            for (size_t i = 0; i < w; ++i) {
                const double v = static_cast<double>(j) / 16.0;
                z[j * w + i] =
                    static_cast<float>(0.5 + 0.3 * v - 0.7 * v * v + 0.2 * static_cast<double>(i));
            }
        const auto s = fitPolynomialSurface(z, w, h, 2);
        ASSERT_TRUE(s) << w;
        EXPECT_EQ(s->terms.size(), w == 1 ? 3u : 5u);
        EXPECT_LE(maxResidual(z, *s), 4.0 * std::numeric_limits<float>::epsilon());
    }
    const std::vector<float> one = {3.5f};
    const auto s = fitPolynomialSurface(one, 1, 1, 2);
    ASSERT_TRUE(s);
    EXPECT_EQ(maxResidual(one, *s), 0.0);
}

TEST(PolynomialFit, SolveSpdSolvesAndRefusesWhatIsNotPositiveDefinite) {
    // A = [[4, 2, 0], [2, 5, 1], [0, 1, 3]], x = (1, −2, 3): b = A·x = (0, −5, 7)
    std::vector<double> b = {0.0, -5.0, 7.0};
    ASSERT_TRUE(solveSpd({4, 2, 0, 2, 5, 1, 0, 1, 3}, b, 3));
    EXPECT_NEAR(b[0], 1.0, 1e-14);
    EXPECT_NEAR(b[1], -2.0, 1e-14);
    EXPECT_NEAR(b[2], 3.0, 1e-14);
    std::vector<double> c = {1.0, 1.0};
    EXPECT_FALSE(solveSpd({1, 2, 2, 1}, c, 2));  // eigenvalues 3 and −1
    EXPECT_FALSE(solveSpd({1, 1, 1, 1}, c, 2));  // singular
    EXPECT_FALSE(solveSpd({0, 0, 0, 0}, c, 2));
}

}  // namespace
}  // namespace sl
