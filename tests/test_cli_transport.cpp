// precompute / relight / optimize through the CLI: relight == render, the cache, refusal of
// damaged and stale files, the outputs of optimize and of a λ sweep.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "TestUtil.h"
#include "core/Image.h"
#include "core/Rng.h"
#include "io/ImageIO.h"

using namespace sl;
using test::runCli;

namespace {

class CliTransport : public ::testing::Test {
  protected:
    test::TempDir dir{"clitm"};
    std::string scene;

    void SetUp() override {
        std::vector<float> h(40 * 40);
        for (int j = 0; j < 40; ++j)
            for (int i = 0; i < 40; ++i)
                h[size_t(j) * 40 + i] =
                    static_cast<float>(0.02 * std::sin(i * 0.6) * std::cos(j * 0.45));
        test::writeNpyF32(dir / "map.npy", 40, 40, h);
        scene = (dir / "scene.json").string();
        test::writeText(scene, R"({"heightmap": {"path": "map.npy", "pixel_pitch": 0.05},
            "material": {"alpha_u": 0.12, "alpha_v": 0.04, "material": "Cu"},
            "camera": {"width": 24, "height": 20},
            "render": {"spp": 4, "max_depth": 3, "seed": 5}})");
        // A random RGB env map on the 50x25 grid (loaded without resampling).
        Image env(50, 25, 3);
        Pcg32 rng(3, 4);
        for (float& v : env.data) v = rng.nextFloat();
        writeExr(dir / "env.exr", env);
    }
    std::string p(const std::string& name) const { return (dir / name).string(); }
};

double maxRel(const Image& a, const Image& b) {
    double scale = 0, diff = 0;
    for (size_t i = 0; i < a.data.size(); ++i) {
        scale = std::max(scale, double(std::abs(b.data[i])));
        diff = std::max(diff, double(std::abs(a.data[i] - b.data[i])));
    }
    return diff / scale;
}

nlohmann::json readJson(const std::string& file) {
    std::ifstream in(file);
    return nlohmann::json::parse(in);
}

}  // namespace

