// The judge and the search: an analytic mirror case, agreement across judge seeds, per-region
// visibility on images with known gradients, truth-mask checks, the halves kernels, the
// cycling (stochastic) loss and multistart.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>

#include "TestUtil.h"
#include "app/bench/Race.h"
#include "app/pipeline/Defaults.h"
#include "app/pipeline/Judge.h"
#include "app/pipeline/Search.h"
#include "app/pipeline/Truth.h"
#include "core/Error.h"
#include "core/Rng.h"
#include "io/ImageIO.h"
#include "io/MaskIO.h"
#include "objective/DefectVisibility.h"
#include "objective/TransportLoss.h"
#include "render/Render.h"
#include "scene/Scene.h"
#include "synth/SurfaceGenerator.h"
#include "transport/TransportSink.h"

using namespace sl;

namespace {

std::unique_ptr<Scene> wavyScene(int res, int n = 48) {
    return std::make_unique<Scene>(test::bumpyPartDesc(res, res), n, n, test::bumpyHeightMap(n));
}

std::vector<double> randomVec(size_t n, uint64_t seed, double scale = 1.0) {
    Pcg32 rng(seed, 3);
    std::vector<double> v(n);
    for (double& x : v) x = scale * rng.nextDouble();
    return v;
}

}  // namespace

// A flat perfect mirror seen by an orthographic camera reflects every camera ray into one
// direction, the centre of texel (row, col): the judge's mean image is that texel's value in
// every part pixel, so its scores are known in closed form.
TEST(Judge, FlatMirrorUnderAKnownEnvMap) {
    const int W = 50, H = 25, row = 8, col = 10;
    const double theta = row * std::numbers::pi / (H - 1),
                 phi = 2 * std::numbers::pi * (col + 0.5) / W;
    const Vec3d r{std::sin(phi) * std::sin(theta), std::cos(theta),
                  -std::cos(phi) * std::sin(theta)};
    SceneDesc d;
    d.heightmap.pitch = 0.05;
    d.material.params.ior = ComplexIor{Rgb{0.0f}, Rgb{1.0f}};  // "none": F == 1
    d.material.params.smooth = true;
    d.camera.type = CameraDesc::Type::Orthographic;
    d.camera.origin = Vec3d{-r.x, r.y, -r.z} * 20.0;  // looking along the mirrored direction
    d.camera.target = Vec3d{0, 0, 0};
    d.camera.up = Vec3d{0, 1, 0};
    d.camera.widthMm = 0.5;
    d.camera.width = d.camera.height = 16;
    d.render.maxDepth = 2;
    Scene scene(d, 160, 160, std::vector<float>(160 * 160, 0.0f));

    JudgeOptions o;
    o.spp = 8;
    Judge judge(scene, o);
    std::vector<double> e = randomVec(size_t(W) * H, 5);
    e[size_t(row) * W + col] = 0.625;
    const std::vector<double> y = judge.meanImage(e);
    size_t part = 0;
    for (size_t p = 0; p < y.size(); ++p) {
        if (!judge.partMask()[p]) continue;
        ++part;
        EXPECT_NEAR(y[p], 0.625, 2e-4);
    }
    EXPECT_EQ(part, y.size());
    const JudgeScore s = judge.score(e, "mirror");
    double meanE = 0, sq = 0;
    size_t dark = 0;
    for (double v : e) {
        meanE += v / static_cast<double>(e.size());
        sq += v * v / static_cast<double>(e.size());
        dark += v < kDarkTexel;
    }
    EXPECT_NEAR(s.meanE, meanE, 1e-14);
    EXPECT_DOUBLE_EQ(s.sparsity, static_cast<double>(dark) / static_cast<double>(e.size()));
    EXPECT_NEAR(s.eq2.lReg, sq, 1e-12);
    EXPECT_NEAR(s.unbiased.lReg, sq, 1e-12);
    // A uniform image has no gradient: both losses sit at their floor.
    EXPECT_LT(s.eq2.G, 1e-3 * s.eq2.S);
    EXPECT_TRUE(s.unbiased.clamped || s.unbiased.G < 1e-6 * s.unbiased.S);
}

