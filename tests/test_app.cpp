// The app layer's pieces without the CLI: gradcheck and bench gradients, the render, transport
// and scratch-map benchmarks, the report's loss curves, and running the plot scripts.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "TestUtil.h"
#include "app/bench/DefectMapBench.h"
#include "app/bench/GradCheck.h"
#include "app/bench/JndBench.h"
#include "app/bench/RenderBench.h"
#include "app/bench/ScratchMapBench.h"
#include "app/bench/TargetsBench.h"
#include "app/bench/TransportBench.h"
#include "app/host/Plot.h"
#include "app/report/Report.h"
#include "core/Error.h"
#include "io/SceneFile.h"
#include "render/Benchmark.h"
#include "render/Footprint.h"
#include "render/Render.h"
#include "scene/Scene.h"
#include "synth/SurfaceGenerator.h"

using namespace sl;

namespace {

/// A small bumpy part with a scratch, a 12×12 image, 2 spp and an 8×5 env map: every gradient
/// method (finite differences too) runs in well under a second.
struct SmallScene {
    test::TempDir dir{"app"};
    std::filesystem::path scene = dir / "scene.json";

    SmallScene() {
        const int n = 32;
        std::vector<float> h(static_cast<size_t>(n) * n);
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                double v = 0.004 * std::sin(0.9 * i) * std::cos(0.7 * j);
                if (std::abs(i - 17) <= 1) v -= 0.006;  // a scratch
                h[static_cast<size_t>(j) * n + i] = static_cast<float>(v);
            }
        test::writeNpyF32(dir / "h.npy", n, n, h);
        test::writeText(scene, R"({"heightmap": {"path": "h.npy", "pixel_pitch": 0.01},
            "material": {"alpha": 0.2, "material": "Al"},
            "camera": {"width": 12, "height": 12, "fov": 30},
            "envmap": {"width": 8, "height": 5},
            "render": {"spp": 2, "max_depth": 3, "seed": 5}})");
    }
};

std::vector<std::string> lines(const std::string& text) {
    std::vector<std::string> out;
    std::istringstream in(text);
    for (std::string l; std::getline(in, l);) out.push_back(l);
    return out;
}

std::string readFile(const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

}  // namespace

TEST(GradCheck, ExactEqualsAutodiffAndEveryRowIsMeasuredAgainstTheReference) {
    SmallScene s;
    GradCheckOptions o;
    o.setup.scene = s.scene;
    o.methods = {"exact", "autodiff", "autodiff-T", "fd"};
    o.repeats = 1;
    const GradCheckReport r = runGradCheck(o);
    EXPECT_EQ(r.width, 12);
    EXPECT_EQ(r.height, 12);
    EXPECT_EQ(r.spp, 2);
    EXPECT_EQ(r.maxDepth, 3);
    EXPECT_EQ(r.seed, 5u);
    EXPECT_EQ(r.texels, 40);
    EXPECT_GT(r.maskPixels, 0u);
    EXPECT_GT(r.loss, 0);
    EXPECT_LE(r.exactVsAutodiffT, 1e-9);  // the same float T
    EXPECT_LE(r.exactVsAutodiffPaths, 1e-5);
    ASSERT_EQ(r.rows.size(), 4u);
    EXPECT_EQ(r.rows[0].method, "exact");
    EXPECT_LE(r.rows[0].relativeError, 1e-5);
    EXPECT_EQ(r.rows[1].method, "autodiff");
    EXPECT_EQ(r.rows[1].relativeError, 0.0);  // the reference itself
    EXPECT_NEAR(r.rows[1].cosine, 1.0, 1e-12);
    EXPECT_LE(r.rows[2].relativeError, 1e-5);
    EXPECT_EQ(r.rows[3].method, "fd");
    EXPECT_EQ(r.rows[3].renders, 2 * 40 + 1);  // central differences (and the base render)
    EXPECT_GT(r.rows[3].cosine, 0.5);
    EXPECT_DOUBLE_EQ(r.rows[3].parameter, o.fd.h);
    for (const GradCheckRow& row : r.rows) EXPECT_GE(row.seconds, 0) << row.method;

    const std::string table = r.table();
    for (const char* m : {"exact", "autodiff-T", "fd"})
        EXPECT_NE(table.find(m), std::string::npos) << m;
    const auto j = nlohmann::json::parse(r.json());
    ASSERT_EQ(j["methods"].size(), 4u);
    EXPECT_EQ(j["methods"][3]["method"], "fd");
    EXPECT_EQ(j["texels"], 40);
}

