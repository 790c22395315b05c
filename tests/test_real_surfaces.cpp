// Measured surfaces: levelling and form removal (scene/Levelling.h, exact on synthetic forms),
// the scene file's heightmap.levelling, non-square pixels, X3P members in a folder, and every
// file of ../shared/real-surfaces (skipped with a message when that folder is absent) read,
// levelled and rendered through the CLI. Tests that need Gwyddion's file modules have
// "Gwyddion" in their name and are skipped only in a build without it (SCRATCHLIGHT_GWYDDION).
#include <gtest/gtest.h>
#include <zip.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "TestUtil.h"
#include "core/Error.h"
#include "io/GwyddionReader.h"
#include "io/HeightmapIO.h"
#include "io/SceneFile.h"
#include "io/X3p.h"
#include "scene/Levelling.h"

namespace sl {
namespace {

namespace fs = std::filesystem;
using Mode = LevellingDesc::Mode;

double coordX(int i, int w, double p) {
    return (i - (w - 1) / 2.0) * p;
}

LevellingDesc mode(Mode m, int degree = 1, char axis = 'y') {
    LevellingDesc d;
    d.mode = m;
    d.degree = degree;
    d.axis = axis;
    return d;
}

double maxAbs(const std::vector<float>& v, const std::vector<uint8_t>& invalid = {}) {
    double m = 0;
    for (size_t k = 0; k < v.size(); ++k)
        if (invalid.empty() || !invalid[k]) m = std::max(m, std::abs(static_cast<double>(v[k])));
    return m;
}

TEST(Levelling, TiltedPlaneLevelsToZeroIgnoringInvalidPoints) {
    const int w = 40, h = 30;
    const double p = 0.01;
    std::vector<float> z(static_cast<size_t>(w * h));
    std::vector<uint8_t> invalid(z.size(), 0);
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i)
            z[static_cast<size_t>(j * w + i)] =
                static_cast<float>(0.3 + 0.02 * coordX(i, w, p) - 0.05 * coordX(j, h, p));
    for (size_t k = 7; k < z.size(); k += 37) {  // invented points far off the plane
        z[k] = 5.0f;
        invalid[k] = 1;
    }
    const LevellingResult r = levelHeights(z, w, h, p, invalid, mode(Mode::Plane), true, "plane");
    EXPECT_LT(maxAbs(z, invalid), 1e-7);
    EXPECT_EQ(r.points, z.size() - 33);
    EXPECT_GT(r.rmsBefore, 0.0);
    EXPECT_LT(r.rmsAfter, 1e-7);
    // auto: a plane for a measured map, nothing for a designed one
    std::vector<float> z2(z.size(), 1.0f);
    EXPECT_EQ(levelHeights(z2, w, h, p, {}, {}, false, "x").applied.mode, Mode::None);
    EXPECT_EQ(z2[0], 1.0f);
    EXPECT_EQ(levelHeights(z2, w, h, p, {}, {}, true, "x").applied.mode, Mode::Plane);
    EXPECT_LT(maxAbs(z2), 1e-7);
}

TEST(Levelling, PolynomialOfDegreeNRemovesADegreeNSurfaceExactly) {
    const int w = 64, h = 48;
    const double p = 0.005;
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-1, 1);
    for (int n = 0; n <= 5; ++n) {
        // Σ c_ab x^a y^b over a + b ≤ n, x and y in mm (|x| ≤ 0.16), heights ~ 0.01 mm
        std::vector<double> c;
        for (int t = 0; t <= n; ++t)
            for (int a = 0; a <= t; ++a) c.push_back(u(rng) * 0.01 / std::pow(0.16, t));
        std::vector<float> z(static_cast<size_t>(w * h));
        double peak = 0;
        for (int j = 0; j < h; ++j)
            for (int i = 0; i < w; ++i) {
                const double x = coordX(i, w, p), y = coordX(j, h, p);
                double v = 0;
                size_t k = 0;
                for (int t = 0; t <= n; ++t)
                    for (int a = 0; a <= t; ++a) v += c[k++] * std::pow(x, a) * std::pow(y, t - a);
                z[static_cast<size_t>(j * w + i)] = static_cast<float>(v);
                peak = std::max(peak, std::abs(v));
            }
        levelHeights(z, w, h, p, {}, mode(Mode::Polynomial, n), true, "poly");
        EXPECT_LT(maxAbs(z), 2e-6 * peak) << "degree " << n;
        // one degree less leaves some of it
        if (n >= 1) {
            std::vector<float> z2(z.size());
            for (int j = 0; j < h; ++j)
                for (int i = 0; i < w; ++i)
                    z2[static_cast<size_t>(j * w + i)] =
                        static_cast<float>(std::pow(coordX(i, w, p), n) * 10);
            levelHeights(z2, w, h, p, {}, mode(Mode::Polynomial, n - 1), true, "poly");
            EXPECT_GT(maxAbs(z2), 1e-4 * std::pow(0.16, n)) << "degree " << n;
        }
    }
}

