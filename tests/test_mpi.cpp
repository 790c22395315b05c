// optimize over MPI ranks (docs/CLUSTER.md, app/host/Mpi.h): two ranks, each holding one row shard of
// T, give the light one process gives on the whole T (to 1e-12), with the default objective
// (unbiased, on T's halves), with eq. 2 and with the defects objective; rank 0 alone writes. What
// cannot run over ranks is refused, and every rank ends with a non-zero exit. Skipped in a build
// without MPI.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "TestUtil.h"
#include "app/host/Mpi.h"

namespace {

using namespace sl;

/// mpirun for `ranks` processes, allowed to run as root (CI containers) and more processes
/// than cores.
std::string mpirun(int ranks) {
    return "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 " + std::string(SL_MPIEXEC) +
           " --oversubscribe -np " + std::to_string(ranks) + " " + SL_CLI_PATH + " ";
}

/// E* as optimize computed it, in full precision (plot-data.json's "optimized" light: E itself
/// for a gray E).
std::vector<double> lightOf(const std::filesystem::path& outDir) {
    std::ifstream in(outDir / "plot-data.json");
    const auto j = nlohmann::json::parse(in);
    return j.at("lights").at("optimized").get<std::vector<double>>();
}

class Mpi : public ::testing::Test {
  protected:
    void SetUp() override {
        if (!mpiBuilt() || std::string(SL_MPIEXEC).empty())
            GTEST_SKIP() << "built without MPI (scripts/install-deps installs libopenmpi-dev and "
                            "openmpi-bin)";
    }
};

/// The largest |a − b| over the texels, relative to the largest |a|.
double relativeDifference(const std::vector<double>& a, const std::vector<double>& b) {
    double worst = 0, largest = 0;
    for (size_t i = 0; i < a.size(); ++i) {
        worst = std::max(worst, std::abs(a[i] - b[i]));
        largest = std::max(largest, std::abs(a[i]));
    }
    return largest > 0 ? worst / largest : 1.0;
}

// The rounding of the gradient's sum (Tᵀ·dL/dY summed rank by rank instead of row by row in one
// process) differs by a few ulps and grows along the optimizer's path: 30 L-BFGS iterations keep
// it well under 1e-12 on this scene (docs/CLUSTER.md gives the measured growth).
TEST_F(Mpi, TwoRanksOnShardsGiveTheOneProcessLight) {
    test::TempDir dir("mpi");
    const std::string scene = std::string(SL_SOURCE_DIR) + "/scenes/default/scene.json";
    const std::string d = dir.path().string() + "/";
    const std::string base = "precompute " + scene + " --size 64 --spp 4 --halves";
    // An uneven split: the ranks hold different numbers of rows.
    ASSERT_EQ(test::runCli(base + " --rows 0:27 -o " + d + "a.tm").exitCode, 0);
    ASSERT_EQ(test::runCli(base + " --rows 27:64 -o " + d + "b.tm").exitCode, 0);
    std::ofstream(dir / "t.shards") << "a.tm\nb.tm\n";
    test::RunResult r;
    const std::string truth = std::string(SL_SOURCE_DIR) + "/scenes/default/part-truth.png";
    for (const std::string& objective : {std::string(), std::string(" --objective paper"),
                                         " --objective defects --defects " + truth + ":255"}) {
        SCOPED_TRACE("objective:" + objective);
        const std::string args = "optimize " + d +
                                 "t.shards --heldout none --iterations 30 --no-figures "
                                 "--no-self-check" +
                                 objective + " -o " + d;
        const std::string tag = objective.empty()                              ? ""
                                : objective.find("paper") != std::string::npos ? "-paper"
                                                                               : "-defects";
        const std::string one = "one" + tag, two = "two" + tag;
        r = test::runCli(args + one);
        ASSERT_EQ(r.exitCode, 0) << r.output;
        r = test::runShell(mpirun(2) + args + two);
        ASSERT_EQ(r.exitCode, 0) << r.output;
        // Rank 0 alone prints the results table.
        const size_t first = r.output.find("initial loss");
        EXPECT_NE(first, std::string::npos) << r.output;
        EXPECT_EQ(r.output.find("initial loss", first + 1), std::string::npos) << r.output;
        const std::vector<double> a = lightOf(dir / one), b = lightOf(dir / two);
        ASSERT_EQ(a.size(), 25u * 50u);
        ASSERT_EQ(b.size(), a.size());
        EXPECT_LE(relativeDifference(a, b), 1e-12);
        const auto summary = nlohmann::json::parse(std::ifstream(dir / two / "summary.json"));
        EXPECT_EQ(summary.at("mpi").at("ranks").get<int>(), 2);
        EXPECT_EQ(
            summary.at("iterations"),
            nlohmann::json::parse(std::ifstream(dir / one / "summary.json")).at("iterations"));
    }
    // Three ranks through scripts/slurm-precompute's jobs (tasks run here by their ids): the
    // three shards' list is the same T, so the same light.
    r = test::runSlurmPrecompute(scene, 64, 3, d + "job", "--size 64 --spp 4 --halves");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    r = test::runShell("OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 MPIRUN='" +
                       std::string(SL_MPIEXEC) + " --oversubscribe' OUT=" + d + "three bash " + d +
                       "job/optimize.sbatch --iterations 30 --no-figures");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_LE(relativeDifference(lightOf(dir / "one"), lightOf(dir / "three")), 1e-12);
}

TEST_F(Mpi, RefusesWhatDoesNotFitTheRanksAndEndsThemAll) {
    test::TempDir dir("mpi-refuse");
    const std::string scene = std::string(SL_SOURCE_DIR) + "/scenes/default/scene.json";
    const std::string d = dir.path().string() + "/";
    const std::string base = "precompute " + scene + " --size 24 --spp 2 --halves";
    ASSERT_EQ(test::runCli(base + " --rows 0:12 -o " + d + "a.tm").exitCode, 0);
    ASSERT_EQ(test::runCli(base + " --rows 12:24 -o " + d + "b.tm").exitCode, 0);
    std::ofstream(dir / "t.shards") << "a.tm\nb.tm\n";
    // Three ranks for two shards.
    auto r = test::runShell(mpirun(3) + "optimize " + d +
                            "t.shards --heldout none --no-figures -o " + d + "o");
    EXPECT_NE(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("lists 2 shards for 3 MPI ranks"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("mpirun -np 2"), std::string::npos) << r.output;
    // The judge's held-out estimate is a whole T.
    r = test::runShell(mpirun(2) + "optimize " + d + "t.shards -o " + d + "o");
    EXPECT_NE(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("--heldout none"), std::string::npos) << r.output;
    // Shards of two traces (other spp), checked by the ranks together: the file is named.
    ASSERT_EQ(test::runCli("precompute " + scene + " --size 24 --spp 4 --halves --rows 12:24 -o " +
                           d + "c.tm")
                  .exitCode,
              0);
    std::ofstream(dir / "mixed.shards") << "a.tm\nc.tm\n";
    r = test::runShell(mpirun(2) + "optimize " + d + "mixed.shards --heldout none -o " + d + "o");
    EXPECT_NE(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("c.tm: was traced with other inputs"), std::string::npos) << r.output;
    // Only optimize runs over ranks.
    r = test::runShell(mpirun(2) + "relight " + d + "t.shards --envmap const:1 -o " + d + "r.exr");
    EXPECT_NE(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("only `optimize` runs over MPI ranks"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "o"));
    EXPECT_FALSE(std::filesystem::exists(dir / "r.exr"));
}

}  // namespace
