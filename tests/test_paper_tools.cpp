// The paper's tools: image-space projection of height-map masks, the specular initial state,
// visibility metrics, colour measures, the HTML report.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <memory>
#include <sstream>
#include <vector>

#include "TestUtil.h"
#include "app/pipeline/InitialState.h"
#include "app/pipeline/Truth.h"
#include "app/report/Report.h"
#include "core/Color.h"
#include "core/Error.h"
#include "io/ImageIO.h"
#include "objective/ImageSpace.h"
#include "objective/Metrics.h"
#include "optimize/SpecularInit.h"
#include "scene/EnvMapPresets.h"
#include "scene/Scene.h"

using namespace sl;

namespace {

// A flat 16×16 map at pitch 1 (extent 15 × 15, samples at x, z = −7.5 … 7.5), a mirror.
std::unique_ptr<Scene> flatScene(CameraSpec cam, int envW = 50, int envH = 25) {
    SceneDesc d;
    d.heightmap.pitch = 1.0;
    d.camera = cam;
    d.material.type = "conductor";
    d.envmap.width = envW;
    d.envmap.height = envH;
    return std::make_unique<Scene>(d, 16, 16, std::vector<float>(256, 0.0f));
}

CameraSpec topView() {
    CameraSpec c;
    c.type = CameraDesc::Type::Orthographic;
    c.origin = Vec3d{0, 10, 0};
    c.target = Vec3d{0, 0, 0};
    c.up = Vec3d{0, 0, -1};  // image top toward −z (row 0), image x toward +x
    c.widthMm = 16.0;
    c.width = 32;
    c.height = 32;
    return c;
}

}  // namespace

// Orthographic top view, 32×32 px over 16 mm: pixel px's centre is at x = 0.5·px − 7.75, so it
// sees sample i = round(0.5·px − 0.25) (no ties), and misses for px = 0 and 31; same in z.
TEST(ImageSpace, OrthographicTopViewMapsPixelsToSamplesAnalytically) {
    auto s = flatScene(topView());
    PrimaryHits h = tracePrimaryHits(*s);
    ASSERT_EQ(h.width, 32);
    ASSERT_EQ(h.mapWidth, 16);
    for (int py = 0; py < 32; ++py)
        for (int px = 0; px < 32; ++px) {
            const int64_t got = h.sample[static_cast<size_t>(py) * 32 + px];
            if (px == 0 || px == 31 || py == 0 || py == 31) {
                EXPECT_EQ(got, -1) << px << "," << py;
                continue;
            }
            const auto i = std::lround(0.5 * px - 0.25), j = std::lround(0.5 * py - 0.25);
            EXPECT_EQ(got, j * 16 + i) << px << "," << py;
        }
    EXPECT_EQ(h.hitCount(), 30u * 30u);

    std::vector<uint8_t> mapMask(256, 0);
    mapMask[9 * 16 + 5] = 255;  // sample i = 5, j = 9 → pixels px ∈ {10, 11}, py ∈ {18, 19}
    std::vector<uint8_t> img = projectToImage(h, mapMask);
    for (int py = 0; py < 32; ++py)
        for (int px = 0; px < 32; ++px)
            EXPECT_EQ(img[static_cast<size_t>(py) * 32 + px] != 0,
                      (px == 10 || px == 11) && (py == 18 || py == 19))
                << px << "," << py;
    EXPECT_THROW(projectToImage(h, std::vector<uint8_t>(255, 0)), InputError);
}

