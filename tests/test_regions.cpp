// Modelling only what a scene needs (issue 16, item 2): a trace of some pixels only
// (RenderOptions::pixels) is the whole trace's rows for those pixels, bit for bit;
// `optimize --trace-mask-only` gives the E* of the whole trace for the region's rays; and
// `--max-depth auto` measures the path length first and records the number it chose.
#include <gtest/gtest.h>

#include <algorithm>
#include <nlohmann/json.hpp>
#include <sstream>

#include "TestUtil.h"
#include "app/bench/DepthBench.h"
#include "app/bench/RegionBench.h"
#include "app/pipeline/Transport.h"
#include "core/Error.h"
#include "io/ImageIO.h"
#include "io/TransportFile.h"
#include "scene/Scene.h"
#include "transport/TransportSink.h"

namespace {

using namespace sl;

TEST(TraceRegion, FlaggedPixelsAreTheWholeTracesRowsBitForBit) {
    const int W = 24, H = 20;
    const Scene scene(test::bumpyPartDesc(W, H), 32, 32, test::bumpyHeightMap(32));
    RenderOptions ro;
    ro.spp = 8;
    ro.sampleSets = 2;
    TransportMatrix whole = precomputeTransport(scene, ro, 1).matrix;
    const TransportProvenance wholeProv = transportProvenance(scene, ro, 1);
    ro.pixels.assign(static_cast<size_t>(W) * H, 0);
    for (int y = 5; y < 14; ++y)
        for (int x = 3; x < 11 + y / 2; ++x) ro.pixels[static_cast<size_t>(y) * W + x] = 255;
    TransportMatrix part = precomputeTransport(scene, ro, 1).matrix;
    const TransportProvenance partProv = transportProvenance(scene, ro, 1);
    whole.toSparse();
    part.toSparse();
    size_t flagged = 0, lit = 0;
    for (size_t p = 0; p < whole.rows(); ++p) {
        const uint64_t b = part.rowPtr[p], e = part.rowPtr[p + 1];
        if (ro.pixels[p] == 0) {
            EXPECT_EQ(b, e) << "pixel " << p << " was not flagged but has entries";
            EXPECT_EQ(part.objectMask[p], 0) << p;
            continue;
        }
        ++flagged;
        const uint64_t wb = whole.rowPtr[p];
        ASSERT_EQ(e - b, whole.rowPtr[p + 1] - wb) << "pixel " << p;
        lit += e > b;
        EXPECT_EQ(part.objectMask[p], whole.objectMask[p]) << p;
        for (uint64_t k = 0; k < e - b; ++k) {
            EXPECT_EQ(part.colIdx[b + k], whole.colIdx[wb + k]);
            for (int s = 0; s < part.stride(); ++s)
                EXPECT_EQ(part.values[(b + k) * part.stride() + s],
                          whole.values[(wb + k) * whole.stride() + s]);
        }
    }
    EXPECT_GT(flagged, 50u);
    EXPECT_GT(lit, flagged / 2);
    // The fingerprint records which pixels were traced (as 0/1, whatever value flags them).
    EXPECT_NE(partProv.fingerprint, wholeProv.fingerprint);
    const auto in = nlohmann::json::parse(partProv.inputs);
    EXPECT_EQ(in.at("pixels").at("traced").get<size_t>(), flagged);
    std::replace(ro.pixels.begin(), ro.pixels.end(), uint8_t{255}, uint8_t{1});
    EXPECT_EQ(transportProvenance(scene, ro, 1).fingerprint, partProv.fingerprint);
}

// Region supersampling (RenderOptions::sppScale): a pixel with multiplier f is the row of a
// plain trace at f·spp, bit for bit, and a pixel with multiplier 1 the row of the plain trace at
// spp; so every row stays an unbiased estimate and T·E a render. The fingerprint records it.
TEST(TraceRegion, SupersampledPixelsAreTheRowsOfAPlainTraceAtTheirSpp) {
    const int W = 24, H = 20;
    const Scene scene(test::bumpyPartDesc(W, H), 32, 32, test::bumpyHeightMap(32));
    RenderOptions ro;
    ro.spp = 4;
    ro.sampleSets = 2;
    for (Sampling sampling : {Sampling::Stratified, Sampling::Mis}) {
        ro.sampling = sampling;
        ro.sppScale.clear();
        ro.spp = 4;
        TransportMatrix base = precomputeTransport(scene, ro, 1).matrix;
        const std::string baseFingerprint = transportProvenance(scene, ro, 1).fingerprint;
        ro.spp = 16;
        TransportMatrix high = precomputeTransport(scene, ro, 1).matrix;
        ro.spp = 4;
        ro.sppScale.assign(static_cast<size_t>(W) * H, 1);
        size_t scaled = 0;
        for (int y = 6; y < 13; ++y)
            for (int x = 5; x < 15; ++x, ++scaled) ro.sppScale[static_cast<size_t>(y) * W + x] = 4;
        TransportMatrix mixed = precomputeTransport(scene, ro, 1).matrix;
        for (TransportMatrix* t : {&base, &high, &mixed}) t->toSparse();
        size_t lit = 0;
        for (size_t p = 0; p < mixed.rows(); ++p) {
            const TransportMatrix& ref = ro.sppScale[p] == 4 ? high : base;
            const uint64_t b = mixed.rowPtr[p], e = mixed.rowPtr[p + 1], rb = ref.rowPtr[p];
            ASSERT_EQ(e - b, ref.rowPtr[p + 1] - rb) << "pixel " << p;
            EXPECT_EQ(mixed.objectMask[p], ref.objectMask[p]) << p;
            lit += ro.sppScale[p] == 4 && e > b;
            for (uint64_t k = 0; k < e - b; ++k) {
                ASSERT_EQ(mixed.colIdx[b + k], ref.colIdx[rb + k]) << p;
                for (int s = 0; s < mixed.stride(); ++s)
                    ASSERT_EQ(mixed.values[(b + k) * mixed.stride() + s],
                              ref.values[(rb + k) * ref.stride() + s])
                        << "pixel " << p;
            }
        }
        EXPECT_GT(lit, scaled / 2);
        const TransportProvenance prov = transportProvenance(scene, ro, 1);
        EXPECT_NE(prov.fingerprint, baseFingerprint);
        const auto in = nlohmann::json::parse(prov.inputs);
        EXPECT_EQ(in.at("render").at("spp_scale").at("max"), 4);
        EXPECT_EQ(in.at("render").at("spp_scale").at("scaled_pixels").get<size_t>(), scaled);
        EXPECT_EQ(in.at("render").at("spp"), 4);
    }
    // Multipliers of the wrong size or above the cap are refused.
    ro.sppScale.assign(5, 2);
    EXPECT_THROW(precomputeTransport(scene, ro, 1), std::invalid_argument);
    ro.sppScale.assign(static_cast<size_t>(W) * H, 1);
    ro.sppScale[7] = static_cast<uint8_t>(kMaxSppScale + 1);
    EXPECT_THROW(precomputeTransport(scene, ro, 1), std::invalid_argument);
}

TEST(TraceRegion, PixelLatticeSpacing) {
    const auto flags = pixelLattice(1000, 500, 2000);  // k = floor(sqrt(250)) = 15
    const auto n = std::count(flags.begin(), flags.end(), 1);
    EXPECT_EQ(n, static_cast<long>(((1000 - 7 + 14) / 15) * ((500 - 7 + 14) / 15)));
    EXPECT_EQ(flags[7 * 1000 + 7], 1);
    EXPECT_EQ(flags[7 * 1000 + 8], 0);
    EXPECT_EQ(flags[22 * 1000 + 22], 1);
    const auto all = pixelLattice(10, 10, 1000);  // more asked than there are: every pixel
    EXPECT_EQ(std::count(all.begin(), all.end(), 1), 100);
}

TEST(TraceRegion, OptimizeTracingOnlyTheMaskFindsTheSameLight) {
    test::TempDir dir("trace-mask");
    const std::string scene = std::string(SL_SOURCE_DIR) + "/scenes/default/scene.json";
    const std::string d = dir.path().string() + "/";
    std::vector<uint8_t> mask(24 * 24, 0);
    for (int y = 9; y < 15; ++y)
        for (int x = 8; x < 16; ++x) mask[static_cast<size_t>(y) * 24 + x] = 255;
    writeMaskPng(dir / "mask.png", mask, 24, 24);
    const std::string base = "optimize " + scene +
                             " --size 24 --spp 8 --iterations 30 --heldout none --no-cache "
                             "--mask " +
                             d + "mask.png";
    auto whole = test::runCli(base + " -o " + d + "whole");
    ASSERT_EQ(whole.exitCode, 0) << whole.output;
    auto part = test::runCli(base + " --trace-mask-only -o " + d + "part");
    ASSERT_EQ(part.exitCode, 0) << part.output;
    const std::string e1 = test::readFile(dir / "whole" / "envmap.exr");
    EXPECT_FALSE(e1.empty());
    EXPECT_EQ(e1, test::readFile(dir / "part" / "envmap.exr"));
    const auto sw = nlohmann::json::parse(test::readFile(dir / "whole" / "summary.json"));
    const auto sp = nlohmann::json::parse(test::readFile(dir / "part" / "summary.json"));
    EXPECT_EQ(sw.at("mask_pixels"), sp.at("mask_pixels"));
    EXPECT_LT(sp.at("transport").at("nnz").get<double>(),
              sw.at("transport").at("nnz").get<double>());
    // The trace's rays, from the log line "traced N rays in ...": the region's only.
    auto rays = [](const std::string& log) {
        const auto at = log.find("traced ");
        return at == std::string::npos ? 0.0 : std::stod(log.substr(at + 7));
    };
    EXPECT_GT(rays(part.output), 0.0) << part.output;
    EXPECT_LT(rays(part.output), 0.6 * rays(whole.output)) << part.output << whole.output;
    // Without a mask there is no region to trace.
    auto none = test::runCli("optimize " + scene + " --size 24 --spp 8 --heldout none " +
                             "--no-cache --trace-mask-only -o " + d + "none");
    EXPECT_EQ(none.exitCode, 1) << none.output;
    EXPECT_NE(none.output.find("--trace-mask-only"), std::string::npos) << none.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "none"));
}

