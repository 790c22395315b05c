// Tests of the synthetic machined-surface generator (src/synth/SurfaceGenerator).
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <functional>
#include <limits>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "TestUtil.h"
#include "app/jobs/PartFiles.h"
#include "core/Error.h"
#include "core/Hash.h"
#include "core/Registry.h"
#include "io/ImageIO.h"
#include "io/MaskIO.h"
#include "synth/SurfaceGenerator.h"
#include "synth/SurfaceGeneratorDetail.h"

namespace {

using sl::GeneratedSurface;
using sl::ScratchSpec;
using sl::SurfaceSpec;

/// A clean ball-end surface: only the tool paths (no feed marks, chatter, roughness, defects).
SurfaceSpec cleanBallEnd() {
    SurfaceSpec s;
    s.width = 256;
    s.height = 256;
    s.pitch = 0.005;
    s.toolRadius = 1.5;
    s.stepover = 0.2;
    s.ballFeedMarks = false;
    s.chatterAmplitude = 0;
    s.roughnessRms = 0;
    s.scratchCount = 0;
    s.gougeCount = 0;
    s.pocketEdge = false;
    return s;
}

/// `s` generated twice and on one thread gives the same heights, truth (and description); with
/// seed 2 over half the heights change (roughness and chatter phases change everywhere).
/// Returns the surfaces of the spec's seed and of seed 2.
std::pair<GeneratedSurface, GeneratedSurface> expectDeterministic(SurfaceSpec s) {
    GeneratedSurface a = sl::generateSurface(s);
    GeneratedSurface b = sl::generateSurface(s);
    EXPECT_EQ(a.heights, b.heights);
    EXPECT_EQ(a.truth, b.truth);
    EXPECT_EQ(a.description, b.description);
    {
        tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
        GeneratedSurface c = sl::generateSurface(s);
        EXPECT_EQ(a.heights, c.heights);
        EXPECT_EQ(a.truth, c.truth);
    }
    s.seed = 2;
    GeneratedSurface d = sl::generateSurface(s);
    size_t differing = 0;
    for (size_t k = 0; k < a.heights.size(); ++k) differing += a.heights[k] != d.heights[k];
    EXPECT_GT(differing, a.heights.size() / 2);
    return {std::move(a), std::move(d)};
}

int col(const GeneratedSurface& g, double x) {
    return static_cast<int>(std::lround(x / g.pitch + 0.5 * (g.width - 1)));
}
int row(const GeneratedSurface& g, double z) {
    return static_cast<int>(std::lround(z / g.pitch + 0.5 * (g.height - 1)));
}

std::pair<float, float> minMax(const GeneratedSurface& g) {
    auto [lo, hi] = std::minmax_element(g.heights.begin(), g.heights.end());
    return {*lo, *hi};
}

/// Indices of strict local maxima of v (plateaus of two equal samples count once).
std::vector<int> localMaxima(const std::vector<double>& v) {
    std::vector<int> idx;
    for (size_t k = 1; k + 1 < v.size(); ++k)
        if (v[k] > v[k - 1] && v[k] >= v[k + 1]) idx.push_back(static_cast<int>(k));
    return idx;
}

double segmentDistance(const ScratchSpec& c, double x, double z) {
    double ux = c.x1 - c.x0, uz = c.z1 - c.z0, L2 = ux * ux + uz * uz;
    double t = std::clamp(((x - c.x0) * ux + (z - c.z0) * uz) / L2, 0.0, 1.0);
    return std::hypot(x - c.x0 - t * ux, z - c.z0 - t * uz);
}

/// How the library names a SurfaceSpec field in a message: "option 'tool-radius'" for toolRadius.
std::string optionOf(const std::string& field) {
    std::string name = "option '";
    for (const char c : field) {
        if (c >= 'A' && c <= 'Z') name += '-';
        name += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    }
    return name + "'";
}

std::string errorOf(const SurfaceSpec& s) {
    try {
        sl::generateSurface(s);
    } catch (const sl::InputError& e) {
        return e.what();
    }
    return "";
}

}  // namespace

TEST(Synth, ScallopHeightIsExactAndFirstOrderS2Over8R) {
    for (double R : {0.5, 3.0, 6.0}) {
        for (double s : {0.01, 0.1, 0.4, 0.9}) {
            double h = sl::scallopHeight(s, R);
            // Exact geometry: the cusp point (s/2, h) lies on the ball, (R − h)² + (s/2)² = R².
            EXPECT_NEAR((R - h) * (R - h) + 0.25 * s * s, R * R, 1e-12 * R * R);
            // First order: h = s²/(8R)·(1 + x²/4 + x⁴/8 + …), x = s/(2R).
            double first = s * s / (8 * R);
            double rel = h / first - 1.0, x = s / (2 * R);
            EXPECT_GT(rel, 0.0);
            if (x <= 0.5) {
                EXPECT_GE(rel, x * x / 4);
                EXPECT_LE(rel, x * x / 4 + x * x * x * x / 6);
            }
        }
    }
    EXPECT_DOUBLE_EQ(sl::scallopHeight(0.0, 3.0), 0.0);
    EXPECT_DOUBLE_EQ(sl::scallopHeight(6.0, 3.0), 3.0);  // s = 2R: the ball's equator
    EXPECT_THROW(sl::scallopHeight(6.1, 3.0), sl::InputError);
    EXPECT_THROW(sl::scallopHeight(0.3, 0.0), sl::InputError);
}

TEST(Synth, BallEndPeakToValleyAndPeriodMatchStepover) {
    SurfaceSpec s = cleanBallEnd();
    // Path k at z = pitch/2 + k·0.2 mm: sample rows 128 + 40k are path centres, 148 + 40k cusps.
    s.pathOffset = 0.5 * s.pitch;
    GeneratedSurface g = sl::generateSurface(s);
    double predicted = sl::scallopHeight(s.stepover, s.toolRadius);
    EXPECT_NEAR(g.scallop, predicted, 1e-15);
    auto [lo, hi] = minMax(g);
    EXPECT_NEAR(lo, 0.0, 1e-9);
    EXPECT_NEAR(hi - lo, predicted, 1e-4 * predicted);  // well within 1%
    EXPECT_NEAR(g.at(17, 148), predicted, 1e-4 * predicted);
    EXPECT_NEAR(g.at(200, 128), 0.0, 1e-9);
    // Heights are constant along the paths (x) and periodic across them (z) with period s.
    std::vector<double> line(static_cast<size_t>(g.height));
    for (int j = 0; j < g.height; ++j) line[static_cast<size_t>(j)] = g.at(100, j);
    std::vector<int> cusps = localMaxima(line);
    ASSERT_GE(cusps.size(), 5u);
    for (size_t k = 1; k < cusps.size(); ++k)
        EXPECT_NEAR((cusps[k] - cusps[k - 1]) * s.pitch, s.stepover, 1e-12);
    for (int i = 0; i < g.width; ++i) EXPECT_EQ(g.at(i, 77), g.at(0, 77));
}

TEST(Synth, BallEndRotatedPathsKeepScallopAndPeriod) {
    SurfaceSpec s = cleanBallEnd();
    s.rasterAngleDeg = 30.0;
    s.pathOffset = 0.0123;
    GeneratedSurface g = sl::generateSurface(s);
    double predicted = sl::scallopHeight(s.stepover, s.toolRadius);
    auto [lo, hi] = minMax(g);
    // Unaligned samples: many of them fall near a cusp and a path centre somewhere in the map.
    EXPECT_NEAR(hi - lo, predicted, 0.01 * predicted);
    // Along a column (direction z) the cusps are s / cos(30°) apart: mean spacing, sub-sample.
    std::vector<double> line(static_cast<size_t>(g.height));
    for (int j = 0; j < g.height; ++j) line[static_cast<size_t>(j)] = g.at(128, j);
    std::vector<int> cusps = localMaxima(line);
    ASSERT_GE(cusps.size(), 4u);
    double mean = (cusps.back() - cusps.front()) * s.pitch / static_cast<double>(cusps.size() - 1);
    EXPECT_NEAR(mean, s.stepover / std::cos(std::numbers::pi / 6.0), 1.5 * s.pitch / 3.0);
    // Paths along z (90°): cusps along a row, period s.
    s.rasterAngleDeg = 90.0;
    s.pathOffset = 0.5 * s.pitch;
    GeneratedSurface g90 = sl::generateSurface(s);
    std::vector<double> r(static_cast<size_t>(g90.width));
    for (int i = 0; i < g90.width; ++i) r[static_cast<size_t>(i)] = g90.at(i, 50);
    std::vector<int> c90 = localMaxima(r);
    ASSERT_GE(c90.size(), 5u);
    for (size_t k = 1; k < c90.size(); ++k)
        EXPECT_NEAR((c90[k] - c90[k - 1]) * s.pitch, s.stepover, 1e-12);
}

