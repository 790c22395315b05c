// The CLI's contract: exit codes 0/1/2, messages that name the file or field and the fix,
// and no output written (nor an existing file clobbered) when the input is bad.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>

#include "TestUtil.h"
#include "core/Image.h"
#include "io/ImageIO.h"

using namespace sl;
using test::runCli;

namespace {

class CliTest : public ::testing::Test {
  protected:
    test::TempDir dir{"cli"};
    std::string out() const { return (dir / "out.exr").string(); }
    std::string png() const { return (dir / "out.png").string(); }

    void writeGoodMap() {
        std::vector<float> h(16 * 12);
        for (size_t i = 0; i < h.size(); ++i) h[i] = 0.001f * static_cast<float>(i % 7);
        test::writeNpyF32(dir / "map.npy", 12, 16, h);
    }
    std::string scene(const std::string& json) {
        auto p = dir / "scene.json";
        test::writeText(p, json);
        return p.string();
    }
    /// Runs `render` and expects a runtime error whose message contains every needle,
    /// and no output files.
    void expectInputError(const std::string& sceneFile, std::vector<std::string> needles,
                          const std::string& extra = "") {
        auto r = runCli("render " + sceneFile + " --spp 1 -o " + out() + " " + extra);
        EXPECT_EQ(r.exitCode, 1) << r.output;
        for (const auto& n : needles)
            EXPECT_NE(r.output.find(n), std::string::npos)
                << "message should mention '" << n << "': " << r.output;
        EXPECT_FALSE(std::filesystem::exists(out()));
        EXPECT_FALSE(std::filesystem::exists(png()));
        for (auto& e : std::filesystem::directory_iterator(dir.path()))
            EXPECT_EQ(e.path().string().find(".tmp"), std::string::npos) << e.path();
    }
    const std::string smallCamera = R"("camera": {"width": 16, "height": 16})";
};

}  // namespace

TEST_F(CliTest, HelpAndUsageErrors) {
    EXPECT_EQ(runCli("--help").exitCode, 0);
    EXPECT_EQ(runCli("render --help").exitCode, 0);
    EXPECT_EQ(runCli("gen-surface --help").exitCode, 0);
    EXPECT_EQ(runCli("bench render --help").exitCode, 0);
    EXPECT_EQ(runCli("").exitCode, 2);
    EXPECT_EQ(runCli("render").exitCode, 2);
    EXPECT_EQ(runCli("render x.json --no-such-option").exitCode, 2);
    EXPECT_EQ(runCli("render x.json --spp 0").exitCode, 2);
    EXPECT_EQ(runCli("render x.json --envmap a.exr --constant 1").exitCode, 2);  // no such flag
    writeGoodMap();
    auto r = runCli("render " + scene(R"({"heightmap": {"path": "map.npy", "pixel_pitch": 0.1}})") +
                    " -o " + (dir / "out.tif").string());
    EXPECT_EQ(r.exitCode, 2) << r.output;
}

// --version names the build and its libraries; an unknown command is named, with the nearest
// command when there is one, and a usage exit code.
TEST_F(CliTest, VersionAndUnknownCommands) {
    auto r = runCli("--version");
    EXPECT_EQ(r.exitCode, 0) << r.output;
    for (const char* s : {"scratchlight 0.", "(commit ", "Embree 3.", "OpenImageIO 2.", "NLopt 2.",
                          "Ceres 2.", "Eigen 3."})
        EXPECT_NE(r.output.find(s), std::string::npos) << s << " in " << r.output;
    r = runCli("optimise x.json");
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.output.find("unknown command 'optimise'; did you mean 'optimize'?"),
              std::string::npos)
        << r.output;
    r = runCli("frobnicate");
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.output.find("unknown command 'frobnicate'"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("did you mean"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("defectmap"), std::string::npos) << r.output;  // the list
}

