// The defect map's `selfsim` method (detect/SelfSimMap.h) on synthetic textures with exact
// ground truth: periodic striations (tool marks repeating across the lay) with white noise, one
// pit and one groove across the lay: the pit and the groove are marked, the striations are not;
// on the pure texture (no defect) the a-contrario test's false detections average at most its
// NFA over independent noise; the Gaussian tail's inverse is exact; scaling the heights by a
// power of two changes nothing and a constant map marks nothing; bad options name themselves;
// the method table has the row and detectDefects runs it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "SyntheticDefects.h"
#include "TestUtil.h"
#include "app/pipeline/Truth.h"
#include "core/Error.h"
#include "detect/DefectMap.h"
#include "detect/MarkShapes.h"
#include "detect/SelfSimMap.h"
#include "scene/Scene.h"

using namespace sl;

namespace {

constexpr int kW = 256, kH = 224;

// Periodic striations along z (constant along the rows' normal direction, varying along x):
// period 9 samples, a sharp cusp profile (|sin|^3, amplitude 1) plus a weaker period-4.5
// harmonic, and white noise of σ = `noise`.
std::vector<float> striations(uint32_t seed, double noise = 0.05) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> nd(0.0, noise);
    std::uniform_real_distribution<double> u(0.0, 2 * M_PI);
    const double phase = u(rng);
    std::vector<float> h(static_cast<size_t>(kW) * kH);
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            const double s = std::sin(M_PI * x / 9.0 + phase);
            const double v =
                std::pow(std::abs(s), 3) + 0.2 * std::sin(4 * M_PI * x / 9.0) + nd(rng);
            h[static_cast<size_t>(y) * kW + x] = static_cast<float>(v);
        }
    return h;
}

// Striae along z with no repeat across them (four incommensurate sines along x, amplitudes
// 0.4-0.1) and white noise of σ 0.05: a texture whose tiles have a lay (along z) and whose
// copies across it do not match (steps 8i and 8j).
std::vector<float> aperiodicStriae(uint32_t seed) {
    std::vector<float> h(static_cast<size_t>(kW) * kH);
    std::mt19937 rng(seed);
    std::normal_distribution<double> noise(0.0, 0.05);
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x)
            h[static_cast<size_t>(y) * kW + x] = static_cast<float>(
                0.4 * std::sin(2 * M_PI * x / 7.3) + 0.3 * std::sin(2 * M_PI * x / 11.9 + 1.0) +
                0.2 * std::sin(2 * M_PI * x / 17.7 + 2.0) +
                0.1 * std::sin(2 * M_PI * x / 29.1 + 3.0) + noise(rng));
    return h;
}

/// Peaked striae along z, period 9 samples (|sin|³ ridges), each column offset by a normal
/// draw of σ `columnSigma` (no repeat across them), plus white noise of σ 0.05 (seed 71; steps
/// 8l's and 8r's tests).
std::vector<float> peakedStriae(double columnSigma) {
    std::vector<float> h(static_cast<size_t>(kW) * kH);
    std::mt19937 rng(71);
    std::normal_distribution<double> white(0.0, 0.05), column(0.0, columnSigma);
    std::vector<double> c(kW);
    for (double& v : c) v = column(rng);
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            const double s = std::sin(M_PI * x / 9.0);
            h[static_cast<size_t>(y) * kW + x] =
                static_cast<float>(std::pow(std::abs(s), 3) + c[x] + white(rng));
        }
    return h;
}

void pit(std::vector<float>& h, std::vector<uint8_t>& t, double cx, double cy, double rho,
         double d) {
    test::paintPit(h, t, kW, cx, cy, rho, d);
}

void groove(std::vector<float>& h, std::vector<uint8_t>& t, double x0, double y0, double x1,
            double y1, double width, double depth) {
    test::paintGroove(h, t, kW, x0, y0, x1, y1, width, depth);
}

struct Counts {
    size_t truth = 0, hits = 0, marked = 0;
};

Counts count(const std::vector<uint8_t>& map, const std::vector<uint8_t>& truth, int border) {
    Counts c;
    for (int y = border; y < kH - border; ++y)
        for (int x = border; x < kW - border; ++x) {
            const size_t i = static_cast<size_t>(y) * kW + x;
            c.truth += truth[i] ? 1 : 0;
            c.marked += map[i] ? 1 : 0;
            c.hits += map[i] && truth[i] ? 1 : 0;
        }
    return c;
}

/// Samples `in` marks and `notIn` does not (what a step adds, or with the maps swapped, drops).
// The options of the map before step 8u, which takes a ring of samples about every mark (tested
// on its own, AMarksEdgeThatKeepsItsSignIsTakenTheTextureBesideItIsNot): a step's test compares
// the maps with and without that step alone.
SelfSimMapOptions before8u() {
    SelfSimMapOptions o;
    o.edgeRingSigma = 0.0;
    return o;
}

size_t markedOnlyIn(const SelfSimMap& in, const SelfSimMap& notIn) {
    size_t n = 0;
    for (size_t i = 0; i < in.map.size(); ++i) n += in.map[i] && !notIn.map[i] ? 1 : 0;
    return n;
}

/// Raises the box x0..x1 × y0..y1 (inclusive) of `h` by `height` and marks it in `mask` (the
/// banks, rims and strips of steps 8g, 8o, 8q and 8l's tests).
void raiseBox(std::vector<float>& h, std::vector<uint8_t>& mask, int x0, int x1, int y0, int y1,
              double height) {
    for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
            const size_t i = static_cast<size_t>(y) * kW + x;
            mask[i] = 1;
            h[i] += static_cast<float>(height);
        }
}

/// Whether `label` holds a sample within `reach` samples (a square) of (x, y).
bool nearLabel(const std::vector<uint8_t>& label, int x, int y, int reach) {
    for (int qy = std::max(0, y - reach); qy <= std::min(kH - 1, y + reach); ++qy)
        for (int qx = std::max(0, x - reach); qx <= std::min(kW - 1, x + reach); ++qx)
            if (label[static_cast<size_t>(qy) * kW + qx]) return true;
    return false;
}

/// The samples a step added: those `with` marks and `without` does not; how many of them lie
/// below the texture (residual <= 0, `with`'s), and how many are not where `onTarget(x, y)` says
/// the step may add.
struct Added {
    size_t added = 0, lowered = 0, away = 0;
};
template <class OnTarget>
Added addedSamples(const SelfSimMap& without, const SelfSimMap& with, OnTarget onTarget) {
    Added n;
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            const size_t i = static_cast<size_t>(y) * kW + x;
            if (!with.map[i] || without.map[i]) continue;
            ++n.added;
            n.lowered += with.residual[i] > 0.0f ? 0 : 1;
            n.away += onTarget(x, y) ? 0 : 1;
        }
    return n;
}

/// Striations (seed 11) strewn with 400 particles whose heights are exponential (mean 0.2: many
/// small, a few as high as 1.5 × the striations), Gaussian domes of σ 1.2 samples at random
/// places 48 samples or more from the edges; `particles` (optional) marks each within 2.5
/// samples of its centre.
std::vector<float> particleField(std::vector<uint8_t>* particles = nullptr) {
    std::vector<float> h = striations(11);
    if (particles) particles->assign(h.size(), 0);
    std::mt19937 rng(12);
    std::uniform_real_distribution<double> ux(48, kW - 48), uy(48, kH - 48);
    std::exponential_distribution<double> amplitude(1.0 / 0.2);
    for (int k = 0; k < 400; ++k) {
        const double cx = ux(rng), cy = uy(rng), a = amplitude(rng);
        for (int y = static_cast<int>(cy) - 4; y <= static_cast<int>(cy) + 4; ++y)
            for (int x = static_cast<int>(cx) - 4; x <= static_cast<int>(cx) + 4; ++x) {
                const double d2 = (x - cx) * (x - cx) + (y - cy) * (y - cy);
                const size_t i = static_cast<size_t>(y) * kW + x;
                h[i] += static_cast<float>(a * std::exp(-d2 / (2 * 1.2 * 1.2)));
                if (particles && d2 <= 2.5 * 2.5) (*particles)[i] = 1;
            }
    }
    return h;
}

/// The border pieces' scene: striations (seed 51) crossed from border to border by a raised
/// ridge (3 × the striations high, 10 samples wide, along y = 112: a region at the border) and
/// a pit (3 × deep, ρ 7) whose rim lies on the ridge's lower flank. The masks are as painted
/// (the pit's overlaps the ridge's).
struct RidgeAndPit {
    std::vector<float> h;
    std::vector<uint8_t> ridge, pit;
};
RidgeAndPit ridgeAndPit() {
    RidgeAndPit s;
    s.h = striations(51);
    s.ridge.assign(s.h.size(), 0);
    s.pit.assign(s.h.size(), 0);
    groove(s.h, s.ridge, 0, 112, kW - 1, 112, 10, -3.0);  // raised, across the whole map
    pit(s.h, s.pit, 90, 122, 7, 3.0);                     // its rim on the ridge's flank
    return s;
}

}  // namespace

// optimize's defect region auto (app/pipeline/Truth.h defectRegionsInImage) on a measured
// part: the map's marks by shape, and what the map could not judge, counted as the map does, so
// optimize can warn that the light was not asked to show it.
TEST(SelfSimMap, TheObjectivesAutoRegionCountsWhatTheMapCouldNotJudge) {
    auto [h, ridge, pitTruth] = ridgeAndPit();
    for (float& v : h) v *= 0.01f;  // heights in mm on the bumpy part's 0.05 mm samples
    Scene scene(test::bumpyPartDesc(64, 56), kW, kH, h);
    scene.load.measured = true;
    const DefectRegions r = defectRegionsInImage(scene, parseRegionSpec("auto", "defects"), {}, {});
    DefectMapOptions measured;
    measured.measured = true;
    const DefectMap d = detectDefects(h, kW, kH, measured);
    ASSERT_GE(d.unjudgedRegions, 1u);
    EXPECT_EQ(r.unjudgedRegions, d.unjudgedRegions);
    EXPECT_DOUBLE_EQ(r.unjudgedShare,
                     static_cast<double>(d.unjudgedCount()) / static_cast<double>(h.size()));
    size_t marked = 0, other = 0;
    for (const uint8_t v : r.defects) {
        marked += v != 0;
        other += v != 0 && !isMarkShapeLabel(static_cast<uint8_t>(v));
    }
    EXPECT_GT(marked, 0u) << "the pit, seen by the camera";
    EXPECT_EQ(other, 0u);
    EXPECT_TRUE(r.reference.empty()) << "the objective's default reference";
    // --reference auto beside --defects auto: the part off the marks, the same map
    const DefectRegions both = defectRegionsInImage(scene, parseRegionSpec("auto", "defects"), {},
                                                    parseRegionSpec("auto", "reference"));
    EXPECT_EQ(both.defects, r.defects);
    ASSERT_EQ(both.reference.size(), r.defects.size());
    size_t wrong = 0;
    for (size_t q = 0; q < r.defects.size(); ++q)
        wrong += both.reference[q] != (r.defects[q] ? 0 : 255);
    EXPECT_EQ(wrong, 0u);
}

TEST(SelfSimMap, StriationsAreTheBackgroundThePitAndTheGrooveAreMarked) {
    std::vector<float> h = striations(3);
    std::vector<uint8_t> pitTruth(h.size(), 0), grooveTruth(h.size(), 0);
    pit(h, pitTruth, 95, 80, 6, 1.0);
    groove(h, grooveTruth, 70, 150, 190, 135, 4, 0.8);  // across the lay, 7° from the x axis
    const SelfSimMapOptions o;
    const SelfSimMap m = detectSelfSimDefects(h, kW, kH, o);
    const Counts p = count(m.map, pitTruth, o.border), g = count(m.map, grooveTruth, o.border);
    std::vector<uint8_t> any(h.size());
    for (size_t i = 0; i < h.size(); ++i) any[i] = pitTruth[i] || grooveTruth[i];
    const Counts all = count(m.map, any, o.border);
    EXPECT_GE(p.hits, p.truth * 8 / 10) << "the pit";
    EXPECT_GE(g.hits, g.truth * 8 / 10) << "the groove";
    // the striations are not marked: every mark lies within 4 samples of a defect (the
    // detection at σ = 1 and the growth leave a halo of a few samples, nothing farther)
    std::vector<uint8_t> near(h.size(), 0);
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x)
            for (int yy = std::max(0, y - 4); yy <= std::min(kH - 1, y + 4) && !near[y * kW + x];
                 ++yy)
                for (int xx = std::max(0, x - 4); xx <= std::min(kW - 1, x + 4); ++xx)
                    if (any[static_cast<size_t>(yy) * kW + xx]) {
                        near[static_cast<size_t>(y) * kW + x] = 1;
                        break;
                    }
    const Counts halo = count(m.map, near, o.border);
    EXPECT_EQ(halo.hits, halo.marked) << all.marked << " marked, " << all.hits
                                      << " on the defects, " << halo.hits << " within 4 samples";
    EXPECT_GE(m.offsetX.size(), 3u);
}

TEST(SelfSimMap, PureTextureFalseDetectionsAverageAtMostTheNfa) {
    // the a-contrario guarantee: on a texture that repeats (striations) with Gaussian noise the
    // residual is close to Gaussian noise, so the expected number of detections (regions holding
    // a sample with NFA <= nfa; regions of one sample count) is at most nfa
    SelfSimMapOptions o;
    o.textureRms = 0;  // the test alone (the texture's own tail, step 7, off too)
    o.textureNfa = 0;
    o.minRegion = 1;
    constexpr int kRuns = 6;
    size_t regions = 0;
    for (int s = 0; s < kRuns; ++s)
        regions += detectSelfSimDefects(striations(100 + s), kW, kH, o).regions;
    EXPECT_LE(static_cast<double>(regions) / kRuns, o.nfa) << regions << " regions in " << kRuns;
    // ... and a looser test (NFA 100) does find noise: the count above is not trivially 0
    o.nfa = 100;
    EXPECT_GT(detectSelfSimDefects(striations(100), kW, kH, o).regions, 0u);
}

// The default method, auto, on a measured texture is the selfsim method: the same map, bit for
// bit, and the result says so; on the same heights not marked measured it is the tool-path
// model, another map.
TEST(SelfSimMap, AutoOnAMeasuredTextureIsTheSelfSimMap) {
    std::vector<float> h = striations(5);
    std::vector<uint8_t> t(h.size(), 0);
    pit(h, t, 120, 100, 6, 1.0);
    DefectMapOptions o;
    o.measured = true;
    const DefectMap m = detectDefects(h, kW, kH, o);
    EXPECT_EQ(m.method, DefectMethod::SelfSim);
    EXPECT_TRUE(m.measuredTexture);
    EXPECT_EQ(m.map, detectSelfSimDefects(h, kW, kH, o.selfsim).map);
    EXPECT_GT(m.markedCount(), 0u);
    const DefectMap machined = detectDefects(h, kW, kH);
    EXPECT_EQ(machined.method, DefectMethod::Auto);
    EXPECT_FALSE(machined.measuredTexture);
    EXPECT_NE(machined.map, m.map);
}

