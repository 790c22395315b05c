// `bench race` (app/bench/Race.h) on one part and seed with two configurations: the paper-loop
// baseline and optimize's defaults with the defects named. Every row is judged; ratios are to
// the baseline in the same run; the defects objective sees the part's truth as its defects.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>

#include "TestUtil.h"
#include "app/bench/Race.h"
#include "app/jobs/PartFiles.h"
#include "core/Error.h"
#include "core/Stats.h"
#include "synth/SurfaceGenerator.h"

namespace {

/// One seed of facemill-scratches at `size`², a 32-spp judge, one thread, paper-loop (the
/// baseline) and the configuration `config`.
sl::RaceOptions tinyRace(const std::filesystem::path& workDir, int size,
                         const std::string& config) {
    sl::RaceOptions o;
    o.parts = {"facemill-scratches"};
    o.sizes = {size};
    o.seeds = 1;
    o.judgeSpp = 32;
    o.threads = 1;
    o.workDir = workDir;
    o.configs.clear();
    for (sl::RaceConfig& c : sl::defaultRaceConfigs())
        if (c.name == "paper-loop" || c.name == config) o.configs.push_back(c);
    return o;
}

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

namespace {

using namespace sl;

RaceRow partRow(const std::string& part, const std::string& config, double vsLamp, double vsPaper,
                double figure = 1.0) {
    RaceRow r;
    r.part = part;
    r.config = config;
    r.seed = -1;
    r.figure = figure;
    r.vsLamp = vsLamp;
    r.vsPaper = vsPaper;
    return r;
}

// The standings: median and worst (min) over parts; the winner is the best worst part, not the
// best median; a config without a figure of its own counts 0 there, a reference without one
// leaves the part out of that ratio.
TEST(Race, StandingsNameTheWinnerByItsWorstPart) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const std::vector<RaceRow> medians{
        partRow("p1", "sharp", 9.0, 3.0),     partRow("p2", "sharp", 5.0, 2.0),
        partRow("p3", "sharp", 0.8, 0.5),     partRow("p1", "steady", 2.0, 1.0),
        partRow("p2", "steady", 1.5, nan),    partRow("p3", "steady", 1.2, 1.4),
        partRow("p1", "failing", 3.0, 3.0),   partRow("p2", "failing", nan, nan, nan),
        partRow("p3", "failing", 4.0, 4.0),   partRow("p1", kLampConfig, 1.0, 0.5),
        partRow("p2", kLampConfig, 1.0, 0.6), partRow("p3", kLampConfig, 1.0, 0.7)};
    const auto st = raceStandings(medians, {"sharp", "steady", "failing", kLampConfig});
    ASSERT_EQ(st.size(), 4u);
    EXPECT_EQ(st[0].parts, 3);
    EXPECT_DOUBLE_EQ(st[0].medianVsLamp, 5.0);
    EXPECT_DOUBLE_EQ(st[0].worstVsLamp, 0.8);
    EXPECT_EQ(st[0].worstLampPart, "p3");
    EXPECT_DOUBLE_EQ(st[0].worstVsPaper, 0.5);
    EXPECT_DOUBLE_EQ(st[1].worstVsLamp, 1.2);
    EXPECT_DOUBLE_EQ(st[1].medianVsPaper, 1.2);  // p2 has no paper-loop figure: left out
    EXPECT_EQ(st[1].failed, 0);
    EXPECT_EQ(st[2].failed, 1);
    EXPECT_DOUBLE_EQ(st[2].worstVsLamp, 0.0);  // no light on p2
    EXPECT_EQ(st[2].worstLampPart, "p2");
    EXPECT_DOUBLE_EQ(st[3].medianVsLamp, 1.0);
    // "sharp" has the best median (5.0), "steady" the best worst part (1.2): steady wins.
    EXPECT_EQ(raceWinner(st), "steady");
    EXPECT_NE(formatRaceStandings(st).find("steady"), std::string::npos);
}

// Where every configuration has JND (the judge's first figure) the winner is the best worst
// part in JND over the lamp's, even when the visibility ratio ranks them the other way; one
// configuration without JND sends the rule back to the ratio for all.
TEST(Race, TheWinnerIsChosenInJndWhereEveryConfigurationHasIt) {
    auto row = [](const char* part, const char* config, double vsLamp, double jndVsLamp) {
        RaceRow r = partRow(part, config, vsLamp, 1.0);
        r.jndVsLamp = jndVsLamp;
        return r;
    };
    std::vector<RaceRow> medians{
        row("p1", "ratio-ish", 3.0, 0.7), row("p2", "ratio-ish", 2.0, 1.1),
        row("p1", "eye", 1.1, 2.0),       row("p2", "eye", 0.9, 1.6),
        row("p1", kLampConfig, 1.0, 1.0), row("p2", kLampConfig, 1.0, 1.0)};
    auto st = raceStandings(medians, {"ratio-ish", "eye", kLampConfig});
    EXPECT_DOUBLE_EQ(st[1].worstJndVsLamp, 1.6);
    EXPECT_EQ(raceWinner(st), "eye");
    for (RaceRow& r : medians)
        if (r.config == std::string("eye")) r.jndVsLamp = std::numeric_limits<double>::quiet_NaN();
    st = raceStandings(medians, {"ratio-ish", "eye", kLampConfig});
    EXPECT_EQ(raceWinner(st), "ratio-ish");
}

// A tiny wide world: a generated part and a "real" texture (an X3P written here, defects
// inserted as insert-defects does) at 32², two configurations; the lamp's reference row on
// every part, the standings' median/worst are the median/min of the per-part rows.
TEST(Race, TinyWideWorldHasLampRowsAndWorstCaseStandings) {
    test::TempDir dir("wide-race");
    SurfaceSpec tex;
    tex.width = tex.height = 160;
    tex.pitch = 0.02;
    tex.pocketEdge = false;
    tex.scratchCount = tex.gougeCount = 0;
    const auto x3p = dir.path() / "texture.x3p";
    writePartFiles(generateSurface(tex), x3p, {});

    RaceOptions o = tinyRace(dir.path() / "race", 32, "default-unbiased");
    o.real = {x3p};
    ASSERT_EQ(o.configs.size(), 2u);
    o.configs.front().search.optimizer.iterations = 10;
    const RaceSummary s = runRace(o);
    ASSERT_EQ(s.rows.size(), 4u);
    ASSERT_EQ(s.lamps.size(), 2u);
    ASSERT_EQ(s.lampMedians.size(), 2u);
    EXPECT_EQ(s.rows[0].part, "facemill-scratches@32");
    EXPECT_EQ(s.rows[2].part, "texture@32");
    for (const RaceRow& l : s.lamps) {
        EXPECT_EQ(l.config, kLampConfig);
        EXPECT_DOUBLE_EQ(l.vsLamp, 1.0);
        EXPECT_TRUE(std::isfinite(l.figure));
        // JND beside the ratio: 1 against itself, undefined where the lamp shows nothing in JND
        // (at 32² the part spans under a degree on the default screen).
        if (l.jnd > 0)
            EXPECT_DOUBLE_EQ(l.jndVsLamp, 1.0);
        else
            EXPECT_TRUE(std::isnan(l.jndVsLamp));
    }
    ASSERT_EQ(s.standings.size(), 3u);  // the two configs, then the lamp
    EXPECT_EQ(s.standings.back().config, kLampConfig);
    for (const RaceStanding& st : s.standings) {
        std::vector<double> lamp, paper;
        for (const RaceRow& r : s.medians)
            if (r.config == st.config) lamp.push_back(r.vsLamp), paper.push_back(r.vsPaper);
        for (const RaceRow& r : s.lampMedians)
            if (r.config == st.config) lamp.push_back(r.vsLamp), paper.push_back(r.vsPaper);
        ASSERT_EQ(lamp.size(), 2u) << st.config;
        EXPECT_EQ(st.parts, 2);
        EXPECT_DOUBLE_EQ(st.medianVsLamp, median(lamp));
        EXPECT_DOUBLE_EQ(st.worstVsLamp, *std::min_element(lamp.begin(), lamp.end()));
        EXPECT_DOUBLE_EQ(st.medianVsPaper, median(paper));
        EXPECT_DOUBLE_EQ(st.worstVsPaper, *std::min_element(paper.begin(), paper.end()));
        // The JND standings over the parts whose lamp shows the defects at all.
        std::vector<double> jnd;
        for (const RaceRow& r : s.medians)
            if (r.config == st.config && std::isfinite(r.jndVsLamp)) jnd.push_back(r.jndVsLamp);
        if (jnd.empty()) {
            EXPECT_TRUE(std::isnan(st.medianJndVsLamp)) << st.config;
        } else {
            EXPECT_DOUBLE_EQ(st.medianJndVsLamp, median(jnd)) << st.config;
            EXPECT_DOUBLE_EQ(st.worstJndVsLamp, *std::min_element(jnd.begin(), jnd.end()));
        }
    }
    EXPECT_DOUBLE_EQ(s.standings[0].medianVsPaper, 1.0);  // paper-loop against itself
    const RaceStanding& a = s.standings[0];
    const RaceStanding& b = s.standings[1];
    EXPECT_EQ(s.winner, a.worstVsLamp >= b.worstVsLamp ? a.config : b.config);
}

// Real textures: a file that is missing or not a height map is refused, naming it, before any
// part is traced.
TEST(Race, RealTextureErrorsNameTheFile) {
    test::TempDir dir("wide-race-real");
    const auto missing = dir.path() / "nowhere.x3p";
    const auto garbage = dir.path() / "garbage.x3p";
    std::ofstream(garbage) << "not a height map";
    for (const auto& file : {missing, garbage}) {
        RaceOptions o;
        o.parts = {};
        o.real = {file};
        o.workDir = dir.path() / "race";
        try {
            runRace(o);
            FAIL() << file << " was accepted";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
        }
    }
}

// Every gen-surface test part and a shallow and deep variant of each generated part are race
// parts; another name is refused with the list.
TEST(Race, KnowsTheTestPartsAndTheirShallowAndDeepVariants) {
    const auto names = knownRaceParts();
    for (const char* n : {"ballend-chatter", "ballend", "facemill", "flatend", "turned",
                          "turned-shallow", "pocket-deep"})
        EXPECT_NE(std::find(names.begin(), names.end(), n), names.end()) << n;
    test::TempDir dir("wide-race-parts");
    try {
        writeRacePart("lathe", dir.path());
        FAIL();
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("flatend-deep"), std::string::npos) << e.what();
    }
}