TEST_F(CliTransport, RelightEqualsRender) {
    auto r = runCli("precompute " + scene + " --rgb -o " + p("rgb.tm"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    r = runCli("relight " + p("rgb.tm") + " --envmap " + p("env.exr") + " -o " + p("relit.exr"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    r = runCli("render " + scene + " --envmap " + p("env.exr") + " -o " + p("render.exr"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    Image a = readImage(p("relit.exr")), b = readImage(p("render.exr"));
    ASSERT_EQ(a.channels, 3);
    double d = maxRel(a, b);
    std::printf("[ measured ] relight (RGB T) vs render: max relative difference %.3g\n", d);
    EXPECT_LE(d, 1e-5);
    EXPECT_TRUE(std::filesystem::exists(p("relit.png")));
}

TEST_F(CliTransport, RefusesDamagedAndWrongFiles) {
    ASSERT_EQ(runCli("precompute " + scene + " -o " + p("g.tm")).exitCode, 0);
    std::string bytes;
    {
        std::ifstream in(p("g.tm"), std::ios::binary);
        bytes.assign((std::istreambuf_iterator<char>(in)), {});
    }
    bytes[bytes.size() / 2] ^= 1;
    test::writeText(p("bad.tm"), bytes);
    auto r = runCli("relight " + p("bad.tm") + " --envmap const:1 -o " + p("x.exr"));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.output.find("damaged"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("precompute"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(p("x.exr")));
    r = runCli("optimize " + p("bad.tm") + " -o " + p("o"));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_FALSE(std::filesystem::exists(p("o/summary.json")));
    // Usage errors.
    EXPECT_EQ(runCli("precompute " + scene + " -o " + p("x.bin")).exitCode, 2);
    EXPECT_EQ(runCli("relight " + p("g.tm") + " -o " + p("x.exr")).exitCode, 2);
    EXPECT_EQ(runCli("optimize " + p("g.tm") + " --optimizer newton").exitCode, 2);
    // A gray T cannot drive an RGB optimization.
    r = runCli("optimize " + p("g.tm") + " --rgb -o " + p("o"));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.output.find("--rgb"), std::string::npos) << r.output;
    // Bad --init, empty mask.
    r = runCli("optimize " + p("g.tm") + " --init const:2 -o " + p("o"));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.output.find("--init"), std::string::npos) << r.output;
    std::vector<uint8_t> zeros(24 * 20, 0);
    writeMaskPng(p("empty.png"), zeros, 24, 20);
    r = runCli("optimize " + p("g.tm") + " --mask " + p("empty.png") + " -o " + p("o"));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.output.find("empty"), std::string::npos) << r.output;
}

TEST_F(CliTransport, OptimizeFromSceneCachesTAndWritesItsOutputs) {
    auto r = runCli("optimize " + scene +
                    " --optimizer adam --objective paper --init const:0.5 --iterations 20 -o " +
                    p("run"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    for (const char* f : {"envmap.exr", "envmap.png", "render.exr", "render.png", "initial.png",
                          "loss.csv", "summary.json"})
        EXPECT_TRUE(std::filesystem::exists(dir / "run" / f)) << f;
    auto s = readJson(p("run/summary.json"));
    for (const char* k : {"optimizer", "lambda", "iterations", "initial_loss", "final_loss",
                          "seconds_precompute", "seconds_optimize"})
        EXPECT_TRUE(s.contains(k)) << k;
    EXPECT_EQ(s["optimizer"], "adam");
    EXPECT_EQ(s["lambda"], 30.0);
    EXPECT_EQ(s["iterations"], 20);
    EXPECT_LT(s["final_loss"].get<double>(), s["initial_loss"].get<double>());
    EXPECT_GT(s["seconds_precompute"].get<double>(), 0.0);
    EXPECT_FALSE(s["transport_cache_hit"].get<bool>());
    // loss.csv: a header and iterations 0..20.
    std::ifstream csv(p("run/loss.csv"));
    std::string line;
    int lines = 0;
    while (std::getline(csv, line)) ++lines;
    EXPECT_EQ(lines, 22);
    // The env map is on the 50x25 grid, within [0, 1].
    Image e = readImage(p("run/envmap.exr"));
    EXPECT_EQ(e.width, 50);
    EXPECT_EQ(e.height, 25);
    for (float v : e.data) {
        EXPECT_GE(v, 0.0f);
        EXPECT_LE(v, 1.0f);
    }
    // Second run: T comes from the cache, no ray is traced, same result.
    r = runCli("optimize " + scene +
               " --optimizer adam --objective paper --init const:0.5 --iterations 20 -o " +
               p("run2"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    auto s2 = readJson(p("run2/summary.json"));
    EXPECT_TRUE(s2["transport_cache_hit"].get<bool>());
    EXPECT_EQ(s2["seconds_precompute"].get<double>(), 0.0);
    EXPECT_EQ(s2["final_loss"], s["final_loss"]);
    // Another seed is another T (not the cached one).
    r = runCli("optimize " + scene +
               " --optimizer adam --objective paper --init const:0.5 --seed 6 --iterations 5 -o " +
               p("run3"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_FALSE(readJson(p("run3/summary.json"))["transport_cache_hit"].get<bool>());
}

TEST_F(CliTransport, LambdaSweepAndEveryOptimizer) {
    ASSERT_EQ(runCli("precompute " + scene + " -o " + p("g.tm")).exitCode, 0);
    // --no-self-check: E* of each λ, not the reference that may beat it on validation.
    auto r = runCli("optimize " + p("g.tm") +
                    " --lambda 0,10,30 --iterations 15 --no-self-check -o " + p("sw"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    for (const char* sub : {"lambda-0", "lambda-10", "lambda-30"})
        EXPECT_TRUE(std::filesystem::exists(dir / "sw" / sub / "summary.json")) << sub;
    EXPECT_TRUE(std::filesystem::exists(dir / "sw" / "sweep.csv"));
    // Without the regulariser the env map drifts up (the paper's blow-out), with it less so.
    auto mean = [&](const std::string& f) {
        Image e = readImage(f);
        double m = 0;
        for (float v : e.data) m += v;
        return m / double(e.data.size());
    };
    EXPECT_GT(mean(p("sw/lambda-0/envmap.exr")), mean(p("sw/lambda-30/envmap.exr")));
    for (const char* opt : {"lbfgs", "mma", "ccsaq", "mlsl", "ceres-lbfgs"}) {
        r = runCli("optimize " + p("g.tm") + " --optimizer " + opt +
                   " --init const:0.5 --iterations 40 -o " + p(std::string("o-") + opt));
        ASSERT_EQ(r.exitCode, 0) << opt << ": " << r.output;
        auto s = readJson(p(std::string("o-") + opt + "/summary.json"));
        EXPECT_EQ(s["optimizer"], opt);
        EXPECT_LT(s["final_loss"].get<double>(), s["initial_loss"].get<double>()) << opt;
    }
    // The image regulariser and a region mask.
    std::vector<uint8_t> half(24 * 20, 0);
    for (int y = 0; y < 20; ++y)
        for (int x = 0; x < 12; ++x) half[size_t(y) * 24 + x] = 255;
    writeMaskPng(p("half.png"), half, 24, 20);
    r = runCli("optimize " + p("g.tm") + " --reg image --mask " + p("half.png") +
               " --iterations 10 -o " + p("masked"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    auto s = readJson(p("masked/summary.json"));
    EXPECT_EQ(s["reg"], "image");
    EXPECT_LE(s["mask_pixels"].get<int>(), 12 * 20);
}

TEST_F(CliTransport, HeldOutScoreAndUnbiasedObjective) {
    // From the scene: T is traced, then a held-out T with another seed; both scores reported.
    auto r = runCli("optimize " + scene +
                    " --objective paper --optimizer adam --init const:0.5 --iterations 20 "
                    "--heldout-every 5 -o " +
                    p("paper"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("held-out"), std::string::npos) << r.output;
    auto s = readJson(p("paper/summary.json"));
    ASSERT_TRUE(s["heldout_loss"].is_number());
    EXPECT_TRUE(s["heldout_paper_loss"].is_number());
    EXPECT_EQ(s["heldout_loss"], s["heldout_paper_loss"]);  // the paper objective is eq. 2
    EXPECT_NE(s["heldout"]["transport"]["seed"], s["transport"]["seed"]);
    EXPECT_EQ(s["heldout"]["transport"]["planes"], 2);
    {
        std::ifstream csv(p("paper/loss.csv"));
        std::string header, line, last;
        std::getline(csv, header);
        EXPECT_NE(header.find("heldout_loss"), std::string::npos);
        int withHeld = 0;
        while (std::getline(csv, line)) {
            last = line;
            if (line.back() != ',') ++withHeld;
        }
        EXPECT_EQ(withHeld, 5);  // iterations 0, 5, 10, 15, 20
        EXPECT_NE(last.back(), ',');
    }
    // The unbiased objective from the scene traces T with two sample sets.
    r = runCli("optimize " + scene + " --objective unbiased --iterations 20 -o " + p("unb"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    auto u = readJson(p("unb/summary.json"));
    EXPECT_EQ(u["objective"], "unbiased");
    EXPECT_EQ(u["transport"]["planes"], 2);
    EXPECT_LT(u["final_loss"].get<double>(), u["initial_loss"].get<double>());
    EXPECT_TRUE(u["heldout_loss"].is_number());
    EXPECT_NE(u["heldout_loss"], u["heldout_paper_loss"]);
    // A plain .tm cannot serve the unbiased objective; one with --halves can.
    ASSERT_EQ(runCli("precompute " + scene + " -o " + p("g.tm")).exitCode, 0);
    r = runCli("optimize " + p("g.tm") + " --objective unbiased -o " + p("x"));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.output.find("--halves"), std::string::npos) << r.output;
    ASSERT_EQ(runCli("precompute " + scene + " --halves -o " + p("h.tm")).exitCode, 0);
    r = runCli("optimize " + p("h.tm") + " --objective unbiased --iterations 5 -o " + p("y"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_TRUE(readJson(p("y/summary.json"))["heldout_loss"].is_number());
    // --heldout none skips it; a held-out .tm of the wrong kind is refused.
    r = runCli("optimize " + p("g.tm") + " --heldout none --iterations 5 -o " + p("z"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_TRUE(readJson(p("z/summary.json"))["heldout_loss"].is_null());
    r = runCli("optimize " + p("g.tm") + " --heldout " + p("g.tm") + " -o " + p("w"));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.output.find("two halves"), std::string::npos) << r.output;
}

TEST_F(CliTransport, BlackBoxOptimizersAndGradientCommands) {
    // fd-adam and spsa render for every gradient: they need the scene, not a .tm.
    auto r = runCli("optimize " + scene + " --optimizer spsa --iterations 6 -o " + p("spsa"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    auto s = readJson(p("spsa/summary.json"));
    EXPECT_EQ(s["optimizer"], "spsa");
    EXPECT_TRUE(s["heldout_loss"].is_number());
    r = runCli("optimize " + scene + " --optimizer fd-adam --iterations 1 -o " + p("fd"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_EQ(readJson(p("fd/summary.json"))["optimizer"], "fd-adam");
    ASSERT_EQ(runCli("precompute " + scene + " -o " + p("g.tm")).exitCode, 0);
    r = runCli("optimize " + p("g.tm") + " --optimizer spsa -o " + p("x"));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.output.find("scene"), std::string::npos) << r.output;
    // gradcheck prints one row per method and writes JSON.
    r = runCli("gradcheck " + scene +
               " --size 16 --spp 2 --methods exact,autodiff,fd --repeats 1 "
               "-o " +
               p("gc.json"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("exact"), std::string::npos);
    EXPECT_NE(r.output.find("autodiff"), std::string::npos);
    auto gc = readJson(p("gc.json"));
    EXPECT_FALSE(gc.empty());
    EXPECT_EQ(runCli("gradcheck " + scene + " --methods bogus").exitCode, 2);
    EXPECT_EQ(runCli("bench gradients --help").exitCode, 0);
    // export-mitsuba writes the scene, the mesh and the env map.
    r = runCli("export-mitsuba " + scene + " -o " + p("mi") + " --envmap " + p("env.exr"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    for (const char* f : {"scene.xml", "heightfield.ply", "envmap.exr"})
        EXPECT_TRUE(std::filesystem::exists(dir / "mi" / f)) << f;
}

TEST_F(CliTransport, BenchNoiseWritesOneRowPerRunAndMediansPerGroup) {
    const std::string csv = p("bn/noise.csv");
    auto r = runCli("bench noise " + scene +
                    " --size 16 --spps 2,4 --heldout-spp 8 --seeds 2 "
                    "--optimizers adam:5,lbfgs:40 -o " +
                    csv);
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("vs top spp"), std::string::npos) << r.output;
    auto lines = [](const std::string& file) {
        std::ifstream in(file);
        std::vector<std::string> out;
        for (std::string l; std::getline(in, l);) out.push_back(l);
        return out;
    };
    const auto runs = lines(csv), groups = lines(p("bn/noise-median.csv"));
    // 2 spp × 2 seeds × 2 objectives × 2 optimizers, and 2 × 2 × 2 groups (plus headers).
    ASSERT_EQ(runs.size(), 17u);
    ASSERT_EQ(groups.size(), 9u);
    EXPECT_EQ(runs[0].rfind("spp,seed,objective,optimizer,", 0), 0u) << runs[0];
    for (size_t i = 1; i < groups.size(); ++i) {
        std::vector<std::string> f;
        std::stringstream ss(groups[i]);
        for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
        ASSERT_EQ(f.size(), 14u) << groups[i];
        EXPECT_EQ(f[3], "2") << groups[i];  // runs: one per seed
        if (f[0] == "4") {                  // the top spp is its own reference
            EXPECT_EQ(f[10], "0") << groups[i];
        }
        EXPECT_LE(std::stod(f[11]), std::stod(f[10]));  // min <= median <= max
        EXPECT_GE(std::stod(f[12]), std::stod(f[10]));
    }

    // Bad optimizer list: exit 1, names the option, writes nothing.
    const std::string csv2 = p("bn2/noise.csv");
    r = runCli("bench noise " + scene + " --size 16 --spps 2 --heldout-spp 8 --seeds 1 " +
               "--optimizers adam:5,newton -o " + csv2);
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("--optimizers"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(csv2));
    r = runCli("bench noise " + scene + " --spps 3 -o " + csv2);
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("--spps"), std::string::npos) << r.output;
}