// What the map could not judge (SelfSimMap::unjudged, DefectMap::unjudged). A raised ridge
// across the whole map stands out of the striations but reaches the border's line: it is never
// marked, and its samples are the unjudged ones (none marked, none in the border); the pit on
// its flank is marked and judged. On striations with a pit and a groove off the border nothing
// is unjudged. DefectMap's copy adds the border (kUnjudgedBorder, exactly the samples outside
// it); auto on a machined part records none.
TEST(SelfSimMap, WhatReachesTheBorderUnmarkedIsUnjudgedTheRestIsJudged) {
    auto [h, ridge, pitTruth] = ridgeAndPit();
    for (size_t i = 0; i < h.size(); ++i) ridge[i] = ridge[i] && !pitTruth[i];
    const SelfSimMapOptions o;
    const SelfSimMap m = detectSelfSimDefects(h, kW, kH, o);
    ASSERT_EQ(m.unjudged.size(), h.size());
    EXPECT_EQ(m.border, o.border);
    EXPECT_GE(m.unjudgedRegions, 1u);
    size_t both = 0, outside = 0, onRidge = 0, ridgeInside = 0;
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            const size_t i = static_cast<size_t>(y) * kW + x;
            const bool inside =
                x >= o.border && y >= o.border && x < kW - o.border && y < kH - o.border;
            both += m.unjudged[i] && m.map[i];
            outside += m.unjudged[i] && !inside;
            ridgeInside += ridge[i] && inside;
            onRidge += ridge[i] && inside && m.unjudged[i];
        }
    EXPECT_EQ(both, 0u) << "a sample both marked and unjudged";
    EXPECT_EQ(outside, 0u) << "an unjudged sample in the border (DefectMap's value for it)";
    EXPECT_GE(onRidge, ridgeInside * 8 / 10) << onRidge << " of the ridge's " << ridgeInside;
    const Counts p = count(m.map, pitTruth, o.border), u = count(m.unjudged, pitTruth, o.border);
    EXPECT_GE(p.hits, p.truth / 2) << "the pit";
    EXPECT_LE(u.hits, p.truth / 10) << "the pit's samples unjudged";

    std::vector<float> clear = striations(3);
    std::vector<uint8_t> t(clear.size(), 0);
    pit(clear, t, 95, 80, 6, 1.0);
    groove(clear, t, 70, 150, 190, 135, 4, 0.8);
    const SelfSimMap judged = detectSelfSimDefects(clear, kW, kH, o);
    EXPECT_EQ(judged.unjudgedRegions, 0u);
    EXPECT_EQ(std::count(judged.unjudged.begin(), judged.unjudged.end(), 0), kW * kH);

    DefectMapOptions measured;
    measured.measured = true;
    EXPECT_EQ(methodInForce(measured), DefectMethod::SelfSim);
    const DefectMap d = detectDefects(h, kW, kH, measured);
    ASSERT_EQ(d.unjudged.size(), h.size());
    EXPECT_EQ(d.unjudgedRegions, m.unjudgedRegions);
    EXPECT_EQ(d.unjudgedCount(),
              static_cast<size_t>(std::count(m.unjudged.begin(), m.unjudged.end(), 255)));
    size_t border = 0, wrong = 0;
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            const size_t i = static_cast<size_t>(y) * kW + x;
            const bool inside =
                x >= o.border && y >= o.border && x < kW - o.border && y < kH - o.border;
            border += !inside;
            const uint8_t want = !inside         ? kUnjudgedBorder
                                 : m.unjudged[i] ? kUnjudgedRegion
                                                 : kJudged;
            wrong += d.unjudged[i] != want;
        }
    EXPECT_EQ(wrong, 0u);
    EXPECT_EQ(
        static_cast<size_t>(std::count(d.unjudged.begin(), d.unjudged.end(), kUnjudgedBorder)),
        border);
    DefectMapOptions machined;
    EXPECT_EQ(methodInForce(machined), DefectMethod::Auto);
    EXPECT_TRUE(detectDefects(h, kW, kH, machined).unjudged.empty());
}

// Step 7's threshold on peaks that are exactly exponential above z0 (their quantiles,
// z0 + β·ln(N/(N − i − ½))): the tail above any quantile is the same exponential (memoryless),
// its median excess is β·ln 2, so the threshold is where N·P(peak ≥ z) = nfa:
// z0 + β·ln(N/nfa), whatever the quantile the tail is measured from (within 0.05: the
// median of a finite sample).
TEST(SelfSimMap, TextureTailThresholdIsWhereTheExponentialTailExpectsNfaRegions) {
    constexpr size_t kN = 4000;
    const double z0 = 2.5, beta = 1.7;
    std::vector<float> peaks;
    for (size_t i = 0; i < kN; ++i)
        peaks.push_back(static_cast<float>(
            z0 + beta * std::log(static_cast<double>(kN) / (static_cast<double>(kN - i) - 0.5))));
    std::mt19937 rng(4);
    std::shuffle(peaks.begin(), peaks.end(), rng);  // the order of the regions does not matter
    for (double q : {0.5, 0.75, 0.9})
        for (double nfa : {1.0, 0.1})
            EXPECT_NEAR(textureTailThreshold(peaks, q, nfa), z0 + beta * std::log(kN / nfa), 0.05)
                << "quantile " << q << ", nfa " << nfa;
    EXPECT_EQ(textureTailThreshold(peaks, 0.75, 0.0), 0.0);  // off
    peaks.resize(kTextureTailMinRegions - 1);
    EXPECT_EQ(textureTailThreshold(peaks, 0.75, 1.0), 0.0);  // too few regions for a tail
}

// The texture's own marks are dropped, the defect is kept: striations strewn with 400
// particles whose heights are exponential (a measured texture's heavy tail: many small, a few
// as high as 1.5 × the striations), and one pit three times deeper than the striations. The
// Gaussian test (step 5) and the texture's RMS (step 6) keep the highest particles; the
// texture's own tail of the regions' peaks (step 7) drops them and keeps the pit: at most
// the one texture region its NFA of 1 expects is left (here one particle of 400 is).
TEST(SelfSimMap, TheTexturesOwnTailDropsItsParticlesAndKeepsThePit) {
    std::vector<uint8_t> particles;
    std::vector<float> h = particleField(&particles);
    std::vector<uint8_t> pitTruth(h.size(), 0);
    pit(h, pitTruth, 128, 112, 6, 3.0);
    for (size_t i = 0; i < h.size(); ++i)
        if (pitTruth[i]) particles[i] = 0;
    SelfSimMapOptions off;
    off.textureNfa = 0;
    off.particleElongation = 0;  // step 8c would drop these raised blobs too: step 7 alone
    SelfSimMapOptions on;
    on.particleElongation = 0;
    const SelfSimMap a = detectSelfSimDefects(h, kW, kH, off),
                     b = detectSelfSimDefects(h, kW, kH, on);
    EXPECT_EQ(a.textureThreshold, 0.0);
    EXPECT_GT(b.textureThreshold, b.threshold) << "the texture's tail above the Gaussian's";
    EXPECT_GE(b.candidates, kTextureTailMinRegions);
    const Counts pa = count(a.map, pitTruth, on.border), pb = count(b.map, pitTruth, on.border);
    EXPECT_GE(pa.hits, pa.truth * 8 / 10) << "the pit, without step 7";
    EXPECT_GE(pb.hits, pb.truth * 8 / 10) << "the pit, with step 7";
    const size_t marksOff = count(a.map, particles, on.border).hits,
                 marksOn = count(b.map, particles, on.border).hits;
    // without step 7 the highest particles are marked; with it the pit and at most the one
    // texture region its NFA of 1 expects
    EXPECT_GE(a.regions, 10u) << marksOff << " samples of particles marked";
    EXPECT_LE(b.regions, 2u) << marksOn << " samples of particles marked, " << b.droppedTexture
                             << " regions dropped at " << b.textureThreshold << " robust sigmas";
    EXPECT_LT(marksOn * 10, marksOff);
    EXPECT_GT(b.droppedTexture, 0u);
}

// Step 7b: a line the texture's own tail of peaks hides. The particles of
// TheTexturesOwnTailDropsItsParticlesAndKeepsThePit set step 7's tail (~38 σ) above a long
// groove across the striations (the striations' amplitude deep, 4 samples wide, 175 long), so
// step 7 drops it; its pieces' line score (mean score × √elongation) stands above the
// texture's own tail of line scores, which the compact particles keep low, so step 7b keeps
// it. It keeps no particle away from the groove (those it touches are marked with it, as step
// 7 marks them with a groove deep enough to pass it), and on the particles alone it keeps
// nothing.
TEST(SelfSimMap, ALineUnderTheTexturesTailOfPeaksIsKeptItsParticlesAreNot) {
    std::vector<uint8_t> particles;
    std::vector<float> h = particleField(&particles);
    const std::vector<float> alone = h;
    std::vector<uint8_t> line(h.size(), 0);
    groove(h, line, 55, 60, 200, 160, 4, 1.0);
    SelfSimMapOptions off;
    off.lineNfa = 0;
    off.particleElongation = 0;  // step 8c would drop the raised particles anyway
    SelfSimMapOptions on;
    on.particleElongation = 0;
    const SelfSimMap a = detectSelfSimDefects(h, kW, kH, off),
                     b = detectSelfSimDefects(h, kW, kH, on);
    EXPECT_EQ(a.lineThreshold, 0.0);
    EXPECT_GT(b.lineThreshold, 0.0);
    EXPECT_LT(b.lineThreshold, b.textureThreshold) << "lines: a lower tail than the peaks'";
    const Counts la = count(a.map, line, on.border), lb = count(b.map, line, on.border);
    EXPECT_EQ(la.hits, 0u) << "step 7 drops the groove";
    EXPECT_GT(a.droppedTexture, 0u);
    EXPECT_GE(lb.hits, lb.truth * 8 / 10) << "step 7b keeps it";
    EXPECT_GE(b.textureLines, 1u);
    // the particles away from the groove (more than 6 samples): none marked by step 7b
    size_t awayA = 0, awayB = 0;
    for (int y = on.border; y < kH - on.border; ++y)
        for (int x = on.border; x < kW - on.border; ++x) {
            const size_t i = static_cast<size_t>(y) * kW + x;
            if (!particles[i] || nearLabel(line, x, y, 6)) continue;
            awayA += a.map[i] ? 1 : 0;
            awayB += b.map[i] ? 1 : 0;
        }
    EXPECT_EQ(awayB, awayA) << "step 7b marks no particle of its own";
    // the particles alone: step 7b finds no line
    const SelfSimMap c = detectSelfSimDefects(alone, kW, kH, on);
    EXPECT_EQ(c.textureLines, 0u);
    EXPECT_GT(c.lineThreshold, 0.0);
}

// Step 8 keeps a weak defect's flanks and revives no texture mark. (1) Striations with a
// shallow groove, 6 samples wide and 6 noise σ deep, labelled where it is at least a tenth of
// its depth: its outer labelled samples stand below the growth at 2.5 σ. With step 8 more of it
// is marked, and every sample step 8 adds lies next to a region kept without it, below the
// region's sign (the groove's), under growSigma; nothing is removed and no region added.
// (2) The particles of TheTexturesOwnTailDropsItsParticlesAndKeepsThePit, which step 7 drops,
// and a pit three times deeper than the striations: a tenth of the pit's peak score is above
// growSigma, so step 8 adds nothing there, and the particles stay dropped: the same map.
TEST(SelfSimMap, TheFlanksOfAWeakDefectAreMarkedAndNoDroppedRegionIsRevived) {
    std::vector<float> h = striations(21);
    std::vector<uint8_t> truth(h.size(), 0);
    groove(h, truth, 70, 150, 190, 135, 6, 0.3);
    SelfSimMapOptions off = before8u();
    off.extendSteps = 0;
    const SelfSimMapOptions on = before8u();
    ASSERT_EQ(on.extendSteps, 1);
    const SelfSimMap a = detectSelfSimDefects(h, kW, kH, off),
                     b = detectSelfSimDefects(h, kW, kH, on);
    EXPECT_EQ(a.extended, 0u);
    EXPECT_EQ(b.regions, a.regions) << "step 8 adds no region";
    const Counts ga = count(a.map, truth, on.border), gb = count(b.map, truth, on.border);
    EXPECT_GE(ga.hits, ga.truth / 2) << "the groove is kept";
    EXPECT_GE(gb.hits, ga.hits + 10) << "its flanks: " << ga.hits << " of " << ga.truth
                                     << " without step 8, " << gb.hits << " with";
    size_t added = 0, addedOnTruth = 0;
    for (int y = 1; y + 1 < kH; ++y)
        for (int x = 1; x + 1 < kW; ++x) {
            const size_t i = static_cast<size_t>(y) * kW + x;
            if (a.map[i]) {
                EXPECT_TRUE(b.map[i]) << "step 8 removes nothing";
                continue;
            }
            if (!b.map[i]) continue;
            ++added;
            addedOnTruth += truth[i] ? 1 : 0;
            EXPECT_LT(b.residual[i], 0.0f) << "the groove's sign at " << x << "," << y;
            // below the growth (its score is |r − the residual's median|/σ; that median is a
            // small share of σ here)
            EXPECT_LT(std::abs(b.residual[i]), (on.growSigma + 0.5) * b.sigma)
                << "below the growth";
            bool nextToKept = false;
            for (int qy = y - 1; qy <= y + 1; ++qy)
                for (int qx = x - 1; qx <= x + 1; ++qx)
                    nextToKept = nextToKept || a.map[static_cast<size_t>(qy) * kW + qx];
            EXPECT_TRUE(nextToKept) << "a sample away from every kept region at " << x << "," << y;
        }
    EXPECT_EQ(added, b.extended);
    EXPECT_GE(addedOnTruth * 10, added * 8) << "what step 8 adds is mostly the groove's";

    // (2) the particles stay dropped, the deep pit is kept as it was
    std::vector<float> p = particleField();
    std::vector<uint8_t> pitTruth(p.size(), 0);
    pit(p, pitTruth, 128, 112, 6, 3.0);
    const SelfSimMap c = detectSelfSimDefects(p, kW, kH, off),
                     d = detectSelfSimDefects(p, kW, kH, on);
    EXPECT_GT(d.droppedTexture, 0u) << "step 7 dropped particles";
    const Counts pd = count(d.map, pitTruth, on.border);
    EXPECT_GE(pd.hits, pd.truth * 8 / 10) << "the pit";
    EXPECT_EQ(d.extended, 0u);
    EXPECT_EQ(d.map, c.map);
}

// Step 8a keeps a deep defect and drops the texture the growth joined to it. Striations with a
// groove 60 noise σ deep (labelled where it is at least a tenth of its depth) and, beside it, a
// shallow depression of the texture (a dark particle, ~4 σ: below the detection alone), close
// enough that the growth at 2.5 σ joins the two into one region, which the groove keeps. Without
// step 8a the depression and the groove's halo (down to a twentieth of its depth) are marked with
// it; with it a tenth of the depression at most and half the marks outside the label, the
// groove's label is marked as before, and nothing is marked that was not marked without it.
TEST(SelfSimMap, ADeepDefectIsKeptAndTheTextureJoinedToItDropped) {
    std::vector<float> h = striations(31);
    std::vector<uint8_t> truth(h.size(), 0), particle(h.size(), 0);
    groove(h, truth, 70, 112, 190, 112, 8, 3.0);
    const double cx = 130, cy = 118;  // 6 samples off the groove's line, 2 beyond its edge
    for (int y = 100; y < 136; ++y)
        for (int x = 112; x < 148; ++x) {
            const double d2 = (x - cx) * (x - cx) + (y - cy) * (y - cy);
            const size_t i = static_cast<size_t>(y) * kW + x;
            h[i] -= static_cast<float>(0.2 * std::exp(-d2 / (2 * 3.0 * 3.0)));
            if (d2 <= 4.0 * 4.0 && !truth[i]) particle[i] = 1;
        }
    SelfSimMapOptions off =
        before8u();  // step 8a alone: the pile-up and the banks (8e, 8g) are tested below
    off.trimShare = 0;
    off.pileUpReach = 0;
    off.grooveBankWidth = 0.0;
    SelfSimMapOptions on = before8u();
    on.pileUpReach = 0;
    on.grooveBankWidth = 0.0;
    ASSERT_GT(on.trimShare, 0.0);
    const SelfSimMap a = detectSelfSimDefects(h, kW, kH, off),
                     b = detectSelfSimDefects(h, kW, kH, on);
    EXPECT_EQ(a.trimmed, 0u);
    EXPECT_GT(b.trimmed, 0u);
    EXPECT_EQ(b.regions, a.regions) << "step 8a drops no region";
    const Counts ga = count(a.map, truth, on.border), gb = count(b.map, truth, on.border);
    EXPECT_GE(ga.hits, ga.truth * 9 / 10) << "the groove, without step 8a";
    EXPECT_GE(gb.hits, ga.hits * 97 / 100) << "the groove, with it: " << gb.hits << " of "
                                           << ga.truth << " (" << ga.hits << " without)";
    const Counts pa = count(a.map, particle, on.border), pb = count(b.map, particle, on.border);
    EXPECT_GE(pa.hits, 10u) << "the depression joined to the groove, without step 8a";
    EXPECT_LE(pb.hits * 10, pa.hits)
        << "the depression, with step 8a: " << pb.hits << " of " << pa.hits << " samples";
    EXPECT_LT((gb.marked - gb.hits) * 2, ga.marked - ga.hits)
        << "marks outside the label: " << ga.marked - ga.hits << " without step 8a, "
        << gb.marked - gb.hits << " with";
    EXPECT_EQ(markedOnlyIn(b, a), 0u) << "samples marked only with step 8a";
}