TEST(TraceRegion, PrecomputeMaxDepthAutoRecordsItsChoice) {
    test::TempDir dir("depth-auto");
    const std::string scene = std::string(SL_SOURCE_DIR) + "/scenes/default/scene.json";
    const auto out = dir / "t.tm";
    auto r = test::runCli("precompute " + scene + " --size 24 --spp 2 --max-depth auto -o " +
                          out.string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const auto at = r.output.find("max_depth ");
    ASSERT_NE(at, std::string::npos) << r.output;
    EXPECT_NE(r.output.find("of the image"), std::string::npos) << r.output;
    const int chosen = std::stoi(r.output.substr(at + 10));
    EXPECT_GE(chosen, 2);
    EXPECT_EQ(readTransportFile(out).provenance.maxDepth, chosen);
    for (const char* bad : {"0", "65", "deep", "3x"}) {
        r = test::runCli("precompute " + scene + " --size 24 --spp 2 --max-depth " + bad + " -o " +
                         (dir / "bad.tm").string());
        EXPECT_EQ(r.exitCode, 2) << bad << ": " << r.output;
        EXPECT_NE(r.output.find("--max-depth"), std::string::npos) << r.output;
    }
    EXPECT_FALSE(std::filesystem::exists(dir / "bad.tm"));
}

}  // namespace

