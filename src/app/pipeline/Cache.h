// The transport-matrix cache: where optimize and judge keep the matrices they trace from a
// scene (transport-<fingerprint>.tm, app/pipeline/Transport.h), so a second run with the same
// scene, camera, material, height map and sampling reads T instead of tracing it. A matrix's
// fingerprint covers every input that changes it, so a stale entry is never used; an entry
// that fails to read is traced again.
//
// Where (the first that applies):
//   CacheLocation::dir given            that folder (the command line's --cache DIR)
//   CacheLocation::disabled             no cache: every run traces (--no-cache)
//   $SCRATCHLIGHT_CACHE                 that folder
//   $XDG_CACHE_HOME/scratchlight        the XDG base-directory rule
//   $HOME/.cache/scratchlight
//   none when HOME is unset either.
// A matrix at the paper's 512² and 1024 spp takes ~40 MB; cacheContents() says how much the
// folder holds and clearCache() removes the matrices (only files this cache writes).
// Size cap: cacheDirectory() trims the folder to CacheLocation::maxBytes (default
// kDefaultCacheMaxBytes) when a command asks for it, least recently used matrix first (a
// matrix's modification time is its last use: a cache hit refreshes it, touchCacheFile).
// Beside the matrices it keeps lights derived from them (light-<key>.json: the paper's light
// optimize computes on its T, and its specular start), so a run on the same T does not compute them
// again; they go with the matrices (listed, trimmed and cleared alike) and are a few kB each.
// Beside them, T's Gram matrices (gram-<key>.gram, io/GramFile.h: the noise-unbiased objective's
// quadratic forms, transport/TransportGram.h), so a run on a cached T does not build them again: a
// few MB each (670² doubles on the bundled part at 256²), trimmed and cleared with the matrices.
// Beside them, a part's record (part-<key>.json, app/pipeline/PartOfTransport.h): what a run on a
// .tm needs of its scene besides its estimates, so that it does not load the height map.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace sl {

class TransportGram;
class TransportLoss;

/// The cache's default size cap: a few 512², 1024-spp matrices of several parts.
inline constexpr uintmax_t kDefaultCacheMaxBytes = 4'000'000'000;

struct CacheLocation {
    std::optional<std::filesystem::path> dir;  // unset: the default (above)
    bool disabled = false;
    std::optional<uintmax_t> maxBytes;  // size cap (unset: kDefaultCacheMaxBytes)
};

/// The folder (empty: no cache), trimmed to the location's size cap (trimCache; what it removes
/// is logged).
std::filesystem::path cacheDirectory(const CacheLocation& location);

struct CacheContents {
    std::filesystem::path dir;
    size_t files = 0;   // transport matrices
    size_t lights = 0;  // lights derived from them (light-<key>.json)
    size_t grams = 0;   // their Gram matrices (gram-<key>.gram)
    size_t parts = 0;   // their parts' records (part-<key>.json)
    uintmax_t bytes = 0;
};

/// What `dir` holds (0 files when it does not exist).
CacheContents cacheContents(const std::filesystem::path& dir);

/// Removes the cache's files from `dir`: the matrices it wrote (transport-<fingerprint>.tm whose
/// header holds that fingerprint) and their temporaries; never a file by its name alone, so a
/// folder given by mistake loses nothing else. Returns what was removed.
CacheContents clearCache(const std::filesystem::path& dir);

/// Removes the least recently used transport matrices of `dir` (oldest modification time first;
/// finished transport-*.tm only) until the rest holds at most maxBytes. Returns what was removed.
CacheContents trimCache(const std::filesystem::path& dir, uintmax_t maxBytes);

/// A light derived from a traced T, read from dir/light-<key>.json: `key` is 32 hex digits over
/// T's fingerprint and every other input of the result (the caller's). Its values as written,
/// bit for bit; nullopt when dir is empty or the file is missing, damaged or holds another key.
/// A hit marks the file used (touchCacheFile).
std::optional<std::vector<double>> readCachedLight(const std::filesystem::path& dir,
                                                   const std::string& key);

/// Stores a derived light as dir/light-<key>.json (atomically; `what` says what it is). Does
/// nothing when dir is empty; a failed write is logged, not thrown: the cache only saves time.
void writeCachedLight(const std::filesystem::path& dir, const std::string& key,
                      const std::string& what, std::span<const double> values);

/// A part's record kept beside T (app/pipeline/PartOfTransport.h): dir/part-<key>.json, `key` 32
/// hex digits, its record as written; nullopt when dir is empty or the file is missing, damaged
/// or holds another key. A hit marks the file used (touchCacheFile).
std::optional<nlohmann::json> readPartRecord(const std::filesystem::path& dir,
                                             const std::string& key);
/// Stores a part's record as dir/part-<key>.json (atomically), as writeCachedLight stores a light.
void writePartRecord(const std::filesystem::path& dir, const std::string& key,
                     const std::string& what, const nlohmann::json& record);
/// T's Gram matrices for `loss` (TransportLoss::gram) kept in `dir` by T's `fingerprint`
/// (TransportLoss::gramKey): those another loss on the same T holds (TransportLoss::
/// shareHeldGram), else read from dir/gram-<key>.gram and installed in the loss
/// (TransportLoss::adoptGram) when stored there, else built now and stored. Returns them, to be
/// held while the losses on this T run (every loss on the same T and pair mask shares them);
/// null, doing nothing, when the loss does not use them (not eligible, or their build does not
/// pay: TransportLoss::gramPays, asked only when no file is stored under the key: a stored file
/// was written by a paying build of the same key) or dir or fingerprint is empty. A failed write
/// is logged, not thrown: the cache only saves time.
std::shared_ptr<const TransportGram> cachedGram(const std::filesystem::path& dir,
                                                const std::string& fingerprint,
                                                const TransportLoss& loss);

/// Where the cache in `dir` keeps the transport matrix of `fingerprint`:
/// transport-<fingerprint>.tm (the name isCacheFile checks against the file's header).
std::filesystem::path transportCachePath(const std::filesystem::path& dir,
                                         const std::string& fingerprint);

/// Marks a cache file as used now (its modification time), for trimCache's order.
void touchCacheFile(const std::filesystem::path& file);

/// "DIR: 3 transport matrices, 118 MB" (", 1 derived light" and ", 1 Gram matrix" after the
/// matrices when there are any; or "no cache").
std::string describeCache(const CacheContents& contents);

}  // namespace sl