// Step 8c drops a particle and keeps the defects: striations with a pit (3 × the striations
// deep, below the texture), a burr (a raised ridge 5 samples wide and 50 long, 3 × the
// striations high) and a particle (a raised dome of the pit's size and height: compact, above
// the texture). Without step 8c -- the default: a person marks particles -- all three are
// marked; with it (elongation 3) the pit and the burr as before and the particle not, one
// region fewer, and nothing marked that was not marked without it.
TEST(SelfSimMap, ARaisedCompactParticleIsDroppedThePitAndTheBurrKept) {
    std::vector<float> h = striations(41);
    std::vector<uint8_t> pitTruth(h.size(), 0), burrTruth(h.size(), 0), particle(h.size(), 0);
    pit(h, pitTruth, 80, 80, 6, 3.0);
    groove(h, burrTruth, 70, 150, 118, 140, 5, -3.0);  // depth < 0: raised
    pit(h, particle, 175, 95, 6, -3.0);                // a dome
    const SelfSimMapOptions off;                       // the default
    SelfSimMapOptions on;
    on.particleElongation = 3.0;
    const SelfSimMap a = detectSelfSimDefects(h, kW, kH, off),
                     b = detectSelfSimDefects(h, kW, kH, on);
    const Counts pa = count(a.map, pitTruth, on.border), pb = count(b.map, pitTruth, on.border);
    const Counts ba = count(a.map, burrTruth, on.border), bb = count(b.map, burrTruth, on.border);
    const Counts qa = count(a.map, particle, on.border), qb = count(b.map, particle, on.border);
    EXPECT_GE(pa.hits, pa.truth * 8 / 10) << "the pit, without step 8c";
    EXPECT_GE(ba.hits, ba.truth * 8 / 10) << "the burr, without step 8c";
    EXPECT_GE(qa.hits, qa.truth * 8 / 10) << "the particle, without step 8c";
    EXPECT_EQ(pb.hits, pa.hits) << "the pit, with step 8c";
    EXPECT_EQ(bb.hits, ba.hits) << "the burr, with step 8c";
    EXPECT_EQ(qb.hits, 0u) << "the particle, with step 8c: " << qb.hits << " of " << qb.truth;
    EXPECT_EQ(a.droppedParticles, 0u);
    EXPECT_GE(b.droppedParticles, 1u);
    EXPECT_EQ(b.regions + b.droppedParticles, a.regions);
    EXPECT_EQ(markedOnlyIn(b, a), 0u) << "samples marked only with step 8c";
}

// Step 8d keeps a defect that the growth joined to a region reaching the border, and not the
// texture's rugged marks there: striations crossed from border to border by a raised ridge (3 ×
// the striations high: a region at the border, never marked), a pit (3 × deep, a paraboloid)
// touching the ridge's lower flank, and a rugged hollow touching its upper flank (a shallow
// depression holding narrow cones of 0.6-3 × the striations' depth: one piece below the
// texture whose score is a cluster of spikes, as a measured land's rough end is). Without step
// 8d nothing of the three is marked (one region, at the border); with it the pit is marked as a
// region of its own would be and the hollow is not; with the fill test off (a tiny share) the
// hollow is marked too: the shape test is what drops it.
TEST(SelfSimMap, ABorderRegionsDefectPieceIsKeptItsRuggedTexturePieceDropped) {
    auto [h, ridge, pitTruth] = ridgeAndPit();
    std::vector<uint8_t> hollow(h.size(), 0), scratch(h.size(), 0);
    pit(h, hollow, 170, 99, 11, 0.6);  // the hollow's base, its rim on the ridge's other flank
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> off(-7.0, 7.0), depth(0.6, 3.0);
    for (int k = 0; k < 12; ++k) pit(h, scratch, 170 + off(rng), 97 + off(rng), 1.6, depth(rng));
    // the ridge's own samples (where the pit and the hollow are not painted over its flanks) and
    // the pit's off the ridge
    for (size_t i = 0; i < h.size(); ++i) {
        const bool pitHere = pitTruth[i] != 0, hollowHere = hollow[i] || scratch[i];
        pitTruth[i] = pitHere && !ridge[i];
        ridge[i] = ridge[i] && !pitHere && !hollowHere;
        hollow[i] = hollowHere;
    }

    SelfSimMapOptions off8d = before8u();
    off8d.borderPieceFill = 0;
    off8d.pileUpReach = 0;
    SelfSimMapOptions on =
        before8u();         // the pieces alone: their pile-up (borderPieceRim, step 8e) is
    on.borderPieceRim = 0;  // tested below
    on.pileUpReach = 0;
    ASSERT_GT(on.borderPieceFill, 0.0);
    SelfSimMapOptions anyShape = on;
    anyShape.borderPieceFill = 1e-6;
    const SelfSimMap a = detectSelfSimDefects(h, kW, kH, off8d),
                     b = detectSelfSimDefects(h, kW, kH, on),
                     c = detectSelfSimDefects(h, kW, kH, anyShape);
    const Counts pa = count(a.map, pitTruth, on.border), pb = count(b.map, pitTruth, on.border),
                 pc = count(c.map, pitTruth, on.border);
    const Counts ha = count(a.map, hollow, on.border), hb = count(b.map, hollow, on.border),
                 hc = count(c.map, hollow, on.border);
    const Counts ra = count(a.map, ridge, on.border), rb = count(b.map, ridge, on.border);
    EXPECT_GE(a.droppedBorder, 1u);
    EXPECT_EQ(a.borderPieces, 0u);
    EXPECT_EQ(pa.hits, 0u) << "the pit, without step 8d (joined to the ridge at the border)";
    EXPECT_EQ(ha.hits, 0u) << "the hollow, without step 8d";
    EXPECT_EQ(ra.hits, 0u) << "the ridge, without step 8d";
    EXPECT_GE(pb.hits, pb.truth * 8 / 10)
        << "the pit, with step 8d: " << pb.hits << " of " << pb.truth;
    EXPECT_EQ(hb.hits, 0u) << "the rugged hollow, with step 8d: " << hb.hits << " of " << hb.truth;
    EXPECT_EQ(rb.hits, 0u) << "the ridge, with step 8d: it reaches the border";
    EXPECT_GE(b.borderPieces, 1u);
    EXPECT_GE(hc.hits, hc.truth / 2)
        << "the hollow with any shape kept: " << hc.hits << " of " << hc.truth;
    EXPECT_GE(pc.hits, pb.hits);
    EXPECT_GT(c.borderPieces, b.borderPieces);
    EXPECT_EQ(markedOnlyIn(a, b), 0u) << "samples marked without step 8d and not with it";
}

// Step 8f splits a region that reaches the border at rising levels of its own score. Striations
// with two rough stretches, each from a border into the map (a shallow trough, 0.3 × the
// striations deep and 24 samples wide, below the texture's RMS, strewn with narrow cones of
// 0.6-3 × their depth, as a measured land's rough end is): at the end of one a pit (3 × deep, a
// paraboloid), at the end of the other a rugged hollow (a shallow depression holding such cones).
// At the growth's 2.5 σ each defect is one piece below the texture with its stretch, which
// reaches the border, so step 8d keeps neither. Above the stretch's score the pit is a piece of
// its own, off the border and shaped as one depression: with step 8f it is marked, the hollow is
// not (its pieces are clusters of spikes), and with the shape tests off (tiny shares) the hollow
// is marked too: they are what drops it. The stretches are never marked.
TEST(SelfSimMap, ABorderRegionSplitAtRisingLevelsKeepsThePitNotTheRuggedHollow) {
    std::vector<float> h = striations(71);
    std::vector<uint8_t> rough(h.size(), 0), pitTruth(h.size(), 0), hollow(h.size(), 0);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> off(-7.0, 7.0), depth(0.6, 3.0), along(0.0, 100.0),
        across(-8.0, 8.0);
    for (int k = 0; k < 150; ++k) {
        pit(h, rough, along(rng), 70 + across(rng), 2.0, depth(rng));
        pit(h, rough, kW - 1 - along(rng) * 1.15, 150 + across(rng), 2.0, depth(rng));
    }
    pit(h, pitTruth, 109, 70, 8, 3.0);  // at the end of the first stretch
    pit(h, hollow, 143, 150, 11, 0.6);  // the hollow's base, at the end of the second
    for (int k = 0; k < 12; ++k) pit(h, hollow, 143 + off(rng), 150 + off(rng), 1.6, depth(rng));
    for (size_t i = 0; i < h.size(); ++i) rough[i] = rough[i] && !pitTruth[i] && !hollow[i];

    SelfSimMapOptions off8f = before8u();
    off8f.borderLevelStep = 0.0;
    SelfSimMapOptions on = before8u();
    ASSERT_EQ(on.borderLevelStep, 1.25);
    SelfSimMapOptions anyShape = on;
    anyShape.borderLevelFill = 1e-6;
    anyShape.borderLevelShape = 1e-6;
    const SelfSimMap a = detectSelfSimDefects(h, kW, kH, off8f),
                     b = detectSelfSimDefects(h, kW, kH, on),
                     c = detectSelfSimDefects(h, kW, kH, anyShape);
    const Counts pa = count(a.map, pitTruth, on.border), pb = count(b.map, pitTruth, on.border);
    const Counts ha = count(a.map, hollow, on.border), hb = count(b.map, hollow, on.border),
                 hc = count(c.map, hollow, on.border);
    const Counts ta = count(a.map, rough, on.border), tb = count(b.map, rough, on.border),
                 tc = count(c.map, rough, on.border);
    EXPECT_GE(a.droppedBorder, 2u);
    EXPECT_EQ(a.borderLevelPieces, 0u);
    EXPECT_EQ(pa.hits, 0u)
        << "the pit, without step 8f (joined to its rough stretch at the border)";
    EXPECT_EQ(ha.hits, 0u) << "the hollow, without step 8f";
    EXPECT_GE(pb.hits, pb.truth / 2) << "the pit, with step 8f: " << pb.hits << " of " << pb.truth;
    EXPECT_EQ(hb.hits, 0u) << "the rugged hollow, with step 8f: " << hb.hits << " of " << hb.truth;
    EXPECT_GE(b.borderLevelPieces, 1u);
    EXPECT_GE(hc.hits, hc.truth / 4)
        << "the hollow with any shape kept: " << hc.hits << " of " << hc.truth;
    EXPECT_GT(c.borderLevelPieces, b.borderLevelPieces);
    EXPECT_EQ(ta.hits + tb.hits, 0u) << "the rough stretches: " << ta.hits << ", " << tb.hits;
    EXPECT_GT(tc.hits, 0u) << "the rough stretches with any shape kept";
    EXPECT_EQ(markedOnlyIn(a, b), 0u) << "samples marked without step 8f and not with it";
}

// Step 8h: a piece step 8f kept takes back its basin. Striations with a rough stretch from a
// border into the map (a shallow trough strewn with narrow cones, as step 8f's test above) and
// a wide pit (a paraboloid, 3 × the striations deep) at its end: step 8f keeps the pit's upper
// part only, the level where it stands off its stretch; its lower flanks, below that level, are
// one piece with the stretch. With step 8h the pit takes them back (at least a quarter more of
// its label, everything step 8f marked still marked) and the stretch's samples stay unmarked
// (its cones are the texture's markers: what floods to them first is theirs); a basin bound
// below what the pit takes back (borderBasinGrowth) gives step 8f's map byte for byte.
TEST(SelfSimMap, ABorderPieceTakesBackItsBasinNotItsRoughStretch) {
    std::vector<float> h = striations(71);
    std::vector<uint8_t> rough(h.size(), 0), pitTruth(h.size(), 0);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> depth(0.6, 3.0), along(0.0, 100.0), across(-8.0, 8.0);
    for (int k = 0; k < 150; ++k) pit(h, rough, along(rng), 70 + across(rng), 2.0, depth(rng));
    pit(h, pitTruth, 109, 70, 8, 3.0);  // at the end of the stretch
    for (size_t i = 0; i < h.size(); ++i) rough[i] = rough[i] && !pitTruth[i];

    SelfSimMapOptions on = before8u();
    ASSERT_EQ(on.borderBasin, 1.1);  // the default
    SelfSimMapOptions off8h = on;
    off8h.borderBasin = 0.0;
    SelfSimMapOptions bounded = on;
    bounded.borderBasinGrowth = 0.01;
    const SelfSimMap a = detectSelfSimDefects(h, kW, kH, off8h),
                     b = detectSelfSimDefects(h, kW, kH, on),
                     c = detectSelfSimDefects(h, kW, kH, bounded);
    const Counts pa = count(a.map, pitTruth, on.border), pb = count(b.map, pitTruth, on.border);
    const Counts ta = count(a.map, rough, on.border), tb = count(b.map, rough, on.border);
    EXPECT_GE(a.borderLevelPieces, 1u);
    EXPECT_EQ(a.borderBasin, 0u);
    EXPECT_GE(pb.hits, pa.hits + pa.hits / 4) << "the pit with its basin: " << pb.hits << " of "
                                              << pb.truth << " (" << pa.hits << " without)";
    EXPECT_GT(b.borderBasin, 0u);
    EXPECT_EQ(ta.hits + tb.hits, 0u) << "the rough stretch: " << ta.hits << ", " << tb.hits;
    EXPECT_EQ(markedOnlyIn(a, b), 0u) << "samples marked without step 8h and not with it";
    EXPECT_EQ(c.map, a.map) << "the basin bounded below what it takes: step 8f's map";
    EXPECT_EQ(c.borderBasin, 0u);
}

