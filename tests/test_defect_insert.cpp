// Inserted defects of known shape (synth/DefectInsert.h) and `insert-defects`: the shapes'
// depths, rims and radii, the labels, determinism, bad input, and the files every --truth
// command takes.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "TestUtil.h"
#include "core/Error.h"
#include "synth/DefectInsert.h"

using namespace sl;
using test::runCli;

TEST(DefectInsert, GrooveCrossSectionDepthAndRimVolume) {
    for (bool rounded : {false, true}) {
        Groove g;
        g.width = 6;
        g.depth = 0.003;
        g.rounded = rounded;
        g.pileUp = 0.6;
        // The middle of a long groove: no taper.
        EXPECT_NEAR(grooveProfile(g, 0, 50, 100), -0.003, 1e-12);
        double removed = 0, piled = 0;
        const double ds = 1e-3;
        for (double s = -20; s <= 20; s += ds) {
            const double v = grooveProfile(g, s, 50, 100);
            (v < 0 ? removed : piled) += std::abs(v) * ds;
        }
        const double area = rounded ? 2.0 / 3.0 * 0.003 * 6 : 0.5 * 0.003 * 6;
        EXPECT_NEAR(removed, area, area * 1e-3);
        EXPECT_NEAR(piled, 0.6 * area, area * 1e-3);
        EXPECT_NEAR(grooveRimHeight(6, 0.003, rounded, 0.6), grooveProfile(g, 3 + 3, 50, 100),
                    1e-12);  // the rim's peak at w/2 + r/2
        // Tapered to nothing at the ends.
        EXPECT_EQ(grooveProfile(g, 0, 0, 100), 0.0);
        EXPECT_EQ(grooveProfile(g, 0, 100, 100), 0.0);
    }
}

TEST(DefectInsert, PitRadiusDepthAndRimVolume) {
    const double r = 8, d = 0.002;
    EXPECT_NEAR(pitProfile(r, d, 0.6, 0), -d, 1e-12);
    EXPECT_NEAR(pitProfile(r, d, 0.6, r), 0.0, 1e-12);  // the crater ends at its radius
    EXPECT_LT(pitProfile(r, d, 0.6, r - 0.1), 0.0);
    EXPECT_GT(pitProfile(r, d, 0.6, r + 0.1), 0.0);
    double removed = 0, piled = 0;
    const double dr = 1e-3;
    for (double rho = dr / 2; rho < 3 * r; rho += dr) {
        const double v = pitProfile(r, d, 0.6, rho) * 2 * M_PI * rho * dr;
        (v < 0 ? removed : piled) += std::abs(v);
    }
    const double volume = M_PI * r * r * d / 2;
    EXPECT_NEAR(removed, volume, volume * 1e-3);
    EXPECT_NEAR(piled, 0.6 * volume, volume * 1e-3);
}

TEST(DefectInsert, LabelsEveryDefectOfTheModelAndLeavesTheFaintOnesOut) {
    const int W = 400, H = 300;
    std::vector<float> flat(W * H, 0.0f);
    for (DefectModel m : {DefectModel::A, DefectModel::B}) {
        InsertSpec s;
        s.model = m;
        s.count = 2;
        s.faint = 1;
        s.depth = 0.002;
        s.faintDepth = 0.00001;
        s.seed = 7;
        const InsertResult r = insertDefects(flat, W, H, s);
        // A defect that does not fit the map is skipped and counted (one here, measured).
        EXPECT_LE(r.skipped, 1);
        EXPECT_EQ(r.defects.size() + static_cast<size_t>(r.skipped), 9u);
        ASSERT_GE(r.defects.size(), 8u);
        std::map<uint8_t, size_t> counts;
        for (uint8_t v : r.truth) ++counts[v];
        for (InsertKind k : modelKinds(m)) {
            const uint8_t label = insertKindRow(k).label;
            EXPECT_GT(counts[label], 20u) << insertKindRow(k).name;
            EXPECT_GE(label, 128);
        }
        size_t labelled = 0;
        for (const InsertedDefect& d : r.defects) {
            EXPECT_EQ(insertKindRow(d.kind).model, m);
            if (!d.labelled) {
                EXPECT_EQ(d.samples, 0u);
                EXPECT_DOUBLE_EQ(d.depth, 0.00001);
                // Its box holds no label: the faint defects are kept out of the truth.
                for (int z = d.z0; z <= d.z1; ++z)
                    for (int x = d.x0; x <= d.x1; ++x) EXPECT_EQ(r.truth[z * W + x], 0);
            } else {
                labelled += d.samples;
                EXPECT_GE(d.x0, s.margin);
                EXPECT_LE(d.x1, W - 1 - s.margin);
                EXPECT_GE(d.depth, 0.7 * 0.002);
                EXPECT_LE(d.depth, 1.3 * 0.002);
            }
        }
        EXPECT_EQ(labelled, W * H - counts[0]);
        // Deepest point: every model-A/B defect goes down by at most 1.3 × depth (the pit
        // chains' pits do not overlap; the burr goes up).
        const auto [lo, hi] = std::minmax_element(r.heights.begin(), r.heights.end());
        EXPECT_GE(*lo, -1.3 * 0.002 - 1e-6);
        EXPECT_LT(*lo, -0.5 * 0.002);
        EXPECT_GT(*hi, 0.0f);
        // Deterministic.
        EXPECT_EQ(insertDefects(flat, W, H, s).heights, r.heights);
        s.seed = 8;
        EXPECT_NE(insertDefects(flat, W, H, s).heights, r.heights);
    }
}