TEST(ImageSpace, MaskFileInHeightMapSpaceIsProjectedAndSizeChecked) {
    test::TempDir dir("imgspace");
    auto s = flatScene(topView());
    std::vector<uint8_t> m(256, 0);
    m[9 * 16 + 5] = 255;
    writeMaskPng(dir / "truth.png", m, 16, 16);
    std::vector<uint8_t> img = projectMaskFile(*s, dir / "truth.png");
    size_t inside = 0;
    for (uint8_t v : img) inside += v != 0;
    EXPECT_EQ(inside, 4u);
    EXPECT_NE(img[18 * 32 + 10], 0);
    writeMaskPng(dir / "small.png", std::vector<uint8_t>(64, 255), 8, 8);
    EXPECT_THROW(projectMaskFile(*s, dir / "small.png"), InputError);
    EXPECT_THROW(projectMaskFile(*s, dir / "missing.png"), InputError);
    // An empty truth mask (no defects) is allowed.
    writeMaskPng(dir / "empty.png", std::vector<uint8_t>(256, 0), 16, 16);
    EXPECT_EQ(loadHeightMapMask(dir / "empty.png", 16, 16), std::vector<uint8_t>(256, 0));
}

TEST(ImageSpace, ScratchMaskImageOfAFlatPartIsEmpty) {
    auto s = flatScene(topView());
    std::vector<uint8_t> img = scratchMaskImage(*s, {3, 4, 0.03});
    EXPECT_EQ(img, std::vector<uint8_t>(32 * 32, 0));
}

// A mirror plane under an orthographic camera looking down at 45° (direction (0,−1,−1)/√2):
// every camera ray reflects to r = (0, 1, −1)/√2: u = atan2(0, 1/√2)/2π = 0, v = 1/4. On the
// 50×25 grid that is x = frac(0 − 0.5/50)·50 = 49.5, y = 0.25·24 = 6: texels (row 6, col 49)
// and (row 6, col 0) with weight ½ each. The normalised histogram is exactly 1 there, 0 elsewhere.
TEST(SpecularInit, MirrorPlaneUnderOrthographicCameraHitsExactlyTheReflectedTexels) {
    CameraSpec c;
    c.type = CameraDesc::Type::Orthographic;
    c.origin = Vec3d{0, 10, 10};
    c.target = Vec3d{0, 0, 0};
    c.up = Vec3d{0, 1, 0};
    c.widthMm = 4.0;
    c.width = 16;
    c.height = 16;
    auto s = flatScene(c);
    for (int depth : {2, 4}) {
        std::vector<double> e = specularInitialEnvMap(*s, depth, false);
        ASSERT_EQ(e.size(), 50u * 25u);
        for (int j = 0; j < 25; ++j)
            for (int i = 0; i < 50; ++i) {
                const double want = (j == 6 && (i == 49 || i == 0)) ? 1.0 : 0.0;
                EXPECT_NEAR(e[static_cast<size_t>(j) * 50 + i], want, 1e-5)
                    << "depth " << depth << " texel " << j << "," << i;
            }
    }
    // The same map through EnvMapBasis::weights of the reflected direction.
    TexelWeights w = s->basis.weights(normalize(Vec3f{0, 1, -1}));
    std::vector<double> e = specularInitialEnvMap(*s, 2, false);
    float wmax = std::max({w.weight[0], w.weight[1], w.weight[2], w.weight[3]});
    for (int k = 0; k < 4; ++k) EXPECT_NEAR(e[w.index[k]], w.weight[k] / wmax, 1e-5);
    // RGB: the same value in all three channels.
    std::vector<double> rgb = specularInitialEnvMap(*s, 2, true);
    ASSERT_EQ(rgb.size(), 3u * 50u * 25u);
    for (size_t t = 0; t < e.size(); ++t)
        for (int ch = 0; ch < 3; ++ch) EXPECT_EQ(rgb[3 * t + ch], e[t]);
    // max_depth 1 lets nothing escape; a camera that misses the part is reported.
    EXPECT_THROW(specularInitialEnvMap(*s, 1, false), InputError);
    c.target = Vec3d{0, 20, 30};
    auto away = flatScene(c);
    try {
        specularInitialEnvMap(*away, 2, false);
        FAIL() << "expected InputError";
    } catch (const InputError& err) {
        EXPECT_NE(std::string(err.what()).find("hits the part"), std::string::npos) << err.what();
    }
}