/// A cylinder of radius R along `axis` (convex or concave), tilted along the axis, plus a small
/// texture across it: levelling by the cylinder leaves the texture.
void cylinderCase(char axis, double sigma) {
    const int w = 200, h = 120;
    const double p = 0.002, R = 2.0;  // a 0.4 × 0.24 mm patch of a 2 mm radius
    std::vector<float> z(static_cast<size_t>(w * h)), texture(z.size());
    std::vector<uint8_t> invalid(z.size(), 0);
    double texMean = 0;
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i) {
            const double x = coordX(i, w, p), y = coordX(j, h, p);
            const double s = axis == 'y' ? x : y, t = axis == 'y' ? y : x;
            const size_t k = static_cast<size_t>(j * w + i);
            const double tex =
                2e-4 * std::sin(2 * M_PI * s / 0.011) * std::cos(2 * M_PI * t / 0.017);
            texture[k] = static_cast<float>(tex);
            texMean += tex;
            z[k] = static_cast<float>(0.1 + sigma * std::sqrt(R * R - (s - 0.03) * (s - 0.03)) +
                                      0.01 * t + tex);
        }
    texMean /= static_cast<double>(z.size());
    for (size_t k = 3; k < z.size(); k += 101) {
        z[k] = -3.0f;
        invalid[k] = 1;
    }
    const LevellingResult r =
        levelHeights(z, w, h, p, invalid, mode(Mode::Cylinder, 1, axis), true, "cyl");
    EXPECT_NEAR(std::abs(r.radius), R, 2e-3 * R) << axis;
    EXPECT_EQ(r.radius > 0, sigma > 0) << axis;
    double worst = 0;
    for (size_t k = 0; k < z.size(); ++k)
        if (!invalid[k]) worst = std::max(worst, std::abs(z[k] - (texture[k] - texMean)));
    EXPECT_LT(worst, 0.03 * 2e-4) << axis << " sigma " << sigma;  // 3 % of the texture's amplitude
    EXPECT_LT(r.rmsAfter, 1.1 * 2e-4 / 2) << axis;
}

TEST(Levelling, CylinderOfKnownRadiusLevelsToTheTexture) {
    cylinderCase('y', 1.0);
    cylinderCase('x', 1.0);
    cylinderCase('y', -1.0);
}

TEST(Levelling, CylinderOnAFlatMapIsAClearError) {
    std::vector<float> z(100, 0.0f);
    for (size_t k = 0; k < z.size(); ++k) z[k] = static_cast<float>(k % 10) * 1e-3f;
    try {
        levelHeights(z, 10, 10, 0.01, {}, mode(Mode::Cylinder, 1, 'y'), true, "flat.x3p");
        FAIL() << "a line has no circle";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("flat.x3p"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("plane"), std::string::npos) << e.what();
    }
}

// --- the scene file -----------------------------------------------------------------------------

TEST(Levelling, SceneFileFieldStringsObjectsAndOverrides) {
    test::TempDir dir("level");
    const int n = 24;
    std::vector<float> mm(static_cast<size_t>(n * n));
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
            mm[static_cast<size_t>(j * n + i)] =
                0.001f * static_cast<float>(i) + 0.0005f * static_cast<float>(j);
    writeX3p(dir / "tilt.x3p", n, n, mm, 0.01);
    test::writeText(dir / "s.json", R"({"heightmap": {"path": "tilt.x3p"}})");
    const auto scene = loadScene(dir / "s.json");
    EXPECT_EQ(scene->load.levelling.applied.mode, Mode::Plane);
    EXPECT_TRUE(scene->load.levelling.automatic);
    EXPECT_LT(maxAbs(scene->heights), 1e-7);
    EXPECT_EQ(loadScene(dir / "s.json", {"heightmap.levelling=none"})->heights[5], mm[5]);
    const auto poly = readSceneFile(dir / "s.json", {"heightmap.levelling=polynomial:3"});
    EXPECT_EQ(poly.heightmap.levelling.mode, Mode::Polynomial);
    EXPECT_EQ(poly.heightmap.levelling.degree, 3);
    const auto cyl =
        readSceneFile(dir / "s.json", {R"(heightmap.levelling={"mode": "cylinder", "axis": "x"})"});
    EXPECT_EQ(cyl.heightmap.levelling.mode, Mode::Cylinder);
    EXPECT_EQ(cyl.heightmap.levelling.axis, 'x');
    const auto cyl2 = readSceneFile(
        dir / "s.json", {"heightmap.levelling.mode=cylinder", "heightmap.levelling.axis=y"});
    EXPECT_EQ(cyl2.heightmap.levelling.axis, 'y');
    const auto refused = [&](const std::string& o, const std::string& part) {
        try {
            readSceneFile(dir / "s.json", {o});
            ADD_FAILURE() << o << " was accepted";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find("heightmap.levelling"), std::string::npos)
                << e.what();
        }
    };
    refused("heightmap.levelling=sphere", "sphere");
    refused("heightmap.levelling=polynomial", "degree");
    refused("heightmap.levelling=polynomial:11", "[0, 10]");
    refused("heightmap.levelling=cylinder", "x or y");
    refused("heightmap.levelling=cylinder:z", "\"z\"");
    refused(R"(heightmap.levelling={"mode": "plane", "axis": "x"})", "cylinder");
    refused(R"(heightmap.levelling={"mode": "plane", "radius": 2})", "radius");
    refused("heightmap.levelling=3", "string or an object");
    // recorded for summaries
    const nlohmann::ordered_json j = heightmapLoadJson(*scene);
    EXPECT_EQ(j["levelling"]["mode"], "plane");
    EXPECT_EQ(j["levelling"]["auto"], true);
    EXPECT_EQ(j["size"][0], n);
    EXPECT_EQ(j["measured"], true);
}

