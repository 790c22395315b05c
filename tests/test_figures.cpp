// optimize's figures drawn in-process (app/report/OptimizeFigures.h on app/host/Canvas.h): each is
// a valid PNG of the expected size with a picture in it, the same input gives the same bytes, bad
// input is refused with a reason and writes nothing, and optimize writes them (or, with
// --no-figures, says in the report that they were not asked for).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <set>
#include <stdexcept>
#include <string>

#include "TestUtil.h"
#include "app/host/Canvas.h"
#include "app/report/OptimizeFigures.h"
#include "app/report/Preview.h"
#include "detect/DefectMap.h"
#include "io/ImageIO.h"

namespace fs = std::filesystem;
using namespace sl;

namespace {

/// A 50 × 25 light with one bright lamp, on the grid's directions as optimize plots them.
OptimizeFiguresInput sampleInput() {
    OptimizeFiguresInput in;
    EnvMapPlot& e = in.envmap;
    e.width = 50;
    e.height = 25;
    for (int i = 0; i < e.width; ++i) e.azimuthDeg.push_back((i + 0.5) * 360.0 / e.width);
    for (int j = 0; j < e.height; ++j) e.elevationDeg.push_back(90.0 - j * 180.0 / (e.height - 1));
    for (int j = 0; j < e.height; ++j)
        for (int i = 0; i < e.width; ++i)
            e.luminance.push_back(std::exp(-0.05 * ((i - 40) * (i - 40) + (j - 6) * (j - 6))));
    in.directions.camera = PlotDirection{180, 45};
    in.directions.mirror = PlotDirection{0, 45};
    in.directions.brightest = {{291.6, 45}, {10, -20}};
    for (int k = 0; k <= 60; ++k) {
        in.loss.iteration.push_back(k);
        in.loss.loss.push_back(10.0 * std::exp(-0.03 * k) + 1.0);
        if (k % 10 == 0) {
            in.loss.heldIteration.push_back(k);
            in.loss.held.push_back(10.0 * std::exp(-0.03 * k) + 1.2);
        }
    }
    in.lossTitle = "lbfgs on unbiased, λ = 30";
    in.title = "scratchlight optimize: loss 11 → 2.65";
    in.lampTitle = "your lamp (studio preset)";
    in.lampView = Image(64, 64, 1, 0.2f);
    in.optimizedView = Image(64, 48, 3);
    for (size_t i = 0; i < in.optimizedView.data.size(); ++i)
        in.optimizedView.data[i] = static_cast<float>(i % 97) / 97.0f;
    return in;
}

AxisSpec range(double lo, double hi, bool log = false) {
    AxisSpec a;
    a.lo = lo;
    a.hi = hi;
    a.log = log;
    return a;
}

/// Width and height from a PNG's IHDR, after checking its signature.
std::pair<uint32_t, uint32_t> pngSize(const std::vector<uint8_t>& png) {
    const uint8_t signature[] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    EXPECT_GE(png.size(), 24u);
    if (png.size() < 24) return {0, 0};
    EXPECT_TRUE(std::equal(std::begin(signature), std::end(signature), png.begin()));
    EXPECT_EQ(std::string(png.begin() + 12, png.begin() + 16), "IHDR");
    auto be = [&](size_t o) {
        return uint32_t(png[o]) << 24 | uint32_t(png[o + 1]) << 16 | uint32_t(png[o + 2]) << 8 |
               uint32_t(png[o + 3]);
    };
    return {be(16), be(20)};
}

/// How many distinct colours a canvas holds (a blank one: 1).
size_t colours(const Canvas& c) {
    const std::vector<uint8_t> px = c.rgb();
    std::set<uint32_t> seen;
    for (size_t i = 0; i + 2 < px.size(); i += 3)
        seen.insert(uint32_t(px[i]) << 16 | uint32_t(px[i + 1]) << 8 | px[i + 2]);
    return seen.size();
}

/// The share of pixels that are not white.
double inked(const Canvas& c) {
    const std::vector<uint8_t> px = c.rgb();
    size_t n = 0;
    for (size_t i = 0; i + 2 < px.size(); i += 3)
        n += px[i] != 255 || px[i + 1] != 255 || px[i + 2] != 255;
    return double(n) / double(px.size() / 3);
}

}  // namespace

TEST(Figures, EachIsAPngOfItsSizeWithAPictureInIt) {
    const OptimizeFiguresInput in = sampleInput();
    struct Case {
        const char* name;
        Canvas canvas;
        uint32_t w, h;
    };
    Case cases[] = {{"envmap", envMapFigure(in.envmap, in.directions), 1170, 432},
                    {"loss", lossFigure(in.loss, in.lossTitle), 675, 378},
                    {"overview", overviewFigure(in), 1360, 368}};
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        const auto [w, h] = pngSize(c.canvas.png());
        EXPECT_EQ(w, c.w);
        EXPECT_EQ(h, c.h);
        EXPECT_GT(colours(c.canvas), 50u);  // text antialiasing, the colour map, the lines
        EXPECT_GT(inked(c.canvas), 0.03);
    }
    // The env map's plots are mostly the dark colour map; the loss plot mostly white.
    EXPECT_GT(inked(cases[0].canvas), 0.4);
    EXPECT_LT(inked(cases[1].canvas), 0.4);
}

