// app/pipeline/Defaults.h: the decisions optimize, lamps and the viewer share, written once.
#include <gtest/gtest.h>

#include <cstring>

#include "TestUtil.h"
#include "app/bench/Race.h"
#include "app/jobs/OptimizeOptions.h"
#include "app/pipeline/Defaults.h"
#include "core/Registry.h"
#include "io/TransportFile.h"
#include "optimize/PaperSetup.h"

namespace sl {
namespace {

TEST(Defaults, ObjectiveIsDefectsWhenNamedUnbiasedOtherwiseEq2WithoutHalves) {
    const OptimizeDefaults d = optimizeDefaults();
    // A scene (T still to be traced, with the halves the objective asks for) and a T with halves.
    for (const std::optional<int> planes : {std::optional<int>{}, std::optional<int>{2}}) {
        EXPECT_EQ(defaultObjective(false, planes), d.objective);
        EXPECT_EQ(defaultObjective(true, planes), d.objectiveWithDefects);
    }
    EXPECT_EQ(d.objective, ObjectiveKind::Unbiased);
    EXPECT_EQ(d.objectiveWithDefects, ObjectiveKind::Defects);
    // A T without halves can only take eq. 2, named defects or not.
    EXPECT_EQ(defaultObjective(false, 1), ObjectiveKind::Paper);
    EXPECT_EQ(defaultObjective(true, 1), ObjectiveKind::Paper);
}

TEST(Defaults, AnOptimizerRowResolvesIntoTheMethodThatRunsAndItsBudget) {
    const OptimizerOptions start = optimizeJobOptimizerOptions();
    EXPECT_EQ(start.method, optimizeDefaults().method);
    EXPECT_EQ(start.iterations, 0);
    for (const OptimizerMethodRow& row : optimizerMethodTable()) {
        OptimizerOptions o = start;
        o.method = row.value;
        o.learningRate = 0.125;  // everything but method and budget passes through
        const OptimizerOptions byDefault = resolveOptimizer(o);
        EXPECT_EQ(byDefault.method, row.runs) << row.name;
        EXPECT_EQ(byDefault.iterations, row.defaultBudget) << row.name;
        EXPECT_EQ(byDefault.learningRate, 0.125) << row.name;
        o.iterations = 7;
        EXPECT_EQ(resolveOptimizer(o).iterations, 7) << row.name;
    }
    OptimizerOptions paperLoop = start;
    paperLoop.method = OptimizerMethod::PaperLoop;
    EXPECT_EQ(resolveOptimizer(paperLoop).method, OptimizerMethod::Adam);
}

TEST(Defaults, ATmIsReadAsItIsAndASceneIsLoadedWithItsOverridesAndTraced) {
    test::TempDir dir("defaults-input");
    ASSERT_EQ(test::writeSmallLabelledPart(dir.path()), 0);
    PrecomputeOptions trace;
    trace.spp = 2;
    trace.sampleSets = 2;
    const InputTransport traced = transportOfInput(
        dir / "scene.json", {"camera.width=24", "camera.height=16"}, trace, /*cacheDir=*/{});
    ASSERT_TRUE(traced.scene);
    EXPECT_EQ(traced.scene->camera.width(), 24);
    const TransportMatrix& t = traced.transport.file.matrix;
    EXPECT_EQ(t.width, 24);
    EXPECT_EQ(t.height, 16);
    EXPECT_EQ(t.planes, 2);
    EXPECT_GT(t.nnz(), 0u);

    writeTransportFile(dir / "t.tm", t, traced.transport.file.provenance);
    const InputTransport read = transportOfInput(dir / "t.tm", {}, trace, {});
    EXPECT_FALSE(read.scene);
    EXPECT_EQ(read.transport.path, dir / "t.tm");
    EXPECT_EQ(read.transport.file.matrix.values, t.values);
    EXPECT_EQ(read.transport.file.matrix.planes, 2);
}

// optimize/PaperSetup.h: the paper's set-up written once; `--preset paper`, the paper-loop
// optimizer (and the race's baseline) and the paper's comparison light (through the preset)
// take it from there and differ only in the estimates of T they cycle over.
TEST(Defaults, ThePaperSetupIsOneAndEachUseDerivesFromIt) {
    const PaperSetup& p = kPaperSetup;
    EXPECT_EQ(paperSetupText(), "eq. 2, lambda 30 on mean(E^2), Adam lr 0.02 x 100 from E0 = 0.5");
    // The preset: the set-up with a fresh estimate every step.
    OptimizeJobOptions o;
    applyOptimizePreset(OptimizePreset::Paper, o);
    EXPECT_EQ(o.optimizer.method, OptimizerMethod::PaperLoop);
    EXPECT_EQ(o.optimizer.iterations, p.steps);
    EXPECT_EQ(o.optimizer.learningRate, p.learningRate);
    EXPECT_EQ(o.lambdas, std::vector<double>{p.lambda});
    EXPECT_EQ(o.objective.reg, p.reg);
    ASSERT_EQ(o.starts.size(), 1u);
    EXPECT_EQ(o.starts[0].spec, p.startSpec);
    EXPECT_EQ(o.starts[0].value, p.start);
    ASSERT_TRUE(o.objectiveKind.has_value());
    EXPECT_EQ(*o.objectiveKind, p.objective);
    EXPECT_EQ(o.estimates, kPaperExperimentEstimates);
    EXPECT_EQ(kPaperExperimentEstimates, p.steps);
    EXPECT_NE(std::string(registryRow(optimizePresetTable(), OptimizePreset::Paper).help)
                  .find(paperSetupText()),
              std::string::npos);
    // paper-loop: the same steps by Adam, cycled over kPaperLoopEstimates estimates.
    const OptimizerMethodRow& loop = methodRow(OptimizerMethod::PaperLoop);
    EXPECT_EQ(loop.defaultBudget, p.steps);
    EXPECT_EQ(loop.runs, OptimizerMethod::Adam);
    EXPECT_EQ(loop.defaultEstimates, kPaperLoopEstimates);
    EXPECT_EQ(methodRow(OptimizerMethod::Adam).defaultBudget, p.steps);
    EXPECT_EQ(OptimizerOptions{}.learningRate, p.learningRate);
    // The race's baseline is paper-loop on the paper's objective from its start.
    const RaceConfig base = defaultRaceConfigs().front();
    EXPECT_EQ(base.name, loop.name);
    EXPECT_EQ(base.search.objective, p.objective);
    EXPECT_EQ(base.search.estimates, kPaperLoopEstimates);
    ASSERT_EQ(base.search.starts.size(), 1u);
    EXPECT_EQ(base.search.starts[0].spec, p.startSpec);
    // The objective's default λ and optimize's are the paper's.
    EXPECT_EQ(ObjectiveOptions{}.lambda, p.lambda);
    EXPECT_EQ(optimizeDefaults().lambda, p.lambda);
}

}  // namespace
}  // namespace sl
