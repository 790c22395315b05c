// The transport-matrix cache (app/pipeline/Cache.h): where it is, that optimize and judge use it
// and say so, --cache/--no-cache, and `scratchlight cache [clear]`. This file also gives every test
// process its own cache folder, so no test reads what another traced.
#include <gtest/gtest.h>
#include <stdlib.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "TestUtil.h"
#include "app/pipeline/Cache.h"
#include "io/TransportFile.h"
#include "transport/TransportMatrix.h"

using namespace sl;
namespace fs = std::filesystem;

namespace {

/// One fresh cache per test process (ctest runs each test in its own), removed at exit; the
/// CLI the tests start inherits it through the environment.
struct ProcessCache {
    test::TempDir dir{"cache"};
    ProcessCache() { ::setenv("SCRATCHLIGHT_CACHE", dir.path().c_str(), 1); }
};
const ProcessCache gProcessCache;

size_t countTm(const fs::path& dir) {
    return cacheContents(dir).files;
}

}  // namespace

TEST(Cache, LocationFollowsFlagThenEnvironmentThenXdg) {
    CacheLocation given;
    given.dir = "/some/where";
    EXPECT_EQ(cacheDirectory(given), fs::path("/some/where"));
    CacheLocation off;
    off.disabled = true;
    EXPECT_TRUE(cacheDirectory(off).empty());
    EXPECT_EQ(cacheDirectory({}), gProcessCache.dir.path());  // $SCRATCHLIGHT_CACHE
    const std::string saved = std::getenv("SCRATCHLIGHT_CACHE");
    ::unsetenv("SCRATCHLIGHT_CACHE");
    ::setenv("XDG_CACHE_HOME", "/xdg", 1);
    EXPECT_EQ(cacheDirectory({}), fs::path("/xdg/scratchlight"));
    ::unsetenv("XDG_CACHE_HOME");
    ::setenv("HOME", "/home/inspector", 1);
    EXPECT_EQ(cacheDirectory({}), fs::path("/home/inspector/.cache/scratchlight"));
    ::setenv("SCRATCHLIGHT_CACHE", saved.c_str(), 1);
}

// The size cap: least recently used first (a hit refreshes a matrix's time), nothing but the
// cache's own finished matrices, and the command line's --cache-max reaches it.
TEST(Cache, SizeCapRemovesTheLeastRecentlyUsedFirst) {
    test::TempDir dir("cache-cap");
    // The cache's own files (a header holding the fingerprint each is named by), ~the same size.
    const TransportMatrix t = test::tinyTransportMatrix();
    auto cacheFile = [&](char c) {
        const std::string fp(32, c);
        TransportProvenance prov;
        prov.fingerprint = fp;
        prov.inputs = "{}";
        const fs::path f = dir / ("transport-" + fp + ".tm");
        writeTransportFile(f, t, prov);
        return f;
    };
    const fs::path a = cacheFile('a'), b = cacheFile('b'), c = cacheFile('c');
    const uintmax_t size = fs::file_size(a);
    test::writeText(dir / "other.tm", std::string(1000, 'x'));
    const auto now = fs::file_time_type::clock::now();
    int age = 4;
    for (const fs::path& f : {a, b, c, dir / "other.tm"})
        fs::last_write_time(f, now - std::chrono::hours(age--));
    touchCacheFile(a);  // the oldest, used now
    const CacheContents removed = trimCache(dir.path(), size + size / 2);
    EXPECT_EQ(removed.files, 2u);
    EXPECT_EQ(removed.bytes, 2 * size);
    EXPECT_TRUE(fs::exists(a));
    EXPECT_FALSE(fs::exists(b));
    EXPECT_FALSE(fs::exists(c));
    EXPECT_TRUE(fs::exists(dir / "other.tm"));  // not the cache's
    EXPECT_EQ(trimCache(dir.path(), size + size / 2).files, 0u);

    CacheLocation capped;
    capped.dir = dir.path();
    capped.maxBytes = 0;
    EXPECT_EQ(cacheDirectory(capped), dir.path());
    EXPECT_FALSE(fs::exists(a));
    EXPECT_TRUE(fs::exists(dir / "other.tm"));

    const fs::path d = cacheFile('d');
    const auto r = test::runCli("judge " + std::string(SL_SOURCE_DIR) +
                                "/scenes/default/scene.json --cache " + dir.path().string() +
                                " --cache-max 500 --size 8 --spp 2 -o " + (dir / "j").string());
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("least recently used"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(d));
    EXPECT_EQ(test::runCli("judge x.json --cache-max lots").exitCode, 2);
}