// A pit with a pile-up rim (model A's shape, synth/DefectInsert.h: a ring of width ρ/2 outside
// the crater, profile h_r·(1 − u²)²) whose rim touches a raised ridge that runs from border to
// border: the crater is kept as a border piece (step 8d); with borderPieceRim its rim, raised and
// within 2 samples of the crater, is marked too; the ridge, more than 2 samples from the crater,
// is not marked either way.
TEST(SelfSimMap, ABorderPiecesPileUpIsMarkedTheRaisedTextureBesideItIsNot) {
    std::vector<float> h = striations(53);
    std::vector<uint8_t> ridge(h.size(), 0), crater(h.size(), 0), rim(h.size(), 0);
    groove(h, ridge, 0, 112, kW - 1, 112, 10, -3.0);  // raised, across the whole map, to y 117
    const double cx = 120, rho = 7, d = 3, w = rho / 2, cy = 117 + rho + w;
    pit(h, crater, cx, cy, rho, d);
    // the rim holds half the crater's volume: 2π (ρ + w/2) w h_r 8/15 = 0.5 π ρ² d / 2
    const double hr = 0.5 * rho * rho * d / 2 / (2 * (rho + w / 2) * w * 8 / 15);
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            const double u = (std::hypot(x - cx, y - cy) - rho - w / 2) / (w / 2);
            if (std::abs(u) >= 1) continue;
            const double v = hr * (1 - u * u) * (1 - u * u);
            const size_t i = static_cast<size_t>(y) * kW + x;
            h[i] += static_cast<float>(v);
            rim[i] = v >= 0.1 * d && !crater[i] ? 1 : 0;  // labelled as the insertion labels
        }
    for (size_t i = 0; i < h.size(); ++i) ridge[i] = ridge[i] && !crater[i] && !rim[i];

    SelfSimMapOptions noRim = before8u();  // the border pieces' rim alone: step 8e is tested below
    noRim.borderPieceRim = 0;
    noRim.pileUpReach = 0;
    SelfSimMapOptions on = before8u();
    on.pileUpReach = 0;
    ASSERT_EQ(on.borderPieceRim, 2);
    const SelfSimMap a = detectSelfSimDefects(h, kW, kH, noRim),
                     b = detectSelfSimDefects(h, kW, kH, on);
    const Counts ca = count(a.map, crater, on.border), cb = count(b.map, crater, on.border);
    const Counts ra = count(a.map, rim, on.border), rb = count(b.map, rim, on.border);
    const Counts ga = count(a.map, ridge, on.border), gb = count(b.map, ridge, on.border);
    EXPECT_GE(a.borderPieces, 1u);
    EXPECT_GE(ca.hits, ca.truth * 8 / 10) << "the crater: " << ca.hits << " of " << ca.truth;
    EXPECT_EQ(cb.hits, ca.hits) << "the crater, with its rim";
    EXPECT_EQ(ra.hits, 0u) << "the rim without borderPieceRim (a raised piece is never kept)";
    EXPECT_GE(rb.hits, rb.truth / 2) << "the rim with it: " << rb.hits << " of " << rb.truth;
    EXPECT_EQ(b.borderRim, rb.marked - ra.marked);
    EXPECT_EQ(ga.hits, 0u) << "the ridge, without the rim rule";
    EXPECT_EQ(gb.hits, 0u) << "the ridge, with it: more than 2 samples from the crater";
    size_t added = 0, outside = 0;
    for (size_t i = 0; i < h.size(); ++i) {
        if (!b.map[i] || a.map[i]) continue;
        ++added;
        outside += rim[i] ? 0 : 1;
    }
    EXPECT_EQ(added, b.borderRim);
    EXPECT_LE(outside, added / 4) << "added samples outside the rim's label";
}

// Step 8e: a kept region below the texture takes its pile-up. Striations with a groove (3 × the
// striations deep, across the lay, off the border) whose banks, the rows just outside its
// label, are raised by 1.8 × the residual's σ_0 (a scratch's pile-up, weaker than the growth's
// 2.5 σ: most of it is no region of its own), and a burr (the same groove raised) whose banks
// are lowered as much. Without step 8e the groove is marked and at most half of its banks'
// samples; with it at least half and twice as many as without, every sample it adds is raised
// and 9 in 10 lie within two samples of the groove's label; the burr's lowered banks are marked
// as without (a raised region takes no pile-up), and nothing marked before is dropped.
TEST(SelfSimMap, AGroovesPileUpIsMarkedTheBanksOfARaisedBurrAreNot) {
    std::vector<float> h = striations(61);
    const double sigma = detectSelfSimDefects(h, kW, kH).sigma;
    ASSERT_GT(sigma, 0.0);
    std::vector<uint8_t> grooveTruth(h.size(), 0), burrTruth(h.size(), 0);
    groove(h, grooveTruth, 70, 80, 190, 80, 6, 3.0);
    groove(h, burrTruth, 70, 150, 190, 150, 6, -3.0);  // depth < 0: raised
    // the banks: the samples just above and below each label, in the columns it spans
    std::vector<uint8_t> grooveBanks(h.size(), 0), burrBanks(h.size(), 0);
    auto banks = [&](const std::vector<uint8_t>& label, std::vector<uint8_t>& bank, double dh) {
        for (int y = 1; y < kH - 1; ++y)
            for (int x = 0; x < kW; ++x) {
                const size_t i = static_cast<size_t>(y) * kW + x;
                if (label[i] || !(label[i - kW] || label[i + kW])) continue;
                bank[i] = 1;
                h[i] += static_cast<float>(dh);
            }
    };
    banks(grooveTruth, grooveBanks, 1.8 * sigma);
    banks(burrTruth, burrBanks, -1.8 * sigma);

    SelfSimMapOptions off;  // step 8e alone: step 8g (the banks, tested below) off in both
    off.pileUpReach = 0;
    off.grooveBankWidth = 0.0;
    SelfSimMapOptions on;
    on.grooveBankWidth = 0.0;
    ASSERT_EQ(on.pileUpReach, 1);
    const SelfSimMap a = detectSelfSimDefects(h, kW, kH, off),
                     b = detectSelfSimDefects(h, kW, kH, on);
    const Counts ga = count(a.map, grooveTruth, on.border),
                 gb = count(b.map, grooveTruth, on.border);
    const Counts pa = count(a.map, grooveBanks, on.border),
                 pb = count(b.map, grooveBanks, on.border);
    const Counts ua = count(a.map, burrTruth, on.border), ub = count(b.map, burrTruth, on.border);
    const Counts la = count(a.map, burrBanks, on.border), lb = count(b.map, burrBanks, on.border);
    EXPECT_GE(ga.hits, ga.truth * 9 / 10) << "the groove, without step 8e";
    EXPECT_GE(ua.hits, ua.truth * 9 / 10) << "the burr, without step 8e";
    EXPECT_EQ(gb.hits, ga.hits) << "the groove, with step 8e";
    EXPECT_EQ(ub.hits, ua.hits) << "the burr, with step 8e";
    EXPECT_EQ(a.pileUp, 0u);
    EXPECT_LE(pa.hits * 2, pa.truth)
        << "the groove's banks without step 8e: " << pa.hits << " of " << pa.truth;
    EXPECT_GE(pb.hits * 2, pb.truth) << "the groove's banks with step 8e: " << pb.hits << " of "
                                     << pb.truth << " (" << pa.hits << " without)";
    EXPECT_GE(pb.hits, 2 * pa.hits);
    EXPECT_EQ(lb.hits, la.hits) << "the burr's lowered banks: a raised region takes no pile-up";
    EXPECT_EQ(markedOnlyIn(a, b), 0u) << "samples marked without step 8e and not with it";
    // what step 8e added: raised, and next to the groove's label or its banks (a bank's sample
    // above the growth's 2.5 σ is in the groove's region, and step 8e reaches a sample beyond)
    const auto [added, lowered, away] =
        addedSamples(a, b, [&](int x, int y) { return nearLabel(grooveTruth, x, y, 2); });
    EXPECT_EQ(added, b.pileUp);
    EXPECT_EQ(lowered, 0u) << "step 8e adds raised samples only";
    EXPECT_LE(away * 10, added) << away << " of the " << added
                                << " samples added lie away from the groove";
}

// Step 8d runs on a texture, not on a map that its own repeats explain almost exactly (a relief
// on a flat background, as the logo: its residual's σ_0 is 1/250-1/440 of its RMS, the measured
// textures' 1/7-1/56, and a step of the relief leaves a band below it as smooth as a defect).
// The ridge-and-pit scene of the border pieces' test, whose σ_0 is ~8 % of its RMS: with the
// default share the pit is kept, as with no share at all; with a share above the scene's own,
// the scene counts as a relief and the map is the one without step 8d.
TEST(SelfSimMap, BorderPiecesAreSplitOnATextureNotOnAMapItsRepeatsExplain) {
    auto [h, ridge, pitTruth] = ridgeAndPit();
    for (size_t i = 0; i < h.size(); ++i) pitTruth[i] = pitTruth[i] && !ridge[i];
    SelfSimMapOptions off8d;
    off8d.borderPieceFill = 0;
    const SelfSimMapOptions on;
    SelfSimMapOptions everyMap, relief;
    everyMap.borderPieceSigma = 0;
    const SelfSimMap a = detectSelfSimDefects(h, kW, kH, off8d),
                     b = detectSelfSimDefects(h, kW, kH, on),
                     c = detectSelfSimDefects(h, kW, kH, everyMap);
    const double share = b.sigma / b.textureRms;
    EXPECT_GT(share, 2 * on.borderPieceSigma) << "a texture";
    EXPECT_LT(share, 0.5);
    relief.borderPieceSigma = 0.5;  // the scene's share below it: a relief
    const SelfSimMap d = detectSelfSimDefects(h, kW, kH, relief);
    const Counts pa = count(a.map, pitTruth, on.border), pb = count(b.map, pitTruth, on.border);
    EXPECT_EQ(pa.hits, 0u) << "the pit without step 8d";
    EXPECT_GE(b.borderPieces, 1u);
    EXPECT_GE(pb.hits, pb.truth * 8 / 10)
        << "the pit on a texture: " << pb.hits << " of " << pb.truth;
    EXPECT_EQ(b.map, c.map) << "on a texture the share changes nothing";
    EXPECT_EQ(d.borderPieces, 0u);
    EXPECT_EQ(d.map, a.map) << "a relief: no piece split off, the map without step 8d";
}

TEST(SelfSimMap, GaussianTailInverseIsExact) {
    EXPECT_NEAR(gaussianTailInverse(0.5), 0.0, 1e-9);
    EXPECT_NEAR(gaussianTailInverse(0.05), 1.6448536269514722, 1e-9);
    EXPECT_NEAR(gaussianTailInverse(0.5 * std::erfc(5.0 / std::sqrt(2.0))), 5.0, 1e-9);
}

TEST(SelfSimMap, ScalingByAPowerOfTwoChangesNothingAndAConstantMapMarksNothing) {
    std::vector<float> h = striations(7);
    std::vector<uint8_t> t(h.size(), 0);
    pit(h, t, 120, 110, 5, 1.0);
    std::vector<float> scaled(h);
    for (float& v : scaled) v *= 4.0f;  // exact in float: every step scales by 4
    const SelfSimMap a = detectSelfSimDefects(h, kW, kH), b = detectSelfSimDefects(scaled, kW, kH);
    EXPECT_EQ(a.map, b.map);
    EXPECT_GT(count(a.map, t, 0).hits, 0u);
    const std::vector<float> flat(h.size(), 3.5f);
    const SelfSimMap c = detectSelfSimDefects(flat, kW, kH);
    EXPECT_EQ(count(c.map, t, 0).marked, 0u);
}

TEST(SelfSimMap, BadOptionsNameThemselvesAndTheMethodIsInTheTable) {
    auto expectNamed = [](SelfSimMapOptions o, const char* name) {
        try {
            checkSelfSimMapOptions(o);
            ADD_FAILURE() << name << " accepted";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
        }
    };
    SelfSimMapOptions o;
    o.patch = 4;
    expectNamed(o, "selfsim-patch");
    o = {};
    o.searchRadius = o.exclusion;
    expectNamed(o, "selfsim-search-radius");
    o = {};
    o.nfa = 0;
    expectNamed(o, "selfsim-nfa");
    o = {};
    o.growScale = o.scales;
    expectNamed(o, "selfsim-grow-scale");
    o = {};
    o.tailQuantile = 1.0;
    expectNamed(o, "selfsim-tail-quantile");
    o = {};
    o.borderPieceRim = -1;
    expectNamed(o, "selfsim-border-piece-rim");
    o = {};
    o.borderPieceSigma = 1.0;
    expectNamed(o, "selfsim-border-piece-sigma");
    o = {};
    o.borderBasin = 1.0;
    expectNamed(o, "selfsim-border-basin");
    o = {};
    o.borderBasinGrowth = -1.0;
    expectNamed(o, "selfsim-border-basin-growth");
    o = {};
    o.lineElongation = 0.5;
    expectNamed(o, "selfsim-line-elongation");
    o = {};
    o.lineAngle = 91;
    expectNamed(o, "selfsim-line-angle");
    o = {};
    o.lineLayContrast = 0.9;
    expectNamed(o, "selfsim-line-lay-contrast");
    o = {};
    o.burrElongation = 0.5;
    expectNamed(o, "selfsim-burr-elongation");
    o = {};
    o.burrBasin = 1.0;
    expectNamed(o, "selfsim-burr-basin");
    o = {};
    o.hollowRowGap = -1.0;
    expectNamed(o, "selfsim-hollow-row-gap");
    o = {};
    o.hollowRowMembers = 1;
    expectNamed(o, "selfsim-hollow-row-members");
    o = {};
    o.chainTolerance = 0.6;
    expectNamed(o, "selfsim-hollow-chain-tolerance");
    o = {};
    o.chainLayAngle = 91.0;
    expectNamed(o, "selfsim-hollow-chain-lay-angle");
    o = {};
    o.farBankReach = -1.0;
    expectNamed(o, "selfsim-far-bank-reach");
    o = {};
    o.roughnessCutoff = -1.0;
    expectNamed(o, "selfsim-roughness-cutoff");
    o = {};
    o.layLineElongation = 0.5;
    expectNamed(o, "selfsim-lay-line-elongation");
    o = {};
    o.layLineAngle = 91.0;
    expectNamed(o, "selfsim-lay-line-angle");
    o = {};
    o.layLineStandOut = -1.0;
    expectNamed(o, "selfsim-lay-line-stand-out");
    o = {};
    o.layLineStandOutMax = -1.0;
    expectNamed(o, "selfsim-lay-line-stand-out-max");
    o = {};
    o.layLineReach = 0;
    expectNamed(o, "selfsim-lay-line-reach");
    o = {};
    o.layLineSigma = 0.0;
    expectNamed(o, "selfsim-lay-line-sigma");
    o = {};
    o.layLineWidth = 0.0;
    expectNamed(o, "selfsim-lay-line-width");
    o = {};
    o.lineCopiesSigma = -1.0;
    expectNamed(o, "selfsim-line-copies-sigma");
    o = {};
    o.valleyLineSigma = -1.0;
    expectNamed(o, "selfsim-valley-line-sigma");
    o = {};
    o.valleyLineGrow = 20.0;
    expectNamed(o, "selfsim-valley-line-grow");
    o = {};
    o.valleyLineGate = 2.0;
    expectNamed(o, "selfsim-valley-line-gate");
    o = {};
    o.rimBandMean = -0.1;
    expectNamed(o, "selfsim-rim-band-mean");
    o = {};
    o.rimBandShare = 1.5;
    expectNamed(o, "selfsim-rim-band-share");
    o = {};
    o.rimBandReach = 0.0;
    expectNamed(o, "selfsim-rim-band-reach");
    o = {};
    o.rimBandSegment = -1.0;
    expectNamed(o, "selfsim-rim-band-segment");
    o = {};
    o.edgeRingSigma = -1.0;
    expectNamed(o, "selfsim-edge-ring-sigma");
    o = {};
    o.edgeRingShare = 0.0;
    expectNamed(o, "selfsim-edge-ring-share");
    o = {};
    o.edgeRingCell = 0;
    expectNamed(o, "selfsim-edge-ring-cell");
    o = {};
    o.valleyRimMean = -1.0;
    expectNamed(o, "selfsim-valley-rim-mean");
    o = {};
    o.valleyRimShare = 1.5;
    expectNamed(o, "selfsim-valley-rim-share");
    o = {};
    o.valleyRimReach = 0.0;
    expectNamed(o, "selfsim-valley-rim-reach");
    o = {};
    o.pileUpReach = -1;
    expectNamed(o, "selfsim-pile-up-reach");
    o = {};
    o.pileUpSigma = 0;
    expectNamed(o, "selfsim-pile-up-sigma");
    o = {};
    o.pileUpShare = 0;
    expectNamed(o, "selfsim-pile-up-share");
    o = {};
    o.grooveBankWidth = -1;
    expectNamed(o, "selfsim-groove-bank-width");
    o = {};
    o.grooveLength = -0.5;
    expectNamed(o, "selfsim-groove-length");
    o = {};
    o.grooveRimSigma = -1.0;
    expectNamed(o, "selfsim-groove-rim-sigma");
    o = {};
    o.grooveRimLength = -1.0;
    expectNamed(o, "selfsim-groove-rim-length");
    o = {};
    o.grooveRimWidth = 0.0;
    expectNamed(o, "selfsim-groove-rim-width");
    o = {};
    o.grooveRimShare = 1.0;
    expectNamed(o, "selfsim-groove-rim-share");
    o = {};
    o.textureNfa = -1;
    expectNamed(o, "selfsim-texture-nfa");
    o = {};
    o.lineNfa = -1;
    expectNamed(o, "selfsim-line-nfa");
    o = {};
    o.textureQuantile = 1.0;
    expectNamed(o, "selfsim-texture-quantile");
    o = {};
    o.extendSteps = -1;
    expectNamed(o, "selfsim-extend-steps");
    o = {};
    o.extendSigma = 0;
    expectNamed(o, "selfsim-extend-sigma");
    o = {};
    o.extendShare = 1.0;
    expectNamed(o, "selfsim-extend-share");
    o = {};
    o.trimShare = 1.0;
    expectNamed(o, "selfsim-trim-share");
    o = {};
    o.particleElongation = -1.0;
    expectNamed(o, "selfsim-particle-elongation");
    o = {};
    o.particleRaisedShare = 0.0;
    expectNamed(o, "selfsim-particle-raised-share");
    o = {};
    o.borderPieceFill = 1.0;
    expectNamed(o, "selfsim-border-piece-fill");
    o = {};
    o.borderPieceMin = 0;
    expectNamed(o, "selfsim-border-piece-min");
    o = {};
    o.borderLevelStep = 1.0;
    expectNamed(o, "selfsim-border-level-step");
    o = {};
    o.borderLevelFill = 1.0;
    expectNamed(o, "selfsim-border-level-fill");
    o = {};
    o.borderLevelShape = -0.1;
    expectNamed(o, "selfsim-border-level-shape");

    EXPECT_EQ(parseDefectMethod("selfsim"), DefectMethod::SelfSim);
    EXPECT_STREQ(defectMethodName(DefectMethod::SelfSim), "selfsim");
    std::vector<float> h = striations(9);
    std::vector<uint8_t> t(h.size(), 0);
    pit(h, t, 100, 100, 6, 1.0);
    DefectMapOptions d;
    d.method = DefectMethod::SelfSim;
    const DefectMap viaTable = detectDefects(h, kW, kH, d);
    EXPECT_EQ(viaTable.map, detectSelfSimDefects(h, kW, kH, d.selfsim).map);
    EXPECT_EQ(viaTable.method, DefectMethod::SelfSim);
    EXPECT_GT(viaTable.selfsimRegions, 0u);
}