// The white furnace's images are rendered once per judge and reused by every light it scores:
// a judge that scored other lights first gives a light the same bits as a fresh one, and the
// brightness is the light's lit sum over the white one's on the part, in pixel order.
TEST(Judge, EveryLightIsScoredOnTheSameWhiteFurnaceAsByAFreshJudge) {
    auto scene = wavyScene(24);
    JudgeOptions o;
    o.spp = 8;
    Judge used(*scene, o);
    const std::vector<double> e1 = randomVec(1250, 31), e2 = randomVec(1250, 32);
    (void)used.score(e2);
    (void)used.scoreWithErrors(e2, {}, 16);
    const JudgeScore a = used.score(e1), ae = used.scoreWithErrors(e1, {}, 16);
    Judge fresh(*scene, o);
    const JudgeScore b = fresh.score(e1);
    Judge freshErrors(*scene, o);
    const JudgeScore be = freshErrors.scoreWithErrors(e1, {}, 16);
    EXPECT_EQ(a.brightness, b.brightness);
    EXPECT_EQ(a.unbiased.total, b.unbiased.total);
    EXPECT_EQ(a.eq2.total, b.eq2.total);
    ASSERT_TRUE(ae.se && be.se);
    EXPECT_EQ(ae.se->brightness, be.se->brightness);
    EXPECT_EQ(ae.se->eq2, be.se->eq2);
    EXPECT_EQ(ae.se->unbiased, be.se->unbiased);
    const std::vector<double> y = fresh.meanImage(e1),
                              w = fresh.meanImage(std::vector<double>(1250, 1.0));
    double lit = 0, white = 0;
    for (size_t p = 0; p < y.size(); ++p)
        if (fresh.partMask()[p]) lit += y[p], white += w[p];
    ASSERT_GT(white, 0.0);
    EXPECT_EQ(b.brightness, lit / white);
}

// Two judges with different seeds agree on U within 2 % at 1024 spp.
TEST(Judge, AgreesWithItselfAcrossSeeds) {
    auto scene = wavyScene(48);
    JudgeOptions a, b;
    a.spp = b.spp = 1024;
    b.seed = kJudgeSeed + 1;
    Judge ja(*scene, a), jb(*scene, b);
    for (uint64_t k = 0; k < 3; ++k) {
        const std::vector<double> e = randomVec(1250, 10 + k);
        const double ua = ja.score(e).unbiased.total, ub = jb.score(e).unbiased.total;
        EXPECT_NEAR(ua / ub, 1.0, 0.02) << "light " << k;
    }
}

TEST(DefectVisibility, KnownGradientsGiveTheirRatio) {
    const int w = 40, h = 30;
    std::vector<double> y(size_t(w) * h);
    std::vector<uint8_t> part(y.size(), 1), labels(y.size(), 0);
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i) {
            const bool in = i >= 5 && i < 15 && j >= 5 && j < 15;
            labels[size_t(j) * w + i] = in ? 255 : 0;
            y[size_t(j) * w + i] = (in ? 0.03 : 0.01) * (i + j) + (in ? 0.5 : 1.0);
        }
    auto v = defectVisibility(w, h, y, y, part, labels, {{255, "scratch"}});
    ASSERT_EQ(v.size(), 1u);
    EXPECT_EQ(v[0].label.name, "scratch");
    EXPECT_EQ(v[0].pixels, 100u);
    EXPECT_NEAR(v[0].rmsGradient, 0.03, 1e-12);
    EXPECT_NEAR(v[0].cleanRmsGradient, 0.01, 1e-12);
    EXPECT_NEAR(v[0].visibility, 3.0, 1e-9);
    EXPECT_LT(v[0].weber, 0.0);  // darker than its surroundings
    double mean = 0;
    for (double x : y) mean += x;
    mean /= static_cast<double>(y.size());
    EXPECT_NEAR(v[0].contrast, 0.03 / mean, 1e-12);
    // Brightening the image 10x changes neither contrast nor visibility.
    std::vector<double> y10(y);
    for (double& x : y10) x *= 10;
    const auto v10 = defectVisibility(w, h, y10, y10, part, labels, {{255, "scratch"}});
    EXPECT_NEAR(v10[0].contrast, v[0].contrast, 1e-12);
    EXPECT_NEAR(v10[0].visibility, v[0].visibility, 1e-9);
    // An unlisted label gets its own region; a listed label without pixels reports NaN.
    labels[size_t(25) * w + 30] = 7;
    v = defectVisibility(w, h, y, y, part, labels, {{255, "scratch"}, {128, "chatter"}});
    ASSERT_EQ(v.size(), 3u);
    EXPECT_EQ(v[1].pixels, 0u);
    EXPECT_TRUE(std::isnan(v[1].visibility));
    EXPECT_EQ(v[2].label.name, "label-7");
}

