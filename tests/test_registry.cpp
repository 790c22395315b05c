// The typed registries (core/Registry.h): every table names each value once, parses back to
// it, and says what the code that consumes it needs; optimize's job resolves its defaults and
// set-ups from them.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>

#include "TestUtil.h"
#include "app/host/ExternalRenderer.h"
#include "app/jobs/OptimizeJob.h"
#include "app/pipeline/HeldOut.h"
#include "app/pipeline/InitialState.h"
#include "app/pipeline/LossMask.h"
#include "core/Error.h"
#include "core/Registry.h"
#include "detect/DefectMap.h"
#include "io/TransportFile.h"
#include "objective/ObjectiveKind.h"
#include "optimize/Methods.h"
#include "scene/RenderDesc.h"
#include "scene/Scene.h"
#include "transport/TransportSink.h"

using namespace sl;

namespace {

/// Names unique and non-empty, help present, each name parses to its own row.
template <class Row>
void expectWellFormed(std::span<const Row> table) {
    std::set<std::string> names;
    std::set<int> values;
    for (const Row& r : table) {
        EXPECT_TRUE(names.insert(r.name).second) << "duplicate name " << r.name;
        EXPECT_TRUE(values.insert(static_cast<int>(r.value)).second) << r.name;
        EXPECT_GT(std::string(r.help).size(), 5u) << r.name;
        EXPECT_EQ(&parseRegistryName(table, r.name, "test"), &r);
        EXPECT_EQ(&registryRow(table, r.value), &r);
    }
    // Values are dense from 0: every enum value up to the last has a row.
    EXPECT_EQ(static_cast<int>(values.size()), *values.rbegin() + 1);
    try {
        parseRegistryName(table, "no-such-name", "option 'x'");
        ADD_FAILURE() << "an unknown name was accepted";
    } catch (const InputError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("option 'x'"), std::string::npos) << msg;
        for (const Row& r : table) EXPECT_NE(msg.find(r.name), std::string::npos) << msg;
    }
}

}  // namespace

TEST(Registry, EveryTableIsWellFormed) {
    expectWellFormed(optimizerMethodTable());
    expectWellFormed(objectiveKindTable());
    expectWellFormed(initialKindTable());
    expectWellFormed(heldOutModeTable());
    expectWellFormed(lossMaskKindTable());
    expectWellFormed(optimizePresetTable());
    expectWellFormed(defectMethodTable());
    expectWellFormed(samplingTable());
    expectWellFormed(rendererKindTable());
}

TEST(Registry, OptimizerMethodsSayWhoRunsThemAndTheirBudget) {
    for (const OptimizerMethodRow& r : optimizerMethodTable()) {
        SCOPED_TRACE(r.name);
        EXPECT_GT(r.defaultBudget, 0);
        EXPECT_GE(r.defaultEstimates, 1);
        // The method that does the work is one minimize() or minimizeBlackBox() runs itself.
        const OptimizerMethodRow& runs = methodRow(r.runs);
        EXPECT_EQ(runs.runs, runs.value);
        EXPECT_EQ(runs.gradient, r.gradient);
    }
    // The lists the entry points accept are the table's rows, split by gradient source.
    const auto exact = optimizerMethods(), box = blackBoxMethods();
    EXPECT_EQ(exact.size() + box.size() + 1, optimizerMethodTable().size());  // + paper-loop
    for (const std::string& m : box)
        EXPECT_EQ(methodRow(parseOptimizerMethod(m)).gradient, GradientSource::Renderer);
}

TEST(Registry, InitialStatesParseOnceWithTheirArguments) {
    const InitialState c = parseInitialState("const:0.25");
    EXPECT_EQ(c.kind, InitialKind::Constant);
    EXPECT_EQ(c.value, 0.25);
    EXPECT_EQ(c.spec, "const:0.25");
    EXPECT_EQ(parseInitialState("random:7").seed, 7u);
    EXPECT_EQ(parseInitialState("envmap:a b.exr").file, std::filesystem::path("a b.exr"));
    // A bare path (a '.' or '/' in it) is envmap:FILE; a bare word is still an unknown kind.
    EXPECT_EQ(parseInitialState("lamps/booth.exr").kind, InitialKind::EnvMapFile);
    EXPECT_EQ(parseInitialState("lamps/booth.exr").spec, "envmap:lamps/booth.exr");
    EXPECT_THROW(parseInitialState("specullar"), InputError);
    EXPECT_EQ(parseInitialState("specular").kind, InitialKind::Specular);
    for (const char* bad : {"const:2", "const:x", "const", "random:-1", "random:1.5",
                            "envmap:", "studio:1", "sunny", ""})
        EXPECT_THROW(parseInitialState(bad, "option 'init'"), InputError) << bad;
    const std::vector<double> e = initialEnvMap(parseInitialState("const:0.25"), 4, 2, true);
    EXPECT_EQ(e, std::vector<double>(24, 0.25));
    EXPECT_EQ(initialSpecForms(), "FILE | const:V | envmap:FILE | random:SEED | studio | specular");
}