TEST(Colour, LuvLightnessKnownValues) {
    EXPECT_NEAR(lightnessLStar01(1, 1, 1), 1.0, 1e-12);
    EXPECT_NEAR(lightnessLStar01(0, 0, 0), 0.0, 1e-12);
    const double mid = srgbDecode(0.5f);  // sRGB-encoded mid gray, linear 0.21404
    EXPECT_NEAR(lightnessLStar01(mid, mid, mid), 0.533889, 1e-5);
}

TEST(Colour, ChromaIsZeroForGrayAndKnownForSrgbPrimaries) {
    for (double v : {0.0, 0.01, 0.3, 1.0}) EXPECT_NEAR(chromaUv01(v, v, v), 0.0, 1e-12);
    EXPECT_NEAR(chromaUv01(1, 0, 0), 1.7904, 1e-3);  // CIE LUV C*uv of sRGB red: 179.04
    EXPECT_NEAR(chromaUv01(0, 0, 1), 1.3068, 1e-3);  // sRGB blue: 130.68
}

TEST(Colour, XyzIsIec61966MatrixWithTheLuminanceAsItsYRow) {
    // One source for the luminance weights: XYZ's Y row is luminance(), bit for bit.
    for (const auto& c : {Rgb(1, 0, 0), Rgb(0, 1, 0), Rgb(0, 0, 1), Rgb(0.3f, 0.7f, 0.11f)}) {
        double X, Y, Z;
        rgbToXyz(c.x, c.y, c.z, X, Y, Z);
        EXPECT_EQ(Y, luminance<double>(c.x, c.y, c.z));
    }
    double X, Y, Z;
    rgbToXyz(1, 1, 1, X, Y, Z);  // D65 white as IEC 61966-2-1 tabulates it
    EXPECT_NEAR(X, 0.9505, 1e-12);
    EXPECT_NEAR(Y, 1.0, 1e-12);
    EXPECT_NEAR(Z, 1.0890, 1e-12);
    // sRGB red's C*uv/100 with this matrix (computed independently in numpy: 1.790787; the
    // seven-digit matrix gives 1.790414).
    EXPECT_NEAR(chromaUv01(1, 0, 0), 1.790787, 1e-6);
}

// Hand-made 3×3 luminance image (values chosen so every metric is a short fraction):
//   0.0 0.2 0.4
//   0.0 0.5 1.0
//   0.1 0.1 0.1
TEST(Metrics, HandMadeImageGivesExactValues) {
    std::vector<double> Y = {0.0, 0.2, 0.4, 0.0, 0.5, 1.0, 0.1, 0.1, 0.1};
    std::vector<uint8_t> object(9, 1), loss = {1, 1, 0, 1, 1, 0, 1, 1, 0}, truth(9, 0);
    truth[4] = 255;  // the centre pixel is a "defect"
    std::vector<double> env = {0.0, 0.0005, 0.5, 1.0};
    MetricsInput in;
    in.width = 3;
    in.height = 3;
    in.image = Y;
    in.objectMask = object;
    in.lossMask = loss;
    in.envmap = env;
    in.truthMask = truth;
    VisibilityMetrics m = computeVisibilityMetrics(in);
    EXPECT_EQ(m.pairsInside, 7u);
    EXPECT_NEAR(m.gradientInside, 1.5 / 7.0, 1e-12);
    EXPECT_EQ(m.pairsOutside, 2u);
    EXPECT_NEAR(m.gradientOutside, 0.75, 1e-12);
    EXPECT_NEAR(m.gradientRatio, 2.0 / 7.0, 1e-12);
    EXPECT_NEAR(m.clippedFraction, 1.0 / 9.0, 1e-12);
    EXPECT_NEAR(m.envSparsity, 0.5, 1e-12);
    EXPECT_EQ(m.envMeanChroma, 0.0);
    ASSERT_TRUE(m.truth.has_value());
    EXPECT_EQ(m.truth->defectPairs, 4u);
    EXPECT_EQ(m.truth->backgroundPairs, 8u);
    EXPECT_NEAR(m.truth->defectGradient, 1.7 / 4.0, 1e-12);
    EXPECT_NEAR(m.truth->backgroundGradient, 0.25, 1e-12);
    EXPECT_NEAR(m.truth->gradientRatio, 1.7, 1e-12);
    EXPECT_NEAR(m.truth->weberContrast, (0.5 - 1.9 / 8.0) / (1.9 / 8.0), 1e-12);

    // Loss mask = object mask: nothing outside → NaN → JSON null; no truth → null.
    in.lossMask = {};
    in.truthMask = {};
    m = computeVisibilityMetrics(in);
    EXPECT_TRUE(std::isnan(m.gradientOutside));
    nlohmann::json j = toJson(m);
    EXPECT_TRUE(j["gradient_outside"].is_null());
    EXPECT_TRUE(j["gradient_ratio"].is_null());
    EXPECT_TRUE(j["truth"].is_null());
    EXPECT_NEAR(j["gradient_inside"].get<double>(), 3.7 / 12.0, 1e-12);
    EXPECT_EQ(j.dump().find("NaN"), std::string::npos);
}