TEST_F(CliTest, RendersAndWritesExrAndPng) {
    writeGoodMap();
    auto r = runCli(
        "render " +
        scene(R"({"heightmap": {"path": "map.npy", "pixel_pitch": 0.1}, )" + smallCamera + "}") +
        " --spp 2 --envmap const:0.5 -o " + out());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    Image exr = readImage(out());
    EXPECT_EQ(exr.width, 16);
    EXPECT_EQ(exr.height, 16);
    EXPECT_EQ(exr.channels, 3);
    EXPECT_TRUE(std::filesystem::exists(png()));
}

// Say what was read: the part's grid, pitch, size in mm, height range and invalid points; a map
// without a pitch is refused unless the scene gives one or --assume-pitch accepts the default.
TEST_F(CliTest, PrintsThePartAndRefusesAMapWithoutAPitch) {
    writeGoodMap();
    const std::string noPitch = scene(R"({"heightmap": {"path": "map.npy"}, )" + smallCamera + "}");
    expectInputError(noPitch, {"map.npy", "carries no sample spacing", "pixel_pitch",
                               "0.01 mm with --assume-pitch"});
    auto r = runCli("render " + noPitch + " --assume-pitch --spp 1 --envmap const:0.5 -o " + out());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("warning: --assume-pitch: the height map's samples are taken to be "
                            "0.01 mm apart"),
              std::string::npos)
        << r.output;
    EXPECT_NE(r.output.find("part map.npy (npy float32): 16 x 12 samples, pitch 0.01 mm, 0.15 x "
                            "0.11 mm, heights 0 .. 0.006 mm, 0 invalid points filled"),
              std::string::npos)
        << r.output;
    // -q keeps the warning, drops the context line.
    r = runCli("render -q " + noPitch + " --assume-pitch --spp 1 --envmap const:0.5 -o " + out());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("warning: --assume-pitch"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("part map.npy"), std::string::npos) << r.output;
}

TEST_F(CliTest, MissingSceneFile) {
    expectInputError((dir / "nope.json").string(), {"nope.json"});
}

TEST_F(CliTest, MissingHeightMap) {
    expectInputError(scene(R"({"heightmap": {"path": "absent.exr"}})"), {"absent.exr"});
}

TEST_F(CliTest, UnreadableImage) {
    test::writeText(dir / "junk.exr", "this is not an image");
    expectInputError(scene(R"({"heightmap": {"path": "junk.exr"}})"), {"junk.exr"});
}

TEST_F(CliTest, NanAndInfHeights) {
    for (float bad :
         {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
        std::vector<float> h(16, 0.0f);
        h[5] = bad;
        test::writeNpyF32(dir / "bad.npy", 4, 4, h);
        expectInputError(scene(R"({"heightmap": {"path": "bad.npy"}})"), {"bad.npy"});
    }
}

TEST_F(CliTest, IntegerMapWithoutHeightRange) {
    Image img(8, 8, 1, 0.5f);
    writePng16(dir / "int.png", img);
    expectInputError(scene(R"({"heightmap": {"path": "int.png"}})"), {"int.png", "height_range"});
}

TEST_F(CliTest, UnknownJsonField) {
    writeGoodMap();
    expectInputError(scene(R"({"heightmap": {"path": "map.npy"}, "material": {"alpah": 0.1}})"),
                     {"material.alpah", "unknown field", "alpha"});
    expectInputError(scene(R"({"heightmap": {"path": "map.npy"}, "lights": []})"),
                     {"lights", "unknown field"});
}

TEST_F(CliTest, NegativePitch) {
    writeGoodMap();
    expectInputError(scene(R"({"heightmap": {"path": "map.npy", "pixel_pitch": -0.01}})"),
                     {"heightmap.pixel_pitch", "> 0"});
}

TEST_F(CliTest, ZeroSizeMap) {
    test::writeNpyF32(dir / "empty.npy", 0, 0, {});
    expectInputError(scene(R"({"heightmap": {"path": "empty.npy"}})"), {"empty.npy"});
}

TEST_F(CliTest, BadValuesNameTheirField) {
    writeGoodMap();
    expectInputError(scene(R"({"heightmap": {"path": "map.npy"}, "material": {"material": "Xx"}})"),
                     {"material.material", "Xx"});
    expectInputError(
        scene(R"({"heightmap": {"path": "map.npy"}, "material": {"distribution": "phong"}})"),
        {"material.distribution", "ggx"});
    expectInputError(scene(R"({"heightmap": {"path": "map.npy"}, "render": {"spp": 0}})"),
                     {"render.spp"});
    expectInputError(scene(R"({"heightmap": {"path": "map.npy"}, "camera": {"fov": "wide"}})"),
                     {"camera.fov"});
    expectInputError(scene(R"({"heightmap": {"path": "map.npy"},)"), {"scene.json", "JSON"});
}

TEST_F(CliTest, FailedRenderKeepsExistingOutput) {
    test::writeText(out(), "precious");
    test::writeText(png(), "precious too");
    auto r = runCli("render " + scene(R"({"heightmap": {"path": "absent.npy"}})") + " -o " + out());
    EXPECT_EQ(r.exitCode, 1);
    std::ifstream a(out()), b(png());
    std::string sa((std::istreambuf_iterator<char>(a)), {}),
        sb((std::istreambuf_iterator<char>(b)), {});
    EXPECT_EQ(sa, "precious");
    EXPECT_EQ(sb, "precious too");
}

TEST_F(CliTest, BenchScratchmapPrintsATableAndWritesCsv) {
    const std::string csv = (dir / "sub dir" / "it's.csv").string();
    auto r = runCli("bench scratchmap --sizes 64,100 --repeats 1 -o \"" + csv + "\"");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("100x100"), std::string::npos) << r.output;
    std::ifstream in(csv);
    int lines = 0;
    for (std::string l; std::getline(in, l);) ++lines;
    EXPECT_EQ(lines, 3);
    EXPECT_EQ(runCli("bench scratchmap --sizes 0").exitCode, 2);
}