// A reference region restricts the defect-free surface the visibility compares against.
TEST(DefectVisibility, AReferenceRegionIsTheSurfaceComparedWith) {
    const int w = 40, h = 30;
    std::vector<double> y(size_t(w) * h);
    std::vector<uint8_t> part(y.size(), 1), labels(y.size(), 0), reference(y.size(), 0);
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i) {
            const size_t q = size_t(j) * w + i;
            const bool in = i >= 5 && i < 15 && j >= 5 && j < 15;
            labels[q] = in ? 255 : 0;
            reference[q] = i >= 27;
            y[q] = (in ? 0.03 : i >= 25 ? 0.02 : 0.01) * (i + j) + 1.0;
        }
    const auto all = defectVisibility(w, h, y, y, part, labels, {{255, "scratch"}});
    const auto ref = defectVisibility(w, h, y, y, part, labels, {{255, "scratch"}}, reference);
    EXPECT_LT(all[0].visibility, 1.0);  // the whole surface: its step at i = 25 included
    EXPECT_NEAR(ref[0].cleanRmsGradient, 0.02, 1e-12);
    EXPECT_NEAR(ref[0].visibility, 1.5, 1e-9);
}

// Independent noise in the two halves does not raise the visibility estimate on average.
TEST(DefectVisibility, NoiseInTheHalvesIsUnbiased) {
    const int w = 200, h = 200;
    std::vector<double> ya(size_t(w) * h), yb(ya.size());
    std::vector<uint8_t> part(ya.size(), 1), labels(ya.size(), 0);
    Pcg32 rng(99, 1);
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i) {
            const size_t p = size_t(j) * w + i;
            labels[p] = i < 100 ? 255 : 0;
            const double clean = (i < 100 ? 0.02 : 0.01) * (i + j);
            ya[p] = clean + 0.05 * (rng.nextDouble() - 0.5);
            yb[p] = clean + 0.05 * (rng.nextDouble() - 0.5);
        }
    auto v = defectVisibility(w, h, ya, yb, part, labels, {{255, "defect"}});
    EXPECT_NEAR(v[0].visibility, 2.0, 0.1);
}

TEST(LabelMask, RejectsAMaskOfTheWrongSizeAndReadsTheLegend) {
    test::TempDir dir("labels");
    std::vector<uint8_t> m(12 * 10, 0);
    m[5] = 255;
    m[17] = 128;
    writeMaskPng(dir / "t-truth.png", m, 12, 10);
    try {
        readLabelMask(dir / "t-truth.png", 16, 16);
        FAIL() << "a 12x10 mask was accepted for a 16x16 height map";
    } catch (const InputError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("t-truth.png"), std::string::npos) << msg;
        EXPECT_NE(msg.find("12x10"), std::string::npos) << msg;
        EXPECT_NE(msg.find("16x16"), std::string::npos) << msg;
    }
    LabelMask l = readLabelMask(dir / "t-truth.png", 12, 10);
    EXPECT_EQ(l.labels[5], 255);
    EXPECT_EQ(l.labels[17], 128);
    ASSERT_EQ(l.legend.size(), 2u);  // no legend file: every value present
    test::writeText(dir / "t-truth.json", R"({"labels": [{"value": 128, "name": "chatter"}]})");
    l = readLabelMask(dir / "t-truth.png", 12, 10);
    ASSERT_EQ(l.legend.size(), 1u);
    EXPECT_EQ(l.legend[0].name, "chatter");
    test::writeText(dir / "t-truth.json", R"({"labels": [{"value": 0, "name": "x"}]})");
    EXPECT_THROW(readLabelMask(dir / "t-truth.png", 12, 10), InputError);
}

