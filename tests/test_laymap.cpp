// The defect map's `lay` method (detect/LayMap.h) on synthetic measured-like textures with
// exact ground truth: striae along a tilted lay (a few much deeper than the rest, as a bullet
// land's are) with one pit and one scratch across the lay: the lay direction is found, the pit
// and the scratch are marked, the striae are not; a rough patch at the border is not marked as a
// block, a pit linked to it through the fine texture still is; invariance to h → a·h + b; a
// constant map marks nothing; bad options name themselves; the method table has the row.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "SyntheticDefects.h"
#include "core/Error.h"
#include "detect/DefectMap.h"
#include "detect/LayMap.h"

using namespace sl;

namespace {

constexpr int kW = 320, kH = 256;
constexpr double kLayDeg = 20.0;  // the striae's direction, degrees from the x axis

// Striae: 60 random sinusoids across the lay (wavelengths 3–40 samples) plus six deep single
// striae (a Gaussian groove 2 samples wide, 2.5 units deep) at offset + [−150, 150] across it,
// and white noise of 0.05; RMS ≈ 0.5. across(x, y): the sample's coordinate across the lay.
template <class Across>
std::vector<float> striae(uint32_t seed, double offset, Across across) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::normal_distribution<double> nd(0.0, 0.05);
    struct Wave {
        double k, a, phase;
    };
    std::vector<Wave> waves;
    for (int i = 0; i < 60; ++i)
        waves.push_back({2 * M_PI / (3.0 + 37.0 * u(rng)), 0.08 * u(rng), 2 * M_PI * u(rng)});
    std::vector<double> deep;
    for (int i = 0; i < 6; ++i) deep.push_back(offset - 150.0 + 300.0 * u(rng));
    std::vector<float> h(static_cast<size_t>(kW) * kH);
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            const double q = across(x, y);
            double v = nd(rng);
            for (const Wave& w : waves) v += w.a * std::sin(w.k * q + w.phase);
            for (double d0 : deep) v -= 2.5 * std::exp(-0.5 * std::pow((q - d0) / 1.0, 2));
            h[static_cast<size_t>(y) * kW + x] = static_cast<float>(v);
        }
    return h;
}

// Striae along the tilted lay (kLayDeg from the x axis), a few much deeper than the rest, as a
// bullet land's are.
std::vector<float> striated(uint32_t seed = 5) {
    const double c = std::cos(kLayDeg * M_PI / 180), s = std::sin(kLayDeg * M_PI / 180);
    return striae(seed, 0.0, [c, s](int x, int y) { return -s * x + c * y; });
}

// A paraboloid pit of radius rho and depth d at (cx, cy); returns its truth (within the radius).
std::vector<uint8_t> pit(std::vector<float>& h, double cx, double cy, double rho, double d) {
    std::vector<uint8_t> t(h.size(), 0);
    test::paintPit(h, t, kW, cx, cy, rho, d);
    return t;
}

void groove(std::vector<float>& h, std::vector<uint8_t>& t, double x0, double y0, double x1,
            double y1, double width, double depth) {
    test::paintGroove(h, t, kW, x0, y0, x1, y1, width, depth);
}

// Arced striae: the striated texture's profile along the radius of circles about (cx, cy)
// (outside the map), as a face mill's or a Wyko part's tool marks: no single lay holds.
std::vector<float> arced(double cx, double cy, uint32_t seed = 7) {
    const double r0 = std::hypot(cx - kW / 2.0, cy - kH / 2.0);
    return striae(seed, r0, [cx, cy](int x, int y) { return std::hypot(x - cx, y - cy); });
}

// A dent with no rim: a spherical cap of lateral radius rho and depth d at (cx, cy), truth
// where it is at least 10 % of its depth.
std::vector<uint8_t> dent(std::vector<float>& h, double cx, double cy, double rho, double d) {
    std::vector<uint8_t> t(h.size(), 0);
    const double R = (rho * rho + d * d) / (2 * d);
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            const double q = std::hypot(x - cx, y - cy);
            if (q >= rho) continue;
            const double off = d - (R - std::sqrt(R * R - q * q));
            h[static_cast<size_t>(y) * kW + x] -= static_cast<float>(off);
            if (off >= 0.1 * d) t[static_cast<size_t>(y) * kW + x] = 1;
        }
    return t;
}

