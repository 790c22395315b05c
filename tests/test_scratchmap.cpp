// Scratch map (paper §5.1): exact small cases, agreement with a naive implementation, recall and
// precision on the synthetic generator's surface at the paper's parameters, a 5000² map.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <vector>

#include "core/Error.h"
#include "detect/ScratchMap.h"
#include "synth/SurfaceGenerator.h"

using namespace sl;

namespace {

// O(W·H·K²) reference of step 1 (shrinking window at the borders).
std::vector<double> naiveDetrend(const std::vector<float>& h, int W, int H, int K) {
    const int lo = (K - 1) / 2, hi = K / 2;
    std::vector<double> d(h.size());
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            double s = 0;
            int c = 0;
            for (int yy = std::max(0, y - lo); yy <= std::min(H - 1, y + hi); ++yy)
                for (int xx = std::max(0, x - lo); xx <= std::min(W - 1, x + hi); ++xx) {
                    s += h[static_cast<size_t>(yy) * W + xx];
                    ++c;
                }
            d[static_cast<size_t>(y) * W + x] = h[static_cast<size_t>(y) * W + x] - s / c;
        }
    return d;
}

}  // namespace

TEST(ScratchMap, DetrendMatchesNaiveOddAndEvenKernels) {
    const int W = 61, H = 47;
    std::mt19937 rng(3);
    std::normal_distribution<float> nd(0.f, 1.f);
    std::vector<float> h(static_cast<size_t>(W) * H);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x)
            h[static_cast<size_t>(y) * W + x] = 100.f + 0.3f * static_cast<float>(x) -
                                                0.2f * static_cast<float>(y) + 0.01f * nd(rng);
    for (int K : {1, 4, 5, 21, 100}) {
        std::vector<double> fast = detrendHeights(h, W, H, K);
        std::vector<double> ref = naiveDetrend(h, W, H, K);
        double err = 0;
        for (size_t k = 0; k < h.size(); ++k) err = std::max(err, std::abs(fast[k] - ref[k]));
        EXPECT_LT(err, 1e-9) << "kernel " << K;
    }
}

TEST(ScratchMap, SpikesMarkExactlyTheirPatchesIncludingPartialBorderTiles) {
    // 101×90 map, patch 40: tiles 3×3, the last column (80..100) and row (80..89) partial.
    const int W = 101, H = 90;
    std::vector<float> h(static_cast<size_t>(W) * H, 5.0f);
    h[45 * W + 45] += 1.0f;  // tile (1, 1); its 21×21 window reaches into tile (0, 0)
    h[85 * W + 95] += 1.0f;  // tile (2, 2), partial in both directions
    ScratchMap m = computeScratchMap(h, W, H, {21, 40, 0.03});
    EXPECT_EQ(m.patchesX, 3);
    EXPECT_EQ(m.patchesY, 3);
    EXPECT_EQ(m.patchesMarked, 2);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const int tx = x / 40, ty = y / 40;
            const bool want = (tx == 1 && ty == 1) || (tx == 2 && ty == 2);
            ASSERT_EQ(m.map[static_cast<size_t>(y) * W + x] != 0, want) << x << "," << y;
        }
    // The detrended extremes: the spike keeps 1 − 1/441, its neighbours get −1/441.
    EXPECT_NEAR(m.detrendedMax, 1.0 - 1.0 / 441.0, 1e-6);
    // The most negative value: the corner sample (100, 89), whose shrunken 11×11 window holds
    // the spike at (95, 85).
    EXPECT_NEAR(m.detrendedMin, -1.0 / 121.0, 1e-9);
}

TEST(ScratchMap, FlatAndTiltedMapsMarkNothingAndBadOptionsAreRefused) {
    const int W = 50, H = 40;
    std::vector<float> flat(static_cast<size_t>(W) * H, 2.0f), tilt(flat.size());
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x)
            tilt[static_cast<size_t>(y) * W + x] =
                0.5f * static_cast<float>(x) + 0.25f * static_cast<float>(y);
    EXPECT_EQ(computeScratchMap(flat, W, H).patchesMarked, 0);
    // A plane is removed exactly by the moving average away from the borders, not AT them
    // (the shrunken window is off-centre): interior tiles stay unmarked.
    ScratchMap t = computeScratchMap(tilt, W, H, {5, 10, 0.5});
    EXPECT_EQ(t.map[static_cast<size_t>(20) * W + 25], 0);
    EXPECT_THROW(computeScratchMap(flat, W, H, {0, 40, 0.03}), InputError);
    EXPECT_THROW(computeScratchMap(flat, W, H, {21, 0, 0.03}), InputError);
    EXPECT_THROW(computeScratchMap(flat, W, H, {21, 40, 1.5}), InputError);
    EXPECT_THROW(computeScratchMap(flat, W + 1, H), InputError);
    std::vector<float> bad = flat;
    bad[7] = std::numeric_limits<float>::quiet_NaN();
    EXPECT_THROW(computeScratchMap(bad, W, H), InputError);
}