// Step 8g: a mark below the texture that is a line takes its banks. Striations with a groove
// (3 × the striations deep, 6 samples wide, across the lay) whose banks, strips 3 samples wide
// on each side of its label, stand 3.5 × the residual's σ_0 above the texture (a scratch's
// pile-up, as wide as the groove: above the growth's 2.5 σ, below the texture's RMS, so not a
// region of its own); a raised strip as high, 16 samples from the groove, parallel to it; and a
// burr (the same groove raised) with such strips beside it. Without step 8g at most 3 in 5 of the
// groove's banks are marked (those the groove's region holds, and step 8e's row); with it at
// least 2 in 3 (a sixth of the banks score below 2.5 σ) and a tenth more, every sample it adds is
// raised and lies within the groove's width of its mark; the far strip and the burr's strips are
// marked neither way (too far; a raised mark takes no banks), nothing marked before is dropped, and
// a pit (as wide as it is long: no line) takes none of its ring.
TEST(SelfSimMap, AGroovesBanksAreMarkedTheRaisedTextureBeyondThemIsNot) {
    std::vector<float> h = striations(67);
    const double sigma = detectSelfSimDefects(h, kW, kH).sigma;
    ASSERT_GT(sigma, 0.0);
    std::vector<uint8_t> grooveTruth(h.size(), 0), burrTruth(h.size(), 0), pitTruth(h.size(), 0);
    groove(h, grooveTruth, 60, 80, 196, 80, 6, 3.0);
    groove(h, burrTruth, 60, 150, 196, 150, 6, -3.0);  // depth < 0: raised
    pit(h, pitTruth, 128, 116, 6, 3.0);
    const double bank = 3.5 * sigma;
    std::vector<uint8_t> grooveBanks(h.size(), 0), farStrip(h.size(), 0), burrBanks(h.size(), 0),
        pitBanks(h.size(), 0);
    auto strip = [&](std::vector<uint8_t>& mask, int x0, int x1, int y0, int y1) {
        raiseBox(h, mask, x0, x1, y0, y1, bank);
    };
    strip(grooveBanks, 60, 196, 75, 77);  // beside the label (rows 78-82)
    strip(grooveBanks, 60, 196, 83, 85);
    strip(farStrip, 60, 196, 96, 98);
    strip(burrBanks, 60, 196, 145, 147);
    strip(burrBanks, 60, 196, 153, 155);
    for (int y = 105; y <= 127; ++y)  // the pit's ring: 6 to 9 samples from its centre
        for (int x = 117; x <= 139; ++x) {
            const double d = std::hypot(x - 128.0, y - 116.0);
            if (d < 6.0 || d > 9.0) continue;
            const size_t i = static_cast<size_t>(y) * kW + x;
            pitBanks[i] = 1;
            h[i] += static_cast<float>(bank);
        }

    SelfSimMapOptions on = before8u();
    ASSERT_EQ(on.grooveBankWidth, 1.0);
    on.rimBandMean = 0.0;  // step 8s judges the banks 8g leaves
    SelfSimMapOptions off = on;
    off.grooveBankWidth = 0.0;
    const SelfSimMap a = detectSelfSimDefects(h, kW, kH, off),
                     b = detectSelfSimDefects(h, kW, kH, on);
    const Counts ga = count(a.map, grooveTruth, on.border),
                 gb = count(b.map, grooveTruth, on.border);
    const Counts ka = count(a.map, grooveBanks, on.border),
                 kb = count(b.map, grooveBanks, on.border);
    const Counts fa = count(a.map, farStrip, on.border), fb = count(b.map, farStrip, on.border);
    const Counts ua = count(a.map, burrTruth, on.border), ub = count(b.map, burrTruth, on.border);
    const Counts la = count(a.map, burrBanks, on.border), lb = count(b.map, burrBanks, on.border);
    const Counts pa = count(a.map, pitTruth, on.border), pb = count(b.map, pitTruth, on.border);
    const Counts ra = count(a.map, pitBanks, on.border), rb = count(b.map, pitBanks, on.border);
    EXPECT_GE(ga.hits, ga.truth * 9 / 10) << "the groove";
    EXPECT_GE(ua.hits, ua.truth * 9 / 10) << "the burr";
    EXPECT_GE(pa.hits, pa.truth * 9 / 10) << "the pit";
    EXPECT_EQ(gb.hits, ga.hits);
    EXPECT_EQ(ub.hits, ua.hits);
    EXPECT_EQ(pb.hits, pa.hits);
    EXPECT_EQ(a.grooveBanks, 0u);
    EXPECT_LE(ka.hits * 5, ka.truth * 3)
        << "the groove's banks without step 8g: " << ka.hits << " of " << ka.truth;
    EXPECT_GE(kb.hits * 3, kb.truth * 2)
        << "the groove's banks with step 8g: " << kb.hits << " of " << kb.truth;
    EXPECT_GE((kb.hits - ka.hits) * 10, kb.truth)
        << "step 8g adds at least a tenth of the banks: " << ka.hits << " -> " << kb.hits;
    EXPECT_EQ(fa.hits + fb.hits, 0u) << "the far strip: " << fa.hits << ", " << fb.hits;
    EXPECT_EQ(lb.hits, la.hits) << "the burr's strips: a raised mark takes no banks";
    EXPECT_EQ(rb.hits, ra.hits) << "the pit's ring: a pit is no line";
    EXPECT_EQ(markedOnlyIn(a, b), 0u) << "samples marked without step 8g and not with it";
    // the groove's mark ± its width (8)
    const auto [added, lowered, away] =
        addedSamples(a, b, [](int, int y) { return y >= 72 && y <= 88; });
    EXPECT_EQ(added, b.grooveBanks);
    EXPECT_GT(added, 0u);
    EXPECT_EQ(lowered, 0u) << "step 8g adds raised samples only";
    EXPECT_EQ(away, 0u) << away << " of the " << added << " samples added lie away from the groove";
}

// Step 8o: a long groove whose ground beside it stands mostly above the texture takes its raised
// rims from a score of 1. Striations with three grooves across the lay (3 × the striations deep,
// 6 samples wide): a long one (165 samples) with rims, strips 3 samples wide on each side of its
// label 1.8 × the residual's σ_0 high (a scratch's pile-up, below the growth's 2.5 σ and step 8g's
// banks); a long one without rims; a short one (20 samples: no line of 15 widths) with such rims.
// Off (the default) step 8o adds nothing; on (1 σ), at least two in three of the long groove's
// rims are marked, a fifth of them more than without it, every sample it adds is raised and lies
// within the groove's width of its mark, the groove without rims and the short groove take
// nothing from it, a raised strip as high beyond the reach is not marked, and nothing is dropped.
TEST(SelfSimMap, AGroovesRaisedRimsAreMarkedAGrooveWithoutRimsTakesNothing) {
    std::vector<float> h = striations(71);
    const double sigma = detectSelfSimDefects(h, kW, kH).sigma;
    ASSERT_GT(sigma, 0.0);
    std::vector<uint8_t> longTruth(h.size(), 0), bareTruth(h.size(), 0), shortTruth(h.size(), 0);
    groove(h, longTruth, 45, 70, 210, 70, 6, 3.0);
    groove(h, bareTruth, 45, 120, 210, 120, 6, 3.0);
    groove(h, shortTruth, 110, 165, 130, 165, 6, 3.0);
    const double rim = 1.8 * sigma;
    std::vector<uint8_t> longRims(h.size(), 0), shortRims(h.size(), 0), farStrip(h.size(), 0);
    auto strip = [&](std::vector<uint8_t>& mask, int x0, int x1, int y0, int y1) {
        raiseBox(h, mask, x0, x1, y0, y1, rim);
    };
    strip(longRims, 45, 210, 65, 67);  // beside the label (rows 68-72)
    strip(longRims, 45, 210, 73, 75);
    strip(farStrip, 45, 210, 92, 94);
    strip(shortRims, 110, 130, 160, 162);
    strip(shortRims, 110, 130, 168, 170);

    SelfSimMapOptions off = before8u();
    ASSERT_EQ(off.grooveRimSigma, 0.0);
    off.rimBandMean = 0.0;  // step 8s judges the rims 8o leaves
    SelfSimMapOptions on = off;
    on.grooveRimSigma = 1.0;
    const SelfSimMap a = detectSelfSimDefects(h, kW, kH, off),
                     b = detectSelfSimDefects(h, kW, kH, on);
    const Counts la = count(a.map, longTruth, on.border), ra = count(a.map, longRims, on.border),
                 rb = count(b.map, longRims, on.border);
    const Counts ba = count(a.map, bareTruth, on.border), sa = count(a.map, shortTruth, on.border);
    const Counts sra = count(a.map, shortRims, on.border), srb = count(b.map, shortRims, on.border);
    const Counts fa = count(a.map, farStrip, on.border), fb = count(b.map, farStrip, on.border);
    EXPECT_GE(la.hits, la.truth * 9 / 10) << "the long groove";
    EXPECT_GE(ba.hits, ba.truth * 9 / 10) << "the groove without rims";
    EXPECT_GE(sa.hits, sa.truth * 9 / 10) << "the short groove";
    EXPECT_EQ(a.grooveRims, 0u);
    EXPECT_GE(rb.hits * 3, rb.truth * 2)
        << "the long groove's rims with step 8o: " << rb.hits << " of " << rb.truth;
    EXPECT_GE((rb.hits - ra.hits) * 5, rb.truth)
        << "step 8o adds at least a fifth of the rims: " << ra.hits << " -> " << rb.hits;
    EXPECT_EQ(srb.hits, sra.hits) << "the short groove's rims: no line";
    EXPECT_EQ(fb.hits, fa.hits) << "the far strip";
    EXPECT_EQ(markedOnlyIn(a, b), 0u) << "samples marked without step 8o and not with it";
    // the long groove's mark ± its width
    const auto [added, lowered, away] =
        addedSamples(a, b, [](int, int y) { return y >= 58 && y <= 82; });
    EXPECT_EQ(added, b.grooveRims);
    EXPECT_GT(added, 0u);
    EXPECT_EQ(lowered, 0u) << "step 8o adds raised samples only";
    EXPECT_EQ(away, 0u) << away << " of the " << added
                        << " samples added lie away from the long groove";
}

// Step 8i: a piece of a region at the border that is a line crossing the texture's lay is kept
// whatever its depth profile. Striae along z that do not repeat across them (the sum of four
// sines along x of incommensurate periods, amplitude 1, and white noise of σ 0.05: a tile
// repeats along z only, its lay) crossed from border to border by a raised ridge (3 × high, 10
// samples wide, along x); from its lower flank two grooves run off, each 1.5 × deep and 5
// samples wide with a deep spot (a pit 6 × deep, ρ 3) in its middle: one across the striae
// (about 7° from x), one along them (along z). At the growth's 2.5 σ each is one region with the
// ridge, which reaches the border; the deep spot puts the groove's mean score far below its
// largest (step 8d's fill) and at every level of step 8f it is no depression (its shape). With
// step 8i the groove across the striae is marked (at least 6 in 10 of its samples, against at
// most a third without it: step 8f keeps the deep spot alone); the one along them gains nothing (a
// stria's direction), the ridge is not marked, and asking for a right angle (lineAngle 90) keeps no
// line. The pile-up and the banks (steps 8e, 8g) are off: they would take the ridge's flank beside
// a kept groove.
TEST(SelfSimMap, ALineAcrossTheLayIsKeptAtTheBorderOneAlongItIsNot) {
    std::vector<float> h = aperiodicStriae(53);
    std::vector<uint8_t> ridge(h.size(), 0), across(h.size(), 0), along(h.size(), 0);
    groove(h, ridge, 0, 112, kW - 1, 112, 10, -3.0);
    groove(h, across, 120, 116, 200, 126, 5, 1.5);
    pit(h, across, 160, 121, 3, 6.0);
    groove(h, along, 70, 116, 70, 176, 5, 1.5);
    pit(h, along, 70, 146, 3, 6.0);
    // the ridge beyond 5 samples of the grooves (where they cut its flank, the groove's tail is
    // its basin)
    const std::vector<uint8_t> ridgePainted = ridge;
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            bool nearGroove = false;
            for (int qy = std::max(0, y - 5); qy <= std::min(kH - 1, y + 5); ++qy)
                for (int qx = std::max(0, x - 5); qx <= std::min(kW - 1, x + 5); ++qx) {
                    const size_t q = static_cast<size_t>(qy) * kW + qx;
                    nearGroove = nearGroove || across[q] || along[q];
                }
            const size_t i = static_cast<size_t>(y) * kW + x;
            ridge[i] = ridgePainted[i] && !nearGroove;
        }

    SelfSimMapOptions off = before8u();
    off.lineElongation = 0.0;
    off.pileUpReach = 0;
    off.grooveBankWidth = 0.0;
    SelfSimMapOptions on = off;
    on.lineElongation = SelfSimMapOptions{}.lineElongation;
    ASSERT_GT(on.lineElongation, 0.0);
    SelfSimMapOptions square = on;
    square.lineAngle = 90.0;
    const SelfSimMap a = detectSelfSimDefects(h, kW, kH, off),
                     b = detectSelfSimDefects(h, kW, kH, on),
                     c = detectSelfSimDefects(h, kW, kH, square);
    const Counts xa = count(a.map, across, on.border), xb = count(b.map, across, on.border);
    const Counts za = count(a.map, along, on.border), zb = count(b.map, along, on.border);
    const Counts rb = count(b.map, ridge, on.border);
    EXPECT_GE(a.droppedBorder, 1u);
    EXPECT_EQ(a.borderLines, 0u);
    EXPECT_LE(xa.hits, xa.truth / 3)
        << "the groove across, without step 8i: " << xa.hits << " of " << xa.truth;
    EXPECT_GE(xb.hits, xb.truth * 6 / 10)
        << "the groove across, with step 8i: " << xb.hits << " of " << xb.truth;
    EXPECT_GE(xb.hits, xa.hits + xa.truth / 4);
    EXPECT_GE(b.borderLines, 1u);
    EXPECT_EQ(zb.hits, za.hits) << "the groove along the striae";
    EXPECT_EQ(rb.hits, 0u) << "the ridge";
    EXPECT_EQ(c.borderLines, 0u) << "a right angle asked for";
    EXPECT_EQ(c.map, a.map) << "a right angle asked for";
}

