// The OUTDIR contract (io/OptimizeOutDir.h): optimize writes every file and summary.json key the
// contract lists, the plot scripts open no file it does not list, README's "What you get"
// names every file in it, and the typed summary its C++ readers read reads only listed keys.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <string>
#include <vector>

#include "TestUtil.h"
#include "core/Error.h"
#include "io/OptimizeOutDir.h"
#include "io/OptimizeSummary.h"

namespace sl {
namespace {

namespace fs = std::filesystem;

std::set<std::string> contractFiles() {
    std::set<std::string> names;
    for (const outdir::OutDirFile& f : outdir::optimizeOutDirFiles()) names.insert(f.name);
    return names;
}

/// `full` with each of `pointers` given an array (which fits no typed key): refused by the typed
/// summary, naming the pointer.
void expectEachRefusedByName(const nlohmann::json& full, const std::vector<std::string>& pointers) {
    for (const std::string& p : pointers) {
        nlohmann::json bad = full;
        bad[nlohmann::json::json_pointer(p)] = nlohmann::json::array({1});
        try {
            outdir::optimizeSummaryFromJson(bad, "summary.json");
            ADD_FAILURE() << p << " with an array was accepted";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("summary.json " + p), std::string::npos)
                << e.what();
        }
    }
}

TEST(OutDir, OptimizeWritesEveryFileAndKeyTheContractLists) {
    test::TempDir dir("outdir");
    ASSERT_EQ(test::writeSmallLabelledPart(dir.path()), 0);
    // The defects objective (a truth), the judge's estimate and the figures: every case but a
    // given reference region, the scratch mask (another loss mask) and a reference as the answer.
    const auto r = test::runCli("optimize " + (dir / "scene.json").string() + " --truth " +
                                (dir / "part-truth.png").string() + " --size 32 --spp 4 --cache " +
                                (dir / "cache").string() + " -o " + (dir / "out").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    for (const outdir::OutDirFile& f : outdir::optimizeOutDirFiles())
        if (f.when != outdir::Written::Reference && f.when != outdir::Written::ScratchMask &&
            f.when != outdir::Written::ReferenceWon) {
            EXPECT_TRUE(fs::exists(dir / "out" / f.name)) << f.name;
        }
    const auto s = nlohmann::json::parse(test::readFile(dir / "out" / outdir::kSummary));
    for (const outdir::SummaryKey& k : outdir::optimizeSummaryKeys())
        if (!k.referenceWon) {
            EXPECT_TRUE(s.contains(nlohmann::json::json_pointer(k.pointer))) << k.pointer;
        }
}

// The typed summary (io/OptimizeSummary.h): each key it types is one the contract lists, is
// read with its type, keeps its default when absent, and is refused by name with another type.
TEST(OutDir, TheTypedSummaryReadsListedKeysAndRefusesAWrongTypeByName) {
    const std::vector<std::string> typed = {
        "/objective",       "/lambda",           "/smooth_abs",     "/reg",
        "/defects_measure", "/optimizer",        "/transport/file", "/truth",
        "/initial_loss",    "/final_loss",       "/metrics",        "/metrics_initial",
        "/compare",         "/compare/judge_spp"};
    std::set<std::string> listed;
    for (const outdir::SummaryKey& k : outdir::optimizeSummaryKeys()) listed.insert(k.pointer);
    for (const std::string& p : typed) EXPECT_TRUE(listed.count(p)) << p << " is not listed";

    const nlohmann::json full = {{"objective", "defects"},
                                 {"lambda", 12.5},
                                 {"smooth_abs", true},
                                 {"reg", "image"},
                                 {"defects_measure", "jnd"},
                                 {"optimizer", "adam"},
                                 {"transport", {{"file", "/tmp/t.tm"}}},
                                 {"truth", "part-truth.png"},
                                 {"initial_loss", 3.25},
                                 {"final_loss", nullptr},
                                 {"metrics", {{"U", 1.5}}},
                                 {"metrics_initial", {{"U", 2.5}}},
                                 {"compare", {{"judge_spp", 256}}},
                                 {"other", 1}};
    const outdir::OptimizeSummary s = outdir::optimizeSummaryFromJson(full, "summary.json");
    EXPECT_EQ(s.objective, "defects");
    EXPECT_EQ(s.lambda, 12.5);
    EXPECT_TRUE(s.smoothAbs);
    EXPECT_EQ(s.reg, "image");
    EXPECT_EQ(s.defectsMeasure, "jnd");
    EXPECT_EQ(s.optimizer, "adam");
    EXPECT_EQ(s.transportFile, "/tmp/t.tm");
    EXPECT_EQ(s.truth, "part-truth.png");
    EXPECT_EQ(s.initialLoss, 3.25);
    EXPECT_TRUE(s.finalLoss.is_null());
    EXPECT_EQ(s.metrics["U"], 1.5);
    EXPECT_EQ(s.metricsInitial["U"], 2.5);
    ASSERT_TRUE(s.judgeSpp.has_value());
    EXPECT_EQ(*s.judgeSpp, 256);
    EXPECT_EQ(s.document, full);

    const outdir::OptimizeSummary empty =
        outdir::optimizeSummaryFromJson(nlohmann::json::object(), "summary.json");
    EXPECT_TRUE(empty.objective.empty());
    EXPECT_TRUE(std::isnan(empty.lambda));
    EXPECT_FALSE(empty.smoothAbs);
    EXPECT_EQ(empty.reg, "envmap");
    EXPECT_TRUE(empty.transportFile.empty());
    EXPECT_TRUE(empty.compare.is_null());
    EXPECT_FALSE(empty.judgeSpp.has_value());

    // Every typed key with a value of another type (an array fits none of them).
    expectEachRefusedByName(full, typed);
    EXPECT_THROW(outdir::optimizeSummaryFromJson(nlohmann::json::array(), "summary.json"),
                 InputError);
    test::TempDir dir("outdir-summary");
    try {
        outdir::readOptimizeSummary(dir.path());
        ADD_FAILURE() << "a folder without summary.json was read";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find(outdir::kSummary), std::string::npos) << e.what();
    }
}

// The comparison typed (io/OptimizeSummary.h Comparison): each light's name, training loss and
// judge score, the answer when a reference won, every key it reads listed by the contract, and
// a key of another type refused by name.
TEST(OutDir, TheTypedComparisonReadsEachLightAndRefusesAWrongTypeByName) {
    std::set<std::string> listed;
    for (const outdir::SummaryKey& k : outdir::optimizeSummaryKeys()) listed.insert(k.pointer);
    const std::vector<std::string> typed = {"/compare/objective",
                                            "/compare/regions",
                                            "/compare/viewing/text",
                                            "/compare/lamp/name",
                                            "/compare/lamp/training/loss",
                                            "/compare/paper/training/loss",
                                            "/compare/optimized/training/loss",
                                            "/compare/optimized/judge/unbiased",
                                            "/compare/optimized/judge/eq2",
                                            "/compare/optimized/judge/brightness",
                                            "/compare/optimized/judge/mean_E",
                                            "/compare/optimized/judge/sparsity",
                                            "/compare/optimized/judge/visibility",
                                            "/compare/optimized/judge/se/least_visible_jnd",
                                            "/compare/answer/name",
                                            "/compare/answer/merit",
                                            "/compare/answer/merit_answer",
                                            "/compare/answer/merit_optimized",
                                            "/compare/answer/optimized_why",
                                            "/compare/answer/judge"};
    for (const std::string& p : typed) EXPECT_TRUE(listed.count(p)) << p << " is not listed";

    auto judge = [](double u, double jnd) {
        return nlohmann::json{
            {"unbiased", u},
            {"eq2", 2 * u},
            {"brightness", 0.5},
            {"mean_E", 0.25},
            {"sparsity", nullptr},  // not finite when written
            {"visibility",
             {{{"name", "scratch"}, {"pixels", 120}, {"visibility", 3.0}, {"jnd", jnd}},
              {{"name", "dent"}, {"pixels", 40}, {"visibility", 1.5}, {"contrast", 0.1}}}},
            {"se", {{"least_visible_jnd", 0.05}}}};
    };
    const nlohmann::json full = {
        {"compare",
         {{"objective", "defects"},
          {"regions", "truth part-truth.png"},
          {"viewing", {{"text", "38.8 px/deg"}}},
          {"judge_spp", 512},
          {"lamp",
           {{"name", "studio preset"}, {"training", {{"loss", 4.0}}}, {"judge", judge(8, 1)}}},
          {"paper", {{"name", "paper's light"}, {"training", {{"loss", 3.0}}}}},
          {"optimized", {{"training", {{"loss", 1.0}}}, {"judge", judge(2, 3)}}},
          {"answer",
           {{"name", "studio preset"},
            {"merit", "JND"},
            {"merit_answer", 2.5},
            {"merit_optimized", 2.0},
            {"optimized_why", ""},
            {"judge", judge(8, 1)}}}}}};
    const outdir::OptimizeSummary s = outdir::optimizeSummaryFromJson(full, "summary.json");
    ASSERT_TRUE(s.comparison.has_value());
    const outdir::Comparison& c = *s.comparison;
    EXPECT_EQ(c.objective, "defects");
    ASSERT_TRUE(c.regions.has_value());
    EXPECT_EQ(*c.regions, "truth part-truth.png");
    EXPECT_EQ(c.viewing, "38.8 px/deg");
    EXPECT_EQ(c.lamp.name, "studio preset");
    EXPECT_EQ(c.lamp.trainingLoss, 4.0);
    EXPECT_EQ(c.paper.trainingLoss, 3.0);
    EXPECT_FALSE(c.paper.judge.has_value());
    EXPECT_TRUE(c.optimized.name.empty());
    ASSERT_TRUE(c.optimized.judge.has_value());
    const outdir::JudgedLight& o = *c.optimized.judge;
    EXPECT_EQ(o.unbiased, 2.0);
    EXPECT_EQ(o.eq2, 4.0);
    EXPECT_EQ(o.brightness, 0.5);
    EXPECT_EQ(o.meanE, 0.25);
    EXPECT_TRUE(std::isnan(o.sparsity));
    EXPECT_EQ(o.leastVisibleJndSe, 0.05);
    ASSERT_TRUE(o.regions.has_value());
    ASSERT_EQ(o.regions->size(), 2u);
    EXPECT_EQ((*o.regions)[0].name, "scratch");
    EXPECT_EQ((*o.regions)[0].pixels, 120);
    EXPECT_EQ((*o.regions)[0].jnd, 3.0);
    EXPECT_TRUE(std::isnan((*o.regions)[0].contrast));
    EXPECT_TRUE(std::isnan((*o.regions)[1].jnd));
    EXPECT_EQ((*o.regions)[1].contrast, 0.1);
    ASSERT_TRUE(c.answer.has_value());
    EXPECT_EQ(c.answer->name, "studio preset");
    EXPECT_EQ(c.answer->merit, "JND");
    EXPECT_EQ(c.answer->meritAnswer, 2.5);
    EXPECT_EQ(c.answer->meritOptimized, 2.0);
    EXPECT_TRUE(c.answer->optimizedWhy.empty());
    ASSERT_TRUE(c.answer->judge.has_value());
    EXPECT_EQ(c.answer->judge->unbiased, 8.0);

    // Without a comparison there is none; a comparison without a judge has no judge scores.
    EXPECT_FALSE(outdir::optimizeSummaryFromJson(nlohmann::json::object(), "summary.json")
                     .comparison.has_value());
    const outdir::OptimizeSummary bare = outdir::optimizeSummaryFromJson(
        {{"compare", {{"lamp", {{"name", "lamp"}}}}}}, "summary.json");
    ASSERT_TRUE(bare.comparison.has_value());
    EXPECT_FALSE(bare.comparison->regions.has_value());
    EXPECT_FALSE(bare.comparison->optimized.judge.has_value());
    EXPECT_FALSE(bare.comparison->answer.has_value());
    EXPECT_TRUE(std::isnan(bare.comparison->optimized.trainingLoss));

    // A typed key, or a region's figure, of another type: refused by its pointer.
    std::vector<std::string> wrong = typed;
    wrong.push_back("/compare/lamp/judge/visibility/1/jnd");
    wrong.push_back("/compare/answer/judge/visibility/0/name");
    expectEachRefusedByName(full, wrong);
}

// The rest of what the report reads typed (io/OptimizeSummary.h): the self-check, the env map's
// marked directions, the warnings, the part, T's image size and the held-out figures; each key
// listed by the contract, absent ones at their defaults, another type refused by name.
TEST(OutDir, TheTypedSummaryReadsTheAnswerDirectionsAndHeldOutFigures) {
    std::set<std::string> listed;
    for (const outdir::SummaryKey& k : outdir::optimizeSummaryKeys()) listed.insert(k.pointer);
    const std::vector<std::string> typed = {"/answer",
                                            "/answer/light",
                                            "/answer/kind",
                                            "/answer/merit",
                                            "/answer/candidates",
                                            "/answer/candidates/0/name",
                                            "/answer/candidates/0/kind",
                                            "/answer/candidates/0/merit",
                                            "/answer/candidates/0/eligible",
                                            "/answer/candidates/0/why",
                                            "/envmap_directions",
                                            "/envmap_directions/camera",
                                            "/envmap_directions/mirror",
                                            "/envmap_directions/brightest",
                                            "/warnings",
                                            "/heightmap",
                                            "/transport/image",
                                            "/heldout_loss",
                                            "/heldout_U"};
    for (const std::string& p : typed) EXPECT_TRUE(listed.count(p)) << p << " is not listed";

    const nlohmann::json full = {
        {"answer",
         {{"light", "studio preset"},
          {"kind", "reference"},
          {"merit", "JND"},
          {"candidates",
           {{{"name", "optimized"}, {"kind", "optimized"}, {"merit", 2.0}, {"why", ""}},
            {{"name", "studio preset"},
             {"kind", "reference"},
             {"merit", nullptr},
             {"eligible", false},
             {"why", "too dark"}}}}}},
        {"envmap_directions",
         {{"camera", {{"azimuth_deg", 180.0}, {"elevation_deg", 45.0}}},
          {"brightest",
           {{{"azimuth_deg", 10.0}, {"elevation_deg", 20.0}},
            {{"azimuth_deg", 30.0}, {"elevation_deg", -5.0}}}}}},
        {"warnings", {"no improvement", "dark"}},
        {"heightmap", {{"file", "part.exr"}, {"format", "exr"}}},
        {"transport", {{"image", {96, 64}}}},
        {"heldout_loss", 1.25},
        {"heldout_U", nullptr}};
    const outdir::OptimizeSummary s = outdir::optimizeSummaryFromJson(full, "summary.json");
    ASSERT_TRUE(s.answer.has_value());
    EXPECT_EQ(s.answer->light, "studio preset");
    EXPECT_EQ(s.answer->kind, "reference");
    EXPECT_EQ(s.answer->merit, "JND");
    ASSERT_EQ(s.answer->candidates.size(), 2u);
    EXPECT_EQ(s.answer->candidates[0].name, "optimized");
    EXPECT_EQ(s.answer->candidates[0].merit, 2.0);
    EXPECT_TRUE(s.answer->candidates[0].eligible);  // absent: eligible
    EXPECT_TRUE(std::isnan(s.answer->candidates[1].merit));
    EXPECT_FALSE(s.answer->candidates[1].eligible);
    EXPECT_EQ(s.answer->candidates[1].why, "too dark");
    ASSERT_TRUE(s.envmapDirections.has_value());
    ASSERT_TRUE(s.envmapDirections->camera.has_value());
    EXPECT_EQ(s.envmapDirections->camera->azimuthDeg, 180.0);
    EXPECT_EQ(s.envmapDirections->camera->elevationDeg, 45.0);
    EXPECT_FALSE(s.envmapDirections->mirror.has_value());
    ASSERT_EQ(s.envmapDirections->brightest.size(), 2u);
    EXPECT_EQ(s.envmapDirections->brightest[1].elevationDeg, -5.0);
    EXPECT_EQ(s.warnings, (std::vector<std::string>{"no improvement", "dark"}));
    EXPECT_EQ(s.heightmap["format"], "exr");
    ASSERT_TRUE(s.image.has_value());
    EXPECT_EQ((*s.image)[0], 96);
    EXPECT_EQ((*s.image)[1], 64);
    EXPECT_EQ(s.heldoutLoss, 1.25);
    EXPECT_TRUE(std::isnan(s.heldoutU));

    const outdir::OptimizeSummary empty =
        outdir::optimizeSummaryFromJson(nlohmann::json::object(), "summary.json");
    EXPECT_FALSE(empty.answer.has_value());
    EXPECT_FALSE(empty.envmapDirections.has_value());
    EXPECT_TRUE(empty.warnings.empty());
    EXPECT_TRUE(empty.heightmap.is_null());
    EXPECT_FALSE(empty.image.has_value());
    EXPECT_TRUE(std::isnan(empty.heldoutLoss));

    // Another type, by its pointer: the typed keys (an array of [1] fits none but the arrays,
    // whose elements are then refused), a candidate's field, a direction's, a warning.
    std::vector<std::string> wrong = {"/answer",
                                      "/answer/light",
                                      "/answer/kind",
                                      "/answer/merit",
                                      "/answer/candidates/0",
                                      "/answer/candidates/1/merit",
                                      "/answer/candidates/1/eligible",
                                      "/answer/candidates/0/why",
                                      "/envmap_directions",
                                      "/envmap_directions/camera",
                                      "/envmap_directions/brightest/0/azimuth_deg",
                                      "/heightmap",
                                      "/heldout_loss",
                                      "/heldout_U"};
    expectEachRefusedByName(full, wrong);
    nlohmann::json badWarning = full;
    badWarning["warnings"][1] = 3;
    EXPECT_THROW(outdir::optimizeSummaryFromJson(badWarning, "summary.json"), InputError);
    nlohmann::json badImage = full;
    badImage["transport"]["image"] = {96};
    try {
        outdir::optimizeSummaryFromJson(badImage, "summary.json");
        ADD_FAILURE() << "an image of one number was accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("summary.json /transport/image"), std::string::npos)
            << e.what();
    }
}

// The plot scripts read summary.json through scripts/outdir_contract.py, by JSON pointers: each
// pointer a script names is one the contract lists, with the script among its readers.
TEST(OutDir, ThePlotScriptsReadOnlyListedSummaryKeys) {
    std::map<std::string, std::string> readers;
    for (const outdir::SummaryKey& k : outdir::optimizeSummaryKeys())
        readers[k.pointer] = k.readers;
    const std::regex pointer(R"re(["'](/[a-z_%/0-9A-Z]+)["'])re");
    for (const char* script : {"scripts/plot_optimize.py", "scripts/plot_before_after.py"}) {
        const std::string text = test::readFile(fs::path(SL_SOURCE_DIR) / script);
        ASSERT_FALSE(text.empty()) << script;
        EXPECT_NE(text.find("from outdir_contract import"), std::string::npos) << script;
        int seen = 0;
        for (std::sregex_iterator m(text.begin(), text.end(), pointer), e; m != e; ++m) {
            const std::string p = (*m)[1];
            std::vector<std::string> pointers;
            if (const size_t at = p.find("%s"); at != std::string::npos) {
                for (const char* key : {"lamp", "paper", "optimized"})
                    pointers.push_back(std::string(p).replace(at, 2, key));
            } else {
                pointers.push_back(p);
            }
            for (const std::string& q : pointers) {
                const auto it = readers.find(q);
                ASSERT_NE(it, readers.end()) << script << " reads " << q << ", which is not listed";
                EXPECT_NE(it->second.find(fs::path(script).filename().string()), std::string::npos)
                    << q << " does not name " << script << " among its readers";
            }
            ++seen;
        }
        EXPECT_GT(seen, 0) << script;
    }
}