TEST(Synth, ChatterAndFeedMarksStayWithinTheirAmplitudes) {
    SurfaceSpec s = cleanBallEnd();
    s.pathOffset = 0.5 * s.pitch;
    s.chatterAmplitude = 0.0005;
    s.chatterWavelength = 0.4;
    GeneratedSurface g = sl::generateSurface(s);
    double sc = sl::scallopHeight(s.stepover, s.toolRadius);
    auto [lo, hi] = minMax(g);
    EXPECT_GE(lo, -s.chatterAmplitude - 1e-9);
    EXPECT_LE(hi, sc + s.chatterAmplitude + 1e-9);
    // Along a path centre (row 128) the height is the chatter sinusoid: period λ, amplitude A.
    std::vector<double> line(static_cast<size_t>(g.width));
    for (int i = 0; i < g.width; ++i) line[static_cast<size_t>(i)] = g.at(i, 128);
    auto [l0, l1] = std::minmax_element(line.begin(), line.end());
    EXPECT_NEAR(*l1 - *l0, 2 * s.chatterAmplitude, 0.01 * s.chatterAmplitude);
    std::vector<int> peaks = localMaxima(line);
    ASSERT_GE(peaks.size(), 2u);
    for (size_t k = 1; k < peaks.size(); ++k)
        EXPECT_NEAR((peaks[k] - peaks[k - 1]) * s.pitch, s.chatterWavelength, 1.01 * s.pitch);
    // Ball feed marks: cusps along the path of height f²/(8R) (to first order) on a path centre.
    s.chatterAmplitude = 0;
    s.ballFeedMarks = true;
    s.feedPerTooth = 0.08;
    s.pitch = 0.0025;  // finer, so the sampled feed cusps are near their crest
    GeneratedSurface gf = sl::generateSurface(s);
    int j = row(gf, 0.5 * 0.005);  // path k = 0 centre (pathOffset is still 0.0025 mm)
    double fmax = 0, fmin = 1;
    for (int i = 0; i < gf.width; ++i) {
        fmax = std::max(fmax, static_cast<double>(gf.at(i, j)));
        fmin = std::min(fmin, static_cast<double>(gf.at(i, j)));
    }
    double feedCusp = sl::scallopHeight(s.feedPerTooth, s.toolRadius);
    EXPECT_NEAR(fmin, 0.0, 0.02 * feedCusp);
    EXPECT_NEAR(fmax, feedCusp, 0.05 * feedCusp);
}

TEST(Synth, FaceMillCrescentsHaveFeedSpacingAndMicronHeights) {
    SurfaceSpec s = cleanBallEnd();
    s.process = SurfaceSpec::Process::FaceMillFeed;
    s.toolRadius = 8.0;  // one pass covers the whole map
    s.stepover = 10.0;
    s.pathOffset = 0.5 * s.pitch;  // pass centre line on row 128
    s.feedPerTooth = 0.08;
    s.insertNoseRadius = 0.8;
    GeneratedSurface g = sl::generateSurface(s);
    double predicted = sl::scallopHeight(s.feedPerTooth, s.insertNoseRadius);
    EXPECT_NEAR(g.scallop, predicted, 1e-15);
    EXPECT_GT(predicted, 0.5e-3);  // "a few µm" or less
    EXPECT_LT(predicted, 5e-3);
    auto [lo, hi] = minMax(g);
    EXPECT_GE(lo, 0.0f);
    EXPECT_LE(hi, predicted * (1 + 1e-6));
    EXPECT_GT(hi, 0.9 * predicted);
    // On the pass centre line the arcs cross perpendicular, f apart: minima spaced by f.
    std::vector<double> line(static_cast<size_t>(g.width));
    for (int i = 0; i < g.width; ++i) line[static_cast<size_t>(i)] = -g.at(i, 128);
    std::vector<int> marks = localMaxima(line);
    ASSERT_GE(marks.size(), 10u);
    double mean = (marks.back() - marks.front()) * s.pitch / static_cast<double>(marks.size() - 1);
    EXPECT_NEAR(mean, s.feedPerTooth, 0.02 * s.feedPerTooth);
    // Off the centre line the marks are arcs: at q = 0.5 mm the arc through a mark point is
    // displaced along t by R − √(R² − q²) relative to the centre line → the pattern curves.
    int jq = row(g, 0.5 + 0.5 * s.pitch);
    std::vector<double> lq(static_cast<size_t>(g.width));
    for (int i = 0; i < g.width; ++i) lq[static_cast<size_t>(i)] = -g.at(i, jq);
    std::vector<int> mq = localMaxima(lq);
    ASSERT_GE(mq.size(), 10u);
    double shift = s.toolRadius - std::sqrt(s.toolRadius * s.toolRadius - 0.25);  // 0.0157 mm
    // Marks on row jq sit `shift` behind (−t) those on the centre line, modulo f.
    double d = std::fmod((marks[3] - mq[3]) * s.pitch + 10 * s.feedPerTooth, s.feedPerTooth);
    double err = std::min(std::abs(d - shift), std::abs(d - shift - s.feedPerTooth));
    err = std::min(err, std::abs(d - shift + s.feedPerTooth));
    EXPECT_LT(err, 1.5 * s.pitch);
}

TEST(Synth, DeterministicFromSeedAndThreadCount) {
    SurfaceSpec s;
    s.width = 256;
    s.height = 192;
    s.pitch = 0.02;
    const auto [a, d] = expectDeterministic(s);
    EXPECT_NE(a.heights, d.heights);
}

TEST(Synth, RoughnessHasRequestedRms) {
    SurfaceSpec s = cleanBallEnd();
    s.toolRadius = 1e6;  // practically flat tool marks: scallop 5e-9 mm
    s.stepover = 0.2;
    s.roughnessRms = 0.0002;
    s.roughnessCorrelation = 0.02;
    GeneratedSurface g = sl::generateSurface(s);
    double sum = 0, sum2 = 0;
    for (float h : g.heights) {
        sum += h;
        sum2 += static_cast<double>(h) * h;
    }
    double n = static_cast<double>(g.heights.size());
    double mean = sum / n, rms = std::sqrt(sum2 / n - mean * mean);
    // 64×64 correlation cells: the sample RMS is within a few percent of the target.
    EXPECT_NEAR(rms, s.roughnessRms, 0.08 * s.roughnessRms);
    EXPECT_NEAR(mean, 0.0, 0.15 * s.roughnessRms);
    // Smoothed: neighbours are strongly correlated (correlation length 4 samples).
    double c = 0;
    for (int j = 0; j < g.height; ++j)
        for (int i = 0; i + 1 < g.width; ++i) c += (g.at(i, j) - mean) * (g.at(i + 1, j) - mean);
    c /= static_cast<double>(g.height) * (g.width - 1) * rms * rms;
    EXPECT_GT(c, 0.8);
}

TEST(Synth, ExplicitScratchLandsWhereSpecifiedAndIsAGroove) {
    SurfaceSpec s = cleanBallEnd();
    s.chatterAmplitude = 0.0005;
    s.roughnessRms = 0.0002;
    s.pocketEdge = true;
    ScratchSpec sc{-0.35, -0.2, 0.45, 0.3, 0.04, 0.004};
    s.scratches = {sc};
    GeneratedSurface g = sl::generateSurface(s);
    ASSERT_EQ(g.scratches.size(), 1u);
    // The cell at the midpoint is marked and lies at the bottom of a groove.
    double mx = 0.5 * (sc.x0 + sc.x1), mz = 0.5 * (sc.z0 + sc.z1);
    int i = col(g, mx), j = row(g, mz);
    EXPECT_TRUE(g.isDefect(i, j));
    // Compare with the same surface without the scratch.
    SurfaceSpec s0 = s;
    s0.scratches.clear();
    s0.scratchCount = 0;
    GeneratedSurface g0 = sl::generateSurface(s0);
    double dx = g.pitch * (i - 0.5 * (g.width - 1)) - mx,
           dz = g.pitch * (j - 0.5 * (g.height - 1)) - mz;
    double L = std::hypot(sc.x1 - sc.x0, sc.z1 - sc.z0);
    double d = std::abs(-dx * (sc.z1 - sc.z0) / L + dz * (sc.x1 - sc.x0) / L);
    EXPECT_NEAR(g0.at(i, j) - g.at(i, j), sc.depth * (1 - 2 * d / sc.width), 1e-6);
    // Every marked cell was lowered, no unmarked cell was lowered by more than 10% of the depth
    // (except the groove's very ends), and the scratch is the only defect.
    size_t marked = 0;
    for (int jj = 0; jj < g.height; ++jj)
        for (int ii = 0; ii < g.width; ++ii) {
            double drop = g0.at(ii, jj) - g.at(ii, jj);
            if (g.isDefect(ii, jj)) {
                ++marked;
                EXPECT_GT(drop, 0.0) << ii << "," << jj;
            } else {
                EXPECT_FALSE(g0.isDefect(ii, jj));
            }
        }
    // Groove area ≈ L·w (cells inside the width, minus the faded ends).
    double area = static_cast<double>(marked) * g.pitch * g.pitch;
    EXPECT_GT(area, 0.8 * L * sc.width);
    EXPECT_LT(area, 1.1 * L * sc.width);
}

TEST(Synth, ScratchCellsLieBelowTheirNeighbours) {
    SurfaceSpec s;  // the default demo spec at a smaller size, random scratches
    s.width = 256;
    s.height = 256;
    s.pitch = 0.01;
    s.gougeCount = 0;
    s.scratchCount = 5;
    GeneratedSurface g = sl::generateSurface(s);
    ASSERT_EQ(g.scratches.size(), 5u);
    const int r = 3;  // 7×7 window: beyond the groove half-width (≤ 1.5 samples)
    size_t marked = 0, below = 0;
    double meanDiff = 0;
    for (int j = r; j < g.height - r; ++j)
        for (int i = r; i < g.width - r; ++i) {
            if (!g.isDefect(i, j)) continue;
            double sum = 0;
            int n = 0;
            for (int b = -r; b <= r; ++b)
                for (int a = -r; a <= r; ++a)
                    if (!g.isDefect(i + a, j + b)) {
                        sum += g.at(i + a, j + b);
                        ++n;
                    }
            if (n == 0) continue;
            double diff = g.at(i, j) - sum / n;
            ++marked;
            below += diff < 0;
            meanDiff += diff;
        }
    ASSERT_GT(marked, 100u);
    meanDiff /= static_cast<double>(marked);
    // Not 100%: a cell near the groove's edge (depth → 0) that sits on a scallop cusp (a kink,
    // ~1 µm above its 7×7 neighbourhood's mean) can stay above its neighbours.
    EXPECT_GT(static_cast<double>(below), 0.85 * static_cast<double>(marked));
    EXPECT_LT(meanDiff, -0.25 * s.scratchDepth);
    // Exactly: every marked cell was lowered by the scratches (same surface without them),
    // except where another scratch's burr (out to one width from its centre line) crosses it.
    SurfaceSpec s0 = s;
    s0.scratchCount = 0;
    GeneratedSurface g0 = sl::generateSurface(s0);
    size_t checked = 0;
    for (int j = 0; j < g.height; ++j)
        for (int i = 0; i < g.width; ++i) {
            if (!g.isDefect(i, j)) continue;
            double x = (i - 0.5 * (g.width - 1)) * g.pitch,
                   z = (j - 0.5 * (g.height - 1)) * g.pitch;
            int near = 0;
            for (const ScratchSpec& c : g.scratches) near += segmentDistance(c, x, z) < c.width;
            if (near > 1) continue;
            ++checked;
            EXPECT_LT(g.at(i, j), g0.at(i, j)) << i << "," << j;
        }
    EXPECT_GT(checked, marked * 9 / 10);
}