// Step 8j's and 8n's scene: aperiodic striae (along z) crossed from border to border by a
// trench along x (3 × deep, 10 samples wide); from its lower bank two burrs rise (2 × high, 5
// samples wide), one 40° from x (50° from the lay), one along z.
struct BurrScene {
    std::vector<float> h;
    std::vector<uint8_t> trench, across, along;
};
BurrScene burrsFromATrench() {
    BurrScene s{aperiodicStriae(59), {}, {}, {}};
    s.trench.assign(s.h.size(), 0);
    s.across.assign(s.h.size(), 0);
    s.along.assign(s.h.size(), 0);
    groove(s.h, s.trench, 0, 112, kW - 1, 112, 10, 3.0);
    groove(s.h, s.across, 120, 118, 180, 168, 5, -2.0);
    groove(s.h, s.along, 60, 118, 60, 178, 5, -2.0);
    return s;
}

// Step 8j: a raised piece of a region at the border that is a line crossing the texture's lay
// (a burr across the striae) is kept. The striae of step 8i's test (along z, no repeat across
// them) crossed from border to border by a trench along x (3 × deep, 10 samples wide); from its
// lower bank two burrs rise (2 × high, 5 samples wide), one 40° from x (50° from the lay), one
// along z. At the growth's 2.5 σ each burr is one region with the trench, which reaches the
// border, and steps 8d-8i keep only pieces below the texture. With step 8j the burr across the
// striae is marked (at least 6 in 10 of its samples), the one along them gains nothing, every
// sample added is raised and on the burr or beside it (8b's flanks), and asking for a right angle
// (lineAngle 90) keeps no raised line.
TEST(SelfSimMap, ARaisedLineAcrossTheLayIsKeptAtTheBorderOneAlongItIsNot) {
    const BurrScene scene = burrsFromATrench();
    const std::vector<float>& h = scene.h;
    const std::vector<uint8_t>&across = scene.across, &along = scene.along;

    SelfSimMapOptions off;
    SelfSimMapOptions on = off;
    on.burrElongation = 8.0;
    SelfSimMapOptions square = on;
    square.lineAngle = 90.0;
    const SelfSimMap a = detectSelfSimDefects(h, kW, kH, off),
                     b = detectSelfSimDefects(h, kW, kH, on),
                     c = detectSelfSimDefects(h, kW, kH, square);
    const Counts xa = count(a.map, across, on.border), xb = count(b.map, across, on.border);
    const Counts za = count(a.map, along, on.border), zb = count(b.map, along, on.border);
    EXPECT_GE(a.droppedBorder, 1u);
    EXPECT_EQ(a.raisedLines, 0u);
    EXPECT_LE(xa.hits, xa.truth / 3)
        << "the burr across, without step 8j: " << xa.hits << " of " << xa.truth;
    EXPECT_GE(xb.hits, xb.truth * 6 / 10)
        << "the burr across, with step 8j: " << xb.hits << " of " << xb.truth;
    EXPECT_GE(b.raisedLines, 1u);
    EXPECT_EQ(zb.hits, za.hits) << "the burr along the striae";
    EXPECT_EQ(markedOnlyIn(a, b), 0u) << "samples marked without step 8j and not with it";
    const auto [added, lowered, away] =
        addedSamples(a, b, [&](int x, int y) { return nearLabel(across, x, y, 2); });
    EXPECT_GT(added, 0u);
    EXPECT_EQ(lowered, 0u) << "step 8j adds raised samples only";
    EXPECT_EQ(away, 0u) << away << " of the " << added << " samples added lie off the burr";
    EXPECT_EQ(c.raisedLines, 0u) << "a right angle asked for";
    EXPECT_EQ(c.map, a.map) << "a right angle asked for";
}

// Step 8n: a burr step 8j kept takes back its basin. The scene of step 8j's test (a raised line
// across the striae joined to a trench that runs from border to border): 8j keeps the burr's
// top, cut at a level above the trench; with 8n its flanks above the texture down to the
// growth's level are marked too, every sample added raised and on the burr (within 2 samples);
// the burr along the striae and the trench are marked neither way; with 8j off 8n marks nothing.
TEST(SelfSimMap, ABurrAcrossTheLayTakesBackItsBasinTheTextureBesideItDoesNot) {
    const BurrScene scene = burrsFromATrench();
    const std::vector<float>& h = scene.h;
    const std::vector<uint8_t>&across = scene.across, &along = scene.along;

    SelfSimMapOptions j = before8u();
    ASSERT_EQ(j.burrBasin, 0.0);  // the default: off
    j.burrElongation = 8.0;
    SelfSimMapOptions n = j;
    n.burrBasin = 1.1;
    SelfSimMapOptions alone = before8u();
    alone.burrBasin = 1.1;
    const SelfSimMap a = detectSelfSimDefects(h, kW, kH, j), b = detectSelfSimDefects(h, kW, kH, n),
                     c = detectSelfSimDefects(h, kW, kH, alone),
                     off = detectSelfSimDefects(h, kW, kH);
    const Counts xa = count(a.map, across, j.border), xb = count(b.map, across, j.border);
    const Counts za = count(a.map, along, j.border), zb = count(b.map, along, j.border);
    ASSERT_GE(a.raisedLines, 1u);
    EXPECT_EQ(a.burrBasin, 0u);
    EXPECT_GT(b.burrBasin, 0u);
    EXPECT_GT(xb.hits, xa.hits) << "the burr across with its basin: " << xb.hits << " of "
                                << xb.truth << " (" << xa.hits << " without)";
    EXPECT_EQ(zb.hits, za.hits) << "the burr along the striae";
    EXPECT_EQ(markedOnlyIn(a, b), 0u) << "samples marked without step 8n and not with it";
    const auto [added, lowered, away] =
        addedSamples(a, b, [&](int x, int y) { return nearLabel(across, x, y, 2); });
    EXPECT_GT(added, 0u);
    EXPECT_EQ(lowered, 0u) << "step 8n adds raised samples only";
    EXPECT_EQ(away, 0u) << away << " of the " << added << " samples added lie off the burr";
    EXPECT_EQ(c.map, off.map) << "step 8j off: no burr, no basin";
    EXPECT_EQ(c.burrBasin, 0u);
}

// Step 8k: a row of hollows, each dropped alone, is kept. Striations (seed 61, noise σ 0.02)
// with three sets of pits, each 0.25 deep (about 8 σ of the residual, under the texture's RMS, so
// step 6 drops each alone) and 3 samples in radius: a row of six, 8 samples apart, 30° from x;
// six scattered 40 samples or more apart; four in a square 8 samples on a side. The row is
// marked (at least 6 in 10 of its samples); the scattered pits and the square (not a line) are
// not; with the step off nothing of them is.
TEST(SelfSimMap, ARowOfHollowsIsKeptScatteredOrClusteredHollowsAreNot) {
    std::vector<float> h = striations(61, 0.02);
    std::vector<uint8_t> row(h.size(), 0), scattered(h.size(), 0), square(h.size(), 0);
    constexpr double kDepth = 0.25, kRho = 3.0;
    for (int k = 0; k < 6; ++k)
        pit(h, row, 70 + 8 * k * std::cos(M_PI / 6), 70 + 8 * k * std::sin(M_PI / 6), kRho, kDepth);
    const double spots[6][2] = {{60, 150}, {110, 170}, {160, 150},
                                {200, 60}, {200, 110}, {150, 60}};
    for (const auto& s : spots) pit(h, scattered, s[0], s[1], kRho, kDepth);
    for (int k = 0; k < 4; ++k) pit(h, square, 180 + 8 * (k % 2), 170 + 8 * (k / 2), kRho, kDepth);

    SelfSimMapOptions off;
    off.hollowRowGap = 0.0;
    SelfSimMapOptions on = off;
    on.hollowRowGap = SelfSimMapOptions{}.hollowRowGap;
    ASSERT_GT(on.hollowRowGap, 0.0);
    const SelfSimMap a = detectSelfSimDefects(h, kW, kH, off),
                     b = detectSelfSimDefects(h, kW, kH, on);
    const Counts ra = count(a.map, row, on.border), rb = count(b.map, row, on.border);
    const Counts sb = count(b.map, scattered, on.border), qb = count(b.map, square, on.border);
    EXPECT_GE(a.droppedShallow, 6u);
    EXPECT_EQ(ra.hits, 0u) << "the row, without step 8k";
    EXPECT_GE(rb.hits, rb.truth * 6 / 10) << "the row: " << rb.hits << " of " << rb.truth;
    EXPECT_EQ(b.hollowRows, 1u);
    EXPECT_EQ(b.rowHollows, 6u);
    EXPECT_EQ(sb.hits, 0u) << "the scattered pits";
    EXPECT_EQ(qb.hits, 0u) << "the square of pits";
    EXPECT_EQ(markedOnlyIn(a, b), 0u) << "samples marked without step 8k and not with it";
    const Added d = addedSamples(a, b, [&](int x, int y) { return nearLabel(row, x, y, 2); });
    const size_t added = d.added, away = d.away;
    EXPECT_GT(added, 0u);
    EXPECT_EQ(away, 0u) << away << " of the " << added << " samples added lie off the row";
}

// Step 8p: a chain of hollows on a rough stretch. Striations with two rough stretches from the
// borders into the map (step 8f's test's: shallow troughs strewn with narrow cones). On the
// first lies a chain of five pits (ρ 2.5, 6 × deep, twice the deepest cone), 9 samples apart on a
// straight line; on the second five such pits on a line unevenly spaced (6, 14, 7 and 13 samples
// apart). Each pit is one piece with its stretch at the growth's 2.5 σ and stands off it above
// the stretch's score, but is smaller than borderPieceMin, so steps 8d and 8f keep none of them
// (and step 8k sees only regions off the border). With step 8p the chain is marked (at least half
// its samples, at least four of its pits kept), the uneven row is not, the stretches gain less than
// half what the chain gains (the pits' flanks where they touch a cone), and nothing marked
// without it is lost.
TEST(SelfSimMap, AChainOfHollowsOnARoughStretchIsKeptAnUnevenRowIsNot) {
    std::vector<float> h = striations(71);
    std::vector<uint8_t> rough(h.size(), 0), chain(h.size(), 0), uneven(h.size(), 0);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> depth(0.6, 3.0), along(0.0, 100.0), across(-8.0, 8.0);
    for (int k = 0; k < 150; ++k) {
        pit(h, rough, along(rng), 70 + across(rng), 2.0, depth(rng));
        pit(h, rough, kW - 1 - along(rng) * 1.15, 150 + across(rng), 2.0, depth(rng));
    }
    constexpr double kRho = 2.5, kDepth = 6.0;
    for (int k = 0; k < 5; ++k) pit(h, chain, 50 + 9 * k, 68 + 1.5 * k, kRho, kDepth);
    const double at[5] = {0, 6, 20, 27, 40};
    for (const double s : at) pit(h, uneven, kW - 92 + s, 148 + 0.2 * s, kRho, kDepth);
    for (size_t i = 0; i < h.size(); ++i) rough[i] = rough[i] && !chain[i] && !uneven[i];

    SelfSimMapOptions off = before8u();
    off.chainTolerance = 0.0;
    SelfSimMapOptions on = off;
    on.chainTolerance = 0.2;
    const SelfSimMap a = detectSelfSimDefects(h, kW, kH, off),
                     b = detectSelfSimDefects(h, kW, kH, on);
    const Counts ca = count(a.map, chain, on.border), cb = count(b.map, chain, on.border);
    const Counts ub = count(b.map, uneven, on.border), ua = count(a.map, uneven, on.border);
    const Counts ta = count(a.map, rough, on.border), tb = count(b.map, rough, on.border);
    EXPECT_GE(a.droppedBorder, 2u);
    EXPECT_EQ(ca.hits, 0u) << "the chain, without step 8p";
    EXPECT_GE(cb.hits, cb.truth / 2) << "the chain: " << cb.hits << " of " << cb.truth;
    EXPECT_EQ(b.hollowChains, 1u);
    EXPECT_GE(b.chainHollows, 4u);
    EXPECT_EQ(ub.hits, ua.hits) << "the uneven row";
    EXPECT_LT(2 * (tb.hits - ta.hits), cb.hits)
        << "the rough stretches (the pits' flanks where they touch a cone): " << ta.hits << " -> "
        << tb.hits;
    EXPECT_EQ(markedOnlyIn(a, b), 0u) << "samples marked without step 8p and not with it";
}

// Step 8q: a groove's far banks. Striations with a groove (3 × the striations deep, 6 samples
// wide, across the lay) whose banks, strips 3 samples wide, stand 6 × the residual's σ_0 above the
// texture 5 samples off its label on each side (apart from it below the growth's 2.5 σ: regions
// of their own, below the texture's RMS, so dropped; step 8g floods only what touches the
// groove); a raised strip as high 17 samples from the groove's axis, parallel to it; and a burr
// (the same groove raised) with such strips beside it. With step 8q (reach 10) the groove's banks
// are marked (at least 3 in 4 of them, in two regions or more; none without it); the far strip and
// the burr's strips are not, and nothing marked without it is lost.
TEST(SelfSimMap, AGroovesFarBanksAreMarkedAFarStripAndABurrsStripsAreNot) {
    std::vector<float> h = striations(67);
    const double sigma = detectSelfSimDefects(h, kW, kH).sigma;
    ASSERT_GT(sigma, 0.0);
    std::vector<uint8_t> grooveTruth(h.size(), 0), burrTruth(h.size(), 0);
    groove(h, grooveTruth, 60, 80, 196, 80, 6, 3.0);
    groove(h, burrTruth, 60, 150, 196, 150, 6, -3.0);  // depth < 0: raised
    std::vector<uint8_t> banks(h.size(), 0), farStrip(h.size(), 0), burrStrips(h.size(), 0);
    auto strip = [&](std::vector<uint8_t>& mask, int y0) {
        raiseBox(h, mask, 60, 196, y0, y0 + 2, 6.0 * sigma);
    };
    strip(banks, 70);  // the label is rows 78-82
    strip(banks, 88);
    strip(farStrip, 96);
    strip(burrStrips, 142);
    strip(burrStrips, 156);

    SelfSimMapOptions off = before8u();
    off.farBankReach = 0.0;
    SelfSimMapOptions on = off;
    on.farBankReach = 10.0;
    const SelfSimMap a = detectSelfSimDefects(h, kW, kH, off),
                     b = detectSelfSimDefects(h, kW, kH, on);
    const Counts ga = count(a.map, grooveTruth, on.border), ka = count(a.map, banks, on.border),
                 kb = count(b.map, banks, on.border);
    const Counts fa = count(a.map, farStrip, on.border), fb = count(b.map, farStrip, on.border);
    const Counts la = count(a.map, burrStrips, on.border), lb = count(b.map, burrStrips, on.border);
    EXPECT_GE(ga.hits, ga.truth * 9 / 10) << "the groove";
    EXPECT_EQ(ka.hits, 0u) << "the banks without step 8q";
    EXPECT_GE(kb.hits * 4, kb.truth * 3) << "the banks: " << kb.hits << " of " << kb.truth;
    EXPECT_GE(b.farBanks, 2u);
    EXPECT_EQ(fb.hits, fa.hits) << "the far strip";
    EXPECT_EQ(lb.hits, la.hits) << "the burr's strips";
    EXPECT_EQ(markedOnlyIn(a, b), 0u) << "samples marked without step 8q and not with it";
}