TEST_F(CliTest, BenchLoadPrintsATableAndWritesCsv) {
    // the bundled part, once: a row naming its reader, the CSV's header and its line
    const std::string part = std::string(SL_SOURCE_DIR) + "/scenes/default/part.exr";
    const std::string csv = (dir / "load.csv").string();
    auto r = runCli("bench load \"" + part + "\" --repeats 1 -o \"" + csv + "\"");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("part.exr"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("exr float32"), std::string::npos) << r.output;
    std::ifstream in(csv);
    int lines = 0;
    for (std::string l; std::getline(in, l);) ++lines;
    EXPECT_EQ(lines, 2);
    EXPECT_EQ(runCli("bench load").exitCode, 2);                           // no file
    EXPECT_EQ(runCli("bench load " + part + " --repeats 0").exitCode, 2);  // a usage error
}

// Issue 35: an output never replaces an input of the same run. `render scene.json -o part.exr`
// overwrote the scene's own height map (exit 0); the PNG preview beside the output may not
// replace it either.
TEST_F(CliTest, RenderRefusesToWriteOverItsInputs) {
    Image hm(16, 12, 1);
    for (size_t i = 0; i < hm.data.size(); ++i) hm.data[i] = 0.001f * static_cast<float>(i % 7);
    writeExr(dir / "part.exr", hm);
    const std::string before = test::readFile(dir / "part.exr");
    const std::string s =
        scene(R"({"heightmap": {"path": "part.exr", "pixel_pitch": 0.1}, )" + smallCamera + "}");
    for (const std::string& o : {(dir / "part.exr").string(), (dir / "." / "part.exr").string()}) {
        const auto r = runCli("render " + s + " --spp 1 --envmap const:0.5 -o " + o);
        EXPECT_EQ(r.exitCode, 1) << r.output;
        EXPECT_NE(r.output.find("is an input of this run"), std::string::npos) << r.output;
        EXPECT_EQ(test::readFile(dir / "part.exr"), before);
    }
    // The preview: a height map part.png and -o part.exr (whose preview is part.png).
    std::filesystem::remove(dir / "part.exr");
    writePng16(dir / "part.png", hm);
    const std::string pngBefore = test::readFile(dir / "part.png");
    const std::string s2 = scene(
        R"({"heightmap": {"path": "part.png", "pixel_pitch": 0.1, "height_range": [0, 0.01]}, )" +
        smallCamera + "}");
    const auto r =
        runCli("render " + s2 + " --spp 1 --envmap const:0.5 -o " + (dir / "part.exr").string());
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("preview"), std::string::npos) << r.output;
    EXPECT_EQ(test::readFile(dir / "part.png"), pngBefore);
    EXPECT_FALSE(std::filesystem::exists(dir / "part.exr"));
}