namespace {

struct Score {
    double recall = 0, precision = 0, precisionNoEdge = 0, markedFraction = 0;
    size_t truth = 0, covered = 0;
    int marked = 0, markedTrue = 0, markedNoEdge = 0, markedTrueNoEdge = 0, edgeMarked = 0;
    int patches = 0;
};

// Recall: true defect cells (scratch/gouge samples) inside a marked patch.
// Precision per patch (the map's unit): marked patches that contain a true defect cell.
// Precision excluding the pocket-edge zone: patches whose x-range meets the wall's x-range
// widened by half the kernel (the detrending reaches that far) are left out.
Score score(const GeneratedSurface& g, const ScratchMapOptions& opt) {
    ScratchMap m = computeScratchMap(g.heights, g.width, g.height, opt);
    Score s;
    s.patches = m.patchesX * m.patchesY;
    s.markedFraction = m.markedFraction();
    for (size_t k = 0; k < g.truth.size(); ++k)
        if (g.truth[k]) ++s.truth, s.covered += m.map[k] != 0;
    s.recall = s.truth ? static_cast<double>(s.covered) / static_cast<double>(s.truth) : 0.0;
    const int P = opt.patch;
    const double half = 0.5 * (g.width - 1);
    const double edgeLo = (g.pocketEdgeX - g.pocketEdgeHalfWidth) / g.pitch + half - opt.kernel / 2;
    const double edgeHi = (g.pocketEdgeX + g.pocketEdgeHalfWidth) / g.pitch + half + opt.kernel / 2;
    for (int ty = 0; ty < m.patchesY; ++ty)
        for (int tx = 0; tx < m.patchesX; ++tx) {
            const int x0 = tx * P, x1 = std::min(g.width, x0 + P) - 1;
            const int y0 = ty * P, y1 = std::min(g.height, y0 + P) - 1;
            if (!m.map[static_cast<size_t>(y0) * g.width + x0]) continue;
            bool hasTrue = false;
            for (int y = y0; y <= y1 && !hasTrue; ++y)
                for (int x = x0; x <= x1 && !hasTrue; ++x) hasTrue = g.isDefect(x, y);
            const bool inEdge = x1 >= edgeLo && x0 <= edgeHi;
            ++s.marked;
            s.markedTrue += hasTrue;
            s.edgeMarked += inEdge;
            if (!inEdge) ++s.markedNoEdge, s.markedTrueNoEdge += hasTrue;
        }
    s.precision = s.marked ? static_cast<double>(s.markedTrue) / s.marked : 0.0;
    s.precisionNoEdge =
        s.markedNoEdge ? static_cast<double>(s.markedTrueNoEdge) / s.markedNoEdge : 0.0;
    return s;
}

void print(const char* label, const ScratchMapOptions& o, const Score& s) {
    std::printf(
        "[%s: kernel %d, patch %d, threshold %.2f] %d/%d patches marked (%.1f%% of the map), "
        "%d in the pocket-edge zone\n"
        "    recall %.3f (%zu/%zu defect cells)   precision %.3f (%d/%d patches)   "
        "precision outside the pocket-edge zone %.3f (%d/%d)\n",
        label, o.kernel, o.patch, o.threshold, s.marked, s.patches, 100.0 * s.markedFraction,
        s.edgeMarked, s.recall, s.covered, s.truth, s.precision, s.markedTrue, s.marked,
        s.precisionNoEdge, s.markedTrueNoEdge, s.markedNoEdge);
}

}  // namespace

// The paper's parameters on the generator's default surface (512×512 samples at 0.01 mm,
// ball-end R 3 mm, stepover 0.4 mm = 40 samples, 4 scratches, a gouge, a pocket edge).
// FINDING: every 40-sample patch holds a full scallop cusp, whose detrended relief is > 18% of
// the map's detrended range, so at threshold 0.03 the map marks EVERY patch: recall 1, precision
// = the share of patches that hold a defect. The threshold is relative to the global range, so
// it must be chosen per surface (the paper says as much); a threshold sweep is printed.
TEST(ScratchMap, RecallAndPrecisionOnSyntheticSurfaceAtPaperParameters) {
    SurfaceSpec spec;
    spec.width = 512;
    spec.height = 512;
    GeneratedSurface g = generateSurface(spec);
    const ScratchMapOptions paper;  // kernel 21, patch 40, threshold 0.03
    Score s = score(g, paper);
    print("scratch map 512x512, paper's parameters", paper, s);
    EXPECT_GE(s.recall, 0.99);
    EXPECT_GT(s.precision, 0.0);
    for (double t : {0.1, 0.2, 0.3, 0.4, 0.5, 0.6}) {
        ScratchMapOptions o = paper;
        o.threshold = t;
        print("  sweep", o, score(g, o));
    }
    // A threshold above the cusps' share separates defects from tool marks much better.
    ScratchMapOptions tuned = paper;
    tuned.threshold = 0.3;
    Score st = score(g, tuned);
    EXPECT_GT(st.precisionNoEdge, s.precisionNoEdge);
}

// The paper's size (its timing is `scratchlight bench scratchmap`, app/bench/ScratchMapBench.h).
TEST(ScratchMap, PaperSizeMapMarksItsScratch) {
    const int N = 5000;
    std::vector<float> h(static_cast<size_t>(N) * N);
    for (int y = 0; y < N; ++y)
        for (int x = 0; x < N; ++x)
            h[static_cast<size_t>(y) * N + x] =
                0.01f * std::sin(0.157f * static_cast<float>(x)) + 1e-5f * static_cast<float>(y);
    h[static_cast<size_t>(2500) * N + 2500] -= 0.05f;  // one "scratch"
    ScratchMap m = computeScratchMap(h, N, N);
    EXPECT_GE(m.patchesMarked, 1);
}