// Step 6 with roughnessCutoff: the RMS a region must reach is the roughness's, not the form's. A
// land's curved shoulders are form the quadratic of step 1 leaves in g (16 u^8 across x, u = -1..1:
// 16 × the striations high at the edges); a pit 1.2 × the striations deep stands far above the
// residual and above the striations' roughness, but below the RMS of g, which the form makes.
// Without the cutoff step 6 drops the pit as shallow; with it (λc 96 samples) the pit is marked
// and nothing farther than 10 samples from its centre. On the striations without the form the
// roughness's RMS is the map's to within 5 % (the filter takes out nothing of a texture whose
// period is well below λc), and a pit 0.2 deep, which stands out of the residual (marked with no
// RMS gate), stays below the roughness: not marked.
TEST(SelfSimMap, TheRoughnessRmsJudgesAPitOnACurvedLandTheFormDoesNot) {
    auto curved = [](std::vector<float> h) {
        for (int y = 0; y < kH; ++y)
            for (int x = 0; x < kW; ++x) {
                const double u = (x - kW / 2.0) / (kW / 2.0);
                h[static_cast<size_t>(y) * kW + x] += static_cast<float>(16.0 * std::pow(u, 8));
            }
        return h;
    };
    std::vector<float> h = striations(61);
    std::vector<uint8_t> pitTruth(h.size(), 0);
    pit(h, pitTruth, 128, 112, 6, 1.2);
    const std::vector<float> land = curved(h);
    SelfSimMapOptions off, on;
    off.roughnessCutoff = 0;
    on.roughnessCutoff = 96;
    const SelfSimMap a = detectSelfSimDefects(land, kW, kH, off),
                     b = detectSelfSimDefects(land, kW, kH, on);
    EXPECT_EQ(a.shallowRms, a.textureRms);
    EXPECT_LT(b.shallowRms * 2.0, b.textureRms) << "the form is most of the map's RMS";
    const Counts pa = count(a.map, pitTruth, on.border), pb = count(b.map, pitTruth, on.border);
    EXPECT_LT(pa.hits * 10, pa.truth) << "dropped as shallower than the form's RMS";
    EXPECT_GT(a.droppedShallow, 0u);
    EXPECT_GE(pb.hits, pb.truth * 8 / 10) << "the pit, judged against the roughness";
    size_t far = 0;
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x)
            if (b.map[static_cast<size_t>(y) * kW + x] && std::hypot(x - 128.0, y - 112.0) > 10.0)
                ++far;
    EXPECT_EQ(far, 0u) << "the striations and the form are not marked";

    // the striations alone (no form): the roughness's RMS is the map's, and a pit that stands
    // out of the residual (marked with no RMS gate) but not out of the roughness is not marked
    std::vector<float> flat = striations(62);
    std::vector<uint8_t> shallowTruth(flat.size(), 0);
    pit(flat, shallowTruth, 128, 112, 6, 0.2);
    SelfSimMapOptions noGate = on;
    noGate.textureRms = 0;
    const SelfSimMap c = detectSelfSimDefects(flat, kW, kH, on),
                     d = detectSelfSimDefects(flat, kW, kH, noGate);
    EXPECT_NEAR(c.shallowRms, c.textureRms, 0.05 * c.textureRms);
    const Counts sc = count(c.map, shallowTruth, on.border),
                 sd = count(d.map, shallowTruth, on.border);
    EXPECT_GE(sd.hits, sd.truth / 3) << "it stands out of the residual";
    EXPECT_EQ(sc.hits, 0u) << "but not out of the roughness (RMS " << c.shallowRms << ")";
}

// Step 8l: a mark along the texture's lay takes the samples beside it that stand out of the
// residual whose copies all cross the lay. Striations along z that repeat exactly along z and
// only roughly across it (a period-9 profile plus a random value per column, σ 0.07, and white
// noise of σ 0.05: the copies across the lay differ more than those along it) with a groove
// along them (x 100, 3 × deep, 6 samples wide) and the same groove across them (y 160, x
// 130-200); beside each, 4 to 5 samples from its axis on both sides, raised strips (its banks,
// 1.5 × the residual's σ high: under the growth's 2.5 σ and beyond the pile-up's reach, so
// steps 6-8i leave most of them); far from both, a strip as high. Step 7 is off (the columns'
// own regions make a tail above the grooves). With step 8l the banks of the groove along the
// lay are marked (at least half of them, against at most a fifth without it); the banks of the
// groove across the lay gain nothing (no line along the lay; the copies across the lay land on
// it, so r keeps more of it than r_x), though a quarter of them are taken when any line is
// asked for (angle 90, no test of what r keeps); the far strip gains nothing; nothing is added
// more than layLineReach samples from the marks it starts from, nor away from the groove along
// the lay; asking for a mark that stands out by 1000 σ adds nothing. Off (the default), nothing
// is added.
TEST(SelfSimMap, ALineAlongTheLayTakesItsBanksOneAcrossItDoesNot) {
    std::vector<float> h = peakedStriae(0.07);
    const double sigma = detectSelfSimDefects(h, kW, kH).sigma;
    ASSERT_GT(sigma, 0.0);
    std::vector<uint8_t> alongTruth(h.size(), 0), acrossTruth(h.size(), 0);
    groove(h, alongTruth, 100, 60, 100, 170, 6, 3.0);
    groove(h, acrossTruth, 130, 160, 200, 160, 6, 3.0);
    std::vector<uint8_t> alongBanks(h.size(), 0), acrossBanks(h.size(), 0), farStrip(h.size(), 0);
    const double bank = 1.5 * sigma;
    auto strip = [&](std::vector<uint8_t>& mask, int x0, int x1, int y0, int y1) {
        raiseBox(h, mask, x0, x1, y0, y1, bank);
    };
    strip(alongBanks, 95, 96, 62, 168);  // the label is x 98-102
    strip(alongBanks, 104, 105, 62, 168);
    strip(acrossBanks, 132, 198, 155, 156);
    strip(acrossBanks, 132, 198, 164, 165);
    strip(farStrip, 150, 151, 60, 130);

    EXPECT_EQ(SelfSimMapOptions{}.layLineElongation, 4.0) << "step 8l is on by default";
    SelfSimMapOptions off = before8u();
    off.textureNfa = 0.0;  // the columns' regions make a tail above the grooves
    off.layLineElongation = 0.0;
    SelfSimMapOptions on = off;
    on.layLineElongation = 4.0;
    SelfSimMapOptions strict = on;
    strict.layLineStandOut = 1000.0;
    SelfSimMapOptions anyLine = on;  // any direction, explained by itself or not
    anyLine.layLineAngle = 90.0;
    anyLine.layLineKept = 0.0;
    const SelfSimMap a = detectSelfSimDefects(h, kW, kH, off),
                     b = detectSelfSimDefects(h, kW, kH, on),
                     c = detectSelfSimDefects(h, kW, kH, strict),
                     d = detectSelfSimDefects(h, kW, kH, anyLine);
    const Counts ga = count(a.map, alongTruth, on.border), gb = count(b.map, alongTruth, on.border);
    const Counts xa = count(a.map, acrossTruth, on.border);
    const Counts ka = count(a.map, alongBanks, on.border), kb = count(b.map, alongBanks, on.border);
    const Counts ca = count(a.map, acrossBanks, on.border),
                 cb = count(b.map, acrossBanks, on.border);
    const Counts fa = count(a.map, farStrip, on.border), fb = count(b.map, farStrip, on.border);
    EXPECT_GE(ga.hits, ga.truth / 2) << "the groove along the lay";
    EXPECT_GE(xa.hits, xa.truth / 2) << "the groove across the lay";
    EXPECT_EQ(a.layLines, 0u);
    EXPECT_EQ(a.layLineSamples, 0u);
    EXPECT_LE(ka.hits * 5, ka.truth)
        << "the banks without step 8l: " << ka.hits << " of " << ka.truth;
    EXPECT_GE(kb.hits * 2, kb.truth) << "the banks with step 8l: " << kb.hits << " of " << kb.truth;
    EXPECT_GE(gb.hits, ga.hits);
    EXPECT_GE(b.layLines, 1u);
    EXPECT_EQ(cb.hits, ca.hits) << "the banks of the groove across the lay";
    const Counts cd = count(d.map, acrossBanks, on.border);
    EXPECT_GE(cd.hits * 4, cb.hits * 4 + cb.truth)
        << "the banks of the groove across the lay, any line taken: " << cd.hits << " of "
        << cd.truth;
    EXPECT_EQ(fb.hits, fa.hits) << "the far strip";
    EXPECT_EQ(markedOnlyIn(a, b), 0u) << "step 8l only adds";
    // what step 8l adds lies within layLineReach samples of the marks it starts from, beside
    // the groove along the lay (x 80-120)
    const Added beside = addedSamples(a, b, [&](int x, int y) {
        return x >= 80 && x <= 120 && nearLabel(a.map, x, y, on.layLineReach);
    });
    const size_t added = beside.added, away = beside.away;
    EXPECT_EQ(added, b.layLineSamples);
    EXPECT_EQ(away, 0u) << away << " of the " << added << " samples added lie away from the groove";
    EXPECT_EQ(c.layLineSamples, 0u) << "a mark standing out by 1000 sigma asked for";
    EXPECT_EQ(c.map, a.map);
    // the cap on the stand-out: below the floor no line passes, far above it every line does
    SelfSimMapOptions capped = on, loose = on;
    capped.layLineStandOutMax = 1.0;
    loose.layLineStandOutMax = 1e6;
    EXPECT_EQ(detectSelfSimDefects(h, kW, kH, capped).map, a.map) << "a cap under the floor";
    EXPECT_EQ(detectSelfSimDefects(h, kW, kH, loose).map, b.map) << "a cap far above it";
}

// Step 8r: a line along the texture's lay judged on copies chosen for it. Striations along z (a
// period-9 profile across x plus a random value per column, σ 0.2, and white noise of σ 0.05:
// the striae repeat along z and poorly across, so every offset step 2 keeps lies along the lay)
// with a long groove 8° off them (x 92-108 over y 52-172, 6 samples wide, 2 × the profile
// deep): the copies of a sample on it are the groove itself further along, shifted by a sample
// or two, so r keeps only its edges and ends. The copies chosen for the line (the offsets
// crossing it, matched on the striae beside it) keep its whole depth: with step 8r at least 3/4
// of the groove is marked, against less than 2/3 without, and everything added lies in its
// corridor (x 84-116); a groove across the lay (y 100, x 140-200: no line along the lay) gains
// nothing. Off (the default) nothing is added, and a threshold of 1000 σ_L adds nothing.
TEST(SelfSimMap, ALineAlongTheLayJudgedOnItsOwnCopiesIsMarkedAlongItsLength) {
    std::vector<float> h = peakedStriae(0.2);
    std::vector<uint8_t> alongTruth(h.size(), 0), acrossTruth(h.size(), 0);
    groove(h, alongTruth, 92, 52, 108, 172, 6, 2.0);
    groove(h, acrossTruth, 140, 100, 200, 100, 6, 2.0);
    EXPECT_EQ(SelfSimMapOptions{}.lineCopiesSigma, 0.0) << "step 8r is off by default";
    SelfSimMapOptions off = before8u();
    off.textureNfa = 0.0;  // the columns' regions make a tail above the grooves
    SelfSimMapOptions on = off, strict = off;
    on.lineCopiesSigma = 4.0;
    strict.lineCopiesSigma = 1000.0;
    const SelfSimMap a = detectSelfSimDefects(h, kW, kH, off),
                     b = detectSelfSimDefects(h, kW, kH, on),
                     c = detectSelfSimDefects(h, kW, kH, strict);
    const Counts ga = count(a.map, alongTruth, on.border), gb = count(b.map, alongTruth, on.border);
    const Counts xa = count(a.map, acrossTruth, on.border),
                 xb = count(b.map, acrossTruth, on.border);
    EXPECT_EQ(a.lineCopyLines, 0u);
    EXPECT_EQ(a.lineCopySamples, 0u);
    EXPECT_LT(ga.hits * 3, ga.truth * 2) << "without step 8r: " << ga.hits << " of " << ga.truth;
    EXPECT_GE(gb.hits * 4, gb.truth * 3) << "with step 8r: " << gb.hits << " of " << gb.truth;
    EXPECT_GE(b.lineCopyLines, 1u);
    EXPECT_EQ(xb.hits, xa.hits) << "the groove across the lay";
    EXPECT_EQ(markedOnlyIn(a, b), 0u) << "step 8r only adds";
    size_t added = 0, away = 0;
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            const size_t i = static_cast<size_t>(y) * kW + x;
            if (!b.map[i] || a.map[i]) continue;
            ++added;
            away += x >= 84 && x <= 116 ? 0 : 1;
        }
    EXPECT_EQ(added, b.lineCopySamples);
    EXPECT_EQ(away, 0u) << away << " of the " << added << " samples added lie off the corridor";
    EXPECT_EQ(c.lineCopySamples, 0u) << "1000 sigma_L asked for";
    EXPECT_EQ(c.map, a.map);
}