TEST(Registry, HeldOutAndMaskChoices) {
    EXPECT_EQ(parseHeldOutSource("judge", "h").mode, HeldOutMode::Judge);
    EXPECT_EQ(parseHeldOutSource("none", "h").mode, HeldOutMode::None);
    const HeldOutSource f = parseHeldOutSource("dir/held.tm", "h");
    EXPECT_EQ(f.mode, HeldOutMode::File);
    EXPECT_EQ(f.file, std::filesystem::path("dir/held.tm"));
    EXPECT_THROW(parseHeldOutSource("held.exr", "h"), InputError);
    EXPECT_EQ(parseLossMask("object").kind, LossMaskKind::Object);
    EXPECT_EQ(parseLossMask("scratch").kind, LossMaskKind::Scratch);
    EXPECT_EQ(parseLossMask("m.png").kind, LossMaskKind::File);
    EXPECT_EQ(parseLossMask("m.png").name(), "m.png");
    EXPECT_EQ(parseLossMask("FILE").kind, LossMaskKind::File);  // the row's label is no name
}

// optimize's job on a small .tm, without a held-out estimate: the defaults come from the
// tables (L-BFGS and its budget; the paper objective for a T without halves), a method that
// stands for a set-up (paper-loop) refuses what it cannot do with a .tm, and a sweep writes one
// row per λ.
TEST(OptimizeJob, ResolvesItsDefaultsFromTheRegistries) {
    test::TempDir dir("optimize-job");
    SceneDesc d;
    d.heightmap.pitch = 0.05;
    d.camera.width = d.camera.height = 12;
    d.render.maxDepth = 3;
    const int n = 24;
    const Scene scene(d, n, n, test::bumpyHeightMap(n));
    RenderOptions ro;
    ro.spp = 2;
    ro.maxDepth = 3;
    const TransportMatrix t = precomputeTransport(scene, ro, 1).matrix;
    const auto tm = dir.path() / "g.tm";
    writeTransportFile(tm, t, transportProvenance(scene, ro, 1));

    OptimizeJobOptions o;
    o.input = tm;
    o.outDir = dir.path() / "out";
    o.heldOut.mode = HeldOutMode::None;
    o.starts = {parseInitialState("const:0.5")};
    o.lambdas = {10.0, 30.0};
    const OptimizeJobSummary s = runOptimizeJob(o);
    ASSERT_EQ(s.runs.size(), 2u);
    for (const OptimizeRun& r : s.runs) {
        EXPECT_EQ(r.optimizer.method, methodName(optimizeDefaults().method));
        EXPECT_LE(r.optimizer.evaluations, methodRow(optimizeDefaults().method).defaultBudget + 1);
        EXPECT_LE(r.final.total, r.initial.total);
        EXPECT_FALSE(r.heldFinal.has_value());
        const auto summary = nlohmann::json::parse(test::readFile(r.dir / "summary.json"));
        EXPECT_EQ(summary["objective"], "paper");
        EXPECT_EQ(summary["mask"], "object");
        EXPECT_EQ(summary["init"], "const:0.5");
    }
    const std::string sweep = test::readFile(o.outDir / "sweep.csv");
    EXPECT_EQ(std::count(sweep.begin(), sweep.end(), '\n'), 3);

    OptimizeJobOptions loop = o;
    loop.optimizer.method = OptimizerMethod::PaperLoop;
    try {
        runOptimizeJob(loop);
        ADD_FAILURE() << "paper-loop ran on a .tm";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find(option("estimates")), std::string::npos) << e.what();
    }
    OptimizeJobOptions box = o;
    box.optimizer.method = OptimizerMethod::Spsa;
    EXPECT_THROW(runOptimizeJob(box), InputError);  // renders: needs the scene file
}
