// The transport-matrix cache: where optimize and judge keep the matrices they trace from a
// scene (transport-<fingerprint>.tm, app/Transport.h), so a second run with the same scene,
// camera, material, height map and sampling reads T instead of tracing it. A matrix's
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
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>

namespace sl {

struct CacheLocation {
    std::optional<std::filesystem::path> dir;  // unset: the default (above)
    bool disabled = false;
};

/// The folder (empty: no cache).
std::filesystem::path cacheDirectory(const CacheLocation& location);

struct CacheContents {
    std::filesystem::path dir;
    size_t files = 0;  // transport matrices
    uintmax_t bytes = 0;
};

/// What `dir` holds (0 files when it does not exist).
CacheContents cacheContents(const std::filesystem::path& dir);

/// Removes the cache's files from `dir`: the matrices it wrote (transport-<fingerprint>.tm whose
/// header holds that fingerprint) and their temporaries; never a file by its name alone, so a
/// folder given by mistake loses nothing else. Returns what was removed.
CacheContents clearCache(const std::filesystem::path& dir);

/// "DIR: 3 transport matrices, 118 MB" (or "no cache").
std::string describeCache(const CacheContents& contents);

}  // namespace sl