// heightmap.measured: unset, the file says (an X3P is a measurement); the scene overrides it
// either way; anything but a boolean is refused naming the field. The defect map's auto follows
// it: on a measurement it is the selfsim method (detect/DefectMap.h).
TEST(Levelling, SceneFileSaysWhetherTheMapIsAMeasurement) {
    test::TempDir dir("measured");
    const int n = 16;
    std::vector<float> mm(static_cast<size_t>(n * n), 0.0f);
    writeX3p(dir / "m.x3p", n, n, mm, 0.01);
    test::writeText(dir / "s.json", R"({"heightmap": {"path": "m.x3p"}})");
    EXPECT_TRUE(loadScene(dir / "s.json")->load.measured);
    EXPECT_FALSE(loadScene(dir / "s.json", {"heightmap.measured=false"})->load.measured);
    EXPECT_FALSE(
        heightmapLoadJson(*loadScene(dir / "s.json", {"heightmap.measured=false"}))["measured"]
            .get<bool>());
    EXPECT_TRUE(loadHeightSource(dir / "m.x3p").measured());
    EXPECT_TRUE(loadHeightSource(dir / "s.json").measured());
    try {
        readSceneFile(dir / "s.json", {"heightmap.measured=1"});
        ADD_FAILURE() << "measured=1 was accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("heightmap.measured"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("true or false"), std::string::npos) << e.what();
    }
}

// --- readers ------------------------------------------------------------------------------------

TEST(FormatsX3p, NonSquarePixelsAreResampledOntoTheFinerPitch) {
    test::TempDir dir("x3p");
    // writeX3p writes square pixels; rewrite its CY increment to 3× CX.
    const int w = 5, h = 4;
    std::vector<float> mm(static_cast<size_t>(w * h));
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i)
            mm[static_cast<size_t>(j * w + i)] =
                0.01f * static_cast<float>(j) + 0.001f * static_cast<float>(i);
    writeX3p(dir / "sq.x3p", w, h, mm, 0.002);
    int err = 0;
    zip_t* z = zip_open((dir / "sq.x3p").c_str(), 0, &err);
    ASSERT_NE(z, nullptr);
    zip_stat_t st;
    ASSERT_EQ(zip_stat(z, "main.xml", 0, &st), 0);
    std::string xml(st.size, '\0');
    zip_file_t* f = zip_fopen(z, "main.xml", 0);
    ASSERT_EQ(zip_fread(f, xml.data(), st.size), static_cast<zip_int64_t>(st.size));
    zip_fclose(f);
    const std::string cy = "<CY><AxisType>I</AxisType><DataType>D</DataType><Increment>2e-06";
    const size_t at = xml.find(cy);
    ASSERT_NE(at, std::string::npos) << xml;
    xml.replace(at, cy.size(), "<CY><AxisType>I</AxisType><DataType>D</DataType><Increment>6e-06");
    zip_source_t* src = zip_source_buffer(z, xml.data(), xml.size(), 0);
    ASSERT_GE(zip_file_add(z, "main.xml", src, ZIP_FL_OVERWRITE), 0);
    zip_delete(z, zip_name_locate(z, "md5checksum.hex", 0));
    ASSERT_EQ(zip_close(z), 0);
    const HeightmapData d = loadHeightmap(dir / "sq.x3p", {});
    EXPECT_EQ(d.width, 5);
    EXPECT_EQ(d.height, 10);  // (4 − 1)·3 + 1 rows at 0.002 mm
    ASSERT_TRUE(d.pitch);
    EXPECT_NEAR(*d.pitch, 0.002, 1e-15);
    EXPECT_FALSE(d.pitchY);
    EXPECT_NE(d.resampling.find("linear interpolation along y"), std::string::npos) << d.resampling;
    for (int j = 0; j < d.height; ++j)  // a linear ramp is kept exactly
        for (int i = 0; i < w; ++i)
            EXPECT_NEAR(d.heights[static_cast<size_t>(j * w + i)], 0.01 * j / 3.0 + 0.001 * i, 1e-7)
                << j << "," << i;
}

/// Repacks an X3P's members into `folder/` with macOS's __MACOSX entries beside them.
void repackInFolder(const fs::path& in, const fs::path& out, const std::string& folder) {
    int err = 0;
    zip_t* a = zip_open(in.c_str(), ZIP_RDONLY, &err);
    ASSERT_NE(a, nullptr);
    zip_t* b = zip_open(out.c_str(), ZIP_CREATE | ZIP_TRUNCATE, &err);
    ASSERT_NE(b, nullptr);
    std::vector<std::string> keep;
    zip_dir_add(b, folder.c_str(), 0);
    for (zip_int64_t i = 0; i < zip_get_num_entries(a, 0); ++i) {
        const std::string name = zip_get_name(a, static_cast<zip_uint64_t>(i), 0);
        zip_stat_t st;
        zip_stat_index(a, static_cast<zip_uint64_t>(i), 0, &st);
        keep.emplace_back(st.size, '\0');
        zip_file_t* f = zip_fopen_index(a, static_cast<zip_uint64_t>(i), 0);
        zip_fread(f, keep.back().data(), st.size);
        zip_fclose(f);
        zip_source_t* s = zip_source_buffer(b, keep.back().data(), keep.back().size(), 0);
        ASSERT_GE(zip_file_add(b, (folder + "/" + name).c_str(), s, 0), 0);
    }
    static const std::string junk = "Mac resource fork";
    for (const char* n : {"__MACOSX/._x", "__MACOSX/x/main.xml"}) {
        zip_source_t* s = zip_source_buffer(b, junk.data(), junk.size(), 0);
        ASSERT_GE(zip_file_add(b, n, s, 0), 0);
    }
    ASSERT_EQ(zip_close(b), 0);
    zip_discard(a);
}