TEST(GradCheck, RejectsUnknownMethodsAndBadRepeats) {
    SmallScene s;
    GradCheckOptions o;
    o.setup.scene = s.scene;
    o.methods = {"exact", "newton"};
    try {
        runGradCheck(o);
        ADD_FAILURE() << "no error for an unknown method";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("newton"), std::string::npos) << e.what();
    }
    o.methods = {"exact"};
    o.repeats = 0;
    EXPECT_THROW(runGradCheck(o), InputError);
    o.repeats = 1;
    o.setup.scene = s.dir / "missing.json";
    EXPECT_THROW(runGradCheck(o), InputError);
    const auto all = gradCheckMethods();
    EXPECT_EQ(all.size(), 8u);
}

TEST(BenchGradients, WritesOneCsvRowPerMeasurementAndTracesEveryOptimization) {
    SmallScene s;
    BenchGradientsOptions o;
    o.setup.scene = s.scene;
    o.fdSteps = {1e-3};
    o.fdFreshSteps = {1e-2};
    o.spsaQ = {1, 4};
    o.spsaC = {0.02};
    o.repeats = 1;
    o.iterations = 3;
    o.spsaIterations = 5;
    o.outDir = s.dir / "bench";
    const BenchGradientsReport r = runBenchGradients(o);
    // exact, exact+precompute, autodiff, autodiff-T, one fd, one fd-fresh, two spsa.
    ASSERT_EQ(r.gradients.rows.size(), 8u);
    EXPECT_EQ(lines(readFile(r.gradientsCsv)).size(), 1u + 8u);
    EXPECT_EQ(r.optimizationCsv, o.outDir / "optimization.csv");
    EXPECT_EQ(lines(readFile(r.optimizationCsv)).size(), 1u + r.trace.size());
    std::vector<std::string> methods;
    for (const BenchTracePoint& p : r.trace)
        if (methods.empty() || methods.back() != p.method) methods.push_back(p.method);
    ASSERT_EQ(methods.size(), 5u);  // exact, autodiff, fd-adam, spsa q=1, spsa q=8
    EXPECT_EQ(methods[0], "exact (Adam)");
    // Exact and autodiff Adam take the same steps: the same loss after each iteration.
    std::vector<double> exact, autodiff;
    for (const BenchTracePoint& p : r.trace) {
        if (p.method == methods[0]) exact.push_back(p.loss);
        if (p.method == methods[1]) autodiff.push_back(p.loss);
        EXPECT_TRUE(std::isfinite(p.loss)) << p.method;
    }
    ASSERT_EQ(exact.size(), autodiff.size());
    for (size_t k = 0; k < exact.size(); ++k) EXPECT_NEAR(exact[k], autodiff[k], 1e-5 * exact[k]);
    EXPECT_LT(exact.back(), exact.front());

    o.optimizations = false;
    o.outDir = s.dir / "bench2";
    const BenchGradientsReport q = runBenchGradients(o);
    EXPECT_TRUE(q.trace.empty());
    EXPECT_TRUE(q.optimizationCsv.empty());
    EXPECT_FALSE(std::filesystem::exists(o.outDir / "optimization.csv"));
}

