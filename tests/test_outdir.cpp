// The OUTDIR contract (io/OptimizeOutDir.h): optimize writes every file and summary.json key the
// contract lists, the plot scripts open no file it does not list, and README's "What you get"
// names every file in it.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <string>

#include "TestUtil.h"
#include "io/OptimizeOutDir.h"

namespace sl {
namespace {

namespace fs = std::filesystem;

std::set<std::string> contractFiles() {
    std::set<std::string> names;
    for (const outdir::OutDirFile& f : outdir::optimizeOutDirFiles()) names.insert(f.name);
    return names;
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
        EXPECT_TRUE(s.contains(nlohmann::json::json_pointer(k.pointer))) << k.pointer;
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
