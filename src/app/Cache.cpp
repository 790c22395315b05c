#include "app/Cache.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <system_error>
#include <vector>

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

namespace {

fs::path locate(const CacheLocation& location) {
    if (location.disabled) return {};
    if (location.dir) return *location.dir;
    if (const char* d = env("SCRATCHLIGHT_CACHE")) return d;
    if (const char* x = env("XDG_CACHE_HOME")) return fs::path(x) / "scratchlight";
    if (const char* h = env("HOME")) return fs::path(h) / ".cache" / "scratchlight";
    return {};
}

}  // namespace

fs::path cacheDirectory(const CacheLocation& location) {
    const fs::path dir = locate(location);
    const uintmax_t cap = location.maxBytes.value_or(kDefaultCacheMaxBytes);
    const CacheContents removed = trimCache(dir, cap);
    if (removed.files > 0)
        spdlog::info(
            "cache {}: removed the {} least recently used transport matri{} ({:.1f} MB) "
            "to stay under its cap of {:.1f} MB",
            dir.string(), removed.files, removed.files == 1 ? "x" : "ces",
            static_cast<double>(removed.bytes) / 1e6, static_cast<double>(cap) / 1e6);
    return dir;
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

CacheContents trimCache(const fs::path& dir, uintmax_t maxBytes) {
    struct Entry {
        fs::path path;
        fs::file_time_type used;
        uintmax_t bytes;
    };
    std::vector<Entry> entries;
    uintmax_t total = 0;
    cacheFiles(dir, [&](const fs::path& p) {
        std::error_code ec;
        const uintmax_t size = fs::file_size(p, ec);
        if (ec) return false;
        total += size;
        if (p.extension() == ".tm") entries.push_back({p, fs::last_write_time(p, ec), size});
        return true;
    });
    CacheContents removed;
    removed.dir = dir;
    std::sort(entries.begin(), entries.end(),
              [](const Entry& a, const Entry& b) { return a.used < b.used; });
    for (const Entry& e : entries) {
        if (total <= maxBytes) break;
        std::error_code ec;
        if (!fs::remove(e.path, ec)) continue;
        total -= e.bytes;
        ++removed.files;
        removed.bytes += e.bytes;
    }
    return removed;
}

void touchCacheFile(const fs::path& file) {
    std::error_code ec;
    fs::last_write_time(file, fs::file_time_type::clock::now(), ec);
}

std::string describeCache(const CacheContents& c) {
    if (c.dir.empty()) return "no cache";
    char buf[96];
    std::snprintf(buf, sizeof buf, ": %zu transport matri%s, %.1f MB", c.files,
                  c.files == 1 ? "x" : "ces", static_cast<double>(c.bytes) / 1e6);
    return c.dir.string() + buf;
}

}  // namespace sl