TEST(Synth, PocketEdgeIsAStepButNotADefect) {
    SurfaceSpec s = cleanBallEnd();
    s.pocketEdge = true;
    s.pocketDepth = 0.3;
    s.cornerRadius = 0.1;
    s.pocketWallFraction = 0.25;
    GeneratedSurface g = sl::generateSurface(s);
    for (uint8_t t : g.truth) ASSERT_EQ(t, 0);
    double extX = (g.width - 1) * g.pitch;
    EXPECT_NEAR(g.pocketEdgeX, 0.5 * extX - 0.25 * extX, 1e-12);
    // depth > 2r: two quarter arcs and a vertical drop; half-width r.
    EXPECT_NEAR(g.pocketEdgeHalfWidth, 0.1, 1e-12);
    double sc = sl::scallopHeight(s.stepover, s.toolRadius);
    for (int j = 0; j < g.height; j += 17) {
        // Top left of the edge, floor right of it: the same tool marks, pocketDepth lower.
        EXPECT_NEAR(g.at(10, j) - g.at(g.width - 10, j), 0.3, sc + 1e-6);
        EXPECT_LE(g.at(10, j), sc + 1e-6);
    }
    // With the default rounding (r = 0.5 > depth/2) the step is an S of two arcs, C1-smooth:
    // the profile is monotone and its slope at the centre is tan θ with cos θ = 1 − d/(2r).
    s.cornerRadius = 0.5;
    s.width = 512;
    GeneratedSurface g2 = sl::generateSurface(s);
    double theta = std::acos(1 - 0.3 / 1.0);
    EXPECT_NEAR(g2.pocketEdgeHalfWidth, 0.5 * std::sin(theta), 1e-12);
    int j = row(g2, 0.5 * g2.pitch);  // a path centre: tool marks are 0 along this row
    for (int i = 1; i < g2.width; ++i) EXPECT_LE(g2.at(i, j), g2.at(i - 1, j) + 1e-7);
    int ic = col(g2, g2.pocketEdgeX);
    double slope = (g2.at(ic + 1, j) - g2.at(ic - 1, j)) / (2 * g2.pitch);
    EXPECT_NEAR(slope, -std::tan(theta), 0.02 * std::tan(theta));
    for (uint8_t t : g2.truth) ASSERT_EQ(t, 0);
}

TEST(Synth, GougeIsMarkedAndDigsToItsDepth) {
    SurfaceSpec s = cleanBallEnd();
    s.gouges = {{-0.3, 0.0025, 0.3, 0.0025, 0.01}};  // along path k = 0 (row 128 with offset)
    s.pathOffset = 0.5 * s.pitch;
    GeneratedSurface g = sl::generateSurface(s);
    auto [lo, hi] = minMax(g);
    EXPECT_NEAR(lo, -0.01, 1e-5);  // the dig's bottom at mid-segment
    EXPECT_NEAR(g.at(col(g, 0.0), 128), -0.01, 1e-5);
    EXPECT_TRUE(g.isDefect(col(g, 0.0), 128));
    EXPECT_FALSE(g.isDefect(col(g, 0.55), 128));
    EXPECT_FALSE(g.isDefect(5, 5));
    // The crater's half-width at mid-length is √(2RD) ≈ 0.17 mm (where the depth runs out).
    EXPECT_TRUE(g.isDefect(col(g, 0.0), row(g, 0.12)));
    EXPECT_FALSE(g.isDefect(col(g, 0.0), row(g, 0.2)));
}

TEST(Synth, DefaultDemoIsSensible) {
    SurfaceSpec s;  // the bundled demo: 1024² at 0.01 mm
    EXPECT_GE(s.stepover, 0.3);
    EXPECT_LE(s.stepover, 0.5);
    double sc = sl::scallopHeight(s.stepover, s.toolRadius);
    EXPECT_LE(s.scratchDepth, 1.0 * sc);  // scratches subtler than the scallops
    GeneratedSurface g = sl::generateSurface(s);
    EXPECT_EQ(g.width, 1024);
    EXPECT_EQ(g.scratches.size(), 4u);
    EXPECT_EQ(g.gouges.size(), 1u);
    EXPECT_NE(g.description.find("scallop height"), std::string::npos);
    EXPECT_EQ(g.description.find('\n'), std::string::npos);
    size_t marked = 0;
    for (uint8_t t : g.truth) marked += t != 0;
    EXPECT_GT(marked, 0u);
    EXPECT_LT(marked, g.truth.size() / 50);  // defects are sparse
    for (float h : g.heights) ASSERT_TRUE(std::isfinite(h));
}

TEST(Synth, ValidationNamesTheField) {
    auto expectField = [](SurfaceSpec s, const std::string& field) {
        std::string msg = errorOf(s);
        const std::string name = optionOf(field);
        EXPECT_NE(msg.find(name), std::string::npos) << "expected '" << name << "' in: " << msg;
    };
    SurfaceSpec base;
    base.width = 16;
    base.height = 16;
    SurfaceSpec s = base;
    s.pitch = 0;
    expectField(s, "pitch");
    s.pitch = -0.01;
    expectField(s, "pitch");
    s.pitch = std::nan("");
    expectField(s, "pitch");
    s = base;
    s.width = 1;
    expectField(s, "width");
    s = base;
    s.height = 0;
    expectField(s, "height");
    s = base;
    s.stepover = 2 * s.toolRadius;
    expectField(s, "stepover");
    s.stepover = -1;
    expectField(s, "stepover");
    s = base;
    s.toolRadius = 0;
    expectField(s, "toolRadius");
    s = base;
    s.chatterAmplitude = -1e-3;
    expectField(s, "chatterAmplitude");
    s = base;
    s.chatterWavelength = 0;
    expectField(s, "chatterWavelength");
    s = base;
    s.roughnessRms = -1;
    expectField(s, "roughnessRms");
    s = base;
    s.scratchCount = -2;
    expectField(s, "scratchCount");
    s = base;
    s.scratchWidth = 0;
    expectField(s, "scratchWidth");
    s = base;
    s.scratches = {{0, 0, 1, 1, 0.0, 0.004}};
    expectField(s, "scratches[0].width");
    s.scratches = {{0.2, 0.2, 0.2, 0.2, 0.03, 0.004}};
    expectField(s, "scratches[0]");
    s = base;
    s.gouges = {{0, 0, 1, 0, -0.01}};
    expectField(s, "gouges[0].depth");
    s = base;
    s.pocketWallFraction = 1.5;
    expectField(s, "pocketWallFraction");
    s = base;
    s.cornerRadius = -0.1;
    expectField(s, "cornerRadius");
    s = base;
    s.process = SurfaceSpec::Process::FaceMillFeed;
    s.feedPerTooth = 2.0;  // ≥ 2·insertNoseRadius
    expectField(s, "feedPerTooth");
    s = base;
    s.rasterAngleDeg = std::numeric_limits<double>::infinity();
    expectField(s, "rasterAngleDeg");
    // A valid spec passes, and the message names the option (gen-surface shows it as its flag,
    // issue 35), not the struct's field.
    EXPECT_EQ(errorOf(base), "");
    s = base;
    s.pitch = 0;
    EXPECT_NE(errorOf(s).find("option 'pitch'"), std::string::npos);
    EXPECT_EQ(errorOf(s).find("SurfaceSpec"), std::string::npos);
}

namespace {

/// One hash of a generated surface's heights (float bits), truth labels and description.
std::string surfaceHash(const GeneratedSurface& g) {
    sl::Hasher h;
    h.add(g.heights.data(), g.heights.size() * sizeof(float));
    h.add(g.truth.data(), g.truth.size());
    h.add(g.description);
    return sl::toHex(h.digest());
}

}  // namespace

// Surfaces of the settings that existed before the test parts (processes flatend/turned and
// the new defect kinds) are pinned bit for bit: new features are opt-in and change none of them.
TEST(Synth, SettingsOfBeforeTheTestPartsAreBitIdentical) {
    SurfaceSpec s;
    s.width = 200;
    s.height = 150;
    EXPECT_EQ(surfaceHash(sl::generateSurface(s)), "c08779db5dd0f867");
    s.process = SurfaceSpec::Process::FaceMillFeed;
    s.chatterStartFraction = 0.5;
    EXPECT_EQ(surfaceHash(sl::generateSurface(s)), "443ad8f4cb577b06");
    SurfaceSpec r;
    r.width = 160;
    r.height = 170;
    r.pitch = 0.02;
    r.rasterAngleDeg = 30;
    r.seed = 7;
    r.scratchCount = 9;
    r.gougeCount = 2;
    r.chatterStartFraction = 0.3;
    r.ballFeedMarks = false;
    EXPECT_EQ(surfaceHash(sl::generateSurface(r)), "63845a497b3622e7");
    r.process = SurfaceSpec::Process::FaceMillFeed;
    r.toolRadius = 4.0;
    r.stepover = 3.0;
    r.scratches = {{-0.5, -0.4, 0.6, 0.3, 0.05, 0.006, ScratchSpec::Shape::Round, 0.5}};
    r.gouges = {{-0.3, 0.2, 0.4, 0.25, 0.01}};
    r.pocketEdge = false;
    EXPECT_EQ(surfaceHash(sl::generateSurface(r)), "b2c798c3b9534898");
}

// ---------------------------------------------------------------------------------------------
// The labelled test parts: flat-end and turned processes, the new defect kinds, measurement
// noise, the legend and gen-surface's options.

