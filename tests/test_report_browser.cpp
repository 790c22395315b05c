// optimize's report.html opened in headless Chromium (scripts/check-report --selfcheck): a small
// optimize on a generated part, then the page's own check (headline sentence, renders with the
// A/B slider, env-map plot, loss plot, metrics; every <img> loaded) read from the DOM, and a
// screenshot at build/test-artifacts/report-screenshot.png (its path is printed). Skipped, with
// the reason, when Chromium is not installed (scripts/install-deps installs it).
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "TestUtil.h"
#include "app/report/OptimizeReport.h"
#include "app/report/Report.h"
#include "core/Text.h"

namespace fs = std::filesystem;
using namespace sl;

namespace {

std::string chromium() {
    for (const char* p : {"/usr/bin/chromium", "/usr/bin/chromium-browser"})
        if (fs::exists(p)) return p;
    return {};
}

}  // namespace

TEST(ReportBrowser, OptimizeReportOpensInHeadlessChromium) {
    if (chromium().empty())
        GTEST_SKIP() << "chromium is not installed (scripts/install-deps installs Debian's "
                        "chromium package)";
    test::TempDir dir("report-browser");
    const std::string part = (dir.path() / "part.exr").string(),
                      scene = (dir.path() / "scene.json").string(),
                      truth = (dir.path() / "part-truth.png").string();
    ASSERT_EQ(test::writeSmallLabelledPart(dir.path()), 0);
    const fs::path out = dir.path() / "out";
    const auto r =
        test::runCli("optimize " + scene + " --truth " + truth +
                     " --heldout-spp 64 --heldout-every 10 --iterations 40 -o " + out.string());
    ASSERT_EQ(r.exitCode, 0) << r.output;

    // The comparisons behind the headline are recorded.
    const auto summary = nlohmann::json::parse(test::readFile(out / "summary.json"));
    ASSERT_TRUE(summary.contains("compare")) << summary.dump(2);
    const auto& cmp = summary["compare"];
    for (const char* light : {"lamp", "paper", "optimized"}) {
        SCOPED_TRACE(light);
        ASSERT_TRUE(cmp[light].contains("judge"));
        EXPECT_FALSE(cmp[light]["judge"]["visibility"].empty());
    }
    EXPECT_EQ(cmp["lamp"]["spec"], "studio");
    for (const char* f : {"compare-lamp.png", "compare-paper.png", "view-lamp.png",
                          "view-optimized.png", "view-regions.png", "plot-data.json"})
        EXPECT_TRUE(fs::exists(out / f)) << f;
    const std::string html = test::readFile(out / "report.html");
    EXPECT_NE(html.find(escapeXml(optimizeHeadline(summary))), std::string::npos);
    // The headline: E* against the lamp (with several kinds, by the least visible), or the
    // reference that beat it on validation.
    EXPECT_TRUE(html.find("Under the optimized light the defects are") != std::string::npos ||
                html.find("Under the optimized light the least visible defect kind is") !=
                    std::string::npos ||
                html.find("The answer is ") != std::string::npos);

    const fs::path shot =
        fs::path(SL_CLI_PATH).parent_path() / "test-artifacts" / "report-screenshot.png";
    fs::create_directories(shot.parent_path());
    const std::string check = std::string(SL_SOURCE_DIR) + "/scripts/check-report";
    const auto c = test::runShell(check + " " + (out / "report.html").string() + " " +
                                  shot.string() + " --size 1400x1800 --selfcheck");
    std::cout << c.output << "report screenshot: " << shot.string() << std::endl;
    RecordProperty("screenshot", shot.string());
    EXPECT_EQ(c.exitCode, 0) << c.output;
    EXPECT_NE(c.output.find("selfcheck: ok"), std::string::npos) << c.output;
    EXPECT_TRUE(fs::exists(shot));
}

// Without its figures (--no-figures, or figures that could not be drawn) the page still opens
// and says why each is missing.
TEST(ReportBrowser, AMissingFigureIsNamedWithItsReason) {
    test::TempDir dir("report-nofig");
    const fs::path out = dir.path();
    std::ofstream(out / "summary.json") << R"({"optimizer": "lbfgs", "objective": "unbiased",
        "lambda": 30, "initial_loss": 2, "final_loss": 1})";
    std::ofstream(out / "loss.csv") << "iteration,loss\n0,2\n1,1\n";
    const std::string html = renderOptimizeReportHtml(out, "loss plot: needs at least one loss");
    EXPECT_NE(html.find("figure not made: loss plot: needs at least one loss"), std::string::npos);
    EXPECT_NE(html.find("no comparison with a lamp"), std::string::npos);
}