TEST(FormatsX3p, MembersInAFolderBesideMacosxEntriesAreRead) {
    test::TempDir dir("x3p");
    const int w = 6, h = 5;
    std::vector<float> mm(static_cast<size_t>(w * h));
    for (size_t k = 0; k < mm.size(); ++k) mm[k] = 0.0001f * static_cast<float>(k);
    writeX3p(dir / "flat.x3p", w, h, mm, 0.003);
    repackInFolder(dir / "flat.x3p", dir / "folder.x3p", "sample-land");
    const HeightmapData d = loadHeightmap(dir / "folder.x3p", {});
    EXPECT_EQ(d.width, w);
    EXPECT_EQ(d.height, h);
    EXPECT_TRUE(d.warnings.empty());
    for (size_t k = 0; k < mm.size(); ++k) EXPECT_FLOAT_EQ(d.heights[k], mm[k]);
    // by content: the same file named .dat is still an X3P
    fs::copy_file(dir / "folder.x3p", dir / "folder.dat");
    EXPECT_EQ(loadHeightmap(dir / "folder.dat", {}).format, "x3p float64");
}

TEST(FormatsGwyddion, ReadsGwyddionsOwnFileByContent) {
    if (!SL_HAVE_GWYDDION) GTEST_SKIP() << "built with -DSCRATCHLIGHT_GWYDDION=OFF";
    test::TempDir dir("gwy");
    const int w = 7, h = 4;
    std::vector<float> mm(static_cast<size_t>(w * h));
    for (size_t k = 0; k < mm.size(); ++k) mm[k] = 0.001f * static_cast<float>(k) - 0.01f;
    mm[9] = std::numeric_limits<float>::quiet_NaN();  // .gwy keeps NaN: filled as an invalid point
    writeGwy(dir / "m.gwy", w, h, mm, 0.0025);
    fs::copy_file(dir / "m.gwy", dir / "m.bin");  // a name that says nothing
    for (const char* name : {"m.gwy", "m.bin"}) {
        const HeightmapData d = loadHeightmap(dir / name, {});
        EXPECT_EQ(d.format.rfind("gwyddion gwyfile", 0), 0u) << d.format;
        EXPECT_EQ(d.width, w);
        EXPECT_EQ(d.height, h);
        ASSERT_TRUE(d.pitch);
        EXPECT_NEAR(*d.pitch, 0.0025, 1e-12);
        EXPECT_EQ(d.invalidFilled, 1u);
        for (size_t k = 0; k < mm.size(); ++k)
            if (k != 9) {
                EXPECT_FLOAT_EQ(d.heights[k], mm[k]) << k;
            }
    }
    test::writeText(dir / "junk.xyz123", "nothing any reader knows\n");
    EXPECT_THROW(loadHeightmap(dir / "junk.xyz123", {}), InputError);
}