namespace {

/// A clean flat-end pocket floor: passes along x, no chatter, roughness or defects.
SurfaceSpec cleanFlatEnd() {
    SurfaceSpec s = cleanBallEnd();
    s.process = SurfaceSpec::Process::FlatEndPocket;
    s.toolRadius = 0.5;
    s.toolCornerRadius = 0.1;
    s.stepover = 0.84;  // the flats (0.8 mm) leave 0.02 mm of each corner arc: a ridge
    s.feedPerTooth = 0;
    s.pathOffset = 0.5 * s.pitch;  // pass k = 0 on row 128, the ridge to pass 1 on row 212
    return s;
}

/// A clean face-turned map: the spiral's centre on sample (128, 128) of a 257² map.
SurfaceSpec cleanTurned() {
    SurfaceSpec s = cleanBallEnd();
    s.width = s.height = 257;
    s.process = SurfaceSpec::Process::Turned;
    s.insertNoseRadius = 0.8;
    s.feedPerTooth = 0.1;
    return s;
}

/// The kinds' values in g's truth, each with its count.
std::vector<std::pair<int, size_t>> labelCounts(const GeneratedSurface& g) {
    std::vector<size_t> n(256, 0);
    for (uint8_t t : g.truth) ++n[t];
    std::vector<std::pair<int, size_t>> out;
    for (int v = 1; v < 256; ++v)
        if (n[static_cast<size_t>(v)] > 0) out.emplace_back(v, n[static_cast<size_t>(v)]);
    return out;
}

size_t countLabel(const GeneratedSurface& g, uint8_t v) {
    return static_cast<size_t>(std::count(g.truth.begin(), g.truth.end(), v));
}

/// Every sample labelled `value` in g differs from g0 (the same spec without the kind) by at
/// least `minChange` mm; g0 has no such label; samples that g did not change keep g0's label.
void expectLabelOnlyWhereChanged(const GeneratedSurface& g, const GeneratedSurface& g0,
                                 uint8_t value, double minChange) {
    ASSERT_EQ(g.heights.size(), g0.heights.size());
    size_t labelled = 0;
    for (size_t k = 0; k < g.heights.size(); ++k) {
        const double change = std::abs(static_cast<double>(g.heights[k]) - g0.heights[k]);
        EXPECT_NE(g0.truth[k], value) << k;
        if (g.truth[k] == value) {
            ++labelled;
            EXPECT_GE(change, minChange) << "sample " << k;
        }
        if (change == 0) {
            EXPECT_EQ(g.truth[k], g0.truth[k]) << k;
        }
    }
    EXPECT_GT(labelled, 0u) << "label " << int(value) << " absent";
}

double xOf(const GeneratedSurface& g, int i) {
    return (i - 0.5 * (g.width - 1)) * g.pitch;
}
double zOf(const GeneratedSurface& g, int j) {
    return (j - 0.5 * (g.height - 1)) * g.pitch;
}

}  // namespace

TEST(Synth, FlatEndRidgeHeightIsTheCornerArcsCusp) {
    // s ≤ 2(R − r_c): the flats overlap, no ridge.
    EXPECT_EQ(sl::flatEndRidgeHeight(1.6, 1.0, 0.2), 0.0);
    EXPECT_EQ(sl::flatEndRidgeHeight(0.5, 1.0, 0.2), 0.0);
    for (double rc : {0.05, 0.2, 0.5}) {
        for (double e : {0.001, 0.01, 0.04}) {  // how far each pass's corner arc reaches in
            double R = 1.0, s = 2 * (R - rc + e);
            double h = sl::flatEndRidgeHeight(s, R, rc);
            // The ridge point (e, h) lies on the corner circle: (r_c − h)² + e² = r_c².
            EXPECT_NEAR((rc - h) * (rc - h) + e * e, rc * rc, 1e-12);
            if (e <= 0.2 * rc) {
                EXPECT_NEAR(h, e * e / (2 * rc), 0.02 * h);  // ≈ e²/(2 r_c)
            }
        }
    }
    // A sharp ball (r_c = R) is the ball-end scallop.
    EXPECT_DOUBLE_EQ(sl::flatEndRidgeHeight(0.4, 3.0, 3.0), sl::scallopHeight(0.4, 3.0));
    EXPECT_THROW(sl::flatEndRidgeHeight(0.5, 1.0, 0.0), sl::InputError);
    EXPECT_THROW(sl::flatEndRidgeHeight(0.5, 1.0, 1.5), sl::InputError);
    EXPECT_THROW(sl::flatEndRidgeHeight(2.5, 1.0, 0.2), sl::InputError);
}

TEST(Synth, FlatEndFloorIsFlatWithRidgesOfTheFormula) {
    SurfaceSpec s = cleanFlatEnd();
    GeneratedSurface g = sl::generateSurface(s);
    const double ridge = sl::flatEndRidgeHeight(s.stepover, s.toolRadius, s.toolCornerRadius);
    EXPECT_NEAR(ridge, 0.1 - std::sqrt(0.01 - 0.0004), 1e-15);  // 2.02 µm
    EXPECT_NEAR(g.scallop, ridge, 1e-15);
    auto [lo, hi] = minMax(g);
    EXPECT_EQ(lo, 0.0f);
    EXPECT_NEAR(hi, ridge, 1e-6 * ridge);
    EXPECT_NEAR(g.at(31, 212), ridge, 1e-6 * ridge);  // the ridge's crest, midway between passes
    for (int j = 0; j < g.height; ++j) {
        double q = std::remainder(zOf(g, j) - s.pathOffset, s.stepover);  // to the nearest pass
        double a = s.toolRadius - s.toolCornerRadius;
        double expected = std::abs(q) <= a ? 0.0 : sl::scallopHeight(2 * (std::abs(q) - a), 0.1);
        for (int i = 0; i < g.width; i += 51) EXPECT_NEAR(g.at(i, j), expected, 1e-9) << i << j;
    }
}

TEST(Synth, FlatEndFeedMarksOnTheFloorMatchTheCornerRadiusFormula) {
    SurfaceSpec s = cleanFlatEnd();
    s.feedPerTooth = 0.05;
    s.pitch = 0.001;  // fine: sampled crests within pitch/2 of the true ones
    s.width = 600;
    s.height = 64;
    s.pathOffset = 0.5 * s.pitch;  // pass 0's centre line on row 32
    GeneratedSurface g = sl::generateSurface(s);
    const double rc = s.toolCornerRadius, f = s.feedPerTooth;
    const double mark = sl::scallopHeight(f, rc);  // r_c − √(r_c² − (f/2)²) ≈ f²/(8 r_c)
    EXPECT_NEAR(g.feedMark, mark, 1e-15);
    EXPECT_NEAR(mark, f * f / (8 * rc), 0.02 * mark);
    std::vector<double> line(static_cast<size_t>(g.width));
    for (int i = 0; i < g.width; ++i) line[static_cast<size_t>(i)] = g.at(i, 32);
    auto [l0, l1] = std::minmax_element(line.begin(), line.end());
    // Along the centre line δ changes at the rate of t, so the sampled crest is within the
    // height change over pitch/2 at δ = f/2: slope (f/2)/√(r_c² − f²/4).
    const double slack = 0.5 * s.pitch * (0.5 * f) / std::sqrt(rc * rc - 0.25 * f * f);
    EXPECT_LE(*l1, mark * (1 + 1e-9));
    EXPECT_GE(*l1, mark - slack);
    EXPECT_LE(*l0, slack);
    EXPECT_GE(*l0, 0.0);
    // Crests f apart (the teeth's spacing).
    std::vector<int> crests = localMaxima(line);
    ASSERT_GE(crests.size(), 8u);
    double mean =
        (crests.back() - crests.front()) * s.pitch / static_cast<double>(crests.size() - 1);
    EXPECT_NEAR(mean, f, 0.02 * f);
    // Everywhere on the floor the marks stay below the centre line's crest.
    for (float h : g.heights) EXPECT_LE(h, mark * (1 + 1e-9));
}

TEST(Synth, TurnedGroovesMatchTheNoseRadiusFormula) {
    SurfaceSpec s = cleanTurned();
    GeneratedSurface g = sl::generateSurface(s);
    const double rn = s.insertNoseRadius, f = s.feedPerTooth;
    const double cusp = sl::scallopHeight(f, rn);  // r_n − √(r_n² − (f/2)²) ≈ f²/(8 r_n)
    EXPECT_NEAR(g.scallop, cusp, 1e-15);
    EXPECT_NEAR(cusp, f * f / (8 * rn), 0.01 * cusp);
    auto [lo, hi] = minMax(g);
    const double slack = 0.5 * s.pitch * (0.5 * f) / std::sqrt(rn * rn - 0.25 * f * f);
    EXPECT_LE(hi, cusp * (1 + 1e-6));
    EXPECT_GE(hi, cusp - slack);
    EXPECT_GE(lo, 0.0f);
    EXPECT_LE(lo, slack);
    // Along a ray from the centre (row 128, +x) the grooves are f apart.
    std::vector<double> ray;
    for (int i = 128; i < g.width; ++i) ray.push_back(g.at(i, 128));
    std::vector<int> crests = localMaxima(ray);
    ASSERT_GE(crests.size(), 4u);
    for (size_t k = 1; k < crests.size(); ++k)
        EXPECT_NEAR((crests[k] - crests[k - 1]) * s.pitch, f, 1.01 * s.pitch);
    // Rings: the height depends on the radius (and the spiral's slow phase), not the angle:
    // samples at the same radius on the four axes differ by the spiral's advance f·Δθ/2π.
    for (int d = 10; d < 120; d += 7) {
        double e = g.at(128 + d, 128), n = g.at(128, 128 + d);  // θ = 0 and θ = 90°
        double rise = std::abs(e - n);
        EXPECT_LE(rise, cusp);  // bounded by the groove, whatever the phase
    }
    // Centre far off the map: a section of straight grooves along z (constant down a column).
    s.turnCentreX = 1000.0;
    GeneratedSurface gs = sl::generateSurface(s);
    for (int i = 0; i < gs.width; i += 9)
        for (int j = 0; j < gs.height; j += 16)
            EXPECT_NEAR(gs.at(i, j), gs.at(i, 128), 0.05 * cusp) << i << "," << j;
    std::vector<double> row(static_cast<size_t>(gs.width));
    for (int i = 0; i < gs.width; ++i) row[static_cast<size_t>(i)] = gs.at(i, 128);
    std::vector<int> c2 = localMaxima(row);
    ASSERT_GE(c2.size(), 8u);
    double mean = (c2.back() - c2.front()) * s.pitch / static_cast<double>(c2.size() - 1);
    EXPECT_NEAR(mean, f, 0.02 * f);
}

