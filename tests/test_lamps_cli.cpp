// `scratchlight lamps` end to end on a small render of the bundled part: its outputs, lamps.json
// read back (io/LampsFile.h) to the same lamps, `export-mitsuba --lamps`, and its input errors.
#include <gtest/gtest.h>

#include <cmath>
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
                          "summary.json", "report.html", "plot-lamps.json", "plot-lamps.png"})
        EXPECT_TRUE(fs::exists(out / f)) << f;
    const auto summary = nlohmann::json::parse(readText(out / "summary.json"));
    EXPECT_EQ(summary["plot"], "plot-lamps.png");  // drawn in-process: no Python needed
    for (const char* phase : {"load", "target", "fit", "judge", "self_check", "outputs"})
        EXPECT_GE(summary["seconds_phases"][phase].get<double>(), 0.0) << phase;
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
    auto r = test::runCli("lamps " + kScene + " --size 64 --spp 4 --count 2 --no-figures --truth " +
                          truth + " --cache " + (dir / "cache").string() + " -o " + out.string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("judge (defect visibility on the held-out estimate"), std::string::npos)
        << r.output;
    // Each region's JND first (the lamps job's judge has the scene's viewing model), its
    // visibility ratio beside it.
    EXPECT_NE(r.output.find("JND under the lamps"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("(visibility ratio"), std::string::npos) << r.output;
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
    // The self-check: every K's lamps and the studio lamp on the validation estimate; the answer
    // is one of them and is said.
    const auto& a = summary["answer"];
    ASSERT_TRUE(a.is_object()) << summary.dump(2);
    ASSERT_EQ(a["candidates"].size(), 3u);  // 1 lamp, 2 lamps, the studio preset
    EXPECT_EQ(a["candidates"][0]["name"], "1 lamp");
    EXPECT_EQ(a["candidates"][1]["name"], "2 lamps");
    EXPECT_EQ(a["candidates"][2]["name"], "studio preset");
    EXPECT_EQ(a["candidates"][2]["kind"], "reference");
    bool found = false;
    for (const auto& c : a["candidates"]) found |= c["name"] == a["light"];
    EXPECT_TRUE(found);
    EXPECT_NE(r.output.find("The answer is"), std::string::npos) << r.output;
    EXPECT_NE(readText(out / "report.html").find("The answer is"), std::string::npos);
}

/// The numbers of attribute `name`="..." of the first element after `from` in `xml`.
std::vector<double> xmlNumbers(const std::string& xml, const std::string& element, size_t from) {
    const size_t at = xml.find(element, from);
    const size_t q = xml.find("value=\"", at) + 7;
    std::vector<double> v;
    std::stringstream s(xml.substr(q, xml.find('"', q) - q));
    for (std::string part; std::getline(s, part, ',');) v.push_back(std::stod(part));
    return v;
}

// Seen from the part's centre, each Mitsuba emitter covers the lamp's angles: a ring's cylinder
// exactly its elevation band, a disk exactly its cone about its direction.
TEST(LampMitsuba, EmittersSubtendTheLampsAngles) {
    constexpr double kDeg = 3.14159265358979323846 / 180;
    LampsFile f;
    f.distanceMm = 400;
    Lamp ring;
    ring.kind = LampKind::Ring;
    ring.elevation = 36 * kDeg;
    ring.size = 4 * kDeg;
    Lamp disk;
    disk.kind = LampKind::Disk;
    disk.azimuth = 30 * kDeg;
    disk.elevation = 50 * kDeg;
    disk.size = 10 * kDeg;
    f.lamps = {ring, disk};
    const std::string xml = mitsubaLampShapes(f);
    const size_t cyl = xml.find("type=\"cylinder\"");
    ASSERT_NE(cyl, std::string::npos) << xml;
    const double y0 = xmlNumbers(xml, "name=\"p0\"", cyl)[1];
    const double y1 = xmlNumbers(xml, "name=\"p1\"", cyl)[1];
    const double radius = xmlNumbers(xml, "name=\"radius\"", cyl)[0];
    EXPECT_NEAR(std::atan2(y0, radius), 32 * kDeg, 1e-7);
    EXPECT_NEAR(std::atan2(y1, radius), 40 * kDeg, 1e-7);
    const size_t dk = xml.find("type=\"disk\"");
    ASSERT_NE(dk, std::string::npos) << xml;
    const size_t sc = xml.find("<scale x=\"", dk) + 10;
    const double r = std::stod(xml.substr(sc, xml.find('"', sc) - sc));
    EXPECT_NEAR(std::atan(r / f.distanceMm), 10 * kDeg, 1e-7);
    const size_t lk = xml.find("origin=\"", dk) + 8;
    std::vector<double> o;
    std::stringstream os(xml.substr(lk, xml.find('"', lk) - lk));
    for (std::string part; std::getline(os, part, ',');) o.push_back(std::stod(part));
    ASSERT_EQ(o.size(), 3u);
    const Vec3d c = lampDirection(disk.azimuth, disk.elevation);
    EXPECT_NEAR(o[0], f.distanceMm * c.x, 1e-4);
    EXPECT_NEAR(o[1], f.distanceMm * c.y, 1e-4);
    EXPECT_NEAR(o[2], f.distanceMm * c.z, 1e-4);
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