struct Counts {
    size_t truth = 0, hits = 0, marked = 0, outside = 0;  // outside: marks > reach from truth
};

Counts count(const std::vector<uint8_t>& map, const std::vector<uint8_t>& truth, int reach = 2) {
    Counts c;
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            const size_t k = static_cast<size_t>(y) * kW + x;
            c.truth += truth[k] != 0;
            if (!map[k]) continue;
            ++c.marked;
            c.hits += truth[k] != 0;
            bool near = false;
            for (int dy = -reach; dy <= reach && !near; ++dy)
                for (int dx = -reach; dx <= reach && !near; ++dx) {
                    const int xx = x + dx, yy = y + dy;
                    near = xx >= 0 && yy >= 0 && xx < kW && yy < kH &&
                           truth[static_cast<size_t>(yy) * kW + xx];
                }
            c.outside += !near;
        }
    return c;
}

}  // namespace

TEST(LayMap, StriaeAreTheBackgroundThePitAndTheScratchAcrossThemAreMarked) {
    std::vector<float> h = striated();
    std::vector<uint8_t> truth = pit(h, 120, 150, 7, 3.0);
    groove(h, truth, 200, 60, 250, 200, 5, 3.0);  // ~70° from the x axis: 50° across the lay
    const LayMap m = detectLayDefects(h, kW, kH);
    const double lay = std::atan2(m.layZ, m.layX) * 180 / M_PI;
    EXPECT_NEAR(std::remainder(lay - kLayDeg, 180.0), 0.0, 2.0) << "lay " << lay;
    const Counts c = count(m.map, truth);
    EXPECT_GE(static_cast<double>(c.hits), 0.8 * static_cast<double>(c.truth));
    // a halo: where a deep stria meets the scratch, the growth at growSigma·σ follows it a few
    // samples; nothing farther than 8 samples from a defect is marked
    EXPECT_LE(static_cast<double>(c.outside), 0.1 * static_cast<double>(c.truth));
    EXPECT_EQ(count(m.map, truth, 8).outside, size_t{0}) << "marked on the striae";
    // the deep striae stand far above the residual's robust σ: without the texture-RMS rule they
    // are what a σ-only threshold marks
    LayMapOptions noRms;
    noRms.textureRms = 0.0;
    noRms.growSigma = 2.0;
    noRms.seedSigma = 3.0;
    const Counts loose = count(detectLayDefects(h, kW, kH, noRms).map, truth, 8);
    EXPECT_GT(loose.outside, size_t{100});
}

TEST(LayMap, ARoughPatchAtTheBorderIsNoBlockAPitLinkedToItStillIs) {
    std::vector<float> h = striated(9);
    // a rough patch (white noise of 1.5, 3× the texture's RMS) in the top-left corner, reaching
    // past the border into the map
    std::mt19937 rng(3);
    std::normal_distribution<double> nd(0.0, 1.5);
    for (int y = 0; y < 110; ++y)
        for (int x = 0; x < 120; ++x)
            h[static_cast<size_t>(y) * kW + x] += static_cast<float>(nd(rng));
    // a pit at the patch's edge, its region linked to the patch at the low grow threshold
    std::vector<uint8_t> truth = pit(h, 130, 90, 8, 4.0);
    const LayMap m = detectLayDefects(h, kW, kH);
    const Counts c = count(m.map, truth);
    EXPECT_GE(static_cast<double>(c.hits), 0.8 * static_cast<double>(c.truth));
    size_t inPatch = 0;
    for (int y = 0; y < 100; ++y)
        for (int x = 0; x < 110; ++x) inPatch += m.map[static_cast<size_t>(y) * kW + x] != 0;
    EXPECT_LE(inPatch, size_t{60}) << "the rough patch at the border is marked as a block";
    EXPECT_GE(m.droppedBorder, size_t{1});
}