TEST(Metrics, RgbClippingCountsAnyChannelAndChromaOfRgbEnvMaps) {
    // 2×1 RGB image: the second pixel's green channel is clipped although Y < 1.
    std::vector<double> img = {0.2, 0.2, 0.2, 0.2, 1.2, 0.1};
    std::vector<uint8_t> object(2, 1);
    std::vector<double> env = {0.5, 0.5, 0.5, 1.0, 0.0, 0.0};  // gray texel, red texel
    MetricsInput in;
    in.width = 2;
    in.height = 1;
    in.channels = 3;
    in.image = img;
    in.objectMask = object;
    in.envmap = env;
    in.envChannels = 3;
    VisibilityMetrics m = computeVisibilityMetrics(in);
    EXPECT_NEAR(m.clippedFraction, 0.5, 1e-12);
    EXPECT_NEAR(m.envMeanChroma, chromaUv01(1, 0, 0) / 2.0, 1e-12);
    EXPECT_NEAR(m.envSparsity, 2.0 / 6.0, 1e-12);
    EXPECT_THROW(
        {
            in.objectMask = std::span<const uint8_t>(object.data(), 1);
            computeVisibilityMetrics(in);
        },
        std::invalid_argument);
}

namespace {

// A fake optimize OUTDIR: summary.json (with metrics), loss.csv and the three PNGs.
void fakeOutDir(const std::filesystem::path& d, double lambda) {
    std::filesystem::create_directories(d);
    Image img(8, 6, 1);
    for (size_t k = 0; k < img.data.size(); ++k) img.data[k] = static_cast<float>(k % 7) / 6.0f;
    writePng(d / "initial.png", img);
    writePng(d / "render.png", img);
    writePng(d / "envmap.png", Image(10, 5, 1, 0.5f));
    test::writeText(d / "loss.csv",
                    "iteration,evaluations,loss,L_grad,L_reg,seconds\n0,1,5,4,0.1,0\n1,2,3,2.5,"
                    "0.05,0.1\n2,3,2,1.8,0.01,0.2\n");
    nlohmann::json s = {{"optimizer", "adam"},       {"lambda", lambda},  {"init", "const:0.5"},
                        {"initial_loss", 5.0},       {"final_loss", 2.0}, {"rgb", false},
                        {"transport", {{"spp", 64}}}};
    s["metrics"] = {{"gradient_inside", 0.0123},
                    {"gradient_outside", nullptr},
                    {"env_sparsity", 0.75},
                    {"truth", {{"gradient_ratio", 1.7}}}};
    test::writeText(d / "summary.json", s.dump(2));
}

size_t count(const std::string& s, const std::string& what) {
    size_t n = 0;
    for (size_t p = s.find(what); p != std::string::npos; p = s.find(what, p + 1)) ++n;
    return n;
}

}  // namespace

