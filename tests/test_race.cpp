// `bench race` (app/Race.h) on one part and seed with two configurations: the paper-loop
// baseline and optimize's defaults with the defects named. Every row is judged; ratios are to
// the baseline in the same run; the defects objective sees the part's truth as its defects.
#include <gtest/gtest.h>

#include <cmath>

#include "TestUtil.h"
#include "app/Race.h"

namespace {

using namespace sl;

TEST(Race, JudgesEveryConfigurationAgainstTheBaselineIncludingTheDefectsDefault) {
    test::TempDir dir("race");
    RaceOptions o;
    o.parts = {"facemill-scratches"};
    o.seeds = 1;
    o.judgeSpp = 64;
    o.workDir = dir.path();
    std::vector<RaceConfig> configs;
    for (RaceConfig& c : defaultRaceConfigs())
        if (c.name == "paper-loop" || c.name == "default-defects") configs.push_back(c);
    ASSERT_EQ(configs.size(), 2u);
    ASSERT_EQ(configs.front().name, "paper-loop");  // the baseline comes first
    configs.front().search.optimizer.iterations = 10;
    o.configs = configs;
    const RaceSummary s = runRace(o);
    ASSERT_EQ(s.rows.size(), 2u);
    const RaceRow& base = s.rows[0];
    const RaceRow& def = s.rows[1];
    EXPECT_EQ(def.config, "default-defects");
    EXPECT_DOUBLE_EQ(base.ratioU, 1.0);
    EXPECT_DOUBLE_EQ(base.ratioSeconds, 1.0);
    EXPECT_NEAR(def.ratioU, def.unbiased / base.unbiased, 1e-12);
    EXPECT_TRUE(std::isfinite(def.visDefect));
    EXPECT_TRUE(std::isnan(def.heldOwn));  // the defects objective is read from visibility
    EXPECT_TRUE(std::isfinite(base.heldOwn));
    // Told where the defects are, the defects objective shows them better than eq. 2's light.
    EXPECT_GT(def.visDefect, base.visDefect) << def.visDefect << " vs " << base.visDefect;
    EXPECT_EQ(s.overall.size(), 2u);
}

}  // namespace

namespace {

using namespace sl;

// `bench settings`: the trace settings raced the same way, the part's own setting first.
TEST(Race, SettingsRaceEachTraceSettingAgainstThePartsOwn) {
    const auto configs =
        settingsRaceConfigs({4, 16}, {Sampling::Bsdf, Sampling::Stratified}, {2, 3});
    ASSERT_EQ(configs.size(), 8u);  // 2 × 2 × 2, the baseline among them
    EXPECT_EQ(configs.front().name, "spp16-stratified-d3");
    EXPECT_EQ(configs[1].name, "spp4-bsdf-d2");
    EXPECT_EQ(configs[1].spp, 4);
    EXPECT_EQ(configs[1].sampling, Sampling::Bsdf);
    EXPECT_EQ(configs[1].maxDepth, 2);
    for (size_t i = 1; i < configs.size(); ++i) EXPECT_NE(configs[i].name, configs[0].name);

    test::TempDir dir("settings");
    RaceOptions o;
    o.parts = {"pocket"};
    o.seeds = 1;
    o.judgeSpp = 32;
    o.judgeMaxDepth = 4;
    o.workDir = dir.path();
    o.configs = {configs[0], configs[1]};
    for (RaceConfig& c : o.configs) c.search.optimizer.iterations = 10;
    const RaceSummary s = runRace(o);
    ASSERT_EQ(s.rows.size(), 2u);
    EXPECT_DOUBLE_EQ(s.rows[0].ratioU, 1.0);
    EXPECT_TRUE(std::isfinite(s.rows[1].unbiased));
    // Another T (a quarter of the samples, one bounce fewer, another sampler): another E*.
    EXPECT_NE(s.rows[1].unbiased, s.rows[0].unbiased);
}

}  // namespace
