// The coarse light grid (objective/CoarseLight.h): E = P·θ with P bilinear, rows summing to 1.
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <vector>

#include "core/Error.h"
#include "core/Rng.h"
#include "objective/CoarseLight.h"

namespace sl {
namespace {

std::vector<double> randomVector(size_t n, uint64_t seed) {
    Pcg32 rng(seed, 7);
    std::vector<double> v(n);
    for (double& x : v) x = rng.nextDouble();
    return v;
}

double dot(const std::vector<double>& a, const std::vector<double>& b) {
    return std::inner_product(a.begin(), a.end(), b.begin(), 0.0);
}

TEST(CoarseLight, TheEnvMapsOwnGridIsTheIdentity) {
    const CoarseLight grid(50, 25, 50, 25);
    EXPECT_TRUE(grid.identity());
    const std::vector<double> theta = randomVector(grid.parameters(), 1);
    EXPECT_EQ(grid.prolong(theta), theta);
    EXPECT_EQ(grid.gradientInNodes(theta), theta);
}

TEST(CoarseLight, AConstantIsKeptAndTheBoxCarriesOver) {
    for (int channels : {1, 3}) {
        const CoarseLight grid(50, 25, 12, 6, channels);
        EXPECT_EQ(grid.parameters(), 72u * channels);
        EXPECT_EQ(grid.envValues(), 1250u * channels);
        for (double c : {0.0, 0.37, 1.0}) {
            const std::vector<double> e = grid.prolong(std::vector<double>(grid.parameters(), c));
            for (double x : e) EXPECT_NEAR(x, c, 1e-6);
            for (double x : grid.project(e)) EXPECT_NEAR(x, c, 1e-6);
        }
        // Any θ in the box gives E in the box: every texel is a convex combination of nodes.
        const std::vector<double> e = grid.prolong(randomVector(grid.parameters(), 2));
        for (double x : e) {
            EXPECT_GE(x, 0.0);
            EXPECT_LE(x, 1.0 + 1e-6);
        }
    }
}

TEST(CoarseLight, TheGradientIsTheAdjointOfTheInterpolation) {
    // ⟨g, P·θ⟩ = ⟨Pᵀ·g, θ⟩ for any g and θ: the chain rule of the search in θ.
    for (int channels : {1, 3}) {
        const CoarseLight grid(50, 25, 9, 5, channels);
        const std::vector<double> theta = randomVector(grid.parameters(), 3);
        const std::vector<double> g = randomVector(grid.envValues(), 4);
        EXPECT_NEAR(dot(g, grid.prolong(theta)), dot(grid.gradientInNodes(g), theta), 1e-9);
    }
}

TEST(CoarseLight, TheProblemInNodesHasTheChainRulesGradient) {
    // f(E) = Σ c_i E_i² over the env map; in θ its gradient is Pᵀ(2 c ⊙ P θ), checked against
    // central differences of f(P θ).
    const CoarseLight grid(50, 25, 8, 4);
    const std::vector<double> c = randomVector(grid.envValues(), 5);
    Problem fine;
    fine.dimension = grid.envValues();
    fine.evaluate = [&c](std::span<const double> e, std::span<double> grad) {
        double f = 0;
        for (size_t i = 0; i < e.size(); ++i) {
            f += c[i] * e[i] * e[i];
            if (!grad.empty()) grad[i] = 2 * c[i] * e[i];
        }
        return f;
    };
    const Problem coarse = grid.over(fine);
    ASSERT_EQ(coarse.dimension, 32u);
    std::vector<double> theta = randomVector(coarse.dimension, 6), grad(coarse.dimension);
    const double f0 = coarse.evaluate(theta, grad);
    EXPECT_DOUBLE_EQ(f0, fine.evaluate(grid.prolong(theta), {}));
    const double h = 1e-6;
    for (size_t k = 0; k < theta.size(); ++k) {
        std::vector<double> up = theta, down = theta;
        up[k] += h;
        down[k] -= h;
        const double fd = (coarse.evaluate(up, {}) - coarse.evaluate(down, {})) / (2 * h);
        EXPECT_NEAR(grad[k], fd, 1e-6 * std::max(1.0, std::abs(fd))) << "node " << k;
    }
}

TEST(CoarseLight, ANodeLightsTheTexelsAroundItsDirectionOnly) {
    // One node on: the texels it reaches lie within one coarse cell of it, and the nearest
    // texel gets the bilinear weight of its distance. Node (row 2, column 3) of a 12×6 grid:
    // v = 2/5 (fine row 10 of 26 exactly), u = 3.5/12 = 14/48, half a fine texel from the
    // centres 13.5/48 and 14.5/48: weight 1 − (0.5/48)/(1/12) = 0.875.
    const CoarseLight grid(48, 26, 12, 6);
    std::vector<double> theta(grid.parameters(), 0.0);
    theta[2 * 12 + 3] = 1.0;
    const std::vector<double> e = grid.prolong(theta);
    double most = 0;
    for (int j = 0; j < 26; ++j)
        for (int i = 0; i < 48; ++i) {
            const double v = e[static_cast<size_t>(j) * 48 + i];
            most = std::max(most, v);
            if (v > 0) {
                const double dv = std::abs(j / 25.0 - 2 / 5.0);         // in v
                const double du = std::abs((i + 0.5) / 48 - 3.5 / 12);  // in u
                EXPECT_LT(dv, 1 / 5.0) << j << "," << i;
                EXPECT_LT(du, 1 / 12.0) << j << "," << i;
            }
        }
    EXPECT_NEAR(most, 0.875, 1e-6);
    EXPECT_NEAR(e[10 * 48 + 13], 0.875, 1e-6);
    EXPECT_NEAR(e[10 * 48 + 14], 0.875, 1e-6);
}

TEST(CoarseLight, AGridLargerThanTheEnvMapIsRefusedNamingTheOption) {
    try {
        CoarseLight(50, 25, 60, 25);
        FAIL() << "no error";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("light-grid"), std::string::npos) << e.what();
    }
    EXPECT_THROW(CoarseLight(50, 25, 10, 1), InputError);
}

}  // namespace
}  // namespace sl