TEST(Synth, NewProcessesAreDeterministicAndThreadIndependent) {
    for (sl::TestPart part : {sl::TestPart::FlatEnd, sl::TestPart::Turned, sl::TestPart::Ground}) {
        SurfaceSpec s = sl::testPartSpec(part);
        s.width = 300;
        s.height = 200;
        s.noiseRms = 0.0001;
        s.spikeCount = 5;
        const auto [a, d] = expectDeterministic(s);
        EXPECT_NE(a.truth, d.truth);  // defects moved
    }
}

TEST(Synth, ProcessDefaultsOfTheOldProcessesAreTheOldSpec) {
    SurfaceSpec s;
    s.width = 200;
    s.height = 150;
    for (SurfaceSpec::Process p :
         {SurfaceSpec::Process::BallEndRaster, SurfaceSpec::Process::FaceMillFeed}) {
        SurfaceSpec d = sl::processDefaults(p);
        d.width = 200;
        d.height = 150;
        s.process = p;
        EXPECT_EQ(surfaceHash(sl::generateSurface(d)), surfaceHash(sl::generateSurface(s)));
    }
    // Every process has a row, every row a valid default spec.
    std::vector<int> seen;
    for (const sl::ProcessRow& r : sl::processTable()) {
        seen.push_back(static_cast<int>(r.value));
        SurfaceSpec d = sl::processDefaults(r.value);
        d.width = d.height = 64;
        EXPECT_EQ(errorOf(d), "") << r.name;
        EXPECT_EQ(&sl::parseRegistryName(sl::processTable(), r.name, "test"), &r);
    }
    EXPECT_EQ(seen, (std::vector<int>{0, 1, 2, 3, 4}));
}

namespace {
/// A ground surface with nothing but its grit tracks: no roughness, chatter, defects or pocket.
SurfaceSpec bareGround(int w, int h) {
    SurfaceSpec s = sl::processDefaults(SurfaceSpec::Process::Ground);
    s.width = w;
    s.height = h;
    s.roughnessRms = 0;
    s.chatterAmplitude = 0;
    s.scratchCount = s.gougeCount = s.dentCount = 0;
    s.pocketEdge = false;
    return s;
}
}  // namespace

// Ground: every sample is exactly the MIN of the wheel's envelope (0) and every grit track, the
// whole list searched (the generator searches only the bins beside the sample's).
TEST(Synth, GroundIsTheMinOfTheWheelAndEveryGritTrack) {
    for (double angle : {0.0, 37.0}) {
        SurfaceSpec s = bareGround(96, 64);
        s.rasterAngleDeg = angle;
        const GeneratedSurface g = sl::generateSurface(s);
        const sl::surfacegen::Frame fr(s);
        const sl::surfacegen::ToolMarks tm = sl::surfacegen::toolMarks(s, fr);
        ASSERT_GT(tm.grits.size(), 100u);
        size_t cut = 0;
        for (int j = 0; j < s.height; ++j)
            for (int i = 0; i < s.width; ++i) {
                const double x = (i - fr.cx) * s.pitch, z = (j - fr.cz) * s.pitch;
                const double t = x * tm.cosA + z * tm.sinA, p = -x * tm.sinA + z * tm.cosA;
                double best = 0;
                for (const sl::surfacegen::GritTrack& k : tm.grits) {
                    const double q = p - k.p;
                    if (t <= k.t0 || t >= k.t1 || q * q >= tm.R2) continue;
                    const double tau = (t - k.t0) / (k.t1 - k.t0);
                    const double w = sl::surfacegen::smoothstep01(std::min(tau, 1.0 - tau) /
                                                                  sl::surfacegen::kGritTaper);
                    best = std::min(best, sl::surfacegen::sphereRise(tm.R, q * q) - k.depth * w);
                }
                const float h = g.heights[static_cast<size_t>(j) * s.width + i];
                ASSERT_EQ(h, static_cast<float>(best)) << angle << " " << i << "," << j;
                cut += h < 0;
            }
        // Some of the surface is cut and some is the wheel's plateau.
        EXPECT_GT(cut, g.heights.size() / 4);
        EXPECT_LT(cut, g.heights.size());
        const double deepest = sl::surfacegen::kGritDepthCut * s.gritDepth;
        for (float h : g.heights) ASSERT_GE(h, -deepest - 1e-9);
    }
}

// The grits' tracks lie along the lay: the height changes far more across the lay than along
// it, and turning the lay by 90° turns that with it; denser tracks leave less plateau.
TEST(Synth, GroundStreaksLieAlongTheLay) {
    auto meanSteps = [](const GeneratedSurface& g) {
        double dx = 0, dz = 0;
        for (int j = 0; j + 1 < g.height; ++j)
            for (int i = 0; i + 1 < g.width; ++i) {
                const size_t k = static_cast<size_t>(j) * g.width + i;
                dx += std::abs(g.heights[k + 1] - g.heights[k]);
                dz += std::abs(g.heights[k + g.width] - g.heights[k]);
            }
        return std::pair{dx, dz};
    };
    SurfaceSpec s = bareGround(128, 128);
    const auto [alongX, acrossZ] = meanSteps(sl::generateSurface(s));
    EXPECT_LT(alongX, 0.25 * acrossZ);
    s.rasterAngleDeg = 90;
    const auto [acrossX, alongZ] = meanSteps(sl::generateSurface(s));
    EXPECT_LT(alongZ, 0.25 * acrossX);
    auto plateau = [](const GeneratedSurface& g) {
        return std::count(g.heights.begin(), g.heights.end(), 0.0f);
    };
    SurfaceSpec dense = bareGround(128, 128);
    dense.stepover = 0.5 * s.stepover;
    EXPECT_LT(plateau(sl::generateSurface(dense)),
              plateau(sl::generateSurface(bareGround(128, 128))));
}

TEST(Synth, DentIsLabelledWhereItLowersTheSurface) {
    SurfaceSpec s = cleanBallEnd();
    s.roughnessRms = 0.0002;
    s.chatterAmplitude = 0.0005;
    s.dents = {{0.1025, -0.0475, 0.005, 0.5}};  // on sample (148, 118)
    GeneratedSurface g = sl::generateSurface(s);
    SurfaceSpec s0 = s;
    s0.dents.clear();
    GeneratedSurface g0 = sl::generateSurface(s0);
    expectLabelOnlyWhereChanged(g, g0, sl::kTruthDent, 0.1 * 0.005 - 1e-7);
    // The bottom is the dent's depth below the undented surface; nothing changed beyond its
    // rim r = √(2 R d − d²), and only lowered.
    EXPECT_NEAR(g0.at(148, 118) - g.at(148, 118), 0.005, 1e-7);
    const double rim = std::sqrt(0.005 * (2 * 0.5 - 0.005));
    for (int j = 0; j < g.height; ++j)
        for (int i = 0; i < g.width; ++i) {
            double change = g.at(i, j) - g0.at(i, j);
            EXPECT_LE(change, 0.0);
            if (change != 0) {
                EXPECT_LT(std::hypot(xOf(g, i) - 0.1025, zOf(g, j) + 0.0475), rim);
            }
        }
    // Random dents: the count asked for, each labelled.
    s.dents.clear();
    s.dentCount = 4;
    GeneratedSurface r = sl::generateSurface(s);
    ASSERT_EQ(r.dents.size(), 4u);
    for (const sl::DentSpec& d : r.dents)
        EXPECT_EQ(r.truth[static_cast<size_t>(row(r, d.z)) * r.width + col(r, d.x)],
                  sl::kTruthDent);
}