// An instrument file of several channels (an AFM's Amplitude beside its Height, both in metres;
// a Phase in degrees): the height channel is read by its title, any channel by number or title
// when heightmap.channel asks, and a channel that holds no heights, is not there or is named
// ambiguously is refused naming heightmap.channel and listing the file's channels.
TEST(FormatsGwyddion, AFileOfSeveralChannelsReadsItsHeightChannelOrTheOneAskedFor) {
    if (!SL_HAVE_GWYDDION) GTEST_SKIP() << "built with -DSCRATCHLIGHT_GWYDDION=OFF";
    test::TempDir dir("gwych");
    const int w = 6, h = 5;
    const size_t n = static_cast<size_t>(w * h);
    std::vector<float> amplitude(n), height(n), phase(n);
    for (size_t k = 0; k < n; ++k) {
        amplitude[k] = 0.0001f * static_cast<float>(k);
        height[k] = 0.002f * std::sin(0.7f * static_cast<float>(k));
        phase[k] = 10.0f + static_cast<float>(k);
    }
    writeGwy(dir / "afm.gwy", w, h,
             {{"Amplitude", "m", amplitude}, {"Height", "m", height}, {"Phase", "deg", phase}},
             0.001);
    const auto read = [&](const std::string& channel) {
        HeightmapOptions o;
        o.channel = channel;
        return loadHeightmap(dir / "afm.gwy", o);
    };
    const auto same = [&](const std::vector<float>& got, const std::vector<float>& want) {
        ASSERT_EQ(got.size(), want.size());
        for (size_t k = 0; k < want.size(); ++k) EXPECT_NEAR(got[k], want[k], 1e-9) << k;
    };
    // the rule: the channel in metres whose title names heights, not the lowest-numbered one
    const HeightmapData byTitle = read("");
    same(byTitle.heights, height);
    EXPECT_NE(byTitle.channel.find("channel 1 \"Height\" (heights in m)"), std::string::npos)
        << byTitle.channel;
    EXPECT_NE(byTitle.channel.find("0 \"Amplitude\" (heights in m)"), std::string::npos);
    EXPECT_NE(byTitle.channel.find("2 \"Phase\" (deg)"), std::string::npos);
    // asked for: by number, by whole title in any case, by a part naming one channel
    same(read("0").heights, amplitude);
    same(read("AMPLITUDE").heights, amplitude);
    same(read("eigh").heights, height);
    EXPECT_NE(read("0").channel.find("as heightmap.channel asks"), std::string::npos);
    const auto refused = [&](const std::string& channel, const std::string& says) {
        HeightmapOptions o;
        o.channel = channel;
        test::expectRefused(dir / "afm.gwy", {"heightmap.channel", says, "1 \"Height\""}, o);
    };
    refused("2", "does not hold heights in metres");
    refused("phase", "does not hold heights in metres");
    refused("7", "no channel \"7\"");
    refused("a", "names more than one channel");  // Amplitude and Phase

    // no title says heights: the lowest-numbered channel in metres
    writeGwy(dir / "untitled.gwy", w, h,
             {{"Error", "V", phase}, {"", "m", height}, {"", "m", amplitude}}, 0.001);
    const HeightmapData first = loadHeightmap(dir / "untitled.gwy", {});
    same(first.heights, height);
    EXPECT_NE(first.channel.find("channel 1 (heights in m), the first in metres"),
              std::string::npos)
        << first.channel;
    // one channel: nothing to say
    writeGwy(dir / "one.gwy", w, h, height, 0.001);
    EXPECT_EQ(loadHeightmap(dir / "one.gwy", {}).channel, "");
    // a file our own reader reads holds one height map: a channel asked of it is refused
    writeX3p(dir / "one.x3p", w, h, height, 0.001);
    HeightmapOptions zero;
    zero.channel = "0";
    test::expectRefused(dir / "one.x3p", {"heightmap.channel"}, zero);

    // the scene's heightmap.channel (and -D), recorded in the summary's heightmap section
    test::writeText(dir / "scene.json",
                    R"({"heightmap": {"path": "afm.gwy", "levelling": "none", "channel": 0}})");
    const std::unique_ptr<Scene> s0 = loadScene(dir / "scene.json", {});
    same(s0->heights, amplitude);
    const std::unique_ptr<Scene> s1 = loadScene(dir / "scene.json", {"heightmap.channel=Height"});
    same(s1->heights, height);
    const nlohmann::ordered_json j = heightmapLoadJson(*s1);
    ASSERT_TRUE(j.at("channel").is_string());
    EXPECT_NE(j.at("channel").get<std::string>().find("\"Height\""), std::string::npos);
    // a bare map takes the same override, as the default scene around it (defectmap, info)
    const HeightSource bare = loadHeightSource(
        dir / "afm.gwy", {"heightmap.channel=amplitude", "heightmap.levelling=none"});
    ASSERT_TRUE(bare.scene);
    same(bare.heights(), amplitude);
    same(loadHeightSource(dir / "afm.gwy").heights(), [&] {  // no override: the Height, levelled
        HeightmapData d = loadHeightmap(dir / "afm.gwy", {});
        levelHeights(d.heights, d.width, d.height, *d.pitch, d.invalid, LevellingDesc{}, true,
                     "afm.gwy");
        return d.heights;
    }());
    test::writeText(dir / "bad.json", R"({"heightmap": {"path": "afm.gwy", "channel": -1}})");
    try {
        loadScene(dir / "bad.json", {});
        ADD_FAILURE() << "read";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("heightmap.channel"), std::string::npos) << e.what();
    }
}

// A channel of heights in metres on a grid without lateral calibration (an AFM file saved in
// pixels): read with a warning, its heights in mm and no pitch, a measurement (levelled as one);
// the scene gives the spacing, and without it the refusal says why and names
// heightmap.pixel_pitch. A channel over lateral axes in another unit (seconds) is not a height map.
TEST(FormatsGwyddion, HeightsOnAnUncalibratedGridTakeTheScenesPitch) {
    if (!SL_HAVE_GWYDDION) GTEST_SKIP() << "built with -DSCRATCHLIGHT_GWYDDION=OFF";
    test::TempDir dir("gwypx");
    const int w = 7, h = 6;
    const size_t n = static_cast<size_t>(w * h);
    std::vector<float> height(n), signal(n);
    for (size_t k = 0; k < n; ++k) {
        height[k] = 0.001f * std::cos(0.5f * static_cast<float>(k));
        signal[k] = 0.002f * static_cast<float>(k);
    }
    writeGwy(dir / "px.gwy", w, h, {{"Height", "m", height, ""}}, 0.001);
    const HeightmapData d = loadHeightmap(dir / "px.gwy", {});
    EXPECT_FALSE(d.pitch);
    EXPECT_TRUE(d.uncalibratedLateral);
    EXPECT_TRUE(d.measured());
    ASSERT_EQ(d.heights.size(), n);
    for (size_t k = 0; k < n; ++k) EXPECT_NEAR(d.heights[k], height[k], 1e-9) << k;
    ASSERT_EQ(d.warnings.size(), 1u);
    EXPECT_NE(d.warnings[0].find("carries no lateral calibration"), std::string::npos)
        << d.warnings[0];
    EXPECT_NE(d.warnings[0].find("heightmap.pixel_pitch"), std::string::npos);
    // a scene without a pitch: refused, saying why and what to add
    test::writeText(dir / "scene.json", R"({"heightmap": {"path": "px.gwy"}})");
    test::expectInputError([&] { loadScene(dir / "scene.json", {}); },
                           {"scene.json", "lateral axes carry no calibration", "pixel_pitch"});
    // with one: its pitch, levelled as a measurement (auto: plane)
    const std::unique_ptr<Scene> s = loadScene(dir / "scene.json", {"heightmap.pixel_pitch=0.002"});
    EXPECT_DOUBLE_EQ(s->desc.heightmap.pitch, 0.002);
    EXPECT_TRUE(s->load.measured);
    EXPECT_TRUE(s->load.levelling.automatic);
    EXPECT_NE(s->load.levelling.text().find("plane"), std::string::npos)
        << s->load.levelling.text();
    // pixels ("px") are uncalibrated too; seconds are not a length: refused, listing channels
    writeGwy(dir / "two.gwy", w, h, {{"Height", "m", height, "px"}, {"Time", "m", signal, "s"}},
             0.001);
    EXPECT_TRUE(loadHeightmap(dir / "two.gwy", {}).uncalibratedLateral);
    HeightmapOptions time;
    time.channel = "Time";
    test::expectRefused(dir / "two.gwy",
                        {"heightmap.channel", "lateral axes in s, not a length",
                         "0 \"Height\" (heights in m, lateral uncalibrated)"},
                        time);
}