// `gen-surface -o g.exr --scene part.exr` wrote scene JSON over a height map; a scene that
// cannot be written left the map behind. Now the scene must be a .json, no two outputs are the
// same file, and the files appear together or not at all.
TEST_F(CliTest, GenSurfaceNeverWritesHalfOrOverAnotherOutput) {
    Image hm(4, 4, 1);
    writeExr(dir / "part.exr", hm);
    const std::string before = test::readFile(dir / "part.exr");
    const std::string small = " --width 24 --height 24 --pitch 0.05";
    auto r = runCli("gen-surface -o " + (dir / "g.exr").string() + " --scene " +
                    (dir / "part.exr").string() + small);
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("must end in .json"), std::string::npos) << r.output;
    EXPECT_EQ(test::readFile(dir / "part.exr"), before);
    EXPECT_FALSE(std::filesystem::exists(dir / "g.exr"));
    // The scene named as the truth legend.
    r = runCli("gen-surface -o " + (dir / "g.exr").string() + " --scene " +
               (dir / "g-truth.json").string() + small);
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("is also the truth legend"), std::string::npos) << r.output;
    // A scene that cannot be written (its folder is a file): nothing at all is left.
    test::writeText(dir / "afile", "x");
    r = runCli("gen-surface -o " + (dir / "g.exr").string() + " --scene " +
               (dir / "afile" / "g.json").string() + small);
    EXPECT_EQ(r.exitCode, 1) << r.output;
    for (const char* name : {"g.exr", "g-truth.png", "g-truth.json"})
        EXPECT_FALSE(std::filesystem::exists(dir / name)) << name;
    for (auto& e : std::filesystem::directory_iterator(dir.path()))
        EXPECT_EQ(e.path().string().find(".tmp"), std::string::npos) << e.path();
    // And the ordinary run writes all four.
    r = runCli("gen-surface -o " + (dir / "g.exr").string() + " --scene " +
               (dir / "g.json").string() + small);
    ASSERT_EQ(r.exitCode, 0) << r.output;
    for (const char* name : {"g.exr", "g-truth.png", "g-truth.json", "g.json"})
        EXPECT_TRUE(std::filesystem::exists(dir / name)) << name;
}

