#include "app/pipeline/Cache.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "io/AtomicFile.h"
#include "io/GramFile.h"
#include "io/TransportFile.h"
#include "objective/TransportLoss.h"

namespace sl {

namespace fs = std::filesystem;

namespace {

bool hexDigits(std::string_view s) {
    return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) {
        return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f');
    });
}

bool digits(std::string_view s) {
    return !s.empty() &&
           std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}

constexpr std::string_view kLightPrefix = "light-", kLightExt = ".json";

/// A derived light's file: JSON whose "key" is `key` and whose "values" are numbers.
std::optional<std::vector<double>> readLightFile(const fs::path& p, const std::string& key) {
    std::error_code ec;
    if (!fs::is_regular_file(p, ec) || fs::file_size(p, ec) > (64u << 20)) return std::nullopt;
    std::ifstream in(p);
    const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
    if (j.is_discarded() || !j.is_object() || j.value("key", std::string()) != key ||
        !j.contains("values") || !j["values"].is_array())
        return std::nullopt;
    std::vector<double> v;
    v.reserve(j["values"].size());
    for (const auto& x : j["values"]) {
        if (!x.is_number()) return std::nullopt;
        v.push_back(x.get<double>());
    }
    return v;
}

/// <prefix><key>.json holding that key (light-: a light, part-: a part's record): its first bytes
/// are writeCachedLight's (writePartRecord's) {"key":"<key>" (nlohmann writes the keys in order).
/// Only the start is read: listing and trimming the cache parsed every light's values three times a
/// run, ~0.06 s with fifty lights.
bool isKeyedJsonFile(const fs::path& p, std::string_view prefix) {
    const std::string name = p.filename().string();
    if (name.size() != prefix.size() + 32 + kLightExt.size() || name.rfind(prefix, 0) != 0 ||
        !name.ends_with(kLightExt))
        return false;
    const std::string key = name.substr(prefix.size(), 32);
    if (!hexDigits(key)) return false;
    const std::string head = "{\"key\":\"" + key + "\",";
    std::string got(head.size(), '\0');
    std::ifstream in(p, std::ios::binary);
    return in.read(got.data(), static_cast<std::streamsize>(got.size())) && got == head;
}

bool isLightFile(const fs::path& p) {
    return isKeyedJsonFile(p, kLightPrefix);
}

/// A transport matrix: transport-<fingerprint>.tm (transportCachePath).
constexpr std::string_view kTransportPrefix = "transport-", kTransportExt = ".tm";

/// A part's record (writePartRecord): part-<key>.json holding that key, as a light's file does.
constexpr std::string_view kPartPrefix = "part-";
bool isPartFile(const fs::path& p) {
    return isKeyedJsonFile(p, kPartPrefix);
}
fs::path partPath(const fs::path& dir, const std::string& key) {
    return dir / (std::string(kPartPrefix) + key + std::string(kLightExt));
}

constexpr std::string_view kGramPrefix = "gram-", kGramExt = ".gram";

/// gram-<key>.gram whose header holds that key (io/GramFile.h peekGramFile).
bool isGramFile(const fs::path& p) {
    const std::string name = p.filename().string();
    if (name.size() != kGramPrefix.size() + 32 + kGramExt.size() ||
        name.rfind(kGramPrefix, 0) != 0 || !name.ends_with(kGramExt))
        return false;
    const std::string key = name.substr(kGramPrefix.size(), 32);
    return hexDigits(key) && peekGramFile(p) == key;
}

fs::path gramPath(const fs::path& dir, const std::string& key) {
    return dir / (std::string(kGramPrefix) + key + std::string(kGramExt));
}

/// Counts a cache file in `c` by its kind (by its name: it may be removed already).
void countFile(CacheContents& c, const fs::path& p) {
    const fs::path ext = p.extension();
    const bool part = p.filename().string().rfind(kPartPrefix, 0) == 0;
    ++(ext == kTransportExt ? c.files : ext == kGramExt ? c.grams : part ? c.parts : c.lights);
}

/// A file this cache wrote, by its name and its content, never by the name alone:
/// transport-<fingerprint>.tm whose header holds that fingerprint (the cache names each matrix
/// by it), or the temporary of one while written (io/AtomicFile.h:
/// .transport-<fingerprint>.tmp-<pid>-<n>.tm) that is empty or starts as a .tm file does; or a
/// derived light, light-<key>.json holding that key; a part's record, part-<key>.json holding
/// it (app/pipeline/PartOfTransport.h); or a Gram file, gram-<key>.gram holding it.
bool isCacheFile(const fs::path& p) {
    if (isLightFile(p) || isGramFile(p) || isPartFile(p)) return true;
    const std::string name = p.filename().string();
    if (name.size() > kTransportPrefix.size() + kTransportExt.size() &&
        name.rfind(kTransportPrefix, 0) == 0 && name.ends_with(kTransportExt)) {
        const std::string fp = name.substr(
            kTransportPrefix.size(), name.size() - kTransportPrefix.size() - kTransportExt.size());
        if (fp.size() != 32 || !hexDigits(fp)) return false;
        std::string inFile;
        return peekTransportFile(p, &inFile) == 2 && inFile == fp;
    }
    // .transport-<fp>.tmp-<pid>-<n>.tm (io/AtomicFile.h's temporary beside transport-<fp>.tm)
    std::string tmpPrefix(1, '.');
    tmpPrefix.append(kTransportPrefix);
    if (name.size() < tmpPrefix.size() + kTransportExt.size() || name.rfind(tmpPrefix, 0) != 0 ||
        !name.ends_with(kTransportExt))
        return false;
    const std::string rest =
        name.substr(tmpPrefix.size(), name.size() - tmpPrefix.size() - kTransportExt.size());
    const size_t tmp = rest.find(".tmp-");
    if (tmp != 32 || !hexDigits(rest.substr(0, 32))) return false;
    const std::string ids = rest.substr(tmp + 5);
    const size_t dash = ids.find('-');
    if (dash == std::string::npos || !digits(ids.substr(0, dash)) || !digits(ids.substr(dash + 1)))
        return false;
    std::error_code ec;
    return fs::file_size(p, ec) == 0 || peekTransportFile(p) > 0;
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

fs::path transportCachePath(const fs::path& dir, const std::string& fingerprint) {
    return dir / (std::string(kTransportPrefix) + fingerprint + std::string(kTransportExt));
}

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
        countFile(c, e.path());
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
        if (p.extension() == kTransportExt || p.extension() == kGramExt || isLightFile(p) ||
            isPartFile(p))
            entries.push_back({p, fs::last_write_time(p, ec), size});
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
        countFile(removed, e.path);
        removed.bytes += e.bytes;
    }
    return removed;
}