// A measurement more than half invalid whose valid points lie in a smaller rectangle (a part
// smaller than the instrument's field) is read as that rectangle, exactly, with a warning; one
// whose valid points are spread over the field is still refused; one at most half invalid keeps
// its grid (its invalid border filled, as before).
TEST(Formats, AMeasurementMostlyInvalidAroundItsPartIsCroppedToIt) {
    test::TempDir dir("crop");
    const int w = 20, h = 10;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    std::vector<float> mm(static_cast<size_t>(w * h), nan);
    const auto at = [&](int x, int y) -> float& { return mm[static_cast<size_t>(y * w + x)]; };
    for (int y = 2; y <= 6; ++y)
        for (int x = 3; x <= 9; ++x) at(x, y) = 0.001f * static_cast<float>(x + 10 * y);
    at(5, 4) = nan;  // an invalid point inside the part: filled
    writeX3p(dir / "part.x3p", w, h, mm, 0.002);
    const HeightmapData d = loadHeightmap(dir / "part.x3p", {});
    ASSERT_EQ(d.width, 7);
    ASSERT_EQ(d.height, 5);
    EXPECT_EQ(d.invalidFilled, 1u);
    for (int y = 0; y < 5; ++y)
        for (int x = 0; x < 7; ++x)
            if (!(x == 2 && y == 2)) {
                EXPECT_FLOAT_EQ(d.heights[static_cast<size_t>(y * 7 + x)], at(x + 3, y + 2));
            }
    ASSERT_EQ(d.warnings.size(), 1u);
    EXPECT_NE(d.warnings[0].find("columns 3..9 and rows 2..6"), std::string::npos) << d.warnings[0];
    // valid points at two far corners: the box is the whole map, still mostly invalid
    std::vector<float> spread(static_cast<size_t>(w * h), nan);
    for (int y = 0; y < 3; ++y)
        for (int x = 0; x < 3; ++x) {
            spread[static_cast<size_t>(y * w + x)] = 0.001f;
            spread[static_cast<size_t>((h - 1 - y) * w + (w - 1 - x))] = 0.002f;
        }
    writeX3p(dir / "spread.x3p", w, h, spread, 0.002);
    test::expectRefused(dir / "spread.x3p", {"more than half", "Crop the measurement"});
    // at most half invalid: the file's grid, the border filled
    std::vector<float> half(static_cast<size_t>(w * h), 0.001f);
    for (int x = 0; x < w; ++x) half[static_cast<size_t>(x)] = nan;  // row 0
    writeX3p(dir / "half.x3p", w, h, half, 0.002);
    const HeightmapData hd = loadHeightmap(dir / "half.x3p", {});
    EXPECT_EQ(hd.width, w);
    EXPECT_EQ(hd.height, h);
    EXPECT_EQ(hd.invalidFilled, static_cast<size_t>(w));
    EXPECT_TRUE(hd.warnings.empty());
}

// A file Gwyddion reads that holds no image says what it holds instead: a point cloud (its XYZ
// text module reads three columns of numbers) is named as one, with how to grid it.
TEST(FormatsGwyddion, APointCloudIsRefusedAsOneWithHowToGridIt) {
    if (!SL_HAVE_GWYDDION) GTEST_SKIP() << "built with -DSCRATCHLIGHT_GWYDDION=OFF";
    test::TempDir dir("xyz");
    std::string text;
    for (int k = 0; k < 200; ++k) {
        // scattered, not on a grid (points on a regular grid are read as an image)
        const double x = 1e-4 * std::fmod(0.618034 * k, 1.0),
                     y = 1e-4 * std::fmod(0.754878 * k + 0.1, 1.0), z = 1e-8 * ((k * 7) % 13);
        text += std::to_string(x) + " " + std::to_string(y) + " " + std::to_string(z) + "\n";
    }
    test::writeText(dir / "points.xyz", text);
    test::expectRefused(dir / "points.xyz",
                        {"1 point cloud (XYZ data), not a grid of heights", "Rasterize"});
}

// A file no reader claims is refused naming the file and the readers there are; a build without
// Gwyddion names the option that adds the instrument formats (README, "Gwyddion's licence").
TEST(Formats, AFileNoReaderClaimsIsRefusedNamingTheReaders) {
    test::TempDir dir("noreader");
    test::writeText(dir / "part.opd", "not what an instrument writes\n");
    test::expectRefused(dir / "part.opd",
                        {"no reader claims this file", "X3P or SDF",
                         SL_HAVE_GWYDDION ? "none of Gwyddion's file modules reads it"
                                          : "-DSCRATCHLIGHT_GWYDDION=ON"});
}