TEST(Figures, TheSameInputGivesTheSameBytes) {
    const OptimizeFiguresInput in = sampleInput();
    EXPECT_EQ(overviewFigure(in).png(), overviewFigure(in).png());
    OptimizeFiguresInput other = in;
    other.envmap.luminance[0] = 2.0;
    EXPECT_NE(envMapFigure(in.envmap, in.directions).png(),
              envMapFigure(other.envmap, other.directions).png());
}

TEST(Figures, ALossThatIsNotPositiveIsPlottedOnALinearAxis) {
    OptimizeFiguresInput in = sampleInput();
    in.loss.loss[3] = -1.0;
    in.loss.loss[4] = std::nan("");  // a gap, not a failure
    EXPECT_NO_THROW(lossFigure(in.loss, in.lossTitle));
    LossCurve one;
    one.iteration = {0};
    one.loss = {5.0};
    EXPECT_GT(inked(lossFigure(one, "one point")), 0.01);
}

TEST(Figures, BadInputIsRefusedWithAReason) {
    auto refused = [](auto f, const std::string& words) {
        try {
            f();
            ADD_FAILURE() << "accepted; expected a refusal naming '" << words << "'";
        } catch (const std::invalid_argument& e) {
            EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
        }
    };
    const OptimizeFiguresInput good = sampleInput();
    {
        EnvMapPlot e = good.envmap;
        e.luminance.pop_back();
        refused([&] { envMapFigure(e, good.directions); }, "do not make a 50 x 25 grid");
    }
    {
        EnvMapPlot e = good.envmap;
        e.luminance[7] = std::nan("");
        refused([&] { envMapFigure(e, good.directions); }, "not finite");
    }
    {
        EnvMapPlot e = good.envmap;
        e.luminance[7] = -1;
        refused([&] { envMapFigure(e, good.directions); }, "negative");
    }
    {
        EnvMapPlot e = good.envmap;
        std::swap(e.elevationDeg[0], e.elevationDeg[1]);
        refused([&] { envMapFigure(e, good.directions); }, "elevations decrease");
    }
    refused([&] { lossFigure(LossCurve{}, "t"); }, "needs at least one loss");
    {
        LossCurve l = good.loss;
        l.held.pop_back();
        refused([&] { lossFigure(l, "t"); }, "held-out");
    }
    {
        OptimizeFiguresInput in = good;
        in.lampView = Image();
        refused([&] { overviewFigure(in); }, "under the lamp");
    }
    refused([] { Canvas(0, 10); }, "1 to 16384");
    refused([] { Canvas(10, 100000); }, "1 to 16384");
    refused(
        [] {
            Canvas c(10, 10);
            Axes(c, 0, 0, 10, 10, range(1, 1), range(0, 1));
        },
        "finite lo < hi");
    refused(
        [] {
            Canvas c(10, 10);
            Axes(c, 0, 0, 10, 10, range(0, 1), range(0, 1, true));
        },
        "log axis");
}

TEST(Figures, WrittenAsThreeFilesOrNone) {
    test::TempDir dir("figures");
    const auto wrote = writeOptimizeFigures(dir.path(), sampleInput());
    ASSERT_EQ(wrote.size(), 3u);
    for (const auto& [name, w, h] :
         {std::tuple{"plot-envmap.png", 1170, 432}, std::tuple{"plot-loss.png", 675, 378},
          std::tuple{"overview.png", 1360, 368}}) {
        SCOPED_TRACE(name);
        const Image img = readImage(dir / name);  // OpenImageIO reads it back
        EXPECT_EQ(img.width, w);
        EXPECT_EQ(img.height, h);
    }
    test::TempDir empty("figures-bad");
    OptimizeFiguresInput bad = sampleInput();
    bad.loss.loss.clear();
    EXPECT_THROW(writeOptimizeFigures(empty.path(), bad), std::invalid_argument);
    EXPECT_TRUE(fs::is_empty(empty.path()));
}

TEST(Figures, TheTicksAreRoundNumbersOverTheRange) {
    EXPECT_EQ(niceTicks(0, 360, 8), (std::vector<double>{0, 50, 100, 150, 200, 250, 300, 350}));
    EXPECT_EQ(niceTicks(0, 169, 6, true), (std::vector<double>{0, 50, 100, 150}));
    EXPECT_EQ(niceTicks(0, 3, 6, true), (std::vector<double>{0, 1, 2, 3}));
    const double coarse[] = {1, 2, 5};
    EXPECT_EQ(logTicks(0.3, 60, coarse), (std::vector<double>{0.5, 1, 2, 5, 10, 20, 50}));
    EXPECT_TRUE(logTicks(0, 1, coarse).empty());
}

