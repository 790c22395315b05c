// Results are the same bit for bit whatever the thread count and from one run to the next
// (README "Limits"): sample s of pixel p is seeded by (seed, p, s), never by thread
// (src/core/Rng.h), sums are reduced in a fixed order, and EXR files carry no timestamp.
// Only what describes the run itself may differ: wall-clock seconds, whether T came from the
// cache and where it is stored, the output directory's name, the command line and the date.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "TestUtil.h"

namespace fs = std::filesystem;
using namespace sl;

namespace {

// summary.json without what measures the run rather than its result.
nlohmann::json withoutRunFacts(nlohmann::json j) {
    if (j.is_object()) {
        nlohmann::json out = nlohmann::json::object();
        for (auto& [k, v] : j.items()) {
            if (k.rfind("seconds", 0) == 0 || k.find("cache_hit") != std::string::npos ||
                k == "name" || k == "file" || k == "date" || k == "command")
                continue;
            out[k] = withoutRunFacts(v);
        }
        return out;
    }
    if (j.is_array()) {
        nlohmann::json out = nlohmann::json::array();
        for (auto& v : j) out.push_back(withoutRunFacts(v));
        return out;
    }
    return j;
}

// loss.csv without its `seconds` column.
std::vector<std::string> withoutSecondsColumn(const std::string& csv) {
    std::istringstream is(csv);
    std::string line;
    std::vector<std::string> rows;
    int secondsCol = -1;
    while (std::getline(is, line)) {
        std::vector<std::string> cells;
        std::string cell;
        std::istringstream ls(line);
        while (std::getline(ls, cell, ',')) cells.push_back(cell);
        if (secondsCol < 0)
            for (size_t c = 0; c < cells.size(); ++c)
                if (cells[c] == "seconds") secondsCol = static_cast<int>(c);
        std::string row;
        for (size_t c = 0; c < cells.size(); ++c)
            if (static_cast<int>(c) != secondsCol) row += cells[c] + ",";
        rows.push_back(row);
    }
    EXPECT_GE(secondsCol, 0) << "loss.csv has no seconds column";
    return rows;
}

}  // namespace

// Three optimize runs, each tracing its own T (separate parents, so separate caches): 1 thread,
// 2 threads, and 2 threads again. Every image and env map is byte-identical; summary.json and
// loss.csv are identical once the timings are removed.
TEST(Reproducible, OptimizeOutputsAreTheSameForAnyThreadCountAndRun) {
    test::TempDir dir("repro");
    const fs::path scene = fs::path(SL_SOURCE_DIR) / "scenes/default/scene.json";
    const std::vector<int> threads = {1, 2, 2};
    std::vector<fs::path> outs;
    for (size_t r = 0; r < threads.size(); ++r) {
        const fs::path parent = dir.path() / ("run" + std::to_string(r));
        fs::create_directories(parent);
        outs.push_back(parent / "out");
        const auto res = test::runCli("optimize " + scene.string() +
                                      " --spp 2 --heldout-spp 4 --iterations 15 --threads " +
                                      std::to_string(threads[r]) + " -o " + outs.back().string());
        ASSERT_EQ(res.exitCode, 0) << res.output;
    }
    std::vector<std::string> files;
    for (const auto& e : fs::directory_iterator(outs[0])) files.push_back(e.path().filename());
    ASSERT_GE(files.size(), 8u);
    for (size_t r = 1; r < outs.size(); ++r) {
        for (const auto& f : files) {
            SCOPED_TRACE("run " + std::to_string(r) + ", " + f);
            ASSERT_TRUE(fs::exists(outs[r] / f));
            const std::string a = test::readFile(outs[0] / f), b = test::readFile(outs[r] / f);
            if (f == "summary.json") {
                EXPECT_EQ(withoutRunFacts(nlohmann::json::parse(a)),
                          withoutRunFacts(nlohmann::json::parse(b)));
            } else if (f == "loss.csv") {
                EXPECT_EQ(withoutSecondsColumn(a), withoutSecondsColumn(b));
            } else if (f == "report.html") {
                // It shows the timings and the directory's name; its pictures are the files
                // compared above.
                EXPECT_FALSE(b.empty());
            } else {
                EXPECT_TRUE(a == b) << "files differ";
            }
        }
    }
}