TEST(Judge, ProjectsTruthAndRejectsAMismatchedOne) {
    auto scene = wavyScene(16);
    test::TempDir dir("judge-truth");
    std::vector<uint8_t> m(48 * 48, 255);
    writeMaskPng(dir / "ok.png", m, 48, 48);
    writeMaskPng(dir / "bad.png", std::vector<uint8_t>(40 * 48, 255), 40, 48);
    JudgeOptions o;
    o.spp = 4;
    o.truth = dir / "bad.png";
    EXPECT_THROW(Judge(*scene, o), InputError);
    o.truth = dir / "ok.png";
    Judge j(*scene, o);
    for (size_t p = 0; p < j.labels().size(); ++p)
        if (j.partMask()[p]) {
            EXPECT_EQ(j.labels()[p], 255);
        }
    // Labels keep their values; their nonzero pixels are the region the whole mask projects
    // to (the race takes its defects region from the judge's labels).
    for (size_t k = 0; k < m.size(); ++k) m[k] = (k % 48) < 20 ? 0 : (k % 48) < 30 ? 128 : 255;
    writeMaskPng(dir / "labels.png", m, 48, 48);
    o.truth = dir / "labels.png";
    Judge jl(*scene, o);
    const std::vector<uint8_t> region = projectRegion(*scene, RegionSpec{o.truth, {}, false});
    ASSERT_EQ(region.size(), jl.labels().size());
    int values[256] = {};
    for (size_t p = 0; p < region.size(); ++p) {
        EXPECT_EQ(region[p] != 0, jl.labels()[p] != 0) << p;
        ++values[jl.labels()[p]];
    }
    EXPECT_GT(values[0], 0);
    EXPECT_GT(values[128], 0);
    EXPECT_GT(values[255], 0);
}

TEST(Transport, HalvesKernelsEqualTheSeparateProducts) {
    auto scene = wavyScene(20);
    RenderOptions ro;
    ro.spp = 8;
    ro.maxDepth = 3;
    ro.sampleSets = 2;
    TransportMatrix t = precomputeTransport(*scene, ro, 1).matrix;
    ASSERT_EQ(t.planes, 2);
    const auto e = randomVec(t.cols(), 1);
    std::vector<double> ya(t.rows()), yb(t.rows()), a(t.rows()), b(t.rows());
    t.applyLuminanceHalves(e, ya, yb);
    t.applyLuminance(e, a, 0);
    t.applyLuminance(e, b, 1);
    for (size_t r = 0; r < t.rows(); ++r) {
        EXPECT_NEAR(ya[r], a[r], 1e-12 * (1 + std::abs(a[r])));
        EXPECT_NEAR(yb[r], b[r], 1e-12 * (1 + std::abs(b[r])));
    }
    const auto ga = randomVec(t.rows(), 2), gb = randomVec(t.rows(), 3);
    std::vector<double> out(t.cols()), sa(t.cols()), sb(t.cols());
    t.applyTransposeLuminanceHalves(ga, gb, out);
    t.applyTransposeLuminance(ga, sa, 0);
    t.applyTransposeLuminance(gb, sb, 1);
    for (size_t c = 0; c < t.cols(); ++c)
        EXPECT_NEAR(out[c], sa[c] + sb[c], 1e-10 * (1 + std::abs(sa[c] + sb[c])));
}

