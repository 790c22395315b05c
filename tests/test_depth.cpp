// `bench depth` (app/bench/DepthBench.h): the rule that picks max_depth from the energy per bounce,
// and the measurement it runs on (a sample's path is the same whatever the path length, so the
// energy grows with max_depth and max_depth 1 shows nothing).
#include <gtest/gtest.h>

#include <filesystem>

#include "TestUtil.h"
#include "app/bench/DepthBench.h"
#include "core/Error.h"
#include "scene/Scene.h"

using namespace sl;

TEST(DepthBench, ChoosesTheFirstDepthWhoseNextBounceAddsLessThanTheThreshold) {
    // energy[d] at max_depth d: bounce 2 adds 4.8 %, bounce 3 0.038 %.
    const std::vector<double> e{0, 0, 1.0, 1.05, 1.0504, 1.0504};
    const DepthChoice c = chooseMaxDepth(e, 0.001);
    EXPECT_EQ(c.maxDepth, 3);
    EXPECT_NE(c.reason.find("0.0381 %"), std::string::npos) << c.reason;
    EXPECT_EQ(chooseMaxDepth(e, 0.0001).maxDepth, 4);  // bounce 4 adds exactly 0
    // Nothing qualifies: the longest measured, and the reason says so.
    const DepthChoice none = chooseMaxDepth({0, 0, 1.0, 1.1, 1.2}, 0.001);
    EXPECT_EQ(none.maxDepth, 4);
    EXPECT_NE(none.reason.find("every measured bounce"), std::string::npos);
}

TEST(DepthBench, EnergyGrowsWithThePathLengthOnTheBundledPart) {
    DepthBenchOptions o;
    o.resolution = 16;
    o.spp = 4;
    o.maxDepth = 5;
    const DepthBenchResult r = runDepthBench(o);
    ASSERT_EQ(r.rows.size(), 5u);
    EXPECT_EQ(r.rows[0].energy, 0.0);  // max_depth 1: the camera sees no light
    EXPECT_GT(r.rows[1].energy, 0.0);
    for (size_t i = 1; i < r.rows.size(); ++i) EXPECT_GE(r.rows[i].energy, r.rows[i - 1].energy);
    EXPECT_GE(r.choice.maxDepth, 2);
    EXPECT_LE(r.choice.maxDepth, 5);
    EXPECT_FALSE(r.choice.reason.empty());
    o.threshold = 0;
    EXPECT_THROW(runDepthBench(o), InputError);
    o.threshold = 0.001;
    o.maxDepth = 2;
    EXPECT_THROW(runDepthBench(o), InputError);
}

TEST(DepthBench, AutoDepthOfAFlatMirrorIsOneReflection) {
    // A flat smooth mirror: no path meets the surface twice, so bounce 2 adds exactly nothing.
    SceneDesc d;
    d.heightmap.pitch = 0.05;
    d.material.params.smooth = true;
    d.camera.width = d.camera.height = 16;
    const Scene s(d, 32, 32, std::vector<float>(32 * 32, 0.0f));
    const DepthChoice c = autoMaxDepth(s, AutoDepthOptions{.spp = 2, .limit = 8});
    EXPECT_EQ(c.maxDepth, 2) << c.reason;
    EXPECT_NE(c.reason.find("would add 0 %"), std::string::npos) << c.reason;
}

TEST(DepthBench, RenderPrintsTheChosenDepthAndItsReason) {
    const auto dir = std::filesystem::temp_directory_path() / "sl_test_auto_depth";
    std::filesystem::create_directories(dir);
    const std::string scene = std::string(SL_SOURCE_DIR) + "/scenes/default/scene.json";
    const auto r = test::runCli("render " + scene + " --size 16 --spp 2 --auto-depth -o " +
                                (dir / "r.exr").string());
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("max_depth "), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("of the image"), std::string::npos) << r.output;
    const auto both = test::runCli("render " + scene + " --size 16 --spp 2 --auto-depth " +
                                   "--max-depth 3 -o " + (dir / "r.exr").string());
    EXPECT_EQ(both.exitCode, 2) << both.output;
    std::filesystem::remove_all(dir);
}