namespace {

using namespace sl;

// Camera::project inverts generateRay: the film position of a point on a pixel's ray.
TEST(TraceRegion, ProjectInvertsGenerateRay) {
    for (const auto type : {CameraDesc::Type::Perspective, CameraDesc::Type::Orthographic}) {
        CameraDesc d;
        d.type = type;
        d.origin = {1.5, 3.0, 4.0};
        d.target = {0.2, -0.1, 0.3};
        d.up = {0.1, 1.0, 0.0};
        d.width = 40;
        d.height = 30;
        const Camera cam(d);
        for (const auto& [x, y] : {std::pair{0.0, 0.0}, {12.25, 7.5}, {39.9, 29.9}, {20.0, 3.0}}) {
            const Ray r = cam.generateRay(x, y);
            const Vec3d o(r.origin), dir(r.direction);
            const auto p = cam.project(o + dir * 4.0);
            ASSERT_TRUE(p.has_value());
            EXPECT_NEAR(p->first, x, 1e-4) << x << "," << y;
            EXPECT_NEAR(p->second, y, 1e-4) << x << "," << y;
        }
        EXPECT_FALSE(cam.project(Vec3d(d.origin) * 2.0 - Vec3d(d.target)).has_value());
    }
}

// Skipping the pixels outside the part's footprint changes nothing but the rays: the same T,
// bit for bit, from cameras that see the part whole, at a grazing angle, from orthographic
// and from so close that the part's corners are behind the camera (no culling then).
TEST(TraceRegion, BackgroundCullingChangesNothingButTheRays) {
    std::vector<CameraSpec> cams(4);
    cams[1].origin = Vec3d{0.0, 0.25, 2.4};  // grazing: the part is a thin band
    cams[1].target = Vec3d{0.0, 0.0, 0.0};
    cams[2].type = CameraDesc::Type::Orthographic;
    cams[2].origin = Vec3d{0.5, 2.0, 1.0};
    cams[2].target = Vec3d{0.0, 0.0, 0.0};
    cams[2].widthMm = 2.5;
    cams[3].origin = Vec3d{0.1, 0.12, 0.0};  // above the part, inside its box's footprint
    cams[3].target = Vec3d{0.1, 0.0, -0.6};
    cams[3].fovDeg = 100;
    uint64_t saved = 0;
    for (size_t c = 0; c < cams.size(); ++c) {
        SceneDesc desc = test::bumpyPartDesc(36, 28);
        desc.camera.type = cams[c].type;
        desc.camera.origin = cams[c].origin;
        desc.camera.target = cams[c].target;
        desc.camera.widthMm = cams[c].widthMm;
        desc.camera.fovDeg = cams[c].fovDeg;
        desc.camera.width = 36;
        desc.camera.height = 28;
        const Scene scene(desc, 40, 40, test::bumpyHeightMap(40));
        RenderOptions ro;
        ro.spp = 4;
        const auto culled = precomputeTransport(scene, ro, 1);
        ro.cullBackground = false;
        const auto all = precomputeTransport(scene, ro, 1);
        TransportMatrix a = culled.matrix, b = all.matrix;
        a.toSparse();
        b.toSparse();
        EXPECT_EQ(a.rowPtr, b.rowPtr) << "camera " << c;
        EXPECT_EQ(a.colIdx, b.colIdx) << "camera " << c;
        EXPECT_EQ(a.values, b.values) << "camera " << c;
        EXPECT_EQ(a.objectMask, b.objectMask) << "camera " << c;
        EXPECT_GT(b.nnz(), 0u) << "camera " << c;
        EXPECT_LE(culled.summary.rays, all.summary.rays) << "camera " << c;
        saved += all.summary.cameraRays - culled.summary.cameraRays;
        if (c == 1) {
            EXPECT_LT(culled.summary.cameraRays, all.summary.cameraRays / 2);
        }
    }
    EXPECT_GT(saved, 0u);
}

}  // namespace