// Issue 35, item 5: messages name the flag and print bounds readably; a list with an empty entry
// is refused; nothing is half-written by an option that cannot work.
TEST_F(CliTest, OptionMessagesNameTheFlagReadably) {
    const std::string s = (dir / "missing.json").string();
    auto r = runCli("optimize " + s + " --lr 0");
    EXPECT_EQ(r.exitCode, 2) << r.output;
    EXPECT_NE(r.output.find("--lr"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("must be a finite number > 0, got '0'"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("0000000000"), std::string::npos) << r.output;  // no 309 digits
    r = runCli("optimize " + s + " --lambda 1,,3");
    EXPECT_EQ(r.exitCode, 2) << r.output;
    EXPECT_NE(r.output.find("--lambda"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("an empty entry"), std::string::npos) << r.output;
    // CLI11 dropped the empty entries of every other list (--starts a,,b was read as a,b).
    for (const std::string& list :
         {"optimize " + s + " --starts const:0.5,,random:1",
          "optimize " + s + " --continuation=4,2,", "lamps " + s + " --kinds disk,,bar",
          "defectmap " + s + " --negatives ,128"}) {
        r = runCli(list);
        EXPECT_EQ(r.exitCode, 2) << list << "\n" << r.output;
        EXPECT_NE(r.output.find("an empty entry"), std::string::npos) << list << "\n" << r.output;
    }
    r = runCli("optimize " + s + " --starts const:0.5,random:1");
    EXPECT_EQ(r.exitCode, 1) << r.output;  // whole lists pass: the run stops at the scene
    r = runCli("optimize " + s + " --lambda 1,x");
    EXPECT_EQ(r.exitCode, 2) << r.output;
    EXPECT_NE(r.output.find("'x' is not a finite number"), std::string::npos) << r.output;
    // gen-surface names its flags, not SurfaceSpec's fields.
    const std::string g = "gen-surface -o " + (dir / "g.exr").string() + " --width 16 --height 16";
    r = runCli(g + " --pitch 0");
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("--pitch"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("SurfaceSpec"), std::string::npos) << r.output;
    r = runCli(g + " --scratches=-1");
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("--scratches"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "g.exr"));
    // Ranges (cli/Common.h inRange): the flag, the kind of value, readable bounds and what was
    // given; CLI11's Range said "Value abc not in range 1 to 16384" and "-90.000000 to 90.000000".
    struct Case {
        std::string args, says;
    };
    for (const Case& c : std::vector<Case>{
             {"render " + s + " --size 0", "--size: must be an integer in 1..16384, got '0'"},
             {"render " + s + " --size abc", "--size: must be an integer in 1..16384, got 'abc'"},
             {"render " + s + " --size 2.5", "--size: must be an integer in 1..16384, got '2.5'"},
             {"lamps " + s + " --min-elevation 95",
              "--min-elevation: must be a number in -90..90, got '95'"},
             {"lamps " + s + " --min-elevation nan",
              "--min-elevation: must be a number in -90..90, got 'nan'"},
             {"bench race --alphas 2", "--alphas: must be a number in 0.0001..1, got '2'"},
             // named --threshold (scratchmap's flag) and checked only after the trace
             {"optimize " + s + " --scratch-threshold 5",
              "--scratch-threshold: must be a number in 0..1, got '5'"},
             {"optimize " + s + " --cache-max 5XB", "--cache-max: '5XB' is not a size"}}) {
        r = runCli(c.args);
        EXPECT_EQ(r.exitCode, 2) << c.args << "\n" << r.output;
        EXPECT_NE(r.output.find(c.says), std::string::npos) << c.args << "\n" << r.output;
        EXPECT_EQ(r.output.find("000000"), std::string::npos) << c.args << "\n" << r.output;
    }
}

// The byte sizes of --cache-max (cli/Common.h parseByteSize): units of 1000 and of 1024, any
// case, are parsed (the run then stops at the missing scene, exit 1); anything else is a usage
// error naming the flag (CLI11's AsSizeValue said "The following arguments were not expected").
TEST_F(CliTest, CacheMaxTakesSizesWithUnits) {
    const std::string s = "optimize " + (dir / "missing.json").string() + " --cache-max ";
    for (const char* good : {"500MB", "8gb", "2GiB", "1.5kb", "4096"}) {
        const auto r = runCli(s + good);
        EXPECT_EQ(r.exitCode, 1) << good << "\n" << r.output;
        EXPECT_EQ(r.output.find("--cache-max"), std::string::npos) << good << "\n" << r.output;
    }
    for (const char* bad : {"MB", "5XB", "1e400", "1..2MB", "99999999999TB"}) {
        const auto r = runCli(s + "'" + bad + "'");
        EXPECT_EQ(r.exitCode, 2) << bad << "\n" << r.output;
        EXPECT_NE(r.output.find("--cache-max: '" + std::string(bad) + "' is not a size"),
                  std::string::npos)
            << bad << "\n"
            << r.output;
    }
}

TEST_F(CliTest, RenderChecksItsOutputsAndSaysWhenItIsBlack) {
    writeGoodMap();
    const std::string s =
        scene(R"({"heightmap": {"path": "map.npy", "pixel_pitch": 0.1}, )" + smallCamera + "}");
    // --exposure nan, and a directory where the preview goes: refused before the work.
    auto r = runCli("render " + s + " --spp 1 --exposure nan -o " + out());
    EXPECT_EQ(r.exitCode, 2) << r.output;
    EXPECT_FALSE(std::filesystem::exists(out()));
    std::filesystem::create_directories(png());
    r = runCli("render " + s + " --spp 1 -o " + out());
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("is a directory"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(out()));
    std::filesystem::remove(png());
    r = runCli("render " + s + " --spp 1 --envmap const:1e39 -o " + out());
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("more than 1e+06"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(out()));
    // Heights of 1e30: a black render, and a word about it.
    std::vector<float> h(16 * 12, 0.0f);
    h[7] = 1e30f;
    test::writeNpyF32(dir / "map.npy", 12, 16, h);
    r = runCli("render " + s + " --spp 1 --envmap const:1 -o " + out());
    EXPECT_NE(r.output.find("the render is black"), std::string::npos) << r.output;
    if (r.exitCode == 0) {
        EXPECT_NE(r.output.find("height map's units"), std::string::npos) << r.output;
    }
}

// Issue 30: on a map so small that the border (never marked) is most of it, defectmap says so,
// names the option of the method that ran and the border that would leave half of the map:
// (w - 2b)(h - 2b) >= w h / 2 at b = 7 for 60 x 50 (46 x 36 = 1656 >= 1500), not at 8.
// An ASCII SDF of w x h samples at 1 um (a measured file: auto is the selfsim method), heights in
// um from height(x, y).
template <class Height>
void writeAsciiSdf(const std::filesystem::path& f, int w, int h, Height height) {
    std::string sdf = "aBCR-1.0\nManufacID = test\nNumPoints = " + std::to_string(w) +
                      "\nNumProfiles = " + std::to_string(h) +
                      "\nXscale = 1e-6\nYscale = 1e-6\nZscale = 1e-6\nDataType = 7\n*\n";
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) sdf += std::to_string(height(x, y)) + " ";
    sdf += "\n*\n";
    test::writeText(f, sdf);
}

TEST_F(CliTest, DefectMapWarnsWhenItsBorderIsMostOfTheMap) {
    const std::filesystem::path f = dir / "small.sdf";
    writeAsciiSdf(f, 60, 50, [](int x, int y) { return (x * 7 + y * 13) % 11 - 5; });
    auto r = runCli("defectmap " + f.string() + " -o " + (dir / "m.png").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("the border of 40 samples"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("--selfsim-border sets the border (7 keeps half"), std::string::npos)
        << r.output;
    r = runCli("defectmap " + f.string() + " --selfsim-border 7 -o " + (dir / "m.png").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_EQ(r.output.find("the border of"), std::string::npos) << r.output;
    r = runCli("defectmap " + f.string() + " --method lay -o " + (dir / "m.png").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("--lay-border sets the border"), std::string::npos) << r.output;
}

// defectmap writes where the map could not judge beside the map (or at --unjudged-output) when
// the method in force records it: on a measured file (an SDF), not on gen-surface's part. A
// periodic texture with a crater (40 um deep, radius 20) whose centre lies 4 samples inside the
// border of 10: the crater reaches the border, so it is unjudged, not marked; the texture far
// from it repeats and is judged; the border is 128. Without the crater the map judges everything
// inside the border.
TEST_F(CliTest, DefectMapWritesWhereItCouldNotJudgeOnAMeasuredFile) {
    const auto texture = [](int x, int y) { return (x * 7 + y * 13) % 11 - 5; };
    const std::filesystem::path f = dir / "part.sdf", plain = dir / "plain.sdf";
    writeAsciiSdf(f, 120, 100, [&](int x, int y) {
        const int r2 = (x - 14) * (x - 14) + (y - 50) * (y - 50);
        return texture(x, y) - (r2 < 400 ? (40 * (400 - r2)) / 400 : 0);
    });
    writeAsciiSdf(plain, 120, 100, texture);
    auto r =
        runCli("defectmap " + f.string() + " --selfsim-border 10 -o " + (dir / "m.png").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("not judged: 1 regions"), std::string::npos) << r.output;
    const Image u = readImage(dir / "m-unjudged.png");
    ASSERT_EQ(u.width, 120);
    ASSERT_EQ(u.height, 100);
    EXPECT_NEAR(u.at(0, 0), 128.0f / 255.0f, 1e-6f) << "the border";
    EXPECT_NEAR(u.at(20, 50), 1.0f, 1e-6f) << "the crater";
    EXPECT_NEAR(u.at(60, 20), 0.0f, 1e-6f) << "judged: the texture repeats there";
    const Image preview = readImage(dir / "m-preview.png");  // a picture of both
    EXPECT_EQ(preview.width, 120);
    EXPECT_EQ(preview.height, 100);
    EXPECT_EQ(preview.channels, 3);
    const Image m = readImage(dir / "m.png");
    EXPECT_NEAR(m.at(20, 50), 0.0f, 1e-6f) << "the crater is not marked";
    r = runCli("defectmap " + plain.string() + " --selfsim-border 10 -o " +
               (dir / "p.png").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("judged everywhere inside the border"), std::string::npos) << r.output;
    EXPECT_TRUE(std::filesystem::exists(dir / "p-unjudged.png"));
    r = runCli("defectmap " + f.string() + " --selfsim-border 10 -o " + (dir / "n.png").string() +
               " --unjudged-output " + (dir / "where.png").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_TRUE(std::filesystem::exists(dir / "where.png"));
    EXPECT_FALSE(std::filesystem::exists(dir / "n-unjudged.png"));
    r = runCli("defectmap " + f.string() + " --unjudged-output " + (dir / "where.txt").string());
    EXPECT_NE(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("--unjudged-output"), std::string::npos) << r.output;
    const std::string g = (dir / "g.exr").string();
    ASSERT_EQ(runCli("gen-surface -o " + g + " --width 64 --height 64").exitCode, 0);
    r = runCli("defectmap " + g + " -o " + (dir / "g-map.png").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_EQ(r.output.find("not judged:"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "g-map-unjudged.png"));
}

// optimize without labels on a measured file (the defect map's regions, auto): what the map
// could not judge is named in the warnings, the summary and the report, so a person looks there.
TEST_F(CliTest, OptimizeWithoutLabelsWarnsWhereTheMapCouldNotJudge) {
    const std::filesystem::path f = dir / "part.sdf";
    writeAsciiSdf(f, 256, 224, [](int x, int y) {
        const int crater = (x - 30) * (x - 30) + (y - 112) * (y - 112);  // reaches the border
        const int pit = (x - 150) * (x - 150) + (y - 100) * (y - 100);
        return (x * 7 + y * 13) % 11 - 5 - (crater < 900 ? (40 * (900 - crater)) / 900 : 0) -
               (pit < 36 ? (40 * (36 - pit)) / 36 : 0);
    });
    {
        std::ofstream scene(dir / "part.json");
        scene << R"({"heightmap": {"path": "part.sdf"}})";
    }
    const auto out = dir / "opt";
    const auto r =
        runCli("optimize " + (dir / "part.json").string() +
               " --defects auto --size 32 --iterations 20 --heldout-spp 16 -o " + out.string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("the defect map could not judge 1 region that stands out"),
              std::string::npos)
        << r.output;
    EXPECT_NE(test::readFile(out / "summary.json").find("the defect map could not judge 1 region"),
              std::string::npos);
    EXPECT_NE(test::readFile(out / "report.html").find("the defect map could not judge 1 region"),
              std::string::npos);
    // lamps says it too (given the height map itself, the default scene around it)
    const auto l = runCli("lamps " + (dir / "part.sdf").string() +
                          " --objective defects --defects auto --count 1 --size 32 -o " +
                          (dir / "lamps").string());
    ASSERT_EQ(l.exitCode, 0) << l.output;
    EXPECT_NE(l.output.find("the defect map could not judge 1 region that stands out"),
              std::string::npos)
        << l.output;
}

// Issue 35 (second pass): defectmap wrote its map, then found a directory where the score CSV
// goes and failed with the map left behind; `defectmap -o` replaced its own truth and
// `--score-output` its height map, `scratchmap -o` a PNG height map it read (exit 0). Their
// outputs are checked against the run's inputs, staged before the work and appear together.
TEST_F(CliTest, MapCommandsWriteAllOrNothingAndNeverOverTheirInputs) {
    const std::string g = (dir / "g.exr").string(), truth = (dir / "g-truth.png").string();
    ASSERT_EQ(runCli("gen-surface -o " + g + " --width 64 --height 64").exitCode, 0);
    const std::string map = (dir / "m.png").string();
    const std::string run = "defectmap " + g + " --truth " + truth + " -o " + map;
    std::filesystem::create_directories(dir / "m-score.csv");
    auto r = runCli(run);
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("m-score.csv"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("is a directory"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(map));
    std::filesystem::remove(dir / "m-score.csv");
    const std::string mapBytes = test::readFile(g), truthBytes = test::readFile(truth),
                      legendBytes = test::readFile(dir / "g-truth.json");
    for (const std::string& over :
         {"defectmap " + g + " --truth " + truth + " -o " + truth, run + " --score-output " + g,
          run + " --score-output " + (dir / "g-truth.json").string()}) {
        r = runCli(over);
        EXPECT_NE(r.exitCode, 0) << over << "\n" << r.output;
        EXPECT_EQ(test::readFile(g), mapBytes) << over;
        EXPECT_EQ(test::readFile(truth), truthBytes) << over;
        EXPECT_EQ(test::readFile(dir / "g-truth.json"), legendBytes) << over;
        EXPECT_FALSE(std::filesystem::exists(map)) << over;
    }
    r = runCli(run);
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_TRUE(std::filesystem::exists(map));
    EXPECT_TRUE(std::filesystem::exists(dir / "m-score.csv"));
    // scratchmap of a scene whose height map is a PNG: neither output may be that PNG.
    const std::string p = (dir / "p.png").string(), ps = (dir / "p.json").string();
    ASSERT_EQ(runCli("gen-surface -o " + p + " --width 64 --height 64 --scene " + ps).exitCode, 0);
    const std::string pngBytes = test::readFile(p);
    for (const std::string& over :
         {"scratchmap " + ps + " -o " + p,
          "scratchmap " + ps + " -o " + (dir / "s.png").string() + " --image-output " + p}) {
        r = runCli(over);
        EXPECT_EQ(r.exitCode, 1) << over << "\n" << r.output;
        EXPECT_NE(r.output.find("is an input of this run"), std::string::npos) << r.output;
        EXPECT_EQ(test::readFile(p), pngBytes) << over;
        EXPECT_FALSE(std::filesystem::exists(dir / "s.png")) << over;
    }
}

TEST_F(CliTest, AHeightMapWhereASceneIsAskedForIsTheDefaultSceneAroundIt) {
    // An instrument file (an SDF: pitch in the file) given to render as it is, -D still applies.
    std::string sdf =
        "aBCR-1.0\nManufacID = test\nCreateDate = 010120241200\n"
        "ModDate = 010120241200\nNumPoints = 8\nNumProfiles = 6\nXscale = 5e-06\n"
        "Yscale = 5e-06\nZscale = 1e-06\nZresolution = -1\nCompression = 0\n"
        "DataType = 5\nCheckType = 0\n*\n";
    for (int k = 0; k < 48; ++k) sdf += std::to_string(k % 5) + (k % 8 == 7 ? "\n" : " ");
    test::writeText(dir / "part.sdf", sdf);
    auto r = runCli("render " + (dir / "part.sdf").string() +
                    " --spp 1 -D camera.width=16 -D camera.height=16 -o " + out());
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("a height map, not a scene file: the default scene around it"),
              std::string::npos)
        << r.output;
    EXPECT_NE(r.output.find("pitch 0.005 mm (the file's)"), std::string::npos) << r.output;
    EXPECT_TRUE(std::filesystem::exists(out()));
    std::filesystem::remove(out());
    std::filesystem::remove(png());
    // Neither JSON nor a height map: the height-map readers' refusal, naming the file.
    test::writeText(dir / "notes.txt", "these are notes, not heights\n");
    expectInputError((dir / "notes.txt").string(), {"notes.txt", "no reader claims this file"});
    // A file named .json is a scene file, whatever it holds.
    test::writeText(dir / "broken.json", "these are notes\n");
    expectInputError((dir / "broken.json").string(), {"broken.json", "not valid JSON"});
}