TEST(FormatsGwyddion, TheCommandLoadsGwyddionOnlyForAFileThatNeedsIt) {
    // Gwyddion is a module loaded on first use (io/GwyddionModule.h): a render of a .gwy part
    // through the command loads it (and Gwyddion's libraries) from beside the executable; a
    // render of an EXR part does not (the dynamic loader lists what it loads: LD_DEBUG=files).
    if (!SL_HAVE_GWYDDION) GTEST_SKIP() << "built with -DSCRATCHLIGHT_GWYDDION=OFF";
    test::TempDir dir("gwycli");
    const int w = 24, h = 24;
    std::vector<float> mm(static_cast<size_t>(w * h));
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i)
            mm[static_cast<size_t>(j * w + i)] = 0.002f * std::sin(0.5f * static_cast<float>(i));
    writeGwy(dir / "part.gwy", w, h, mm, 0.01);
    test::writeText(dir / "scene.json", R"({"heightmap": {"path": "part.gwy"}})");
    auto render = [&](const std::string& scene, const std::string& out) {
        return test::runShell("LD_DEBUG=files " + std::string(SL_CLI_PATH) + " render " + scene +
                              " --size 16 --spp 1 -o " + (dir / out).string() + " 2>&1");
    };
    const test::RunResult gwy = render((dir / "scene.json").string(), "gwy.exr");
    ASSERT_EQ(gwy.exitCode, 0) << gwy.output.substr(
        gwy.output.size() > 4000 ? gwy.output.size() - 4000 : 0);
    EXPECT_NE(gwy.output.find("libscratchlight-gwyddion"), std::string::npos);
    EXPECT_NE(gwy.output.find("libgwyddion2"), std::string::npos);
    EXPECT_NE(gwy.output.find("gwyddion gwyfile"), std::string::npos);  // the part line
    EXPECT_TRUE(fs::exists(dir / "gwy.exr"));
    const test::RunResult exr =
        render(std::string(SL_SOURCE_DIR) + "/scenes/default/scene.json", "exr.exr");
    ASSERT_EQ(exr.exitCode, 0);
    EXPECT_NE(exr.output.find("libtbb"), std::string::npos);  // LD_DEBUG does list libraries
    EXPECT_EQ(exr.output.find("libscratchlight-gwyddion"), std::string::npos);
    EXPECT_EQ(exr.output.find("libgwy"), std::string::npos);
    EXPECT_EQ(exr.output.find("libgtk"), std::string::npos);
}

// --- the shared real surfaces -------------------------------------------------------------------

fs::path sharedDir() {
    return fs::path(SL_SOURCE_DIR) / ".." / "shared" / "real-surfaces";
}

struct RealFile {
    const char* name;
    bool needsGwyddion;
    int width, height;  // after resampling
    double pitch;       // mm
    size_t invalid;
    const char* levelling;  // the scene's, "" = auto (plane)
};

// What each file is (../shared/real-surfaces/README.md): the OPD's 1.634 × 1.907 µm pixels are
// resampled onto 1.634 µm (480 rows → ⌊479·1.90661/1.63424⌋ + 1 = 559). The bullet lands
// are curved across the land: the NanoFocus land across y (its axis runs along x), the Sensofar
// one across x.
const RealFile kRealFiles[] = {
    {"wyko-circular-toolmarks.opd", true, 736, 559, 0.00163424, 809, ""},
    {"sensofar-periodic-lines.plu", true, 768, 576, 0.000332, 0, ""},
    {"nanofocus-bullet-land-striations.x3p", false, 501, 1588, 0.0015625, 24829, "cylinder:x"},
    {"sensofar-bullet-land-in-folder.x3p", false, 918, 256, 0.00258, 25292, "cylinder:y"},
    {"logo-in-folder.x3p", false, 741, 419, 0.000645, 0, ""},
};