TEST(RenderBench, RendererAndBareEmbreeTraceTheSameCameraRays) {
    SmallScene s;
    RenderBenchOptions o;
    o.scene = s.scene;
    o.sizes = {16};
    o.resolution = 8;
    o.spp = 2;
    o.repeats = 2;
    const RenderBenchResult r = runRenderBench(o);
    ASSERT_EQ(r.rows.size(), 2u);
    EXPECT_EQ(r.rows[0].map, "scene.json");
    EXPECT_EQ(r.rows[0].genSeconds, 0.0);
    EXPECT_EQ(r.rows[1].map, "16x16");
    for (const RenderBenchRow& row : r.rows) {
        EXPECT_GE(row.renderer.rays, 8u * 8u * 2u) << row.map;  // at least the camera rays
        EXPECT_GE(row.bare.rays, 8u * 8u * 2u) << row.map;
        EXPECT_GT(row.heightfield.vertexBytes, 0u) << row.map;
        EXPECT_GT(row.ratio(), 0) << row.map;
        // The footprint's rays: at least its camera rays, at most every pixel's rays.
        EXPECT_LE(row.rendererFootprint.rays, row.renderer.rays) << row.map;
        EXPECT_LE(row.bareFootprint.rays, row.bare.rays) << row.map;
        EXPECT_GT(row.bareFootprint.rays, 0u) << row.map;
        EXPECT_GT(row.footprintRatio(), 0) << row.map;
    }
    {
        // Both loops trace the footprint's camera rays: with maxDepth 1 they count the same.
        SceneDesc d = readSceneFile(s.scene);
        d.camera.width = d.camera.height = 8;
        d.render.maxDepth = 1;
        auto scene = loadScene(d);
        uint64_t footprint = 0;
        for (const PixelSpan& sp : partFootprint(*scene)) footprint += uint64_t(sp.end - sp.begin);
        RenderOptions opt = renderOptionsFor(*scene);
        opt.spp = 2;
        opt.cullBackground = true;
        EXPECT_EQ(benchRenderer(*scene, opt).rays, 2 * footprint);
        EXPECT_EQ(benchBareEmbree(*scene, opt).rays, 2 * footprint);
    }
    const auto csv = lines(r.csv());
    ASSERT_EQ(csv.size(), 3u);
    EXPECT_EQ(csv[0].rfind("height_map,", 0), 0u);
    EXPECT_NE(csv[0].find(",footprint_ratio"), std::string::npos);
    EXPECT_EQ(csv[2].rfind("16x16,", 0), 0u);

    o.repeats = 0;
    EXPECT_THROW(runRenderBench(o), InputError);
    o.repeats = 1;
    o.sizes = {1};
    EXPECT_THROW(runRenderBench(o), InputError);
}

TEST(RenderBench, BareEmbreeTracesTheTracersCameraRays) {
    // With the background culled (the tracer's default), the bare loop traces the camera rays
    // of the footprint's pixels only, as the tracer does; without, every pixel's.
    SmallScene s;
    SceneDesc d = readSceneFile(s.scene);
    d.camera.width = d.camera.height = 24;
    auto scene = loadScene(d);
    RenderOptions opt = renderOptionsFor(*scene);
    opt.spp = 2;
    opt.maxDepth = 1;  // camera rays only
    uint64_t footprint = 0;
    for (const PixelSpan& sp : partFootprint(*scene)) footprint += uint64_t(sp.end - sp.begin);
    ASSERT_LT(footprint, 24u * 24u);
    ASSERT_GT(footprint, 0u);
    opt.cullBackground = true;
    EXPECT_EQ(benchBareEmbree(*scene, opt).rays, 2 * footprint);
    struct NullSink : PathSink {
        void consume(const PixelPaths&) override {}
    } sink;
    EXPECT_EQ(PathTracer(*scene).trace(opt, sink).cameraRays, 2 * footprint);
    opt.cullBackground = false;
    EXPECT_EQ(benchBareEmbree(*scene, opt).rays, 2u * 24u * 24u);
}

TEST(RenderBench, MedianOfRepeatsIsTheTrueMedianOfTheSeconds) {
    std::vector<ThroughputRow> rows{
        {"w", 100, 4.0}, {"w", 100, 1.0}, {"w", 100, 2.0}, {"w", 100, 8.0}};
    const ThroughputRow m = medianThroughput(rows);
    EXPECT_EQ(m.workload, "w");
    EXPECT_EQ(m.rays, 100u);
    EXPECT_DOUBLE_EQ(m.seconds, 3.0);  // mean of the two middle values
    rows.pop_back();
    EXPECT_DOUBLE_EQ(medianThroughput(rows).seconds, 2.0);
    EXPECT_EQ(medianThroughput({}).rays, 0u);
}