TEST(LayMap, InvariantToScaleAndOffsetAndAConstantMapMarksNothing) {
    std::vector<float> h = striated();
    pit(h, 160, 128, 7, 3.0);
    const LayMap m = detectLayDefects(h, kW, kH);
    for (const auto& [a, b] : {std::pair{4.0, 1.0}, std::pair{-0.5, 3.0}}) {
        std::vector<float> g(h.size());
        for (size_t k = 0; k < h.size(); ++k) g[k] = static_cast<float>(a * h[k] + b);
        const LayMap mg = detectLayDefects(g, kW, kH);
        size_t differ = 0;
        for (size_t k = 0; k < h.size(); ++k) differ += (m.map[k] != 0) != (mg.map[k] != 0);
        EXPECT_LE(differ, h.size() / 2000) << "a " << a << " b " << b;  // rounding only
    }
    const std::vector<float> flat(h.size(), 2.5f);
    const LayMap f = detectLayDefects(flat, kW, kH);
    for (uint8_t v : f.map) ASSERT_EQ(v, 0);
}

TEST(LayMap, BadOptionsNameThemselvesAndTheMethodIsInTheTable) {
    const std::vector<float> h(64 * 64, 0.0f);
    LayMapOptions o;
    o.layLength = 60;
    try {
        detectLayDefects(h, 64, 64, o);
        FAIL() << "an even lay length was accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("lay-length"), std::string::npos) << e.what();
    }
    o = {};
    o.growSigma = 7.0;  // above the seed
    EXPECT_THROW(detectLayDefects(h, 64, 64, o), InputError);
    auto names = [&](const LayMapOptions& bad, const char* name) {
        try {
            detectLayDefects(h, 64, 64, bad);
            ADD_FAILURE() << name << " accepted";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
        }
    };
    o = {};
    o.fieldSigma = -1;
    names(o, "lay-field-sigma");
    o = {};
    o.fieldCoherence = 1.5;
    names(o, "lay-field-coherence");
    o = {};
    o.layPasses = 0;
    names(o, "lay-passes");
    o = {};
    o.fieldExclude = -1;
    names(o, "lay-field-exclude");
    EXPECT_EQ(parseDefectMethod("lay"), DefectMethod::Lay);
    DefectMapOptions d;
    d.method = DefectMethod::Lay;
    std::vector<float> s = striated();
    pit(s, 160, 128, 7, 3.0);
    const DefectMap dm = detectDefects(s, kW, kH, d);
    EXPECT_EQ(dm.method, DefectMethod::Lay);
    EXPECT_EQ(dm.map, detectLayDefects(s, kW, kH).map);
}

TEST(LayMap, ArcedStriaeFollowTheLocalLayThePitAndTheRimlessDentAreMarked) {
    // circles about a centre 180 samples left of the map: the lay turns by ~70° over it
    std::vector<float> h = arced(-180, 128);
    std::vector<uint8_t> pitTruth = pit(h, 230, 90, 6, 3.0);
    std::vector<uint8_t> dentTruth = dent(h, 120, 170, 20, 3.0);
    std::vector<uint8_t> both(pitTruth);
    for (size_t k = 0; k < both.size(); ++k) both[k] |= dentTruth[k];
    // the local lay field, a median twice as long, a level wider than the dent
    LayMapOptions curved;
    curved.fieldSigma = 16;
    curved.layLength = 161;
    curved.levelWindow = 81;
    const LayMap m = detectLayDefects(h, kW, kH, curved);
    const Counts p = count(m.map, pitTruth), d = count(m.map, dentTruth);
    EXPECT_GE(static_cast<double>(p.hits), 0.8 * static_cast<double>(p.truth));
    EXPECT_GE(static_cast<double>(d.hits), 0.8 * static_cast<double>(d.truth));
    // the arcs are not marked as a whole: what lies farther than 8 samples from the defects
    // is under a tenth of their samples (93 of 1239 at this seed)
    const double truth = static_cast<double>(p.truth + d.truth);
    EXPECT_LE(static_cast<double>(count(m.map, both, 8).outside), 0.1 * truth)
        << "marked on the arcs";
    // the defaults (one straight lay, 81 samples, a level of 31): the level takes the dent,
    // 40 samples wide, for background
    const LayMap s = detectLayDefects(h, kW, kH);
    const Counts ds = count(s.map, dentTruth);
    EXPECT_LT(static_cast<double>(ds.hits), 0.5 * static_cast<double>(ds.truth))
        << "straight " << count(s.map, both, 8).outside << " outside";
}