void checkRealFile(const RealFile& f) {
    const fs::path file = sharedDir() / f.name;
    if (!fs::exists(file)) GTEST_SKIP() << file << " is absent (../shared/real-surfaces)";
    if (f.needsGwyddion && !SL_HAVE_GWYDDION)
        GTEST_SKIP() << "built with -DSCRATCHLIGHT_GWYDDION=OFF";
    test::TempDir dir("real");
    std::string json = R"({"heightmap": {"path": ")" + file.string() + "\"";
    if (*f.levelling) json += std::string(R"(, "levelling": ")") + f.levelling + "\"";
    json += "}}";
    test::writeText(dir / "scene.json", json);
    const auto scene = loadScene(dir / "scene.json");
    EXPECT_EQ(scene->mapWidth, f.width);
    EXPECT_EQ(scene->mapHeight, f.height);
    EXPECT_NEAR(scene->desc.heightmap.pitch, f.pitch, 1e-6 * f.pitch);
    EXPECT_EQ(scene->load.invalidFilled, f.invalid);
    for (float v : scene->heights) ASSERT_TRUE(std::isfinite(v));
    const LevellingResult& lv = scene->load.levelling;
    EXPECT_EQ(lv.applied.mode, *f.levelling ? Mode::Cylinder : Mode::Plane);
    EXPECT_LT(lv.rmsAfter, lv.rmsBefore);
    // Nothing of the form is left: fitting it again on the valid points removes (almost)
    // nothing.
    const std::vector<uint8_t> invalid = loadHeightmap(file, {}).invalid;
    std::vector<float> again = scene->heights;
    const double pitch = scene->desc.heightmap.pitch;
    const int w = scene->mapWidth, h = scene->mapHeight;
    const LevellingResult re =
        levelHeights(again, w, h, pitch, invalid, mode(Mode::Plane), true, f.name);
    EXPECT_GT(re.rmsAfter, 0.999 * re.rmsBefore) << f.name;
    if (*f.levelling) {
        // and no curvature across the land: the mean profile across the axis has a parabola's
        // sag over the land below 5 % of the removed cylinder's, (half width)²/(2R) (3.5 %
        // measured on the Sensofar land, whose scan reaches into the grooves beside the land).
        const bool alongY = f.levelling[9] == 'y';  // the axis runs along y: s = x
        const int ns = alongY ? w : h;
        std::vector<double> sum(static_cast<size_t>(ns), 0), cnt(static_cast<size_t>(ns), 0);
        for (int j = 0; j < h; ++j)
            for (int i = 0; i < w; ++i) {
                const size_t k = static_cast<size_t>(j) * w + i;
                if (invalid.empty() || !invalid[k]) {
                    sum[static_cast<size_t>(alongY ? i : j)] += scene->heights[k];
                    cnt[static_cast<size_t>(alongY ? i : j)] += 1;
                }
            }
        std::vector<float> prof;
        std::vector<uint8_t> none;
        for (int k = 0; k < ns; ++k)  // the profile as a map of three equal rows
            prof.push_back(static_cast<float>(cnt[k] > 0 ? sum[k] / cnt[k] : 0.0));
        std::vector<float> two = prof;
        two.insert(two.end(), prof.begin(), prof.end());
        two.insert(two.end(), prof.begin(), prof.end());
        std::vector<float> lin = two;
        const LevellingResult p1 =
            levelHeights(lin, ns, 3, pitch, none, mode(Mode::Polynomial, 1), true, f.name);
        const LevellingResult p2 =
            levelHeights(two, ns, 3, pitch, none, mode(Mode::Polynomial, 2), true, f.name);
        // the parabola's contribution beyond the line, as an RMS
        const double parabola =
            std::sqrt(std::max(0.0, p1.rmsAfter * p1.rmsAfter - p2.rmsAfter * p2.rmsAfter));
        const double half = (ns - 1) * pitch / 2;
        const double sag = half * half / (2 * std::abs(lv.radius));
        // a parabola of sag S over [−a, a] has RMS about its line 2S/(3√5) ≈ 0.298 S
        EXPECT_LT(parabola, 0.05 * 0.298 * sag) << f.name << ": sag " << sag;
    }
    // The CLI renders it at 64² with its real pitch, levelled.
    const test::RunResult r = test::runCli("render " + (dir / "scene.json").string() +
                                           " -D camera.width=64 -D camera.height=64 --spp 2 -o " +
                                           (dir / "r.exr").string());
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_TRUE(fs::exists(dir / "r.png")) << r.output;
    EXPECT_NE(r.output.find("levelling: "), std::string::npos) << r.output;
}

TEST(RealSurfacesGwyddion, WykoOpdNonSquarePixels) {
    checkRealFile(kRealFiles[0]);
}
TEST(RealSurfacesGwyddion, SensofarPlu) {
    checkRealFile(kRealFiles[1]);
}
TEST(RealSurfaces, NanofocusX3pBulletLandCylinder) {
    checkRealFile(kRealFiles[2]);
}
TEST(RealSurfaces, SensofarX3pInAFolderCylinder) {
    checkRealFile(kRealFiles[3]);
}
TEST(RealSurfaces, LogoX3pInAFolder) {
    checkRealFile(kRealFiles[4]);
}

TEST(RealSurfaces, LogoWarnsAboutItsEditedMainXmlAndItsZIncrement) {
    const fs::path file = sharedDir() / "logo-in-folder.x3p";
    if (!fs::exists(file)) GTEST_SKIP() << file << " is absent (../shared/real-surfaces)";
    const HeightmapData d = loadHeightmap(file, {});
    ASSERT_EQ(d.warnings.size(), 2u);
    EXPECT_NE(d.warnings[0].find("main.xml does not match"), std::string::npos) << d.warnings[0];
    // Its float64 heights are metres beside CZ/Increment 1e-06 (x3ptools' older writer): read as
    // stored, the logo's 8-bit relief of about 0.6 µm, not 1e-13 m.
    EXPECT_NE(d.warnings[1].find("CZ/Increment is 1e-06"), std::string::npos) << d.warnings[1];
    const auto [lo, hi] = std::minmax_element(d.heights.begin(), d.heights.end());
    EXPECT_GT(*hi - *lo, 0.4e-3);  // mm
    EXPECT_LT(*hi - *lo, 1.0e-3);
    EXPECT_TRUE(
        loadHeightmap(sharedDir() / "sensofar-bullet-land-in-folder.x3p", {}).warnings.empty());
}

TEST(RealSurfacesGwyddion, OurX3pReaderAgreesWithGwyddions) {
    if (!SL_HAVE_GWYDDION) GTEST_SKIP() << "built with -DSCRATCHLIGHT_GWYDDION=OFF";
    const fs::path file = sharedDir() / "nanofocus-bullet-land-striations.x3p";
    if (!fs::exists(file)) GTEST_SKIP() << file << " is absent (../shared/real-surfaces)";
    const HeightmapData ours = loadHeightmap(file, {});
    const HeightmapData gwy = loadHeightmap(file, {}, HeightmapReader::Gwyddion);
    ASSERT_EQ(ours.width, gwy.width);
    ASSERT_EQ(ours.height, gwy.height);
    EXPECT_EQ(ours.invalidFilled, gwy.invalidFilled);
    EXPECT_NEAR(*ours.pitch, *gwy.pitch, 1e-12);
    size_t differ = 0;
    for (size_t k = 0; k < ours.heights.size(); ++k)
        differ += ours.invalid[k] == 0 && ours.heights[k] != gwy.heights[k];
    EXPECT_EQ(differ, 0u);
}

}  // namespace
}  // namespace sl