TEST(DefectInsert, CrackIsOptInAndCutsTheGeneratorsCrack) {
    // Not among model B's default kinds (what --kinds left out inserts is unchanged).
    const std::vector<InsertKind> b = modelKinds(DefectModel::B);
    EXPECT_EQ(b,
              (std::vector<InsertKind>{InsertKind::Gouge, InsertKind::PitChain, InsertKind::Dent}));
    EXPECT_EQ(parseInsertKind("crack", "--kinds"), InsertKind::Crack);
    EXPECT_EQ(insertKindRow(InsertKind::Crack).label, kTruthCrack);
    const int W = 400, H = 300;
    std::vector<float> flat(W * H, 0.0f);
    InsertSpec s;
    s.model = DefectModel::B;
    s.kinds = {InsertKind::Crack};
    s.count = 3;
    s.faint = 0;
    s.depth = 0.002;
    s.seed = 5;
    const InsertResult r = insertDefects(flat, W, H, s);
    ASSERT_EQ(r.defects.size(), 3u);
    // On a flat map the heights are the cracks' offsets: never raised (no rim), at most
    // 1.3 × depth deep, and labelled exactly where lowered by >= 10 % of the crack's depth.
    for (float h : r.heights) ASSERT_LE(h, 0.0f);
    for (const InsertedDefect& d : r.defects) {
        EXPECT_EQ(d.kind, InsertKind::Crack);
        EXPECT_GE(d.size, 2.0);
        EXPECT_LE(d.size, 4.0);
        EXPECT_GT(d.samples, 20u);
        for (int z = d.z0; z <= d.z1; ++z)
            for (int x = d.x0; x <= d.x1; ++x) {
                const size_t i = static_cast<size_t>(z) * W + x;
                EXPECT_GE(r.heights[i], -d.depth * (1 + 1e-6));
                if (r.truth[i] != 0) {
                    EXPECT_EQ(r.truth[i], kTruthCrack);
                    EXPECT_LE(r.heights[i], -0.1 * d.depth * (1 - 1e-6));
                } else {
                    EXPECT_GT(r.heights[i], -0.1 * d.depth * (1 + 1e-6));
                }
            }
    }
    // Every labelled sample is counted by its crack.
    size_t labelled = 0;
    for (uint8_t v : r.truth) labelled += v != 0;
    size_t counted = 0;
    for (const InsertedDefect& d : r.defects) counted += d.samples;
    EXPECT_EQ(labelled, counted);
    // Not the model's kind: refused by name.
    s.model = DefectModel::A;
    EXPECT_THROW(insertDefects(flat, W, H, s), InputError);
}

TEST(DefectInsert, BadInputIsNamed) {
    std::vector<float> h(200 * 200, 0.0f);
    InsertSpec s;
    s.kinds = {InsertKind::Gouge};  // model B's, with model A
    try {
        insertDefects(h, 200, 200, s);
        FAIL();
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("kinds"), std::string::npos) << e.what();
    }
    s.kinds.clear();
    s.depth = -1;
    EXPECT_THROW(insertDefects(h, 200, 200, s), InputError);
    s.depth = 0.001;
    EXPECT_THROW(insertDefects(h, 100, 100, s), InputError);  // smaller than the margins
    EXPECT_THROW(parseInsertKind("spall", "kinds"), InputError);
    EXPECT_EQ(parseInsertKind("pit-chain", "kinds"), InsertKind::PitChain);
}