TEST(TransportBench, MeasuresTracingTAndTheIterationOnT) {
    SmallScene s;
    TransportBenchOptions o;
    o.scene = s.scene;
    o.resolution = 10;
    o.spp = 2;
    o.iterations = 3;
    o.repeats = 1;
    const TransportBenchResult r = runTransportBench(o);
    EXPECT_EQ(r.width, 10);
    EXPECT_EQ(r.height, 10);
    EXPECT_EQ(r.maxDepth, 3);
    // The transport sink follows the renderer's paths: the same rays.
    EXPECT_EQ(r.precompute.rays, r.renderer.rays);
    EXPECT_GT(r.bare.rays, 0u);
    EXPECT_GT(r.precomputeVsBare(), 0);
    EXPECT_GT(r.nnz, 0u);
    EXPECT_GT(r.bytes, 0u);
    EXPECT_GT(r.density, 0);
    EXPECT_LE(r.density, 1);
    EXPECT_EQ(r.productRepeats, 5);
    for (double t :
         {r.streamingRead, r.apply, r.iterationTwoPass, r.iterationFused, r.adam, r.applySlices,
          r.iterationTwoPassSlices, r.iterationFusedSlices, r.adamSlices, r.slicesBuild})
        EXPECT_GE(t, 0);
    EXPECT_GT(r.slicesBytes, 0u);
    EXPECT_GE(r.slicesPadding, 1.0);
    const auto csv = lines(r.csv());
    ASSERT_EQ(csv.size(), 2u);
    EXPECT_NE(csv[1].find(",3,"), std::string::npos) << csv[1];  // adam_iterations

    o.scene = s.dir / "missing.json";
    EXPECT_THROW(runTransportBench(o), InputError);
}

// bench targets: a row per issue-32 target, its bound, and the phases inside the job's wall time
// (the optimizer's seconds, the scene row's trace and the lamps' E* and fits are parts of it, so
// the rest is >= 0); the scene row traces T (its cache is emptied before each run), the others
// read it.
TEST(TargetsBench, ARowPerTargetWithItsBoundAndPhasesInsideTheWallTime) {
    test::TempDir dir("targets-bench");
    TargetsBenchOptions o;
    o.size = 16;
    o.spp = 2;
    o.repeats = 2;
    o.lampCount = 1;
    o.workDir = dir.path();
    const TargetsBenchResult r = runTargetsBench(o);
    ASSERT_EQ(r.rows.size(), 4u);
    EXPECT_EQ(r.rows[0].target, "re-optimize T at lambda 10, no held-out");
    EXPECT_EQ(r.rows[1].target, "re-optimize T at lambda 10, judge's held-out");
    EXPECT_EQ(r.rows[2].target, "optimize SCENE at 16x16, no held-out, uncached");
    EXPECT_EQ(r.rows[3].target, "lamps on T, K = 1");
    EXPECT_EQ(r.rows[0].targetSeconds, 0.2);
    EXPECT_EQ(r.rows[1].targetSeconds, 0.2);
    EXPECT_EQ(r.rows[2].targetSeconds, 1.0);
    EXPECT_EQ(r.rows[3].targetSeconds, 1.0);
    for (const TargetsBenchRow& row : r.rows) {
        SCOPED_TRACE(row.target);
        EXPECT_GT(row.evaluations, 0);
        EXPECT_GT(row.optimizerSeconds, 0);
        EXPECT_GE(row.rest(), 0);
        EXPECT_LE(row.secondsMin, row.seconds);
        EXPECT_GE(row.secondsMax, row.seconds);
        EXPECT_DOUBLE_EQ(row.ratio(), row.seconds / row.targetSeconds);
    }
    EXPECT_EQ(r.rows[0].secondsTrace, 0);
    EXPECT_EQ(r.rows[1].secondsTrace, 0);
    EXPECT_GT(r.rows[2].secondsTrace, 0);  // the scene row traces T
    EXPECT_EQ(r.rows[3].secondsTrace, 0);
    EXPECT_GT(r.rows[3].secondsTarget, 0);  // lamps optimized E* first
    const std::string csv = r.csv();
    EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 5);
    EXPECT_TRUE(std::filesystem::exists(dir.path() / "optimize" / "report.html"));
    EXPECT_TRUE(std::filesystem::exists(dir.path() / "optimize-scene" / "report.html"));
}

