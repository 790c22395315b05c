// Row shards of T (io/TransportFile.h SHARDS, `precompute --rows`): put together they are the
// one-process trace bit for bit, with its fingerprint; a .shards list reads as that T; shards
// that overlap, leave a gap or come from other inputs are refused naming the list.
#include <gtest/gtest.h>

#include <fstream>

#include "TestUtil.h"
#include "core/Error.h"
#include "io/TransportFile.h"
#include "scene/Scene.h"
#include "transport/TransportSink.h"

namespace {

using namespace sl;

struct ShardScene {
    ShardScene() : scene(test::bumpyPartDesc(24, 20), 32, 32, test::bumpyHeightMap(32)) {}
    TransportFile trace(int rowBegin, int rowEnd, int spp = 8) const {
        RenderOptions ro;
        ro.spp = spp;
        ro.maxDepth = 3;
        ro.sampleSets = 2;
        ro.rowBegin = rowBegin;
        ro.rowEnd = rowEnd;
        TransportFile f;
        f.matrix = precomputeTransport(scene, ro, 1).matrix;
        f.provenance = transportProvenance(scene, ro, 1);
        return f;
    }
    Scene scene;
};

void expectSameMatrix(TransportMatrix a, TransportMatrix b) {
    a.toSparse();
    b.toSparse();
    EXPECT_EQ(a.rowPtr, b.rowPtr);
    EXPECT_EQ(a.colIdx, b.colIdx);
    EXPECT_EQ(a.values, b.values);
    EXPECT_EQ(a.objectMask, b.objectMask);
}

TEST(Shards, PutTogetherTheyAreTheWholeTraceBitForBit) {
    const ShardScene s;
    const TransportFile whole = s.trace(0, 0);
    std::vector<TransportFile> shards{s.trace(13, 20), s.trace(0, 7), s.trace(7, 13)};
    // A shard's rows outside its range are empty, and its fingerprint is its own.
    TransportMatrix first = shards[1].matrix;
    first.toSparse();
    EXPECT_EQ(first.rowPtr[7 * 24], first.rowPtr.back());
    EXPECT_GT(first.rowPtr[7 * 24], 0u);
    EXPECT_NE(shards[0].provenance.fingerprint, whole.provenance.fingerprint);
    const TransportFile merged = mergeTransportShards(shards, "test");
    expectSameMatrix(merged.matrix, whole.matrix);
    EXPECT_EQ(merged.provenance.fingerprint, whole.provenance.fingerprint);
    EXPECT_EQ(merged.provenance.inputs, whole.provenance.inputs);
}

TEST(Shards, AListFileReadsAsTheMergedMatrix) {
    const ShardScene s;
    test::TempDir dir("shards");
    const TransportFile a = s.trace(0, 11), b = s.trace(11, 20);
    writeTransportFile(dir / "a.tm", a.matrix, a.provenance);
    std::filesystem::create_directories(dir / "sub");
    writeTransportFile(dir / "sub" / "b.tm", b.matrix, b.provenance);
    std::ofstream(dir / "t.shards") << "# rows 0-10 and 11-19\na.tm\n\n  sub/b.tm  \n";
    const TransportFile whole = s.trace(0, 0);
    const TransportFile read = readTransportFile(dir / "t.shards", whole.provenance.fingerprint);
    expectSameMatrix(read.matrix, whole.matrix);
    // Errors from a list name the shards' files.
    std::ofstream(dir / "twice.shards") << "a.tm\na.tm\nsub/b.tm\n";
    try {
        readTransportFile(dir / "twice.shards");
        ADD_FAILURE() << "overlap not refused";
    } catch (const InputError& e) {
        const std::string m = e.what();
        EXPECT_NE(m.find("row 0 is in two shards"), std::string::npos) << m;
        EXPECT_NE(m.find("a.tm and "), std::string::npos) << m;
        EXPECT_NE(m.find("twice.shards"), std::string::npos) << m;
    }
    // A list that lists a list (itself, here) is refused, not followed.
    std::ofstream(dir / "self.shards") << "a.tm\nself.shards\n";
    EXPECT_THROW(readTransportFile(dir / "self.shards"), InputError);
}

TEST(Shards, RefusesOverlapsGapsOtherInputsAndWholeMatrices) {
    const ShardScene s;
    auto message = [](std::vector<TransportFile> shards) {
        try {
            mergeTransportShards(std::move(shards), "list.shards");
        } catch (const InputError& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    std::string m = message({s.trace(0, 12), s.trace(10, 20)});
    EXPECT_NE(m.find("row 10 is in two shards"), std::string::npos) << m;
    m = message({s.trace(0, 8), s.trace(10, 20)});
    EXPECT_NE(m.find("no shard has image row 8"), std::string::npos) << m;
    m = message({s.trace(0, 10), s.trace(10, 20, 4)});
    EXPECT_NE(m.find("other inputs"), std::string::npos) << m;
    m = message({s.trace(0, 0)});
    EXPECT_NE(m.find("not a shard"), std::string::npos) << m;
    EXPECT_NE(m.find("list.shards"), std::string::npos) << m;
    m = message({});
    EXPECT_NE(m.find("no shard"), std::string::npos) << m;
}

// The command line: two `precompute --rows` shards in a list give `optimize` the same light as
// the whole T; a bad range is a usage error (2) or an input error (1) naming --rows.
TEST(Shards, PrecomputeRowsAndOptimizeOnTheList) {
    test::TempDir dir("shards-cli");
    const std::string scene = std::string(SL_SOURCE_DIR) + "/scenes/default/scene.json";
    const std::string base = "precompute " + scene + " --size 24 --spp 4 --halves";
    const std::string d = dir.path().string() + "/";
    ASSERT_EQ(test::runCli(base + " -o " + d + "whole.tm").exitCode, 0);
    ASSERT_EQ(test::runCli(base + " --rows 0:9 -o " + d + "a.tm").exitCode, 0);
    ASSERT_EQ(test::runCli(base + " --rows 9:24 -o " + d + "b.tm").exitCode, 0);
    std::ofstream(dir / "t.shards") << "a.tm\nb.tm\n";
    auto r = test::runCli("optimize " + d + "whole.tm -o " + d + "o1");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    r = test::runCli("optimize " + d + "t.shards -o " + d + "o2");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    auto bytes = [](const std::filesystem::path& p) {
        std::ifstream in(p, std::ios::binary);
        return std::string(std::istreambuf_iterator<char>(in), {});
    };
    const std::string e1 = bytes(dir / "o1" / "envmap.exr");
    EXPECT_FALSE(e1.empty());
    EXPECT_EQ(e1, bytes(dir / "o2" / "envmap.exr"));
    r = test::runCli(base + " --rows 3-5 -o " + d + "c.tm");
    EXPECT_EQ(r.exitCode, 2) << r.output;
    r = test::runCli(base + " --rows 20:30 -o " + d + "c.tm");
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("--rows"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "c.tm"));
}

// scripts/slurm-precompute: its job array, each task run here as Slurm would (by its task id),
// leaves shards whose list is the whole T.
TEST(Shards, SlurmScriptsTasksGiveTheWholeMatrix) {
    test::TempDir dir("shards-slurm");
    const std::string scene = std::string(SL_SOURCE_DIR) + "/scenes/default/scene.json";
    const std::string d = dir.path().string();
    auto r = test::runSlurmPrecompute(scene, 20, 3, d + "/job", "--size 20 --spp 4");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    ASSERT_EQ(
        test::runCli("precompute " + scene + " --size 20 --spp 4 -o " + d + "/whole.tm").exitCode,
        0);
    const TransportFile whole = readTransportFile(dir / "whole.tm");
    const TransportFile merged =
        readTransportFile(dir.path() / "job" / "T.shards", whole.provenance.fingerprint);
    expectSameMatrix(merged.matrix, whole.matrix);
    r = test::runShell(std::string(SL_SOURCE_DIR) + "/scripts/slurm-precompute " + scene +
                       " 20 30 " + d + "/bad");
    EXPECT_EQ(r.exitCode, 2) << r.output;
    EXPECT_NE(r.output.find("SHARDS"), std::string::npos) << r.output;
}

}  // namespace