TEST(DefectInsert, TextureSqLeavesOutTheQuadraticForm) {
    const int W = 120, H = 80;
    std::vector<float> h(W * H);
    double ss = 0;
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            const double t = ((i * 7 + j * 13) % 5 - 2) * 1e-4;  // zero-mean texture
            ss += t * t;
            h[j * W + i] = static_cast<float>(0.5 + 0.01 * i - 0.02 * j + 1e-4 * i * i + t);
        }
    const double sq = std::sqrt(ss / (W * H));
    EXPECT_NEAR(textureSq(h, W, H), sq, 0.05 * sq);
}

TEST(DefectInsert, ResampleKeepsTheMeanAndScalesThePitch) {
    int W = 300, H = 100;
    std::vector<float> h(W * H, 2.0f);
    h[0] = 2.0f;
    const double f = resampleToMaxSide(h, W, H, 150);
    EXPECT_DOUBLE_EQ(f, 2.0);
    EXPECT_EQ(W, 150);
    EXPECT_EQ(H, 50);
    for (float v : h) EXPECT_FLOAT_EQ(v, 2.0f);
    EXPECT_DOUBLE_EQ(resampleToMaxSide(h, W, H, 500), 1.0);  // already small enough
}

TEST(InsertDefectsCli, WritesWhatEveryTruthCommandTakes) {
    test::TempDir dir("insert-defects");
    auto r = runCli(
        "gen-surface --process turned --width 300 --height 300 --scratches 0 "
        "--gouges 0 -o " +
        (dir / "part.exr").string() + " --scene " + (dir / "part.json").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const std::string out = (dir / "ins.exr").string();
    r = runCli("insert-defects " + (dir / "part.json").string() + " --seed 3 --model B -o " + out);
    ASSERT_EQ(r.exitCode, 0) << r.output;
    for (const char* f : {"ins.exr", "ins-truth.png", "ins-truth.json", "ins.json"})
        EXPECT_TRUE(std::filesystem::exists(dir / f)) << f;
    std::ifstream in(dir / "ins-truth.json");
    const nlohmann::json legend = nlohmann::json::parse(in);
    EXPECT_EQ(legend["inserted"].size(), 12u);  // 3 kinds × (3 labelled + 1 faint)
    EXPECT_NEAR(legend["texture"]["pitch_mm"].get<double>(), 0.01, 1e-12);
    r = runCli("defectmap " + (dir / "ins.json").string() + " --truth " +
               (dir / "ins-truth.png").string() + " -o " + (dir / "map.png").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("pit-chain"), std::string::npos) << r.output;
    // a simulator's part: the tool-path model (auto), and its scene says nothing of measurement
    EXPECT_EQ(r.output.find("measured texture"), std::string::npos) << r.output;
    {
        std::ifstream sin(dir / "ins.json");
        EXPECT_FALSE(nlohmann::json::parse(sin)["heightmap"].contains("measured"));
    }
    // defects in a measured texture (an X3P): the scene written says so and defectmap's auto
    // is the selfsim method
    r = runCli(
        "gen-surface --process turned --width 300 --height 300 --scratches 0 --gouges 0 "
        "-o " +
        (dir / "m.x3p").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    r = runCli("insert-defects " + (dir / "m.x3p").string() + " --seed 3 -o " +
               (dir / "mins.exr").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    {
        std::ifstream sin(dir / "mins.json");
        EXPECT_EQ(nlohmann::json::parse(sin)["heightmap"]["measured"], true);
    }
    r = runCli("defectmap " + (dir / "mins.json").string() + " -o " + (dir / "m.png").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("defect map (selfsim)"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("measured texture"), std::string::npos) << r.output;
    // A bare EXR carries no pitch: the error names the fix; nothing is written.
    r = runCli("insert-defects " + (dir / "part.exr").string() + " -o " +
               (dir / "bad.exr").string());
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("--pitch"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "bad.exr"));
    // Model A's kinds are refused with model B.
    r = runCli("insert-defects " + (dir / "part.json").string() + " --model B --kinds scratch -o " +
               (dir / "bad2.exr").string());
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "bad2.exr"));
}