TEST(Report, Base64MatchesRfc4648Vectors) {
    EXPECT_EQ(base64Encode(""), "");
    EXPECT_EQ(base64Encode("f"), "Zg==");
    EXPECT_EQ(base64Encode("fo"), "Zm8=");
    EXPECT_EQ(base64Encode("foo"), "Zm9v");
    EXPECT_EQ(base64Encode("foobar"), "Zm9vYmFy");
    EXPECT_EQ(base64Encode(std::string("\xff\x00\x80", 3)), "/wCA");
}

TEST(Report, PageIsSelfContainedWithImagesLossCurveMetricsAndSettings) {
    test::TempDir dir("report");
    fakeOutDir(dir / "a", 30);
    fakeOutDir(dir / "b", 10);
    ReportContent c;
    c.title = "Fig. 4 <test>";
    c.notes = {"the common env map is the built-in studio preset"};
    ReportFigure f;
    f.title = "Fig. 4";
    f.caption = "L2 & no L2";
    f.combinedLossPlot = true;
    f.runs.push_back(reportRunFromOutDir(dir / "a", "(a) lambda 30"));
    f.runs.push_back(reportRunFromOutDir(dir / "b", "(b) lambda 10"));
    c.figures.push_back(f);
    ReportFigure g;
    g.title = "single";
    g.runs.push_back(reportRunFromOutDir(dir / "a", "", RunState::Initial));
    c.figures.push_back(g);
    writeReport(dir / "out" / "report.html", c);
    std::ifstream in(dir / "out" / "report.html");
    std::stringstream ss;
    ss << in.rdbuf();
    const std::string html = ss.str();
    EXPECT_EQ(html.rfind("<!DOCTYPE html>", 0), 0u);
    EXPECT_NE(html.find("</html>"), std::string::npos);
    EXPECT_EQ(count(html, "src=\"data:image/png;base64,iVBORw0KGgo"), 3u * 2u + 1u);
    EXPECT_EQ(count(html, "<svg"), 1u);  // the combined plot (figure 2 shows no curve)
    EXPECT_EQ(count(html, "<polyline"), 2u);
    EXPECT_NE(html.find("Fig. 4 &lt;test&gt;"), std::string::npos);
    EXPECT_NE(html.find("L2 &amp; no L2"), std::string::npos);
    EXPECT_NE(html.find("gradient_inside"), std::string::npos);
    EXPECT_NE(html.find("truth.gradient_ratio"), std::string::npos);
    EXPECT_NE(html.find("0.0123"), std::string::npos);
    EXPECT_NE(html.find("loss_final"), std::string::npos);
    EXPECT_NE(html.find("const:0.5"), std::string::npos);
    EXPECT_NE(html.find("studio preset"), std::string::npos);
    // No external references: nothing loaded from anywhere.
    for (const char* bad : {"<script", "<link", "href=", "http://", "https://", "url(", "@import"})
        EXPECT_EQ(html.find(bad), std::string::npos) << bad;

    test::writeText(dir / "bad" / "summary.json", "{");
    EXPECT_THROW(reportRunFromOutDir(dir / "bad"), InputError);
    EXPECT_THROW(reportRunFromOutDir(dir / "missing"), InputError);
}