// Issue 35: `cache clear` deleted a user's transport-notes.tm by its name alone. A file is the
// cache's only when its content says so (a .tm header holding the fingerprint it is named by).
TEST(Cache, ClearRemovesOnlyTheCachesFiles) {
    test::TempDir dir("cache-clear");
    const std::string fp = "0123456789abcdef0123456789abcdef";
    const TransportMatrix t = test::tinyTransportMatrix();
    TransportProvenance prov;
    prov.fingerprint = fp;
    prov.inputs = "{}";
    writeTransportFile(dir / ("transport-" + fp + ".tm"), t, prov);
    const uintmax_t tmBytes = fs::file_size(dir / ("transport-" + fp + ".tm"));
    // A temporary of a killed run, cut short after the magic.
    test::writeText(dir / (".transport-" + fp + ".tmp-123-0.tm"), "SLTMATRX");
    // The user's files, however their names look.
    test::writeText(dir / "transport-notes.tm", "the user's notes");
    test::writeText(dir / ("transport-" + std::string(32, 'f') + ".tm"), std::string(100, 'x'));
    prov.fingerprint = std::string(32, 'e');  // a real matrix, but not named by its fingerprint
    writeTransportFile(dir / ("transport-" + std::string(32, 'd') + ".tm"), t, prov);
    test::writeText(dir / (".transport-" + fp + ".tmp-1-2.tm"), "a user's draft");
    test::writeText(dir / "notes.txt", "the user's");
    const CacheContents before = cacheContents(dir.path());
    EXPECT_EQ(before.files, 2u);
    EXPECT_EQ(before.bytes, tmBytes + 8);
    const CacheContents removed = clearCache(dir.path());
    EXPECT_EQ(removed.files, 2u);
    EXPECT_FALSE(fs::exists(dir / ("transport-" + fp + ".tm")));
    for (const std::string& kept :
         {std::string("transport-notes.tm"), "transport-" + std::string(32, 'f') + ".tm",
          "transport-" + std::string(32, 'd') + ".tm", ".transport-" + fp + ".tmp-1-2.tm",
          std::string("notes.txt")})
        EXPECT_TRUE(fs::exists(dir / kept)) << kept;
    EXPECT_EQ(cacheContents(dir.path()).files, 0u);
    EXPECT_EQ(cacheContents(dir / "missing").files, 0u);
}