// bench jnd: one evaluation row per size whose two band-filter methods agree to rounding, and an
// optimize row per measure whose phases lie inside its wall time.
TEST(JndBench, EvaluationRowsAgreeAndOptimizePhasesFitTheWallTime) {
    test::TempDir dir("jnd-bench");
    JndBenchOptions o;
    o.sizes = {48};
    o.evaluationSpp = 2;
    o.evaluations = 1;
    o.optimizeSize = 48;
    o.repeats = 1;
    o.workDir = dir.path();
    const JndBenchResult r = runJndBench(o);
    ASSERT_EQ(r.evaluations.size(), 1u);
    const JndEvaluationRow& e = r.evaluations[0];
    EXPECT_EQ(e.size, 48);
    EXPECT_GT(e.secondsDirect, 0);
    EXPECT_GT(e.secondsFourier, 0);
    EXPECT_GT(e.secondsRatio, 0);
    EXPECT_LT(e.lossDifference, 1e-12);
    EXPECT_LT(e.gradientDifference, 1e-10);
    ASSERT_EQ(r.optimize.size(), 2u);
    EXPECT_EQ(r.optimize[0].measure, "jnd");
    EXPECT_EQ(r.optimize[1].measure, "ratio");
    for (const JndOptimizeRow& row : r.optimize) {
        SCOPED_TRACE(row.measure);
        ASSERT_EQ(row.samples.size(), 1u);
        const JndOptimizeSample& x = row.samples[0];
        EXPECT_GT(x.trace, 0);
        EXPECT_GT(x.search, 0);
        EXPECT_GT(x.judge, 0);
        EXPECT_GE(x.rest, 0);
        EXPECT_GE(x.spp, 1);
        EXPECT_GE(x.rounds, 1);
        EXPECT_TRUE(std::isfinite(x.jnd));
    }
    const std::string csv = r.csv();
    EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 4);
}

TEST(ScratchMapBench, MarksTheScratchAndWritesOneRowPerSize) {
    ScratchMapBenchOptions o;
    o.sizes = {64, 200};
    o.repeats = 2;
    const ScratchMapBenchResult r = runScratchMapBench(o);
    ASSERT_EQ(r.rows.size(), 2u);
    EXPECT_EQ(r.rows[0].size, 64);
    EXPECT_EQ(r.rows[0].patches, 4);  // 40-sample patches: 2 × 2 (partial ones included)
    EXPECT_EQ(r.rows[1].patches, 25);
    for (const ScratchMapBenchRow& row : r.rows) {
        EXPECT_GE(row.patchesMarked, 1);
        EXPECT_GE(row.seconds, 0);
        EXPECT_GT(row.markedFraction, 0);
    }
    EXPECT_EQ(lines(r.csv()).size(), 3u);
    const std::vector<float> h = scratchMapBenchHeights(5);
    EXPECT_FLOAT_EQ(h[2 * 5 + 2], 0.01f * std::sin(0.157f * 2) + 2e-5f - 0.05f);
    o.repeats = 0;
    EXPECT_THROW(runScratchMapBench(o), InputError);
    o.repeats = 1;
    o.sizes = {0};
    EXPECT_THROW(runScratchMapBench(o), InputError);
}

TEST(DefectMapBench, EachColumnIsTheMapItNamesOnTheSameHeights) {
    // the columns are detectDefects on the ball-end part: as a simulator's map (the tool-path
    // model), as a measured texture (the selfsim method) and the paper's scratch map
    DefectMapBenchOptions o;
    o.sizes = {96};
    o.repeats = 1;
    const DefectMapBenchResult r = runDefectMapBench(o);
    ASSERT_EQ(r.rows.size(), 1u);
    SurfaceSpec spec = testPartSpec(TestPart::BallEnd);
    spec.width = spec.height = 96;
    const GeneratedSurface part = generateSurface(spec);
    DefectMapOptions m;
    m.method = DefectMethod::Auto;
    const DefectMap simulator = detectDefects(part.heights, 96, 96, m);
    m.measured = true;
    const DefectMap measured = detectDefects(part.heights, 96, 96, m);
    EXPECT_FALSE(simulator.measuredTexture);
    EXPECT_TRUE(measured.measuredTexture);
    m = DefectMapOptions{};
    m.method = DefectMethod::Paper;
    const DefectMap paper = detectDefects(part.heights, 96, 96, m);
    EXPECT_EQ(r.rows[0].markedAuto, simulator.markedFraction());
    EXPECT_EQ(r.rows[0].markedMeasured, measured.markedFraction());
    EXPECT_EQ(r.rows[0].markedPaper, paper.markedFraction());
    EXPECT_GT(r.rows[0].secondsMeasured, 0.0);
    EXPECT_EQ(lines(r.csv()).size(), 2u);
    o.measured = false;
    EXPECT_EQ(runDefectMapBench(o).rows[0].secondsMeasured, 0.0);
    o.sizes = {1};
    EXPECT_THROW(runDefectMapBench(o), InputError);
}