TEST(PaperCli, ScratchmapAndReportCommands) {
    test::TempDir dir("papercli");
    // Height map with one pit: scratchmap marks its patch only.
    Image hm(40, 30, 1, 1.0f);
    hm.at(25, 15) = 0.5f;  // its 5×5 window stays inside patch (row 1, column 2)
    writeExr(dir / "h.exr", hm);
    auto r = test::runCli("scratchmap " + (dir / "h.exr").string() + " --kernel 5 --patch 10 -o " +
                          (dir / "m.png").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("1 of 12 patches marked"), std::string::npos) << r.output;
    std::vector<uint8_t> m = loadHeightMapMask(dir / "m.png", 40, 30);
    EXPECT_NE(m[15 * 40 + 25], 0);
    EXPECT_NE(m[10 * 40 + 20], 0);  // the whole patch
    EXPECT_EQ(m[15 * 40 + 19], 0);
    EXPECT_EQ(m[0], 0);
    EXPECT_EQ(test::runCli("scratchmap " + (dir / "h.exr").string() + " --patch 0").exitCode, 2);
    EXPECT_EQ(test::runCli("scratchmap " + (dir / "nope.exr").string()).exitCode, 1);

    fakeOutDir(dir / "run", 30);
    r = test::runCli("report " + (dir / "run").string() + " -o " + (dir / "r.html").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_TRUE(std::filesystem::exists(dir / "r.html"));
    test::writeText(dir / "spec.json", R"({"title": "t", "figures": [{"title": "F",
        "loss_plot": true, "runs": [{"dir": "run", "title": "x"},
        {"images": [{"png": "run/render.png", "caption": "c"}], "title": "y",
         "metrics": {"note": "from a render"}}]}]})");
    r = test::runCli("report --spec " + (dir / "spec.json").string() + " -o " +
                     (dir / "s.html").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_EQ(test::runCli("report").exitCode, 2);
    EXPECT_EQ(test::runCli("report " + (dir / "none").string() + " -o " + (dir / "x.html").string())
                  .exitCode,
              1);
    EXPECT_FALSE(std::filesystem::exists(dir / "x.html"));
}

TEST(PaperCli, EnvMapPresetIsAnRgbImageThatInitialisesThroughLStar) {
    // A preset stands in for a photographed environment: written as RGB, so `--init envmap:`
    // applies the paper's CIE L*/100 (a one-channel file would be taken as E itself).
    test::TempDir dir("preset");
    const auto exr = dir / "studio.exr";
    auto r = test::runCli("envmap-preset studio -o " + exr.string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const Image img = readImage(exr);
    ASSERT_EQ(img.channels, 3);
    ASSERT_EQ(img.width, 50);
    ASSERT_EQ(img.height, 25);
    const EnvMap studio = studioEnvMap(50, 25);
    const std::vector<double> e =
        initialEnvMap(parseInitialState("envmap:" + exr.string()), 50, 25, false);
    for (size_t t = 0; t < studio.texelCount(); ++t) {
        const float v = studio.texels[t];
        ASSERT_EQ(img.data[3 * t], v);
        ASSERT_EQ(img.data[3 * t + 1], v);
        ASSERT_EQ(img.data[3 * t + 2], v);
        EXPECT_NEAR(e[t], std::clamp(lightnessLStar01(v, v, v), 0.0, 1.0), 1e-6) << t;
    }
}

TEST(SpecularInit, KeptInTheCacheByTsFingerprintAndReadBackBitForBit) {
    // The specular start of a run on a cached T comes from the cache (app/pipeline/InitialState.h): the
    // second call traces no ray (the BVH of a fresh scene stays unbuilt) and gives the same
    // values; another fingerprint or max_depth is another entry.
    test::TempDir dir{"specular-cache"};
    CameraSpec c;
    c.type = CameraDesc::Type::Orthographic;
    c.origin = Vec3d{0, 10, 10};
    c.target = Vec3d{0, 0, 0};
    c.up = Vec3d{0, 1, 0};
    c.widthMm = 4.0;
    c.width = c.height = 16;
    const InitialState spec = parseInitialState("specular");
    auto first = flatScene(c);
    const std::vector<double> want = specularInitialEnvMap(*first, 3, false);
    const std::vector<double> stored =
        initialEnvMap(spec, 50, 25, false, first.get(), 3, dir.path(), "fp-1");
    EXPECT_EQ(stored, want);
    auto fresh = flatScene(c);
    EXPECT_EQ(initialEnvMap(spec, 50, 25, false, fresh.get(), 3, dir.path(), "fp-1"), want);
    EXPECT_FALSE(fresh->surface->built());
    // Another T or path length traces again.
    EXPECT_EQ(initialEnvMap(spec, 50, 25, false, fresh.get(), 3, dir.path(), "fp-2"), want);
    EXPECT_TRUE(fresh->surface->built());
    auto third = flatScene(c);
    EXPECT_EQ(initialEnvMap(spec, 50, 25, false, third.get(), 2, dir.path(), "fp-1"),
              specularInitialEnvMap(*third, 2, false));
}