TEST(Synth, CrackIsANarrowMeanderingBranchingFissureWithNoRim) {
    // A crack (SurfaceGenerator.h crackPaths) on a rough, chattering ball-end surface: the
    // change it makes is its V (depth·e at the trunk's middle, width·e/2 either side of its
    // path, nothing beyond: no rim), and its label is exactly where it lowers the surface by
    // >= 10 % of its depth.
    SurfaceSpec s = cleanBallEnd();
    s.roughnessRms = 0.0002;
    s.chatterAmplitude = 0.0005;
    s.crackCount = 2;
    s.crackLength = 0.8;
    s.crackWidth = 0.03;
    s.crackDepth = 0.006;
    s.crackBranches = 2;
    GeneratedSurface g = sl::generateSurface(s);
    SurfaceSpec s0 = s;
    s0.crackCount = 0;
    GeneratedSurface g0 = sl::generateSurface(s0);
    ASSERT_EQ(g.cracks.size(), 2u);
    EXPECT_NE(g.description.find("2 crack(s)"), std::string::npos) << g.description;
    std::vector<std::vector<sl::CrackPath>> pieces;
    for (const sl::CrackSpec& c : g.cracks) {
        EXPECT_GE(c.depth, 0.5 * s.crackDepth);
        EXPECT_LE(c.depth, s.crackDepth);
        EXPECT_GE(c.width, 0.5 * s.crackWidth);
        EXPECT_LE(c.width, s.crackWidth);
        pieces.push_back(sl::crackPaths(c));
        const std::vector<sl::CrackPath>& p = pieces.back();
        // Branching: the trunk and its branches, each starting on a trunk vertex, shallower.
        ASSERT_EQ(p.size(), 3u);
        const sl::CrackPath& trunk = p[0];
        ASSERT_EQ(trunk.x.size(), 17u);
        for (size_t b = 1; b < p.size(); ++b) {
            EXPECT_TRUE(p[b].branch);
            bool onTrunk = false;
            for (size_t k = 0; k < trunk.x.size(); ++k)
                onTrunk = onTrunk || (p[b].x[0] == trunk.x[k] && p[b].z[0] == trunk.z[k]);
            EXPECT_TRUE(onTrunk);
            EXPECT_LE(p[b].depth, 0.6 * c.depth);
        }
        // Meandering: the trunk is `length` long along its path, its chord shorter, its chord's
        // midpoint at the centre, and its vertices off the chord.
        double arc = 0, off = 0;
        const double cx = trunk.x.back() - trunk.x[0], cz = trunk.z.back() - trunk.z[0];
        const double chord = std::hypot(cx, cz);
        for (size_t k = 0; k + 1 < trunk.x.size(); ++k) {
            arc += std::hypot(trunk.x[k + 1] - trunk.x[k], trunk.z[k + 1] - trunk.z[k]);
            off = std::max(
                off,
                std::abs((trunk.x[k] - trunk.x[0]) * cz - (trunk.z[k] - trunk.z[0]) * cx) / chord);
        }
        EXPECT_NEAR(arc, c.length, 1e-12);
        EXPECT_LT(chord, 0.999 * c.length);
        EXPECT_GT(off, 0.01 * c.length);
        EXPECT_NEAR(0.5 * (trunk.x[0] + trunk.x.back()), c.x, 1e-12);
        EXPECT_NEAR(0.5 * (trunk.z[0] + trunk.z.back()), c.z, 1e-12);
        // Depth: the trunk's middle vertex (arc L/2, e = 1) is `depth` deep; nowhere deeper.
        EXPECT_NEAR(sl::crackOffset(p, trunk.x[8], trunk.z[8]), -c.depth, 1e-12 * c.depth);
        // Width: across the middle of trunk piece 7 (arc 7.5/16 of L, e = √(1 − (1/16)²)) the
        // V is width·e wide: half its depth at a quarter of that from the path, 0 beyond half.
        const double e = std::sqrt(1.0 - 1.0 / 256.0);
        const double mx = 0.5 * (trunk.x[7] + trunk.x[8]), mz = 0.5 * (trunk.z[7] + trunk.z[8]);
        const double dx = trunk.x[8] - trunk.x[7], dz = trunk.z[8] - trunk.z[7];
        const double nx = -dz / std::hypot(dx, dz), nz = dx / std::hypot(dx, dz);
        const double half = 0.5 * c.width * e;
        for (double side : {-1.0, 1.0}) {
            EXPECT_NEAR(sl::crackPathOffset(trunk, mx + side * 0.5 * half * nx,
                                            mz + side * 0.5 * half * nz),
                        -0.5 * c.depth * e, 1e-12 * c.depth);
            EXPECT_LT(sl::crackPathOffset(trunk, mx + side * 0.999 * half * nx,
                                          mz + side * 0.999 * half * nz),
                      0.0);
            EXPECT_EQ(sl::crackPathOffset(trunk, mx + side * 1.001 * half * nx,
                                          mz + side * 1.001 * half * nz),
                      0.0);
        }
    }
    // The map: the change is the cracks' offsets (to float rounding), never a rise (no rim,
    // bit for bit), and the label is exactly where a crack lowers by >= 10 % of its depth.
    size_t labelled = 0, changed = 0;
    for (int j = 0; j < g.height; ++j)
        for (int i = 0; i < g.width; ++i) {
            const size_t k = static_cast<size_t>(j) * g.width + i;
            const double x = (i - 0.5 * (g.width - 1)) * g.pitch;
            const double z = (j - 0.5 * (g.height - 1)) * g.pitch;
            double expected = 0;
            bool deep = false;
            for (size_t c = 0; c < pieces.size(); ++c) {
                const double o = sl::crackOffset(pieces[c], x, z);
                EXPECT_GE(o, -g.cracks[c].depth);
                expected += o;
                deep = deep || o <= -0.1 * g.cracks[c].depth;
            }
            ASSERT_LE(g.heights[k], g0.heights[k]) << i << "," << j;
            EXPECT_NEAR(g.heights[k] - g0.heights[k], expected, 1e-8) << i << "," << j;
            EXPECT_EQ(g.truth[k], deep ? sl::kTruthCrack : 0) << i << "," << j;
            labelled += g.truth[k] != 0;
            changed += g.heights[k] != g0.heights[k];
        }
    // Narrow: the labelled samples are a thin line, fewer than the trunks' and branches' length
    // times their widest opening in samples.
    EXPECT_GT(labelled, 100u);
    EXPECT_LT(static_cast<double>(labelled),
              2 * (1 + 2 * 0.5) * s.crackLength * s.crackWidth / (g.pitch * g.pitch));
    EXPECT_GE(changed, labelled);
    // Validation names the fields.
    SurfaceSpec bad = s;
    bad.crackWidth = 0;
    EXPECT_NE(errorOf(bad).find(optionOf("crackWidth")), std::string::npos);
    bad = s;
    bad.crackLength = -1;
    EXPECT_NE(errorOf(bad).find(optionOf("crackLength")), std::string::npos);
    bad = s;
    bad.crackBranches = -1;
    EXPECT_NE(errorOf(bad).find(optionOf("crackBranches")), std::string::npos);
}

TEST(Synth, PocketBurrIsLabelledWhereItRaisesTheEdge) {
    SurfaceSpec s = cleanBallEnd();
    s.pocketEdge = true;
    s.roughnessRms = 0.0002;
    s.pocketBurrHeight = 0.004;
    GeneratedSurface g = sl::generateSurface(s);
    SurfaceSpec s0 = s;
    s0.pocketBurrHeight = 0;
    GeneratedSurface g0 = sl::generateSurface(s0);
    // Labelled where raised by ≥ 10% of the local height (≥ 0.5·H along the edge).
    expectLabelOnlyWhereChanged(g, g0, sl::kTruthBurr, 0.1 * 0.5 * 0.004 - 1e-7);
    const double xTop = g.pocketEdgeX - g.pocketEdgeHalfWidth;
    double maxRaise = 0;
    for (int j = 0; j < g.height; ++j) {
        double rowMax = 0;
        for (int i = 0; i < g.width; ++i) {
            double change = g.at(i, j) - g0.at(i, j);
            EXPECT_GE(change, -1e-9);
            if (change > 0) {
                EXPECT_LT(std::abs(xOf(g, i) - xTop), 0.5 * s.pocketBurrWidth);
            }
            rowMax = std::max(rowMax, change);
        }
        // Along the edge the burr's height varies in [0.5, 1]·H (sampled near its crest).
        EXPECT_GE(rowMax, 0.5 * 0.004 * 0.9);
        EXPECT_LE(rowMax, 0.004 + 1e-7);
        maxRaise = std::max(maxRaise, rowMax);
    }
    EXPECT_GT(maxRaise, 0.75 * 0.004);
    // A burr needs an edge to sit on.
    s.pocketEdge = false;
    EXPECT_NE(errorOf(s).find(optionOf("pocketBurrHeight")), std::string::npos);
}

TEST(Synth, ScratchLipsLabelledBurrOnlyWhenAskedAndWhereRaised) {
    SurfaceSpec s = cleanBallEnd();
    s.scratches = {{-0.35, -0.2, 0.45, 0.3, 0.04, 0.004, ScratchSpec::Shape::V, 0.3}};
    GeneratedSurface plain = sl::generateSurface(s);
    EXPECT_EQ(countLabel(plain, sl::kTruthBurr), 0u);
    s.labelScratchLips = true;
    GeneratedSurface g = sl::generateSurface(s);
    EXPECT_EQ(g.heights, plain.heights);  // labelling changes no height
    SurfaceSpec s0 = s;
    s0.scratches.clear();
    s0.scratchCount = 0;
    GeneratedSurface g0 = sl::generateSurface(s0);
    // Lips: raised by ≥ 10% of the lip's height burr·depth (where the scratch is at ≥ 10% of
    // its depth); the groove keeps 255.
    expectLabelOnlyWhereChanged(g, g0, sl::kTruthBurr, 0.1 * 0.1 * 0.3 * 0.004 - 1e-7);
    for (size_t k = 0; k < g.truth.size(); ++k) {
        if (g.truth[k] == sl::kTruthBurr) {
            EXPECT_GT(g.heights[k], g0.heights[k]);
        }
        EXPECT_EQ(g.truth[k] == sl::kTruthDefect, plain.truth[k] == sl::kTruthDefect);
    }
}

TEST(Synth, ToolChangeStepShiftsOneSideAndLabelsItsRamp) {
    for (SurfaceSpec base : {cleanBallEnd(), cleanTurned()}) {
        base.roughnessRms = 0.0002;
        SurfaceSpec s = base;
        const bool turned = s.process == SurfaceSpec::Process::Turned;
        s.toolChangeStep = 0.003;
        s.toolChangeAt = turned ? 0.4 : -0.2;
        GeneratedSurface g = sl::generateSurface(s);
        GeneratedSurface g0 = sl::generateSurface(base);
        expectLabelOnlyWhereChanged(g, g0, sl::kTruthToolChange, 0.1 * 0.003 - 1e-7);
        const double w = std::max(s.toolChangeWidth, 2 * s.pitch);
        for (int j = 0; j < g.height; ++j)
            for (int i = 0; i < g.width; ++i) {
                double c = turned ? std::hypot(xOf(g, i), zOf(g, j)) : zOf(g, j);
                double change = g.at(i, j) - g0.at(i, j);
                uint8_t t = g.truth[static_cast<size_t>(j) * g.width + i];
                if (c < s.toolChangeAt - 0.5 * w) {
                    EXPECT_EQ(change, 0.0);
                }
                if (c > s.toolChangeAt + 0.5 * w) {
                    EXPECT_NEAR(change, -0.003, 1e-7);  // the plateau: shifted, not labelled
                    EXPECT_NE(t, sl::kTruthToolChange);
                }
                if (t == sl::kTruthToolChange) {
                    EXPECT_LT(std::abs(c - s.toolChangeAt), 0.5 * w);
                }
            }
    }
}