TEST(Report, LossCsvColumnsAreFoundByNameAndErrorsNameTheLine) {
    test::TempDir dir("report-csv");
    test::writeText(dir / "loss.csv", "seconds,loss,iteration\n0.1,5,0\n0.2,3.5,1\n\n0.3,2,2\n");
    const LossSeries s = readLossCsv(dir / "loss.csv");
    EXPECT_EQ(s.iteration, (std::vector<double>{0, 1, 2}));
    EXPECT_EQ(s.loss, (std::vector<double>{5, 3.5, 2}));
    test::writeText(dir / "noloss.csv", "iteration,total\n0,1\n");
    EXPECT_THROW(readLossCsv(dir / "noloss.csv"), InputError);
    test::writeText(dir / "bad.csv", "iteration,loss\n0,1\n1,x\n");
    try {
        readLossCsv(dir / "bad.csv");
        ADD_FAILURE() << "no error for a non-number";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("bad.csv:3"), std::string::npos) << e.what();
    }
    EXPECT_THROW(readLossCsv(dir / "missing.csv"), InputError);
}

TEST(Report, LossCurveUsesALogAxisOnlyForAWideRangeOfPositiveLosses) {
    LossSeries narrow{"a", {0, 1, 2}, {5, 4, 3}};
    LossSeries wide{"b", {0, 1, 2}, {1000, 10, 1}};
    const std::string lin = lossCurveSvg({narrow});
    const std::string log = lossCurveSvg({wide});
    EXPECT_EQ(lin.rfind("<svg", 0), 0u);
    EXPECT_NE(lin.find("<polyline"), std::string::npos);
    EXPECT_NE(log.find("loss (log)"), std::string::npos) << log;  // 1000× range
    EXPECT_EQ(lin.find("(log)"), std::string::npos) << lin;
    EXPECT_EQ(lossCurveSvg({LossSeries{}}), "<p>(no loss values)</p>");
    const std::string two = lossCurveSvg({narrow, wide});
    size_t n = 0;
    for (size_t p = two.find("<polyline"); p != std::string::npos; p = two.find("<polyline", p + 1))
        ++n;
    EXPECT_EQ(n, 2u);
}

TEST(Plot, ScriptsAreFoundBesideTheExecutableAndRunWithoutAShell) {
    // The test binary lives in the build directory, like the CLI: ../scripts is the source's.
    const std::filesystem::path p = findScript("plot_gradients.py");
    ASSERT_FALSE(p.empty());
    EXPECT_TRUE(std::filesystem::equivalent(p, SL_SOURCE_DIR "/scripts/plot_gradients.py"));
    EXPECT_TRUE(findScript("no_such_script.py").empty());
    EXPECT_GE(scriptDirs().size(), 2u);

    EXPECT_EQ(shellQuoted({"python3", "a b.py", "it's", "x=1,y"}),
              "python3 'a b.py' 'it'\\''s' x=1,y");
    EXPECT_EQ(runProcess({"true"}), 0);
    EXPECT_EQ(runProcess({"false"}), 1);
    // Arguments arrive as given: a quote in a path is just a character.
    test::TempDir dir("plot");
    const std::string odd = (dir / "it's a \"dir\"").string();
    EXPECT_EQ(runProcess({"mkdir", odd}), 0);
    EXPECT_TRUE(std::filesystem::is_directory(odd));
    EXPECT_THROW(runProcess({"/no/such/program"}), std::runtime_error);

    const PlotOutcome missing = runPlotScript("no_such_script.py", {"x"});
    EXPECT_FALSE(missing.ran);
    EXPECT_NE(missing.message.find("no_such_script.py"), std::string::npos);
    const PlotOutcome hint = runPlotScript("plot_noise.py", {odd}, false);
    EXPECT_FALSE(hint.ran);
    ASSERT_EQ(hint.command.size(), 3u);
    EXPECT_EQ(hint.command[2], odd);
}
