// The eight equirectangular HDR photos Debian's blender-data ships (scripts/install-deps --hdris:
// /usr/share/blender/datafiles/studiolights/world/*.exr): each carries resampling ringing (3 to
// ~5 000 slightly negative pixels against maxima of 55–34 000), which every light-reading path
// clamps with one warning line (io/EnvMapIO.h kEnvNegativeTolerance). Each is read on the env-map
// grid, rendered and judged through the CLI, once per file; a file that is not installed is
// skipped by name. The synthetic case of the rule is tests/test_io.cpp
// EnvMapIO.TinyNegativeTexelsAreClampedWithOneWarningLargeOnesRefused.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>

#include "TestUtil.h"
#include "io/EnvMapIO.h"
#include "scene/EnvMap.h"

namespace sl {
namespace {

namespace fs = std::filesystem;

const fs::path kBlenderWorlds = "/usr/share/blender/datafiles/studiolights/world";

size_t occurrences(const std::string& text, const std::string& what) {
    size_t n = 0;
    for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
    return n;
}

class BlenderHdri : public ::testing::TestWithParam<const char*> {};

TEST_P(BlenderHdri, RendersAndIsJudgedWithOneWarning) {
    const fs::path file = kBlenderWorlds / (std::string(GetParam()) + ".exr");
    if (!fs::exists(file))
        GTEST_SKIP() << file << " is absent: blender-data is not installed "
                     << "(scripts/install-deps --hdris)";
    // On the grid, in colour: clamped, so no texel is negative, and the map is not black.
    const EnvMap env = loadEnvMap(file, 50, 25, 3);
    EXPECT_GE(*std::min_element(env.texels.begin(), env.texels.end()), 0.0f);
    EXPECT_GT(*std::max_element(env.texels.begin(), env.texels.end()), 0.0f);

    test::TempDir dir("hdri");
    ASSERT_EQ(test::writeSmallLabelledPart(dir.path()), 0);
    const std::string scene = (dir / "scene.json").string();
    const test::RunResult render =
        test::runCli("render " + scene + " --size 24 --envmap " + file.string() + " -o " +
                     (dir / "look.exr").string() + " 2>&1");
    ASSERT_EQ(render.exitCode, 0) << render.output;
    EXPECT_TRUE(fs::exists(dir / "look.exr")) << render.output;
    EXPECT_EQ(occurrences(render.output, "warning: " + file.string() + ": "), 1u) << render.output;
    EXPECT_EQ(occurrences(render.output, "clamped to 0"), 1u) << render.output;

    // The judge reads it as a light to score (as optimize --compare does).
    const test::RunResult judge =
        test::runCli("judge " + scene + " --size 24 --spp 8 " + file.string() + " --cache " +
                     (dir / "cache").string() + " -o " + (dir / "judge").string() + " 2>&1");
    ASSERT_EQ(judge.exitCode, 0) << judge.output;
    EXPECT_EQ(occurrences(judge.output, "clamped to 0"), 1u) << judge.output;
    EXPECT_NE(judge.output.find(std::string(GetParam()) + " "), std::string::npos)
        << judge.output;  // its row in the judge's table
}

INSTANTIATE_TEST_SUITE_P(RealHdris, BlenderHdri,
                         ::testing::Values("city", "courtyard", "forest", "interior", "night",
                                           "studio", "sunrise", "sunset"),
                         [](const ::testing::TestParamInfo<const char*>& p) {
                             return std::string(p.param);
                         });

}  // namespace
}  // namespace sl