// Step 8s: a groove's rims judged along it. Striations (seed 71) crossed by three grooves along
// x, each 6 samples wide and 3 × deep: one with rims (a strip of 3 rows on each side raised by
// 3 σ_0), one bare, and one with a strip of the same height 20 rows away (beyond any reach). With
// step 8s the rims beside the first are marked (at least a third more of them), nothing is added
// beside the bare groove or on the far strip, and what is added is above the texture and within the
// first groove's band; asking for a mean of 1000 σ adds nothing. The copies along x (the
// striations' period) follow the strips, so r keeps a quarter to a third of their height: a
// segment's mean is 0.4-1 σ_0.
TEST(SelfSimMap, AGroovesRimsJudgedAlongItAreMarkedABareGrooveTakesNothing) {
    std::vector<float> h = striations(71);
    const double sigma = detectSelfSimDefects(h, kW, kH).sigma;
    ASSERT_GT(sigma, 0.0);
    std::vector<uint8_t> rimmed(h.size(), 0), bare(h.size(), 0), far(h.size(), 0);
    groove(h, rimmed, 45, 70, 210, 70, 6, 3.0);
    groove(h, bare, 45, 120, 210, 120, 6, 3.0);
    groove(h, far, 45, 160, 210, 160, 6, 3.0);
    std::vector<uint8_t> rims(h.size(), 0), farStrip(h.size(), 0);
    raiseBox(h, rims, 45, 210, 64, 66, 3.0 * sigma);
    raiseBox(h, rims, 45, 210, 74, 76, 3.0 * sigma);
    raiseBox(h, farStrip, 45, 210, 178, 180, 3.0 * sigma);

    EXPECT_EQ(SelfSimMapOptions{}.rimBandMean, 0.6) << "step 8s is on by default";
    SelfSimMapOptions off = before8u();
    off.rimBandMean = 0.0;
    const SelfSimMapOptions on = before8u();
    SelfSimMapOptions strict = before8u();
    strict.rimBandMean = 1000.0;
    const SelfSimMap a = detectSelfSimDefects(h, kW, kH, off),
                     b = detectSelfSimDefects(h, kW, kH, on),
                     c = detectSelfSimDefects(h, kW, kH, strict);
    const Counts ga = count(a.map, rimmed, on.border), ba = count(a.map, bare, on.border);
    const Counts ra = count(a.map, rims, on.border), rb = count(b.map, rims, on.border);
    const Counts fa = count(a.map, farStrip, on.border), fb = count(b.map, farStrip, on.border);
    EXPECT_GE(ga.hits, ga.truth * 9 / 10) << "the rimmed groove";
    EXPECT_GE(ba.hits, ba.truth * 9 / 10) << "the bare groove";
    EXPECT_EQ(a.rimBands, 0u);
    EXPECT_EQ(a.rimBandSamples, 0u);
    EXPECT_GE((rb.hits - ra.hits) * 3, rb.truth)
        << "step 8s adds at least a third of the rims: " << ra.hits << " -> " << rb.hits << " of "
        << rb.truth;
    EXPECT_GE(b.rimBands, 1u);
    EXPECT_EQ(fb.hits, fa.hits) << "the strip 20 rows from its groove";
    EXPECT_EQ(markedOnlyIn(a, b), 0u) << "step 8s only adds";
    // the rimmed groove's core ± 0.9 × its width (6 samples) and a sample of rounding
    const auto [added, lowered, away] =
        addedSamples(a, b, [](int, int y) { return y >= 60 && y <= 80; });
    EXPECT_EQ(added, b.rimBandSamples);
    EXPECT_EQ(lowered, 0u) << "step 8s adds raised samples only";
    EXPECT_EQ(away, 0u) << away << " of the " << added
                        << " samples added lie away from the rimmed groove";
    EXPECT_EQ(c.rimBandSamples, 0u) << "1000 sigma asked for";
    EXPECT_EQ(c.map, a.map);
}

// Step 8t's response is a valley's depth below its sides: on flat ground a V groove along x (a
// grid direction), 6 samples wide (inside the ± kValleyOffset the sides are read at), d deep,
// gives d on its axis away from its ends, a ridge -d there is never above 0 and flat ground 0.
TEST(SelfSimMap, TheValleyResponseIsAStraightValleysDepthBelowItsSides) {
    const int w = 96, h = 64;
    std::vector<float> g(static_cast<size_t>(w) * h, 0.0f);
    const double d = 0.75;
    for (int y = 0; y < h; ++y)
        for (int x = 8; x < 88; ++x) {
            const double s = std::abs(y - 20.0);
            if (s < 3.0) g[static_cast<size_t>(y) * w + x] -= static_cast<float>(d * (1 - s / 3));
            const double t = std::abs(y - 44.0);
            if (t < 3.0) g[static_cast<size_t>(y) * w + x] += static_cast<float>(d * (1 - t / 3));
        }
    const std::vector<float> v = valleyResponse(g, w, h);
    for (int x = 30; x <= 66; ++x) {
        EXPECT_NEAR(v[static_cast<size_t>(20) * w + x], d, 1e-6) << "the groove's axis at x " << x;
        EXPECT_LE(v[static_cast<size_t>(44) * w + x], 1e-6) << "the ridge's axis at x " << x;
        EXPECT_NEAR(v[static_cast<size_t>(32) * w + x], 0.0, 1e-6) << "between them at x " << x;
    }
}

// Step 8t on given marks: white noise (σ 0.05, seed 5) with two valleys along x, 5 samples wide
// and 0.3 deep (about 27 σ of the texture's valley response): one continues a mark (a box over
// its first stretch, standing for a groove the map found), the other lies 40 rows away from any
// mark. The first is taken, the second not (no mark within reach), and nothing else; on
// striations, whose own valleys are everywhere, the default gate keeps the step from taking
// anything.
TEST(SelfSimMap, AValleyBesideAMarkIsTakenOneAloneOrOnAValleyedTextureIsNot) {
    std::mt19937 rng(5);
    std::normal_distribution<double> noise(0.0, 0.05);
    std::vector<float> g(static_cast<size_t>(kW) * kH);
    for (float& v : g) v = static_cast<float>(noise(rng));
    std::vector<uint8_t> continued(g.size(), 0), alone(g.size(), 0), map(g.size(), 0);
    for (int y = 0; y < kH; ++y)
        for (int x = 60; x < 200; ++x) {
            const size_t i = static_cast<size_t>(y) * kW + x;
            const double s = std::abs(y - 80.0), t = std::abs(y - 150.0);
            if (s <= 2.0) {
                g[i] -= static_cast<float>(0.3 * (1 - s / 3));
                if (x < 110)
                    map[i] = 255;  // the stretch the map found
                else
                    continued[i] = 1;
            }
            if (t <= 2.0) {
                g[i] -= static_cast<float>(0.3 * (1 - t / 3));
                alone[i] = 1;
            }
        }
    const SelfSimMapOptions o;
    EXPECT_EQ(o.valleyLineSigma, 15.0) << "step 8t is on by default";
    // the two valleys are 4 % of this small map's texture: the gate at 5 % (the default's
    // 0.3 % is for a map of 10^5 samples and more; the striations below test it)
    std::vector<uint8_t> m = map;
    const auto [taken, added] = takeValleyLines(m, g, kW, kH, o.border, o.minRegion,
                                                o.valleyLineSigma, o.valleyLineGrow, 0.05);
    const Counts c = count(m, continued, o.border), a = count(m, alone, o.border);
    EXPECT_GE(taken, 1u);  // the continuation (and the response past the valleys' start)
    EXPECT_GE(c.hits * 10, c.truth * 9) << c.hits << " of the continued valley's " << c.truth;
    EXPECT_EQ(a.hits, 0u) << "the valley with no mark beside it";
    size_t away = 0, n = 0;
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            const size_t i = static_cast<size_t>(y) * kW + x;
            if (!m[i] || map[i]) continue;
            ++n;
            away += std::abs(y - 80) <= 4 ? 0 : 1;
        }
    EXPECT_EQ(n, added);
    EXPECT_EQ(away, 0u) << away << " of the " << added << " samples added lie off the valley";

    std::vector<float> s = striations(3);
    std::vector<uint8_t> sm(s.size(), 0);
    for (int y = 78; y <= 82; ++y)
        for (int x = 60; x < 110; ++x) sm[static_cast<size_t>(y) * kW + x] = 255;
    const std::vector<uint8_t> before = sm;
    const auto [t2, a2] = takeValleyLines(sm, s, kW, kH, o.border, o.minRegion, o.valleyLineSigma,
                                          o.valleyLineGrow, o.valleyLineGate);
    EXPECT_EQ(a2, 0u) << "the striations' own valleys close the gate";
    EXPECT_EQ(sm, before);
}

// Step 8u on given marks and residual (σ_0 1): a mark over x 32-63, y 40-45 (r -6) whose edge
// below it (y 46) keeps its sign (r -1.5, a defect's fringe the copies took most of) and whose
// edge above it (y 39) is the texture (r +1.5 but every third sample -1.5: either sign, 2-3 of 8
// with the mark's). Its ends (x 31 and 64: 6 ring samples in a cell each) are too few to judge.
// The 8 × 8 cells of the fringe are all hits and are taken whole; the texture's cells and the
// ends take nothing; a second mark's fringe inside the border is never taken; a score of 1000
// adds nothing and a share of 1 still takes the fringe.
TEST(SelfSimMap, AMarksEdgeThatKeepsItsSignIsTakenTheTextureBesideItIsNot) {
    const int border = 8;
    std::vector<float> r(static_cast<size_t>(kW) * kH, 0.0f);
    std::vector<uint8_t> map(r.size(), 0), fringe(r.size(), 0);
    const auto at = [](int x, int y) { return static_cast<size_t>(y) * kW + x; };
    for (int x = 32; x <= 63; ++x) {
        for (int y = 40; y <= 45; ++y) {
            map[at(x, y)] = 255;
            r[at(x, y)] = -6.0f;
        }
        r[at(x, 46)] = -1.5f;
        fringe[at(x, 46)] = 1;
        r[at(x, 39)] = x % 3 == 0 ? -1.5f : 1.5f;
        r[at(x, 31)] = r[at(x, 32)] = -1.5f;  // beside nothing marked: not on the ring
    }
    for (int y = 40; y <= 45; ++y) r[at(31, y)] = r[at(64, y)] = -1.5f;
    // a mark against the border, its fringe inside it
    for (int x = 96; x <= 127; ++x) {
        map[at(x, border)] = 255;
        r[at(x, border)] = -6.0f;
        r[at(x, border - 1)] = -1.5f;
    }
    const SelfSimMapOptions o;
    EXPECT_EQ(o.edgeRingSigma, 1.0) << "step 8u is on by default";
    std::vector<uint8_t> m = map;
    const auto [cells, added] =
        takeEdgeRing(m, r, 1.0, kW, kH, border, o.edgeRingSigma, o.edgeRingShare, o.edgeRingCell);
    EXPECT_EQ(cells, 4u) << "the fringe's four cells (x 32-63)";
    EXPECT_EQ(added, 32u);
    std::vector<uint8_t> expected = map;
    for (size_t i = 0; i < m.size(); ++i)
        if (fringe[i]) expected[i] = 255;
    EXPECT_EQ(m, expected) << "the mark and its fringe, nothing else";
    std::vector<uint8_t> strict = map, whole = map;
    EXPECT_EQ(takeEdgeRing(strict, r, 1.0, kW, kH, border, 1000.0, o.edgeRingShare, o.edgeRingCell)
                  .second,
              0u)
        << "1000 sigma asked for";
    EXPECT_EQ(strict, map);
    EXPECT_EQ(
        takeEdgeRing(whole, r, 1.0, kW, kH, border, o.edgeRingSigma, 1.0, o.edgeRingCell).second,
        32u)
        << "every sample of the fringe's cells is a hit";
    // the sign is the mark's: the same fringe raised (+1.5) beside a mark below the texture
    std::vector<float> flipped = r;
    for (int x = 32; x <= 63; ++x) flipped[at(x, 46)] = 1.5f;
    std::vector<uint8_t> f = map;
    EXPECT_EQ(takeEdgeRing(f, flipped, 1.0, kW, kH, border, o.edgeRingSigma, o.edgeRingShare,
                           o.edgeRingCell)
                  .second,
              0u)
        << "a raised edge beside a mark below the texture";
}

// Step 8v on given marks and heights: white noise (σ 0.05, seed 9) with two valleys along x
// (x 60-199, 5 samples wide, 0.3 deep, each marked: lines the map holds), one with a rim on each
// side (rows 3-6 from its axis raised by 0.1, 2 σ of the noise: a scratch's pile-up), one bare.
// Its band (its width, 6 samples) stands 1-2 σ above its ground and is taken: at least 3/4 of
// the rims' samples, nothing beside the bare valley, nothing away from the rimmed one; a mean of
// 1000 σ takes nothing, and with the gate shut (scores.open false) nothing is taken. Off by
// default.
TEST(SelfSimMap, ARimTheHeightsShowBesideAValleyLineIsTakenABareValleyTakesNothing) {
    std::mt19937 rng(9);
    std::normal_distribution<double> noise(0.0, 0.05);
    std::vector<float> g(static_cast<size_t>(kW) * kH);
    for (float& v : g) v = static_cast<float>(noise(rng));
    std::vector<uint8_t> map(g.size(), 0), rims(g.size(), 0);
    for (int y = 0; y < kH; ++y)
        for (int x = 60; x < 200; ++x) {
            const size_t i = static_cast<size_t>(y) * kW + x;
            for (const int axis : {80, 150}) {
                const double s = std::abs(y - static_cast<double>(axis));
                if (s <= 2.0) {
                    g[i] -= static_cast<float>(0.3 * (1 - s / 3));
                    map[i] = 255;
                }
                if (axis == 80 && s >= 3.0 && s <= 6.0) {
                    g[i] += 0.1f;
                    rims[i] = 1;
                }
            }
        }
    const SelfSimMapOptions o;
    EXPECT_EQ(o.valleyRimMean, 0.0) << "step 8v is off by default";
    const ValleyScores scores =
        scoreValleys(map, g, kW, kH, o.border, o.valleyLineSigma, /*gate=*/0.05);
    ASSERT_TRUE(scores.open);
    std::vector<uint8_t> m = map;
    const auto [segments, added] = takeValleyRims(m, g, scores, kW, kH, o.border, o.valleyLineSigma,
                                                  o.valleyLineGrow, 0.5, 0.7, 1.0);
    const Counts c = count(m, rims, o.border);
    EXPECT_GE(segments, 1u);
    EXPECT_GE(c.hits * 4, c.truth * 3) << c.hits << " of the rims' " << c.truth;
    size_t n = 0, beside = 0, away = 0;
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            const size_t i = static_cast<size_t>(y) * kW + x;
            if (!m[i] || map[i]) continue;
            ++n;
            if (std::abs(y - 150) <= 10) ++beside;
            if (std::abs(y - 80) > 8) ++away;
        }
    EXPECT_EQ(n, added);
    EXPECT_EQ(beside, 0u) << "beside the bare valley";
    EXPECT_EQ(away, 0u) << away << " of the " << added << " samples added lie off the band";

    std::vector<uint8_t> strict = map;
    EXPECT_EQ(takeValleyRims(strict, g, scores, kW, kH, o.border, o.valleyLineSigma,
                             o.valleyLineGrow, 1000.0, 0.7, 1.0)
                  .second,
              0u);
    EXPECT_EQ(strict, map);
    ValleyScores shut = scores;
    shut.open = false;
    std::vector<uint8_t> closed = map;
    EXPECT_EQ(takeValleyRims(closed, g, shut, kW, kH, o.border, o.valleyLineSigma, o.valleyLineGrow,
                             0.5, 0.7, 1.0)
                  .second,
              0u)
        << "the gate shut";
    EXPECT_EQ(closed, map);
}

TEST(SelfSimMap, AnEmptyMapSaysWhyWhenRegionsStoodOut) {
    DefectMap m;
    m.method = DefectMethod::SelfSim;
    m.map.assign(16, 0);
    m.selfsimThreshold = 4.998;
    m.selfsimTextureThreshold = 35.16;
    m.selfsimTextureRms = 0.00343;
    EXPECT_EQ(m.whyNothingMarked(), "");  // nothing stood out: nothing to explain
    m.selfsimDroppedTexture = 100;
    m.selfsimDroppedShallow = 2;
    const std::string why = m.whyNothingMarked();
    EXPECT_NE(why.find("102 regions stood out"), std::string::npos) << why;
    EXPECT_NE(why.find("100 no higher than the texture's own tail (35.2 robust sigmas)"),
              std::string::npos)
        << why;
    EXPECT_NE(why.find("2 shallower than its RMS (0.00343"), std::string::npos) << why;
    EXPECT_EQ(why.find("tail of lines"), std::string::npos) << why;  // step 7b off
    m.selfsimLineThreshold = 15.6;
    EXPECT_NE(m.whyNothingMarked().find("(35.2 robust sigmas) and holding no line above its "
                                        "tail of lines"),
              std::string::npos)
        << m.whyNothingMarked();
    EXPECT_EQ(why.find("--"), std::string::npos) << why;  // the library names no option
    m.map[3] = 255;                                       // something marked: nothing to explain
    EXPECT_EQ(m.whyNothingMarked(), "");
    m.map[3] = 0;
    m.method = DefectMethod::Paper;  // only the self-similarity map has these gates
    EXPECT_EQ(m.whyNothingMarked(), "");
}
