// The env-map convention (Mitsuba 3.8.0 envmap.cpp), checked against hand-computed cases.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/Rng.h"
#include "scene/EnvMapBasis.h"

using namespace sl;

namespace {
float weightOf(const TexelWeights& w, int row, int col, int W) {
    float s = 0;
    for (int k = 0; k < 4; ++k)
        if (w.index[k] == static_cast<uint32_t>(row * W + col)) s += w.weight[k];
    return s;
}
}  // namespace

TEST(EnvMapBasis, UvDirectionRoundTrip) {
    Pcg32 rng(1, 2);
    for (int n = 0; n < 10000; ++n) {
        double u = rng.nextDouble() - 0.5, v = 0.001 + 0.998 * rng.nextDouble();
        Vec3d d = EnvMapBasis::uvToDirection(u, v);
        EXPECT_NEAR(length(d), 1.0, 1e-12);
        auto uv = EnvMapBasis::directionToUv(d);
        EXPECT_NEAR(uv[0], u, 1e-9);
        EXPECT_NEAR(uv[1], v, 1e-9);
    }
}

TEST(EnvMapBasis, MitsubaAxes) {
    // Mitsuba: u = atan2(d.x, -d.z)/2π, v = acos(d.y)/π.
    auto uv = EnvMapBasis::directionToUv({0, 0, -1});
    EXPECT_NEAR(uv[0], 0.0, 1e-12);
    EXPECT_NEAR(uv[1], 0.5, 1e-12);
    uv = EnvMapBasis::directionToUv({1, 0, 0});
    EXPECT_NEAR(uv[0], 0.25, 1e-12);
    uv = EnvMapBasis::directionToUv({0, 1, 0});
    EXPECT_NEAR(uv[1], 0.0, 1e-12);
    uv = EnvMapBasis::directionToUv({0, -1, 0});
    EXPECT_NEAR(uv[1], 1.0, 1e-12);
}

TEST(EnvMapBasis, HandComputedBilinearWeights) {
    const int W = 50, H = 25;
    EnvMapBasis b(W, H);
    // -z: u = 0 -> x = frac(0 - 0.5/W)·W = W - 0.5: half on the last column, half on column 0
    // (the padded column); v = 0.5 -> y = 12 exactly.
    TexelWeights w = b.weights({0, 0, -1});
    EXPECT_NEAR(weightOf(w, 12, 49, W), 0.5f, 1e-5);
    EXPECT_NEAR(weightOf(w, 12, 0, W), 0.5f, 1e-5);
    // +x: u = 0.25 -> x = 12 exactly: the centre of column 12 (u = 12.5/50).
    w = b.weights({1, 0, 0});
    EXPECT_NEAR(weightOf(w, 12, 12, W), 1.0f, 1e-5);
    // +Y pole: row 0 only.
    w = b.weights({0, 1, 0});
    float row0 = 0;
    for (int i = 0; i < W; ++i) row0 += weightOf(w, 0, i, W);
    EXPECT_NEAR(row0, 1.0f, 1e-6);
    // -Y pole: last row only (j0 clamps to H-2, fy = 1).
    w = b.weights({0, -1, 0});
    float rowLast = 0;
    for (int i = 0; i < W; ++i) rowLast += weightOf(w, H - 1, i, W);
    EXPECT_NEAR(rowLast, 1.0f, 1e-6);
}

TEST(EnvMapBasis, TexelCentresReadTheirTexel) {
    for (auto [W, H] : {std::pair{50, 25}, std::pair{8, 5}, std::pair{33, 17}}) {
        EnvMapBasis b(W, H);
        for (int j = 1; j < H - 1; ++j)
            for (int i = 0; i < W; ++i)
                EXPECT_NEAR(weightOf(b.weights(Vec3f(b.texelDirection(j, i))), j, i, W), 1.0f, 2e-4)
                    << W << "x" << H << " texel " << j << "," << i;
    }
}

TEST(EnvMapBasis, WeightsArePartitionOfUnity) {
    EnvMapBasis b(50, 25);
    Pcg32 rng(7, 3);
    for (int n = 0; n < 20000; ++n) {
        Vec3f d = normalize(
            Vec3f{rng.nextFloat() - 0.5f, rng.nextFloat() - 0.5f, rng.nextFloat() - 0.5f});
        TexelWeights w = b.weights(d);
        float s = 0;
        for (int k = 0; k < 4; ++k) {
            EXPECT_GE(w.weight[k], 0.0f);
            EXPECT_LT(w.index[k], 50u * 25u);
            s += w.weight[k];
        }
        EXPECT_NEAR(s, 1.0f, 1e-6);
    }
}

TEST(EnvMapBasis, RejectsTooSmall) {
    EXPECT_THROW(EnvMapBasis(1, 25), std::runtime_error);
    EXPECT_THROW(EnvMapBasis(50, 2), std::runtime_error);
}