// The job: optimize writes the figures beside the report, which shows them; --no-figures
// writes none and the report says so.
TEST(Figures, OptimizeWritesThemAndTheReportShowsThem) {
    test::TempDir dir("figures-job");
    ASSERT_EQ(test::writeSmallLabelledPart(dir.path()), 0);
    const std::string scene = (dir / "scene.json").string(),
                      common = " --size 48 --spp 4 --iterations 10 --heldout none --cache " +
                               (dir / "cache").string() + " -o ";
    auto r = test::runCli("optimize " + scene + common + (dir / "a").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const std::string html = test::readFile(dir / "a" / "report.html");
    for (const auto& [name, alt, w, h] : {std::tuple{"plot-envmap.png", "env-map plot", 1170, 432},
                                          std::tuple{"plot-loss.png", "loss plot", 675, 378},
                                          std::tuple{"overview.png", "overview", 1360, 368}}) {
        SCOPED_TRACE(name);
        const Image img = readImage(dir / "a" / name);
        EXPECT_EQ(img.width, w);
        EXPECT_EQ(img.height, h);
        EXPECT_NE(html.find("alt=\"" + std::string(alt) + "\" src=\"data:image/png;base64,"),
                  std::string::npos);
    }
    EXPECT_EQ(html.find("figure not made"), std::string::npos);
    EXPECT_EQ(r.output.find("matplotlib"), std::string::npos) << r.output;

    r = test::runCli("optimize " + scene + common + (dir / "b").string() + " --no-figures");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    for (const char* name : {"plot-envmap.png", "plot-loss.png", "overview.png"})
        EXPECT_FALSE(fs::exists(dir / "b" / name)) << name;
    EXPECT_NE(test::readFile(dir / "b" / "report.html").find("figures not asked for"),
              std::string::npos);
}

// defectmap's preview: the hill shade is lit from the top left, so a plane rising to the right
// (facing left) is brighter than a flat map's 1/sqrt(3) and one rising to the left darker; the
// slopes are in units of their own spread, so heights scaled by a power of two shade the same,
// bit for bit. The preview outlines a mark red and an unjudged region blue and halves the
// border's brightness.
TEST(DefectMapPreview, LitFromTheTopLeftWhateverTheHeightsScaleMarksRedUnjudgedBlue) {
    const int w = 24, h = 20;
    std::vector<float> flat(static_cast<size_t>(w) * h, 3.0f), right(flat), left(flat), rough(flat);
    for (int z = 0; z < h; ++z)
        for (int x = 0; x < w; ++x) {
            const size_t i = static_cast<size_t>(z) * w + x;
            right[i] = 0.01f * static_cast<float>(x);
            left[i] = -0.01f * static_cast<float>(x);
            rough[i] = static_cast<float>(((x * 7 + z * 13) % 11) - 5) * 0.125f;
        }
    const std::vector<double> f = hillShade(flat, w, h), r = hillShade(right, w, h),
                              l = hillShade(left, w, h);
    for (const double v : f) EXPECT_DOUBLE_EQ(v, 1.0 / std::sqrt(3.0));
    const size_t mid = static_cast<size_t>(h / 2) * w + w / 2;
    EXPECT_GT(r[mid], f[mid] + 0.1);
    EXPECT_LT(l[mid], f[mid] - 0.1);
    std::vector<float> scaled(rough);
    for (float& v : scaled) v *= 32.0f;
    EXPECT_EQ(hillShade(rough, w, h), hillShade(scaled, w, h));

    std::vector<uint8_t> map(flat.size(), 0), unjudged(flat.size(), kJudged);
    for (int z = 8; z < 12; ++z)
        for (int x = 4; x < 8; ++x) map[static_cast<size_t>(z) * w + x] = 255;
    for (int z = 8; z < 12; ++z)
        for (int x = 14; x < 18; ++x) unjudged[static_cast<size_t>(z) * w + x] = kUnjudgedRegion;
    for (int x = 0; x < w; ++x) unjudged[x] = kUnjudgedBorder;  // the top row: the border
    const Image plain = defectMapPreview(flat, w, h, map, {});
    const Image p = defectMapPreview(flat, w, h, map, unjudged);
    const OutlineColour& red = outlineOf(255);
    const OutlineColour& blue = outlineOf(128);
    EXPECT_EQ(p.at(4, 8, 0), red.r);
    EXPECT_EQ(p.at(4, 8, 1), red.g);
    EXPECT_EQ(p.at(14, 8, 2), blue.b);
    EXPECT_EQ(p.at(14, 8, 0), blue.r);
    EXPECT_EQ(plain.at(14, 8, 0), plain.at(20, 15, 0)) << "no unjudged: plain shade there";
    EXPECT_FLOAT_EQ(p.at(10, 0, 0), 0.5f * plain.at(10, 0, 0)) << "the border dimmed";
    EXPECT_EQ(p.at(20, 15, 0), plain.at(20, 15, 0)) << "judged, unmarked: the shade";
}
