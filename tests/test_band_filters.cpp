// perception/BandFilters.h: the Fourier-domain Gaussians are the direct sums' operator (the same
// truncated, normalized kernels on the part, zero outside the image), rounding apart, on sizes
// that are odd, not square, narrower than the widest kernel, and on a part with holes; and the
// adjoint is the transpose of the forward map exactly.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "perception/BandFilters.h"

using namespace sl;

namespace {

struct Case {
    int w, h;
    std::vector<uint8_t> part;
    std::vector<double> y;
    std::vector<std::vector<double>> dG;  // kJndBands + 1 images
};

/// A disc-shaped part with holes and a ragged edge, a random image and random dG.
Case makeCase(int w, int h, unsigned seed) {
    Case c{w, h, {}, {}, {}};
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const size_t n = static_cast<size_t>(w) * h;
    c.part.resize(n);
    c.y.resize(n);
    for (int yy = 0; yy < h; ++yy)
        for (int x = 0; x < w; ++x) {
            const double dx = (x - 0.5 * w) / w, dy = (yy - 0.5 * h) / h;
            const double r = std::hypot(dx, dy);
            const bool hole = std::hypot(dx - 0.1, dy) < 0.05 || (x % 11 == 3 && yy % 7 == 2);
            const size_t p = static_cast<size_t>(yy) * w + x;
            c.part[p] = r < 0.45 + 0.03 * std::sin(13.0 * std::atan2(dy, dx)) && !hole;
            c.y[p] = 0.3 + 0.5 * u(rng);
        }
    // dG on the part only, as the JND objective's (its band products are summed on the part).
    c.dG.assign(kJndBands + 1, std::vector<double>(n, 0.0));
    for (auto& g : c.dG)
        for (size_t p = 0; p < n; ++p) g[p] = c.part[p] ? u(rng) - 0.5 : 0.0;
    return c;
}

double maxAbs(const std::vector<double>& v) {
    double m = 0;
    for (double x : v) m = std::max(m, std::abs(x));
    return m;
}

}  // namespace

TEST(BandFilters, FourierGaussiansAreTheDirectSums) {
    // 20×13: the widest kernel (radius 96) is wider than the image; 150×97 and 64×64 are larger.
    for (const auto& [w, h] : {std::pair{20, 13}, std::pair{150, 97}, std::pair{64, 64}}) {
        const Case c = makeCase(w, h, static_cast<unsigned>(w * 131 + h));
        const BandFilterBank direct(w, h, c.part, GaussianMethod::Direct);
        const BandFilterBank fourier(w, h, c.part, GaussianMethod::Fourier);
        const auto gd = direct.gaussians(c.y);
        const auto gf = fourier.gaussians(c.y);
        for (int j = 0; j <= kJndBands; ++j) {
            ASSERT_EQ(gd[j].size(), gf[j].size());
            double onPart = 0, offPart = 0;
            for (size_t p = 0; p < gd[j].size(); ++p)
                (c.part[p] ? onPart : offPart) =
                    std::max(c.part[p] ? onPart : offPart, std::abs(gd[j][p] - gf[j][p]));
            // G is a weighted mean of values in [0.3, 0.8] where the part reaches (0 elsewhere).
            // The transform's rounding is absolute, ~1e-16 of the sums, so G = sum / weight
            // carries it relative to the weight: on the part the weight is at least the kernel's
            // centre tap squared; off it (where nothing reads G) it can be 1e-6 of that.
            EXPECT_LT(onPart, 1e-12) << w << "x" << h << " Gaussian " << j;
            EXPECT_LT(offPart, 1e-8) << w << "x" << h << " Gaussian " << j;
            // ... and the template the autodiff check runs is the direct one.
            const std::vector<double> gt = direct.gaussian<double>(j, c.y);
            for (size_t p = 0; p < gt.size(); ++p) ASSERT_EQ(gt[p], gd[j][p]);
        }
        const std::vector<double> ad = direct.adjointSum(c.dG);
        const std::vector<double> af = fourier.adjointSum(c.dG);
        double diff = 0;
        for (size_t p = 0; p < ad.size(); ++p) diff = std::max(diff, std::abs(ad[p] - af[p]));
        EXPECT_LT(diff, 1e-12 * maxAbs(ad)) << w << "x" << h << " adjoint";
    }
}

TEST(BandFilters, AdjointIsTheTransposeOfTheGaussians) {
    // Σ_j <dG_j, G_j(Y)> = <adjointSum(dG), Y> for every Y and dG (G is linear in Y).
    for (const GaussianMethod m : {GaussianMethod::Direct, GaussianMethod::Fourier}) {
        const Case c = makeCase(57, 41, 7);
        const BandFilterBank bank(c.w, c.h, c.part, m);
        const auto g = bank.gaussians(c.y);
        double lhs = 0, rhs = 0, scale = 0;
        for (int j = 0; j <= kJndBands; ++j)
            for (size_t p = 0; p < c.y.size(); ++p) {
                lhs += c.dG[j][p] * g[j][p];
                scale += std::abs(c.dG[j][p] * g[j][p]);
            }
        const std::vector<double> a = bank.adjointSum(c.dG);
        for (size_t p = 0; p < c.y.size(); ++p) rhs += a[p] * c.y[p];
        EXPECT_NEAR(lhs, rhs, 1e-13 * scale);
        // Off the part the gradient is 0 (the part's pixels alone enter G).
        size_t offPartNonzero = 0;
        for (size_t p = 0; p < c.y.size(); ++p) offPartNonzero += !c.part[p] && a[p] != 0.0;
        EXPECT_EQ(offPartNonzero, 0u);
    }
}

TEST(BandFilters, TwoImagesAtOnceAreEachAlone) {
    const Case c = makeCase(40, 30, 3);
    const BandFilterBank bank(c.w, c.h, c.part);
    std::vector<double> y2 = c.y;
    std::reverse(y2.begin(), y2.end());
    const auto [ga, gb] = bank.gaussians(c.y, y2);
    EXPECT_EQ(ga, bank.gaussians(c.y));
    EXPECT_EQ(gb, bank.gaussians(y2));
    std::vector<std::vector<double>> dG2 = c.dG;
    std::reverse(dG2.begin(), dG2.end());
    const auto [aa, ab] = bank.adjointSums(c.dG, dG2);
    EXPECT_EQ(aa, bank.adjointSum(c.dG));
    EXPECT_EQ(ab, bank.adjointSum(dG2));
}