TEST(Cache, OptimizeUsesItSaysSoAndTheCommandClearsIt) {
    test::TempDir dir("cache-cli");
    const std::string scene = std::string(SL_SOURCE_DIR) + "/scenes/default/scene.json";
    const fs::path cache = dir / "c";
    const std::string common =
        " --size 32 --spp 4 --heldout-spp 8 --iterations 5 --cache " + cache.string() + " -o ";
    auto r = test::runCli("optimize " + scene + common + (dir / "a").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    // Training T (two halves), the validation estimate and the judge's estimate.
    EXPECT_EQ(countTm(cache), 3u) << r.output;
    EXPECT_NE(r.output.find("cache " + cache.string() + ": 3 transport matrices"),
              std::string::npos)
        << r.output;
    // The paper's light on T and the specular start are kept beside it (issue 32: nothing
    // done twice).
    EXPECT_NE(r.output.find(": 3 transport matrices, 2 derived lights"), std::string::npos)
        << r.output;
    EXPECT_EQ(r.output.find("the paper's light on T from cache"), std::string::npos) << r.output;
    r = test::runCli("optimize " + scene + common + (dir / "b").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("transport matrix from cache"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("the paper's light on T from cache"), std::string::npos) << r.output;
    // The same light, bit for bit: the same file and the same scores.
    EXPECT_EQ(test::readFile(dir / "a" / "compare-paper-envmap.exr"),
              test::readFile(dir / "b" / "compare-paper-envmap.exr"));
    EXPECT_EQ(test::readFile(dir / "a" / "plot-data.json"),
              test::readFile(dir / "b" / "plot-data.json"));

    // --no-cache traces and keeps nothing.
    r = test::runCli("optimize " + scene +
                     " --size 32 --spp 4 --heldout-spp 8 --iterations 5 --no-cache -o " +
                     (dir / "n").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_EQ(r.output.find("from cache"), std::string::npos) << r.output;
    EXPECT_EQ(countTm(gProcessCache.dir.path()), 0u);

    r = test::runCli("cache --cache " + cache.string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("3 transport matrices"), std::string::npos) << r.output;
    r = test::runCli("cache clear --cache " + cache.string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("removed 3 transport matrices and 2 derived lights"), std::string::npos)
        << r.output;
    EXPECT_EQ(countTm(cache), 0u);
    EXPECT_EQ(cacheContents(cache).lights, 0u);
}

namespace {

/// A summary without what the clock measured (every "seconds..." key, at any depth).
nlohmann::json withoutSeconds(nlohmann::json j) {
    if (j.is_object()) {
        for (auto it = j.begin(); it != j.end();)
            if (it.key().rfind("seconds", 0) == 0)
                it = j.erase(it);
            else
                *it++ = withoutSeconds(*it);
    } else if (j.is_array()) {
        for (auto& x : j) x = withoutSeconds(x);
    }
    return j;
}

}  // namespace

// Issue 32: a re-optimization of a .tm whose estimates are cached reads no height map. The first
// run loads the scene and keeps the part's record beside T (app/pipeline/PartOfTransport.h); the
// next finds V by T's recorded inputs, the specular start and the record in the cache, so it runs
// with the height map deleted, and writes the same answer and summary bit for bit.
TEST(Cache, ATmRunOnCachedEstimatesReadsNoHeightMap) {
    test::TempDir dir("cache-tm-part");
    ASSERT_EQ(test::writeSmallLabelledPart(dir.path()), 0);
    const fs::path cache = dir / "cache", tm = dir / "part.tm";
    auto r = test::runCli("precompute " + (dir / "scene.json").string() +
                          " --size 32 --spp 4 --halves -o " + tm.string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const std::string common = "optimize " + tm.string() + " --lambda 10 --heldout none --cache " +
                               cache.string() + " -o ";
    r = test::runCli(common + (dir / "a").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_EQ(cacheContents(cache).parts, 1u) << r.output;
    r = test::runCli(common + (dir / "b").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    fs::remove(dir / "part.exr");
    r = test::runCli(common + (dir / "c").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("part part.exr"), std::string::npos) << r.output;  // as loaded
    const auto summary = [&](const char* run) {
        return withoutSeconds(nlohmann::json::parse(test::readFile(dir / run / "summary.json")));
    };
    nlohmann::json a = summary("a");
    ASSERT_TRUE(a.contains("part") && a.contains("heightmap") && a.contains("validation"));
    // The command line (its output folder) differs, and V was traced by the first run only.
    a.erase("scratchlight");
    ASSERT_FALSE(a["validation"]["transport"]["cache_hit"].get<bool>());
    a["validation"]["transport"]["cache_hit"] = true;
    for (const char* run : {"b", "c"}) {
        nlohmann::json s = summary(run);
        s.erase("scratchlight");
        EXPECT_EQ(s.dump(), a.dump()) << run;
        EXPECT_EQ(test::readFile(dir / run / "plot-data.json"),
                  test::readFile(dir / "a" / "plot-data.json"))
            << run;
        EXPECT_EQ(test::readFile(dir / run / "envmap.exr"),
                  test::readFile(dir / "a" / "envmap.exr"))
            << run;
    }
    // The part's record goes with the matrices.
    EXPECT_EQ(clearCache(cache).parts, 1u);
}

// A light derived from T (the paper's light) is read back bit for bit, only under its own key,
// and is listed, trimmed and cleared with the matrices.
TEST(Cache, DerivedLightsReadBackExactlyUnderTheirKeyAndGoWithTheMatrices) {
    test::TempDir dir("cache-lights");
    const std::string key(32, 'a'), other(32, 'b');
    const std::vector<double> e{0.1, 1.0 / 3.0, 2e-300, 0.0, 123456.789012345678};
    EXPECT_FALSE(readCachedLight(dir.path(), key));
    writeCachedLight(dir.path(), key, "a test light", e);
    const auto back = readCachedLight(dir.path(), key);
    ASSERT_TRUE(back);
    EXPECT_EQ(*back, e);  // exactly
    EXPECT_FALSE(readCachedLight(dir.path(), other));
    EXPECT_FALSE(readCachedLight({}, key));
    writeCachedLight({}, key, "nowhere", e);  // no cache: nothing, no error
    // A file named like one but holding another key, or not JSON: not the cache's.
    test::writeText(dir / ("light-" + other + ".json"),
                    "{\"key\": \"" + key + "\", \"values\": []}");
    test::writeText(dir / ("light-" + std::string(32, 'c') + ".json"), "the user's notes");
    EXPECT_FALSE(readCachedLight(dir.path(), other));
    const CacheContents c = cacheContents(dir.path());
    EXPECT_EQ(c.files, 0u);
    EXPECT_EQ(c.lights, 1u);
    EXPECT_NE(describeCache(c).find("0 transport matrices, 1 derived light"), std::string::npos)
        << describeCache(c);
    EXPECT_EQ(trimCache(dir.path(), 0).lights, 1u);
    EXPECT_FALSE(readCachedLight(dir.path(), key));
    writeCachedLight(dir.path(), key, "a test light", e);
    EXPECT_EQ(clearCache(dir.path()).lights, 1u);
    EXPECT_TRUE(fs::exists(dir / ("light-" + other + ".json")));
    EXPECT_TRUE(fs::exists(dir / ("light-" + std::string(32, 'c') + ".json")));
}
