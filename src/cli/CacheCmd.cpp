// scratchlight cache [--cache DIR]          where the cache is and what it holds
// scratchlight cache clear [--cache DIR]    removes its transport matrices
#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>

#include "app/pipeline/Cache.h"
#include "cli/Commands.h"
#include "cli/Common.h"

namespace sl::cli {

namespace {
struct CacheArgs {
    CacheLocation location;
    bool clear = false;
};

int runCache(const CacheArgs& a) {
    CacheLocation where = a.location;
    where.maxBytes = UINTMAX_MAX;  // looking trims nothing
    const auto dir = cacheDirectory(where);
    if (dir.empty()) {
        std::printf("no cache (HOME is not set; give --cache DIR or set SCRATCHLIGHT_CACHE)\n");
        return kOk;
    }
    if (a.clear) {
        const CacheContents removed = clearCache(dir);
        std::string lights;
        if (removed.lights > 0)
            lights = " and " + std::to_string(removed.lights) + " derived light" +
                     (removed.lights == 1 ? "" : "s");
        if (removed.grams > 0)
            lights += " and " + std::to_string(removed.grams) + " Gram matri" +
                      (removed.grams == 1 ? "x" : "ces");
        if (removed.parts > 0)
            lights += " and " + std::to_string(removed.parts) + " part record" +
                      (removed.parts == 1 ? "" : "s");
        std::printf("removed %zu transport matri%s%s (%.1f MB) from %s\n", removed.files,
                    removed.files == 1 ? "x" : "ces", lights.c_str(),
                    static_cast<double>(removed.bytes) / 1e6, dir.string().c_str());
        return kOk;
    }
    std::printf("%s\n", describeCache(cacheContents(dir)).c_str());
    std::printf(
        "optimize and judge keep the matrices they trace there (--cache DIR elsewhere, "
        "--no-cache not at all); `scratchlight cache clear` removes them\n");
    return kOk;
}
}  // namespace

void registerCache(CLI::App& app, std::function<int()>& run) {
    auto a = std::make_shared<CacheArgs>();
    CLI::App* c = app.add_subcommand(
        "cache", "Where the transport-matrix cache is, what it holds; `cache clear` empties it");
    c->add_option_function<std::string>(
        "--cache", [a](const std::string& d) { a->location.dir = d; },
        "The cache folder (default: $SCRATCHLIGHT_CACHE, else ~/.cache/scratchlight)");
    CLI::App* clear = c->add_subcommand("clear", "Remove the cache's transport matrices");
    clear->fallthrough();
    clear->callback([a] { a->clear = true; });
    c->callback([a, &run] { run = [a] { return runCache(*a); }; });
}

}  // namespace sl::cli