std::optional<std::vector<double>> readCachedLight(const fs::path& dir, const std::string& key) {
    if (dir.empty()) return std::nullopt;
    const fs::path file = dir / (std::string(kLightPrefix) + key + std::string(kLightExt));
    auto v = readLightFile(file, key);
    if (v) touchCacheFile(file);
    return v;
}

void writeCachedLight(const fs::path& dir, const std::string& key, const std::string& what,
                      std::span<const double> values) {
    if (dir.empty()) return;
    const nlohmann::json j = {{"key", key},
                              {"what", what},
                              {"values", std::vector<double>(values.begin(), values.end())}};
    try {
        std::error_code ec;
        fs::create_directories(dir, ec);
        // nlohmann writes doubles so that they read back bit for bit.
        writeTextAtomically(dir / (std::string(kLightPrefix) + key + std::string(kLightExt)),
                            j.dump() + "\n");
    } catch (const std::exception& e) {
        spdlog::warn("cache {}: the {} was not stored: {}", dir.string(), what, e.what());
    }
}

std::optional<nlohmann::json> readPartRecord(const fs::path& dir, const std::string& key) {
    if (dir.empty()) return std::nullopt;
    const fs::path file = partPath(dir, key);
    std::error_code ec;
    if (!fs::is_regular_file(file, ec) || fs::file_size(file, ec) > (16u << 20))
        return std::nullopt;
    std::ifstream in(file);
    nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
    if (j.is_discarded() || !j.is_object() || j.value("key", std::string()) != key ||
        !j.contains("record") || !j["record"].is_object())
        return std::nullopt;
    touchCacheFile(file);
    return std::move(j["record"]);
}

void writePartRecord(const fs::path& dir, const std::string& key, const std::string& what,
                     const nlohmann::json& record) {
    if (dir.empty()) return;
    const nlohmann::json j = {{"key", key}, {"what", what}, {"record", record}};
    try {
        std::error_code ec;
        fs::create_directories(dir, ec);
        writeTextAtomically(partPath(dir, key), j.dump() + "\n");
    } catch (const std::exception& e) {
        spdlog::warn("cache {}: the {} was not stored: {}", dir.string(), what, e.what());
    }
}

std::shared_ptr<const TransportGram> cachedGram(const fs::path& dir, const std::string& fingerprint,
                                                const TransportLoss& loss) {
    if (dir.empty() || fingerprint.empty() || !loss.gramEligible()) return nullptr;
    const std::string key = loss.gramKey(fingerprint);
    const fs::path file = gramPath(dir, key);
    // A stored file answers gramPays without its pass over T (TransportGram::buildWork, ~3 % of a
    // re-optimization's CPU): only a loss whose build paid stores one, and the key holds all that
    // decides it (T, its shape, the products and the pairs).
    std::error_code statError;
    const bool stored = fs::is_regular_file(file, statError);
    if (!stored && !loss.gramPays()) return nullptr;
    if (loss.shareHeldGram()) return loss.gramIfBuilt();  // held by another loss on this T
    if (auto read = stored ? readGramFile(file, key, loss.matrix().cols()) : std::nullopt) {
        touchCacheFile(file);
        loss.adoptGram(std::make_shared<const TransportGram>(std::move(*read)));
        spdlog::debug("T's Gram matrices from cache {}", file.string());
        return loss.gramIfBuilt();
    }
    if (!loss.gramPays()) return nullptr;
    const TransportGram& built = loss.gram();
    try {
        std::error_code ec;
        fs::create_directories(dir, ec);
        writeGramFile(file, key, built);
    } catch (const std::exception& e) {
        spdlog::warn("cache {}: T's Gram matrices were not stored: {}", dir.string(), e.what());
    }
    return loss.gramIfBuilt();
}

void touchCacheFile(const fs::path& file) {
    std::error_code ec;
    fs::last_write_time(file, fs::file_time_type::clock::now(), ec);
}

std::string describeCache(const CacheContents& c) {
    if (c.dir.empty()) return "no cache";
    char buf[96];
    std::string lights;
    if (c.lights > 0)
        lights = ", " + std::to_string(c.lights) + " derived light" + (c.lights == 1 ? "" : "s");
    std::snprintf(buf, sizeof buf, ": %zu transport matri%s", c.files, c.files == 1 ? "x" : "ces");
    if (c.grams > 0)
        lights += ", " + std::to_string(c.grams) + " Gram matri" + (c.grams == 1 ? "x" : "ces");
    if (c.parts > 0)
        lights += ", " + std::to_string(c.parts) + " part record" + (c.parts == 1 ? "" : "s");
    std::string out = c.dir.string() + buf + lights;
    std::snprintf(buf, sizeof buf, ", %.1f MB", static_cast<double>(c.bytes) / 1e6);
    return out + buf;
}

}  // namespace sl