TEST(Synth, ChatterBandsConfineChatterAndAreLabelled) {
    for (SurfaceSpec base : {cleanBallEnd(), cleanTurned()}) {
        SurfaceSpec s = base;
        const bool turned = s.process == SurfaceSpec::Process::Turned;
        s.chatterBands = 2;
        s.chatterBandWidth = 0.2;
        s.chatterBandAmplitude = 0.001;
        GeneratedSurface g = sl::generateSurface(s);
        GeneratedSurface g0 = sl::generateSurface(base);
        ASSERT_EQ(g.chatterBands.size(), 2u);
        // Labelled on every sample of a band, which the chatter changed; unchanged elsewhere.
        expectLabelOnlyWhereChanged(g, g0, sl::kTruthChatterBand, 1e-12);
        for (int j = 0; j < g.height; ++j)
            for (int i = 0; i < g.width; ++i) {
                double c = turned ? std::hypot(xOf(g, i), zOf(g, j)) : zOf(g, j);
                bool inBand = false;
                for (double b : g.chatterBands) inBand = inBand || std::abs(c - b) < 0.1;
                size_t k = static_cast<size_t>(j) * g.width + i;
                EXPECT_EQ(g.truth[k] == sl::kTruthChatterBand, inBand) << i << "," << j;
                if (!inBand) {
                    EXPECT_EQ(g.heights[k], g0.heights[k]);
                }
                if (inBand) {
                    EXPECT_LE(std::abs(g.heights[k] - g0.heights[k]), 2 * 0.001 + 1e-9);
                }
            }
    }
    // Ball-end: on a path centre inside a band the height is the band's sinusoid, ±A_band.
    SurfaceSpec s = cleanBallEnd();
    s.pathOffset = 0.5 * s.pitch;
    s.chatterBands = 1;
    s.chatterBandWidth = 2.0;  // wider than the map's range of p: the band covers it all
    GeneratedSurface g = sl::generateSurface(s);
    std::vector<double> line(static_cast<size_t>(g.width));
    for (int i = 0; i < g.width; ++i) line[static_cast<size_t>(i)] = g.at(i, 128);
    auto [l0, l1] = std::minmax_element(line.begin(), line.end());
    EXPECT_NEAR(*l1 - *l0, 2 * s.chatterBandAmplitude, 0.01 * s.chatterBandAmplitude);
}

TEST(Synth, ScratchSpreadSetsDirectionDepthAndWidth) {
    SurfaceSpec s;
    s.width = 256;
    s.height = 256;
    s.scratchCount = 12;
    s.scratchDirectionDeg = 30;
    s.scratchDirectionSpreadDeg = 0;
    s.scratchDepthMin = 0.2;
    s.scratchWidthMin = 0.4;
    GeneratedSurface g = sl::generateSurface(s);
    ASSERT_EQ(g.scratches.size(), 12u);
    double dmin = 1, dmax = 0, wmin = 1, wmax = 0;
    for (const ScratchSpec& c : g.scratches) {
        double a = std::atan2(c.z1 - c.z0, c.x1 - c.x0) * 180 / std::numbers::pi;
        EXPECT_NEAR(a, 30.0, 1e-9);
        dmin = std::min(dmin, c.depth);
        dmax = std::max(dmax, c.depth);
        wmin = std::min(wmin, c.width);
        wmax = std::max(wmax, c.width);
    }
    EXPECT_GE(dmin, 0.2 * s.scratchDepth);
    EXPECT_LE(dmax, s.scratchDepth);
    EXPECT_LT(dmin, 0.5 * s.scratchDepth);  // reaches below the default's floor of 0.5
    EXPECT_GE(wmin, 0.4 * s.scratchWidth);
    EXPECT_LE(wmax, s.scratchWidth);
    EXPECT_LT(wmin, 0.75 * s.scratchWidth);
    s.scratchDirectionSpreadDeg = 40;
    GeneratedSurface g2 = sl::generateSurface(s);
    double amin = 90, amax = -90;
    for (const ScratchSpec& c : g2.scratches) {
        double a = std::atan2(c.z1 - c.z0, c.x1 - c.x0) * 180 / std::numbers::pi;
        amin = std::min(amin, a);
        amax = std::max(amax, a);
    }
    EXPECT_GE(amin, 10.0 - 1e-9);
    EXPECT_LE(amax, 50.0 + 1e-9);
    EXPECT_GT(amax - amin, 10.0);
}

TEST(Synth, OverlappingLabelsTakeTheHigherValue) {
    SurfaceSpec s = cleanBallEnd();
    s.chatterAmplitude = 0.0005;
    s.chatterStartFraction = 0.5;  // 128 on the right half
    s.chatterBands = 1;            // 144 across all of it (wider than the map)
    s.chatterBandWidth = 2.5;
    s.toolChangeStep = 0.003;  // 192 along z = 0.3
    s.toolChangeAt = 0.3;
    s.dents = {{0.3, 0.3, 0.005, 0.5}};                 // 224 on the step line
    s.scratches = {{0.2, 0.3, 0.5, 0.3, 0.04, 0.004}};  // 255 through the dent
    GeneratedSurface g = sl::generateSurface(s);
    EXPECT_EQ(g.truth[static_cast<size_t>(row(g, 0.3)) * g.width + col(g, 0.3)],
              sl::kTruthDefect);  // scratch > dent
    EXPECT_EQ(g.truth[static_cast<size_t>(row(g, 0.3)) * g.width + col(g, 0.6)],
              sl::kTruthToolChange);  // step > band
    EXPECT_EQ(g.truth[static_cast<size_t>(row(g, -0.2)) * g.width + col(g, 0.4)],
              sl::kTruthChatterBand);                 // band > 128
    EXPECT_EQ(countLabel(g, sl::kTruthChatter), 0u);  // the band covers the chatter region
    EXPECT_GT(countLabel(g, sl::kTruthDent), 0u);     // outside the groove
}

TEST(Synth, MeasurementNoiseIsWhiteSpikesAreSingleSamplesNeitherIsLabelled) {
    SurfaceSpec s = cleanBallEnd();
    s.scratchCount = 3;
    GeneratedSurface g0 = sl::generateSurface(s);
    s.noiseRms = 0.0001;
    GeneratedSurface g = sl::generateSurface(s);
    EXPECT_EQ(g.truth, g0.truth);
    double sum = 0, sum2 = 0, lag = 0;
    const size_t n = g.heights.size();
    for (size_t k = 0; k < n; ++k) {
        double d = static_cast<double>(g.heights[k]) - g0.heights[k];
        sum += d;
        sum2 += d * d;
        if (k + 1 < n) lag += d * (static_cast<double>(g.heights[k + 1]) - g0.heights[k + 1]);
    }
    double rms = std::sqrt(sum2 / static_cast<double>(n));
    EXPECT_NEAR(rms, s.noiseRms, 0.02 * s.noiseRms);
    EXPECT_NEAR(sum / static_cast<double>(n), 0.0, 0.02 * s.noiseRms);
    EXPECT_LT(std::abs(lag / sum2), 0.02);  // white: neighbours uncorrelated
    s.noiseRms = 0;
    s.spikeCount = 7;
    s.spikeHeight = 0.005;
    GeneratedSurface gs = sl::generateSurface(s);
    EXPECT_EQ(gs.truth, g0.truth);
    ASSERT_EQ(gs.spikes.size(), 7u);
    size_t changed = 0;
    for (size_t k = 0; k < n; ++k) changed += gs.heights[k] != g0.heights[k];
    EXPECT_LE(changed, 7u);
    EXPECT_GE(changed, 6u);  // two spikes may share a sample
    for (const sl::Spike& sp : gs.spikes) {
        EXPECT_GE(std::abs(sp.height), 0.5 * s.spikeHeight);
        EXPECT_LE(std::abs(sp.height), s.spikeHeight);
    }
    for (float h : gs.heights) ASSERT_TRUE(std::isfinite(h));  // no dropouts
}

TEST(Synth, LegendNamesEveryLabelPresent) {
    // The kinds: unique values ≥ 128 (a half-scale binarisation counts every one as a defect),
    // unique names, highest value first.
    std::vector<int> values;
    std::vector<std::string> names;
    for (const sl::TruthKind& k : sl::truthKinds()) {
        values.push_back(k.value);
        names.emplace_back(k.name);
        EXPECT_GE(k.value, 128);
    }
    EXPECT_TRUE(std::is_sorted(values.rbegin(), values.rend()));
    EXPECT_EQ(std::adjacent_find(values.begin(), values.end()), values.end());
    EXPECT_EQ(names, (std::vector<std::string>{"defect", "scratch", "gouge", "pit", "pit-chain",
                                               "crack", "dent", "tool-change-step", "burr",
                                               "chatter-band", "chatter"}));
    // As always: "defect" even when absent, "chatter" only when present.
    std::vector<uint8_t> empty(16, 0);
    auto legend = sl::truthLegend(empty);
    ASSERT_EQ(legend.size(), 1u);
    EXPECT_EQ(legend[0].value, sl::kTruthDefect);
    EXPECT_EQ(legend[0].name, "defect");
    // Every test part holds every kind, and its legend names each value present.
    for (const sl::TestPartRow& r : sl::testPartTable()) {
        GeneratedSurface g = sl::generateSurface(sl::testPartSpec(r.value));
        auto counts = labelCounts(g);
        legend = sl::truthLegend(g.truth);
        ASSERT_EQ(counts.size(), 6u) << r.name;
        ASSERT_EQ(legend.size(), 6u) << r.name;
        for (auto [v, n] : counts) {
            bool named = false;
            for (const sl::RegionLabel& l : legend) named = named || l.value == v;
            EXPECT_TRUE(named) << r.name << " " << v;
            EXPECT_GT(n, 50u) << r.name << " " << v;
        }
    }
}

