// scripts/eval-real's diagnostics: its port of the selfsim residual (detect/SelfSimMap.h steps
// 1-4) and the rule that says which inserted defects lie above the texture's own residual (the
// "recall on the detectable truth" column), checked by the script's --self-test on identities:
// a pit on a flat map is its own residual, the residual scales with the heights, a defect
// below the texture's p99 |r| around it is not counted detectable.
#include <gtest/gtest.h>

#include <filesystem>

#include "app/host/Plot.h"

namespace sl {

TEST(EvalReal, SelfTestOfTheResidualPortAndTheDetectableTruth) {
    const std::filesystem::path script = SL_SOURCE_DIR "/scripts/eval-real";
    ASSERT_TRUE(std::filesystem::exists(script));
    if (!std::filesystem::exists("/usr/bin/python3")) GTEST_SKIP() << "no /usr/bin/python3";
    EXPECT_EQ(runProcess({"/usr/bin/python3", script.string(), "--self-test"}), 0);
}

}  // namespace sl
