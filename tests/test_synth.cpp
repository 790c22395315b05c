// Tests of the synthetic machined-surface generator (src/synth/SurfaceGenerator).
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "core/Error.h"
#include "core/Hash.h"
#include "synth/SurfaceGenerator.h"

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
    EXPECT_NE(a.heights, d.heights);
    size_t differing = 0;
    for (size_t k = 0; k < a.heights.size(); ++k) differing += a.heights[k] != d.heights[k];
    EXPECT_GT(differing, a.heights.size() / 2);  // roughness and chatter phases change everywhere
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
        EXPECT_NE(msg.find(field), std::string::npos) << "expected '" << field << "' in: " << msg;
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
    // A valid spec passes, and the message says which struct the field belongs to.
    EXPECT_EQ(errorOf(base), "");
    s = base;
    s.pitch = 0;
    EXPECT_NE(errorOf(s).find("SurfaceSpec.pitch"), std::string::npos);
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