namespace {

using namespace sl;

TEST(TraceRegion, TraceOptionsTakeTheSamplerAndPathLengthAsked) {
    const Scene scene(test::bumpyPartDesc(8, 8), 16, 16, test::bumpyHeightMap(16));
    PrecomputeOptions p;
    EXPECT_EQ(traceOptions(scene, p).sampling, RenderDesc{}.sampling);
    p.sampling = Sampling::Mis;
    p.maxDepth = 5;
    EXPECT_EQ(traceOptions(scene, p).sampling, Sampling::Mis);
    EXPECT_EQ(traceOptions(scene, p).maxDepth, 5);
    p.autoMaxDepth = true;  // must be resolved into a number first
    EXPECT_THROW(traceOptions(scene, p), std::logic_error);
    const auto choice = resolveMaxDepth(scene, p);
    ASSERT_TRUE(choice.has_value());
    EXPECT_FALSE(p.autoMaxDepth);
    EXPECT_EQ(p.maxDepth, choice->maxDepth);
    EXPECT_EQ(traceOptions(scene, p).maxDepth, choice->maxDepth);
}

}  // namespace

namespace {

using namespace sl;

TEST(TraceRegion, RegionBenchReportsTheSavings) {
    RegionBenchOptions o;
    o.resolution = 48;
    o.spp = 4;
    o.repeats = 1;
    const RegionBenchResult r = runRegionBench(o);
    ASSERT_EQ(r.rows.size(), 4u);
    EXPECT_EQ(r.rows[0].name, "every pixel");
    EXPECT_EQ(r.rows[0].pixels, 48u * 48u);
    EXPECT_TRUE(r.rows[1].sameAsBaseline);
    EXPECT_LT(r.rows[1].cameraRays, r.rows[0].cameraRays);  // the bundled view has background
    EXPECT_EQ(r.rows[1].nnz, r.rows[0].nnz);
    EXPECT_LE(r.rows[2].rays, r.rows[1].rays);
    EXPECT_LE(r.rows[2].nnz, r.rows[1].nnz);
    EXPECT_NE(r.rows[3].detail.find("max_depth"), std::string::npos) << r.rows[3].detail;
    std::istringstream csv(r.csv());
    std::string line;
    int lines = 0;
    while (std::getline(csv, line)) ++lines;
    EXPECT_EQ(lines, 5);
    o.spp = 3;  // two halves need an even spp
    EXPECT_THROW(runRegionBench(o), InputError);
}

}  // namespace