TEST(Search, CyclingLossUsesTheNextEstimateForEveryGradient) {
    auto scene = wavyScene(16);
    RenderOptions ro;
    ro.spp = 4;
    ro.maxDepth = 3;
    std::vector<TransportMatrix> ts;
    for (uint64_t s = 0; s < 3; ++s) {
        ro.seed = s;
        ts.push_back(precomputeTransport(*scene, ro, 1).matrix);
    }
    ImageObjective obj(16, 16, ts[0].objectMask, ObjectiveOptions{});
    std::vector<std::unique_ptr<TransportLoss>> losses;
    std::vector<const TransportLoss*> ptrs;
    for (const auto& t : ts) {
        losses.push_back(std::make_unique<TransportLoss>(t, obj, false));
        ptrs.push_back(losses.back().get());
    }
    CyclingLoss cyc(ptrs);
    const auto e = randomVec(1250, 4);
    std::vector<double> g(1250);
    for (int n = 0; n < 6; ++n) {
        const double v = cyc.evaluate(e, g).total;
        EXPECT_DOUBLE_EQ(v, losses[size_t(n % 3)]->evaluate(e, {}).total) << "evaluation " << n;
    }
    double mean = 0;
    for (const auto& l : losses) mean += l->evaluate(e, {}).total / 3.0;
    EXPECT_NEAR(cyc.evaluate(e, {}).total, mean, 1e-12 * mean);
}

TEST(Search, MultistartKeepsTheLowestTrainingLoss) {
    auto scene = wavyScene(16);
    RenderOptions ro;
    ro.spp = 4;
    ro.maxDepth = 3;
    TransportMatrix t = precomputeTransport(*scene, ro, 1).matrix;
    SearchInputs in;
    in.set = {&t};
    in.mask = t.objectMask;
    SearchOptions o;
    o.optimizer.method = OptimizerMethod::Adam;
    o.optimizer.iterations = 5;
    o.starts = {parseInitialState("const:0.5"), parseInitialState("random:1"),
                parseInitialState("const:0.2")};
    const SearchResult r = search(in, o);
    ASSERT_EQ(r.startLosses.size(), 3u);
    double best = 1e300;
    std::string bestName;
    for (const auto& [name, loss] : r.startLosses)
        if (loss < best) best = loss, bestName = name;
    EXPECT_EQ(r.start, bestName);
    EXPECT_DOUBLE_EQ(r.training.total, best);
    // Each start alone reproduces its entry.
    for (const auto& [name, loss] : r.startLosses) {
        SearchOptions one = o;
        one.starts = {parseInitialState(name)};
        EXPECT_DOUBLE_EQ(search(in, one).training.total, loss) << name;
    }
}

// The stall stop is optimize's default only where the loss is in −2·log units of a gain: the
// defects objective on the JND measure or on both measures, when the optimizer has no stall stop
// of its own; the ratio measure and the other objectives run to their budget.
TEST(Search, TheStallStopIsTheJndAndBothMeasuresOnly) {
    ObjectiveOptions jnd, ratio, both;
    jnd.defectMeasure = DefectMeasure::Jnd;
    ratio.defectMeasure = DefectMeasure::Ratio;
    both.defectMeasure = DefectMeasure::Both;
    const OptimizerOptions none;
    for (const ObjectiveOptions& o : {jnd, both}) {
        const OptimizerOptions s = withJndStall(none, ObjectiveKind::Defects, o);
        EXPECT_EQ(s.stallEvaluations, kJndStallEvaluations);
        EXPECT_EQ(s.stallTolerance, kJndStallTolerance);
        EXPECT_EQ(s.iterations, none.iterations);
    }
    EXPECT_EQ(withJndStall(none, ObjectiveKind::Defects, ratio).stallEvaluations, 0);
    EXPECT_EQ(withJndStall(none, ObjectiveKind::Unbiased, jnd).stallEvaluations, 0);
    EXPECT_EQ(withJndStall(none, ObjectiveKind::Paper, jnd).stallEvaluations, 0);
    OptimizerOptions own;
    own.stallEvaluations = 7;
    own.stallTolerance = 0.5;
    const OptimizerOptions kept = withJndStall(own, ObjectiveKind::Defects, jnd);
    EXPECT_EQ(kept.stallEvaluations, 7);
    EXPECT_EQ(kept.stallTolerance, 0.5);
}

