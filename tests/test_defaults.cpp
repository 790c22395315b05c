// app/pipeline/Defaults.h: the decisions optimize, lamps and the viewer share, written once.
#include <gtest/gtest.h>

#include "TestUtil.h"
#include "app/pipeline/Defaults.h"
#include "io/TransportFile.h"

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

}  // namespace
}  // namespace sl