namespace {

using namespace sl;

TEST(TraceRegion, PrecomputeSppAutoFromTheGradientsNoise) {
    test::TempDir dir("spp-auto");
    const std::string scene = std::string(SL_SOURCE_DIR) + "/scenes/default/scene.json";
    auto chosen = [&](const std::string& tolerance) {
        const auto out = dir / ("t" + tolerance + ".tm");
        const auto r = test::runCli("precompute " + scene + " --size 32 --max-depth 2 --spp auto" +
                                    " --tolerance " + tolerance + " -o " + out.string());
        EXPECT_EQ(r.exitCode, 0) << r.output;
        const std::string log = "\n" + r.output;
        const auto at = log.find("\nspp ");
        if (at == std::string::npos) {
            ADD_FAILURE() << r.output;
            return 0;
        }
        EXPECT_NE(r.output.find("relative noise"), std::string::npos) << r.output;
        const int spp = std::stoi(log.substr(at + 5));
        EXPECT_EQ(readTransportFile(out).provenance.spp, spp);
        return spp;
    };
    const int loose = chosen("0.5"), tight = chosen("0.1");
    EXPECT_EQ(loose, kSppAutoPilot);  // the pilot's noise is below 0.5 already
    EXPECT_GT(tight, loose);
    EXPECT_EQ(tight & (tight - 1), 0);  // a power of two
    for (const char* bad :
         {"--spp 0", "--spp many", "--spp auto --tolerance 0", "--spp auto --tolerance 1.5"}) {
        const auto r = test::runCli("precompute " + scene + " --size 32 " + bad + " -o " +
                                    (dir / "bad.tm").string());
        EXPECT_EQ(r.exitCode, 2) << bad << ": " << r.output;
    }
    EXPECT_FALSE(std::filesystem::exists(dir / "bad.tm"));
}

}  // namespace

namespace {

using namespace sl;

// eq. 2 rewards noise, so optimize starts at its spp floor under --spp auto too, and the
// train/validation rule measures what is left.
TEST(TraceRegion, OptimizeSppAutoKeepsEq2sFloor) {
    test::TempDir dir("spp-auto-paper");
    const std::string scene = std::string(SL_SOURCE_DIR) + "/scenes/default/scene.json";
    const auto r = test::runCli("optimize " + scene +
                                " --size 24 --max-depth 2 --spp auto --tolerance 0.9 --objective "
                                "paper --iterations 3 --heldout none --no-cache --no-figures -o " +
                                (dir / "o").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("training noise: 512 spp"), std::string::npos) << r.output;
    const auto s = nlohmann::json::parse(test::readFile(dir / "o" / "summary.json"));
    EXPECT_EQ(s.at("transport").at("spp").get<int>(), 512);
}

}  // namespace