// The whole optimize job as a race configuration: the row's light is the job's self-checked
// answer (envmap.exr of its output), scored on the race's judge like every other row.
TEST(Race, TheWholeOptimizeJobIsRacedByItsAnswer) {
    test::TempDir dir("race-job");
    RaceOptions o = tinyRace(dir.path() / "race", 64, "optimize");
    ASSERT_EQ(o.configs.size(), 2u);
    ASSERT_TRUE(o.configs[1].wholeJob);
    o.configs.front().search.optimizer.iterations = 10;
    std::string log;
    o.log = [&log](const std::string& line) { log += line + "\n"; };
    const RaceSummary s = runRace(o);
    ASSERT_EQ(s.rows.size(), 2u);
    const RaceRow& job = s.rows[1];
    EXPECT_EQ(job.config, "optimize");
    ASSERT_TRUE(std::isfinite(job.figure)) << log;
    EXPECT_GT(job.seconds, 0.0);
    // The job wrote its output where the race says, with the rule's rounds and the answer the
    // race scored (its name in the race's log line).
    const auto out = o.workDir / "jobs" / "facemill-scratches@64-optimize-seed0";
    ASSERT_TRUE(std::filesystem::exists(out / "envmap.exr")) << out;
    ASSERT_TRUE(std::filesystem::exists(out / "summary.json"));
    const std::string summary = test::readFile(out / "summary.json");
    EXPECT_NE(summary.find("\"training_noise\""), std::string::npos);
    const auto answer = nlohmann::json::parse(summary)["answer"];
    ASSERT_TRUE(answer.is_object()) << summary;
    EXPECT_NE(log.find("optimize: " + answer["light"].get<std::string>() + ", "), std::string::npos)
        << log;
}

}  // namespace