TEST(OutDir, ThePlotScriptsOpenOnlyFilesTheContractLists) {
    const std::set<std::string> names = contractFiles();
    const std::regex quoted(R"re("([a-z%-]+\.(png|json|csv|exr))")re");
    for (const char* script : {"scripts/plot_optimize.py", "scripts/plot_before_after.py"}) {
        const std::string text = test::readFile(fs::path(SL_SOURCE_DIR) / script);
        ASSERT_FALSE(text.empty()) << script;
        int seen = 0;
        for (std::sregex_iterator m(text.begin(), text.end(), quoted), e; m != e; ++m) {
            std::string name = (*m)[1];
            // "view-%s.png" % key: the three views.
            if (const size_t p = name.find("%s"); p != std::string::npos) {
                for (const char* key : {"lamp", "paper", "optimized"})
                    EXPECT_TRUE(names.count(std::string(name).replace(p, 2, key)))
                        << script << ": " << name << " with " << key;
            } else {
                EXPECT_TRUE(names.count(name)) << script << " opens " << name;
            }
            ++seen;
        }
        EXPECT_GT(seen, 0) << script;
    }
}

TEST(OutDir, ReadmeNamesEveryFile) {
    const std::string readme = test::readFile(fs::path(SL_SOURCE_DIR) / "README.md");
    const size_t begin = readme.find("## What you get");
    ASSERT_NE(begin, std::string::npos);
    const std::string section = readme.substr(begin, readme.find("\n## ", begin + 1) - begin);
    // README's names, with * as a wildcard (`compare-lamp.*`, `initial*.png`).
    std::vector<std::regex> documented;
    const std::regex code("`([^` ]+)`");
    for (std::sregex_iterator m(section.begin(), section.end(), code), e; m != e; ++m) {
        std::string glob;
        for (char c : (*m)[1].str())
            glob += c == '*' ? std::string("[^/]*") : c == '.' ? "\\." : std::string(1, c);
        documented.emplace_back(glob);
    }
    for (const std::string& name : contractFiles()) {
        bool found = false;
        for (const std::regex& g : documented) found = found || std::regex_match(name, g);
        EXPECT_TRUE(found) << name << " is not in README's \"What you get\"";
    }
}

}  // namespace
}  // namespace sl
