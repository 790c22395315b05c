// `scratchlight lamps` end to end on a small render of the bundled part: its outputs, lamps.json
// read back (io/LampsFile.h) to the same lamps, `export-mitsuba --lamps`, and its input errors.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "TestUtil.h"
#include "io/LampsFile.h"

namespace {

using namespace sl;
namespace fs = std::filesystem;

const std::string kScene = std::string(SL_SOURCE_DIR) + "/scenes/default/scene.json";

std::string readText(const fs::path& p) {
    std::ifstream in(p);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

TEST(LampCli, WritesTheLampsTheirLightAndTheReport) {
    test::TempDir dir("lamps-cli");
    const fs::path out = dir / "out";
    auto r = test::runCli("lamps " + kScene + " --size 24 --spp 4 --count 2 --no-judge --cache " +
                          (dir / "cache").string() + " --min-elevation 10 -o " + out.string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("of E*'s"), std::string::npos) << r.output;
    for (const char* f : {"lamps.json", "lamps-envmap.exr", "lamps-envmap.png", "target-envmap.exr",
                          "render-lamps.exr", "render-target.png", "renders.png", "greedy.csv",
                          "summary.json", "report.html", "plot-lamps.json"})
        EXPECT_TRUE(fs::exists(out / f)) << f;
    const auto summary = nlohmann::json::parse(readText(out / "summary.json"));
    EXPECT_EQ(summary["greedy"].size(), 2u);
    const LampsFile lamps = readLampsFile(out / "lamps.json");
    EXPECT_GE(lamps.lamps.size(), 1u);
    EXPECT_EQ(lamps.distanceMm, 500.0);
    const auto json = nlohmann::json::parse(readText(out / "lamps.json"));
    for (size_t i = 0; i < lamps.lamps.size(); ++i) {
        EXPECT_GE(json["lamps"][i]["elevation_deg"].get<double>(), 10.0 - 1e-9);
        // Read back to the same lamp: its JSON again is the same JSON.
        const auto again = lampsToJson({lamps.lamps[i]}, lamps.distanceMm)["lamps"][0];
        EXPECT_NEAR(again["solid_angle_sr"].get<double>(),
                    json["lamps"][i]["solid_angle_sr"].get<double>(), 1e-9);
        EXPECT_NEAR(again["elevation_deg"].get<double>(),
                    json["lamps"][i]["elevation_deg"].get<double>(), 1e-9);
    }
    // The lamps as Mitsuba area emitters, the only light.
    r = test::runCli("export-mitsuba " + kScene + " --lamps " + (out / "lamps.json").string() +
                     " -o " + (dir / "mitsuba").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const std::string xml = readText(dir / "mitsuba" / "scene.xml");
    EXPECT_NE(xml.find("<emitter type=\"area\">"), std::string::npos) << xml;
    EXPECT_LT(xml.find("<emitter type=\"area\">"), xml.rfind("</scene>"));
}

// The defects objective (the default when a truth names the defects), judged on the held-out
// estimate with the objective itself and per-region visibility.
TEST(LampCli, FitsTheDefectsObjectiveAndJudgesIt) {
    test::TempDir dir("lamps-cli-defects");
    const fs::path out = dir / "out";
    const std::string truth = std::string(SL_SOURCE_DIR) + "/scenes/default/part-truth.png";
    auto r = test::runCli("lamps " + kScene + " --size 64 --spp 4 --count 1 --no-figures --truth " +
                          truth + " --cache " + (dir / "cache").string() + " -o " + out.string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("judge (defect visibility on the held-out estimate"), std::string::npos)
        << r.output;
    EXPECT_NE(r.output.find("visibility of"), std::string::npos) << r.output;
    const auto summary = nlohmann::json::parse(readText(out / "summary.json"));
    EXPECT_EQ(summary["objective"], "defects");
    const auto& j = summary["judge"]["objective"];
    EXPECT_TRUE(j["higher_is_better"].get<bool>());
    const double target = j["target"].get<double>(), lamps = j["lamps"].get<double>();
    EXPECT_NEAR(j["lamps_gap"].get<double>(), (target - lamps) / target, 1e-12);
    // The measure is the judge's visibility of the defect region.
    ASSERT_EQ(summary["judge"]["lamps"]["visibility"].size(), 1u);
    EXPECT_NEAR(summary["judge"]["lamps"]["visibility"][0]["visibility"].get<double>(), lamps,
                1e-12 * std::abs(lamps));
    EXPECT_NE(readText(out / "report.html").find("visibility: "), std::string::npos);
}

TEST(LampCli, RefusesBadInputWithTheRightExitCode) {
    test::TempDir dir("lamps-cli-bad");
    const std::string base = "lamps " + kScene + " --size 16 --spp 2 --no-judge --cache " +
                             (dir / "cache").string() + " -o " + (dir / "o").string();
    auto r = test::runCli(base + " --kinds dome");
    EXPECT_EQ(r.exitCode, 2) << r.output;
    r = test::runCli(base + " --count 9");
    EXPECT_EQ(r.exitCode, 2) << r.output;
    r = test::runCli(base + " --forbid-azimuth 10-20");
    EXPECT_EQ(r.exitCode, 2) << r.output;
    EXPECT_NE(r.output.find("FROM:TO"), std::string::npos) << r.output;
    r = test::runCli(base + " --min-elevation 60 --max-elevation 30");
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("--min-elevation"), std::string::npos) << r.output;
    r = test::runCli(base + " --from " + (dir / "missing.exr").string());
    EXPECT_EQ(r.exitCode, 1) << r.output;
    r = test::runCli(base + " --objective defects --defects " + (dir / "missing.png").string());
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("missing.png"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir / "o"));
    r = test::runCli("export-mitsuba " + kScene + " --lamps " + (dir / "none.json").string() +
                     " -o " + (dir / "m").string());
    EXPECT_EQ(r.exitCode, 1) << r.output;
}

}  // namespace