// The stall stop belongs to the default budget (app/pipeline/Defaults.h resolveOptimizer), so
// every command that searches with it gets it: optimize and the viewer's "optimize from this
// light" alike. No budget given: the method's default budget and, on the JND measure, the stall
// stop; a given budget runs to its end; other objectives and the ratio measure run to their
// budget; the method that stands for a set-up resolves to the one that runs.
TEST(Defaults, TheDefaultBudgetCarriesTheJndStallStop) {
    ObjectiveOptions jnd, ratio;
    jnd.defectMeasure = DefectMeasure::Jnd;
    ratio.defectMeasure = DefectMeasure::Ratio;
    OptimizerOptions asked = optimizeJobOptimizerOptions();
    ASSERT_EQ(asked.iterations, 0);
    const OptimizerOptions d = resolveOptimizer(asked, ObjectiveKind::Defects, jnd);
    EXPECT_EQ(d.iterations, methodRow(asked.method).defaultBudget);
    EXPECT_EQ(d.method, resolveOptimizer(asked).method);
    EXPECT_EQ(d.stallEvaluations, kJndStallEvaluations);
    EXPECT_EQ(d.stallTolerance, kJndStallTolerance);
    EXPECT_EQ(resolveOptimizer(asked, ObjectiveKind::Defects, ratio).stallEvaluations, 0);
    EXPECT_EQ(resolveOptimizer(asked, ObjectiveKind::Unbiased, jnd).stallEvaluations, 0);
    OptimizerOptions given = asked;
    given.iterations = 50;
    const OptimizerOptions g = resolveOptimizer(given, ObjectiveKind::Defects, jnd);
    EXPECT_EQ(g.iterations, 50);
    EXPECT_EQ(g.stallEvaluations, 0);
    OptimizerOptions loop;
    loop.method = OptimizerMethod::PaperLoop;
    loop.iterations = 0;
    const OptimizerOptions l = resolveOptimizer(loop, ObjectiveKind::Defects, jnd);
    EXPECT_EQ(l.method, OptimizerMethod::Adam);
    EXPECT_EQ(l.iterations, methodRow(OptimizerMethod::PaperLoop).defaultBudget);
    EXPECT_EQ(l.stallEvaluations, kJndStallEvaluations);
}

TEST(Synth, ConfinedChatterIsLabelledOnItsSideOnly) {
    SurfaceSpec s;
    s.width = s.height = 64;
    s.pitch = 0.02;
    s.chatterStartFraction = 0.5;
    s.pocketEdge = false;
    s.scratchCount = 0;
    s.gougeCount = 0;
    const GeneratedSurface g = generateSurface(s);
    for (int j = 0; j < 64; ++j)
        for (int i = 0; i < 64; ++i)
            EXPECT_EQ(g.truth[size_t(j) * 64 + i], i >= 32 ? kTruthChatter : 0) << i << "," << j;
    s.chatterStartFraction = 1.5;
    EXPECT_THROW(generateSurface(s), InputError);
}

// `judge` from the command line: scores the lights given and the references, writes the report
// with each light's render outlined in its regions' colours; a light file that does not exist
// is refused before any work, and the previous results stay.
TEST(JudgeCommand, WritesTheReportWithOutlinedRegions) {
    test::TempDir dir("judge-cli");
    const std::string part = (dir.path() / "part.exr").string(),
                      scene = (dir.path() / "scene.json").string(),
                      truth = (dir.path() / "part-truth.png").string();
    ASSERT_EQ(test::runCli("gen-surface -o " + part +
                           " --width 128 --height 128 --scratches 2 --gouges 0 "
                           "--chatter-start 0.5 --scene " +
                           scene + " --image-size 48 --spp 4 --max-depth 3")
                  .exitCode,
              0);
    const std::filesystem::path out = dir.path() / "judged";
    auto r = test::runCli("judge " + scene + " --truth " + truth + " --spp 16 -o " + out.string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("contrast"), std::string::npos) << r.output;
    std::ifstream is(out / "report.html");
    std::stringstream html;
    html << is.rdbuf();
    for (const char* s : {"uniform-0.5", "studio", "visibility.defect", "contrast.chatter",
                          "defect red", "chatter blue"})
        EXPECT_NE(html.str().find(s), std::string::npos) << s;
    // The truth's scratch boundary is drawn in red on the render; the labels are projected the
    // same way the judge scores them.
    const Image img = readImage(out / "light-1.png");
    ASSERT_EQ(img.channels, 3);
    int red = 0;
    for (size_t p = 0; p < img.pixelCount(); ++p)
        red +=
            img.data[3 * p] > 0.99f && img.data[3 * p + 1] < 0.01f && img.data[3 * p + 2] < 0.01f;
    EXPECT_GT(red, 0);
    // A missing light: an error naming it, exit 1, the previous results untouched.
    r = test::runCli("judge " + scene + " " + (dir.path() / "nope.exr").string() + " -o " +
                     out.string());
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.output.find("nope.exr"), std::string::npos) << r.output;
    EXPECT_TRUE(std::filesystem::exists(out / "report.html"));
}

