#include "app/Cache.h"

#include <cstdio>
#include <cstdlib>
#include <string>
#include <system_error>

namespace sl {

namespace fs = std::filesystem;

namespace {

/// A file this cache writes: transport-<hex>.tm, or its temporary while written.
bool isCacheFile(const fs::path& p) {
    const std::string name = p.filename().string();
    return name.rfind("transport-", 0) == 0 && name.find(".tm") != std::string::npos;
}

const char* env(const char* name) {
    const char* v = std::getenv(name);
    return v && *v ? v : nullptr;
}

}  // namespace

fs::path cacheDirectory(const CacheLocation& location) {
    if (location.disabled) return {};
    if (location.dir) return *location.dir;
    if (const char* d = env("SCRATCHLIGHT_CACHE")) return d;
    if (const char* x = env("XDG_CACHE_HOME")) return fs::path(x) / "scratchlight";
    if (const char* h = env("HOME")) return fs::path(h) / ".cache" / "scratchlight";
    return {};
}

namespace {

/// The cache files of `dir` for which `count(path)` is true (it may remove the file first),
/// with their sizes.
template <class Count>
CacheContents cacheFiles(const fs::path& dir, Count&& count) {
    CacheContents c;
    c.dir = dir;
    std::error_code ec;
    if (dir.empty() || !fs::is_directory(dir, ec)) return c;
    for (const auto& e : fs::directory_iterator(dir, ec)) {
        if (!e.is_regular_file(ec) || !isCacheFile(e.path())) continue;
        const uintmax_t size = e.file_size(ec);
        if (!count(e.path())) continue;
        ++c.files;
        c.bytes += size;
    }
    return c;
}

}  // namespace

CacheContents cacheContents(const fs::path& dir) {
    return cacheFiles(dir, [](const fs::path&) { return true; });
}

CacheContents clearCache(const fs::path& dir) {
    return cacheFiles(dir, [](const fs::path& p) {
        std::error_code ec;
        return fs::remove(p, ec);
    });
}

std::string describeCache(const CacheContents& c) {
    if (c.dir.empty()) return "no cache";
    char buf[96];
    std::snprintf(buf, sizeof buf, ": %zu transport matri%s, %.1f MB", c.files,
                  c.files == 1 ? "x" : "ces", static_cast<double>(c.bytes) / 1e6);
    return c.dir.string() + buf;
}

}  // namespace sl