TEST(Synth, ValidationNamesTheNewFields) {
    auto expectField = [](SurfaceSpec s, const std::string& field) {
        std::string msg = errorOf(s);
        const std::string name = optionOf(field);
        EXPECT_NE(msg.find(name), std::string::npos) << "expected '" << name << "' in: " << msg;
    };
    SurfaceSpec base;
    base.width = 16;
    base.height = 16;
    SurfaceSpec s = sl::processDefaults(SurfaceSpec::Process::FlatEndPocket);
    s.width = s.height = 16;
    EXPECT_EQ(errorOf(s), "");
    s.toolCornerRadius = 0;
    expectField(s, "toolCornerRadius");
    s.toolCornerRadius = 1.5;  // > toolRadius
    expectField(s, "toolCornerRadius");
    s.toolCornerRadius = 0.2;
    s.feedPerTooth = 0.5;  // ≥ 2·r_c
    expectField(s, "feedPerTooth");
    s = sl::processDefaults(SurfaceSpec::Process::Turned);
    s.width = s.height = 16;
    EXPECT_EQ(errorOf(s), "");
    s.feedPerTooth = 0;
    expectField(s, "feedPerTooth");
    s.feedPerTooth = 0.1;
    s.turnCentreX = std::nan("");
    expectField(s, "turnCentreX");
    s = sl::processDefaults(SurfaceSpec::Process::Ground);
    s.width = s.height = 16;
    EXPECT_EQ(errorOf(s), "");
    s.gritDepth = 0;
    expectField(s, "gritDepth");
    s.gritDepth = 0.001;
    s.gritLength = -1;
    expectField(s, "gritLength");
    s = base;  // another process: a negative grit length is still a mistake
    s.gritLength = -1;
    expectField(s, "gritLength");
    s = base;
    s.chatterBands = 2;
    s.chatterBandWidth = 0;
    expectField(s, "chatterBandWidth");
    s.chatterBandWidth = 0.5;
    s.chatterBandAmplitude = -1;
    expectField(s, "chatterBandAmplitude");
    // A length the process does not use is still refused when negative or infinite (a
    // ball-end part given a nose radius of -5, a map without dents given a dent depth of -1),
    // and 0 there is allowed: it says "none".
    for (auto [field, set] :
         std::vector<std::pair<std::string, std::function<void(SurfaceSpec&, double)>>>{
             {"insertNoseRadius", [](SurfaceSpec&t, double v) { t.insertNoseRadius = v; }},
             {"toolCornerRadius", [](SurfaceSpec&t, double v) { t.toolCornerRadius = v; }},
             {"dentDepth", [](SurfaceSpec&t, double v) { t.dentDepth = v; }},
             {"gougeLength", [](SurfaceSpec&t, double v) { t.gougeLength = v; }},
             {"chatterWavelength", [](SurfaceSpec&t, double v) { t.chatterWavelength = v; }}}) {
        s = base;  // ball-end, no dents, no gouges, no chatter: none of them used
        s.dentCount = s.gougeCount = s.chatterBands = 0;
        s.chatterAmplitude = 0;
        set(s, -5);
        expectField(s, field);
        set(s, std::numeric_limits<double>::infinity());
        expectField(s, field);
        set(s, 0);
        EXPECT_EQ(errorOf(s), "") << field;
    }
    s = base;
    s.scratchDepthMin = 1.5;
    expectField(s, "scratchDepthMin");
    s = base;
    s.scratchWidthMin = 0;
    expectField(s, "scratchWidthMin");
    s = base;
    s.scratchDirectionSpreadDeg = 200;
    expectField(s, "scratchDirectionSpreadDeg");
    s = base;
    s.dentCount = 2;
    s.dentRadius = 0;
    expectField(s, "dentRadius");
    s = base;
    s.dents = {{0, 0, 0.6, 0.5}};  // deeper than the indenter's radius
    expectField(s, "dents[0].depth");
    s = base;
    s.pocketBurrHeight = -0.001;
    expectField(s, "pocketBurrHeight");
    s = base;
    s.toolChangeStep = std::numeric_limits<double>::infinity();
    expectField(s, "toolChangeStep");
    s = base;
    s.noiseRms = -1;
    expectField(s, "noiseRms");
    s = base;
    s.spikeCount = -1;
    expectField(s, "spikeCount");
    s = base;  // issue 35: a negative largest spike was read (each spike's sign is random)
    s.spikeCount = 1;
    s.spikeHeight = -1;
    expectField(s, "spikeHeight");
}

TEST(GenSurface, PartFilesLegendNamesEveryLabelOfTheTruth) {
    sl::test::TempDir dir("gensurface-legend");
    for (sl::TestPart part : {sl::TestPart::Turned, sl::TestPart::BallEnd}) {
        SurfaceSpec s = sl::testPartSpec(part);
        if (part == sl::TestPart::BallEnd) {  // a part with fewer kinds: only those present
            s.width = s.height = 300;
            s.dentCount = 0;
            s.toolChangeStep = 0;
            s.chatterStartFraction = 0;
        }
        GeneratedSurface g = sl::generateSurface(s);
        const sl::PartFiles f = sl::writePartFiles(g, dir / "p.exr", {});
        sl::LabelMask m = sl::readLabelMask(f.truth, g.width, g.height);
        EXPECT_EQ(m.labels, g.truth);
        std::vector<int> present, named;
        for (auto [v, n] : labelCounts(g)) present.push_back(v);
        for (const sl::RegionLabel& l : m.legend)
            if (l.value != sl::kTruthDefect || countLabel(g, l.value) > 0) named.push_back(l.value);
        std::sort(named.begin(), named.end());
        EXPECT_EQ(named, present);
        for (const sl::RegionLabel& l : m.legend) {
            bool known = false;
            for (const sl::TruthKind& k : sl::truthKinds())
                known = known || (k.value == l.value && l.name == k.name);
            EXPECT_TRUE(known) << int(l.value) << " " << l.name;
        }
        if (part == sl::TestPart::Turned) {
            EXPECT_EQ(m.legend.size(), 6u);
        }
    }
}

TEST(GenSurface, WithoutNewOptionsTheCommandWritesTheSurfaceOfBefore) {
    sl::test::TempDir dir("gensurface-default");
    auto r = sl::test::runCli("gen-surface -o " + (dir / "d.exr").string() + " --width 300");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    SurfaceSpec s;
    s.width = 300;
    GeneratedSurface g = sl::generateSurface(s);
    EXPECT_EQ(surfaceHash(g), "833d26d53e61bc46");  // as made before the test parts existed
    sl::Image hm = sl::readImage(dir / "d.exr");
    EXPECT_EQ(hm.data, g.heights);
    EXPECT_EQ(sl::readLabelMask(dir / "d-truth.png", 300, 1024).labels, g.truth);
    r = sl::test::runCli("gen-surface -o " + (dir / "f.exr").string() +
                         " --width 300 --process facemill --chatter-start 0.5");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    s.process = SurfaceSpec::Process::FaceMillFeed;
    s.chatterStartFraction = 0.5;
    g = sl::generateSurface(s);
    EXPECT_EQ(surfaceHash(g), "74b7f74d4c453215");  // as made before the test parts existed
    EXPECT_EQ(sl::readImage(dir / "f.exr").data, g.heights);
    sl::LabelMask m = sl::readLabelMask(dir / "f-truth.png", 300, 1024);
    EXPECT_EQ(m.labels, g.truth);
    ASSERT_EQ(m.legend.size(), 2u);
    EXPECT_EQ(m.legend[1].name, "chatter");
}

TEST(GenSurface, PartAndProcessOptions) {
    sl::test::TempDir dir("gensurface-part");
    // A named part with options overriding it: the library's spec with the same overrides.
    auto r = sl::test::runCli("gen-surface -o " + (dir / "t.exr").string() +
                              " --part flatend --width 400 --height 300 --dents 6 --seed 3"
                              " --noise 0.0001 --spikes 4");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    SurfaceSpec s = sl::testPartSpec(sl::TestPart::FlatEnd);
    s.width = 400;
    s.height = 300;
    s.dentCount = 6;
    s.seed = 3;
    s.noiseRms = 0.0001;
    s.spikeCount = 4;
    GeneratedSurface g = sl::generateSurface(s);
    EXPECT_EQ(sl::readImage(dir / "t.exr").data, g.heights);
    EXPECT_EQ(sl::readLabelMask(dir / "t-truth.png", 400, 300).labels, g.truth);
    EXPECT_NE(r.output.find("6 dent(s)"), std::string::npos) << r.output;
    // A process's own tool defaults, overridable.
    r = sl::test::runCli("gen-surface -o " + (dir / "u.exr").string() +
                         " --process turned --width 200 --height 200 --feed 0.12 --no-pocket"
                         " --chatter-bands 1 --tool-change-step 0.002 --tool-change-at 0.5");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    s = sl::processDefaults(SurfaceSpec::Process::Turned);
    s.width = s.height = 200;
    s.feedPerTooth = 0.12;
    s.pocketEdge = false;
    s.chatterBands = 1;
    s.toolChangeStep = 0.002;
    s.toolChangeAt = 0.5;
    g = sl::generateSurface(s);
    EXPECT_EQ(sl::readImage(dir / "u.exr").data, g.heights);
    sl::LabelMask m = sl::readLabelMask(dir / "u-truth.png", 200, 200);
    EXPECT_EQ(m.labels, g.truth);
    EXPECT_EQ(m.legend.size(), 3u);  // defect (always), tool-change-step, chatter-band
    // --part and --process exclude each other; unknown names are usage errors; a burr without
    // its pocket edge is an input error naming the field.
    EXPECT_EQ(sl::test::runCli("gen-surface -o " + (dir / "v.exr").string() +
                               " --part turned --process ballend")
                  .exitCode,
              2);
    EXPECT_EQ(
        sl::test::runCli("gen-surface -o " + (dir / "v.exr").string() + " --part nope").exitCode,
        2);
    r = sl::test::runCli("gen-surface -o " + (dir / "v.exr").string() +
                         " --width 64 --height 64 --burr 0.004 --no-pocket");
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.output.find("--burr"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "v.exr"));
}