// judge --defects/--reference, as optimize takes them: the judge scores the region optimize
// --objective defects optimized (auto: the defect map), with the numbers optimize's held-out
// judge reported for the same estimate.
TEST(JudgeCommand, ScoresTheDefectRegionAsOptimizeDoes) {
    test::TempDir dir("judge-defects");
    const std::string part = (dir.path() / "part.exr").string(),
                      scene = (dir.path() / "scene.json").string(),
                      truth = (dir.path() / "part-truth.png").string();
    ASSERT_EQ(test::runCli("gen-surface -o " + part +
                           " --width 160 --height 160 --scratches 3 --chatter-start 0.5 --scene " +
                           scene + " --image-size 40 --spp 8 --max-depth 3")
                  .exitCode,
              0);
    const auto opt = dir.path() / "opt";
    auto r =
        test::runCli("optimize " + scene +
                     " --objective defects --iterations 20 --heldout-spp 16 -o " + opt.string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const auto summary = nlohmann::json::parse(test::readFile(opt / "summary.json"));
    ASSERT_EQ(summary.value("defects", ""), "auto") << summary.dump(1);
    const auto& optimized = summary.at("judge").at("visibility");
    // The report's caption names each region's outline colour (app/report/Preview.h outlineOf).
    EXPECT_NE(test::readFile(opt / "report.html").find("Outlines: defect region auto (lines red"),
              std::string::npos);

    const auto out = dir.path() / "judged";
    r = test::runCli("judge " + scene + " " + opt.string() +
                     " --defects auto --spp 16 --no-references -o " + out.string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const auto judged = nlohmann::json::parse(test::readFile(out / "judge.json"));
    EXPECT_EQ(judged.value("defects", ""), "auto");
    // auto's marks by shape (detect/MarkShapes.h): the scratches are lines
    const auto& regions = judged.at("lights").at(0).at("visibility");
    ASSERT_EQ(regions.size(), optimized.size());
    EXPECT_EQ(regions.at(0).value("name", ""), "lines");
    for (size_t k = 0; k < regions.size(); ++k) {
        const auto &v = regions.at(k), &o = optimized.at(k);
        EXPECT_TRUE(v.value("name", "") == "lines" || v.value("name", "") == "spots") << v;
        EXPECT_EQ(v.value("name", ""), o.value("name", "?"));
        EXPECT_EQ(v.value("pixels", 0), o.value("pixels", -1));
        EXPECT_NEAR(v.value("visibility", 0.0), o.value("visibility", -1.0),
                    1e-6 * std::abs(o.value("visibility", 1.0)));  // E* saved as float32
    }

    // A labelled region and a reference; a reference alone is refused, naming --defects.
    r = test::runCli("judge " + scene + " --truth " + truth + " --defects " + truth +
                     ":defect --reference " + truth + ":none --spp 16 -o " +
                     (dir.path() / "j2").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(test::readFile(dir.path() / "j2" / "judge.json")
                  .find("\"reference\": \"" + truth + ":none\""),
              std::string::npos);
    r = test::runCli("judge " + scene + " --reference " + truth + ":none --spp 16 -o " +
                     (dir.path() / "j3").string());
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("--defects"), std::string::npos) << r.output;
}
