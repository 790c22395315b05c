// Transport-matrix files (.tm): one binary file, little-endian.
//
//   "SLTMATRX" (8 bytes) | u32 format version | u32 header length | header (JSON text)
//   | u64 hash of the header text | sections, in the order the header lists them
//
// The header holds the dimensions, storage, nnz, env-map convention, what produced the matrix
// (the resolved scene parameters, height-map content hash, spp, seed, max_depth) with its
// fingerprint, and for every section (mask, row pointers, column indices, values) its offset,
// size and hash. Loading checks the magic, version, header hash, file size and every section's
// hash, and, when the caller knows which inputs it wants, the fingerprint: a damaged or stale
// file is refused with a message that says which and how to fix it. Files are written to a
// temporary name and renamed into place.
//
// SHARDS (a trace split by image rows, `precompute --rows A:B`, for a cluster): a shard is a .tm
// of the whole image whose rows outside [A, B) are empty, its inputs recording "rows": [A, B].
// A shard list (.shards: a text file, one .tm path per line, relative to the list's folder;
// blank lines and lines starting with # skipped) reads as the merged T: every row from the
// shard that traced it. The shards must share every other input and cover each row once. As
// each pixel's samples depend only on (seed, pixel, sample), the merged T is the one-process
// trace bit for bit, with its fingerprint.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <istream>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "render/PathTracer.h"
#include "scene/Camera.h"
#include "transport/TransportMatrix.h"

namespace sl {

struct Scene;

/// The env-map convention T's columns follow (stored in the header; checked on load).
inline constexpr const char* kTransportConvention =
    "mitsuba3-envmap-bilinear: u=atan2(x,-z)/2pi, v=acos(y)/pi, rows at j*pi/(H-1), "
    "columns at (i+0.5)/W";

struct TransportProvenance {
    std::string fingerprint;  // 32 hex digits over everything that determines T
    std::string inputs;       // JSON text of those inputs (for people and `relight`)
    int spp = 0, maxDepth = 0;
    uint64_t seed = 0;
};

/// Fingerprint of the inputs that determine T: resolved camera, material, env-map size,
/// height-map pitch and content, spp, seed, max_depth, channels, convention.
TransportProvenance transportProvenance(const Scene& scene, const RenderOptions& options,
                                        int channels);
/// The same from the scene's share of the inputs (transportSceneInputs), which every T of a
/// scene records alike: the fingerprint of another estimate of the same part (another spp or
/// seed) without its height map, e.g. from a .tm's recorded inputs (sceneInputsOfTransport).
TransportProvenance transportProvenance(const nlohmann::json& sceneInputs,
                                        const RenderOptions& options, int channels);
/// The scene's share of T's inputs: the resolved camera, the material, the env-map grid, the
/// height map's grid, pitch, content hash and file name, the scene file and its overrides.
nlohmann::json transportSceneInputs(const Scene& scene);
/// The same, as a T recorded them (its provenance's inputs without what its trace set).
nlohmann::json sceneInputsOfTransport(const TransportProvenance& provenance);
/// The camera a T was traced through (its recorded "camera" input).
CameraDesc cameraOfTransport(const TransportProvenance& provenance);

/// Writes T atomically (a temporary renamed into place). `result`: the file is the command's
/// result (precompute's), so its rename is the command's commit (core/Interrupt.h enterCommit:
/// Ctrl-C before it writes nothing, after it lets the file appear whole); a cache file is not.
void writeTransportFile(const std::filesystem::path& file, const TransportMatrix& t,
                        const TransportProvenance& provenance, bool result = false);

struct TransportFile {
    TransportMatrix matrix;
    TransportProvenance provenance;
};

/// Reads and verifies a .tm file (or a .shards list of them, merged). If expectedFingerprint is
/// non-empty and differs, throws InputError saying the file is stale. Damage, truncation, wrong
/// version: InputError. (Opens the file and calls readTransport.)
TransportFile readTransportFile(const std::filesystem::path& file,
                                const std::string& expectedFingerprint = {});

/// What a file holds, peeked at without reading T: 0 not a transport-matrix file (or not
/// readable), 1 its magic only (a file cut short while written), 2 a whole checked header; then
/// `fingerprint` is the header's. Never throws.
int peekTransportFile(const std::filesystem::path& file, std::string* fingerprint = nullptr);

/// T put together from its row shards (see SHARDS above); `where` names them in errors, and
/// `names` (optional, one per shard: their files) each shard. InputError for a shard that is not
/// one, mismatched inputs, overlapping rows or a gap.
TransportFile mergeTransportShards(std::vector<TransportFile> shards, const std::string& where,
                                   const std::vector<std::string>& names = {});

/// What a shard records of itself: its rows [rowBegin, rowEnd), and the inputs and fingerprint
/// of the whole trace it is a part of (its own without the rows: the merged T's). `name` names
/// it in the InputError for a whole T.
struct ShardOf {
    int rowBegin = 0, rowEnd = 0;
    std::string inputs, fingerprint;
};
ShardOf shardOf(const TransportFile& shard, const std::string& name);

/// Which shard holds each image row: ranges[k] = shard k's rows [begin, end). InputError for a
/// range outside the image (naming shard k: `where`: names[k], else `where` shard k+1), a row
/// in two shards (naming `where` and, when given, both shards' names) or a row in none.
std::vector<int> shardRowOwners(const std::vector<std::array<int, 2>>& ranges, int height,
                                const std::string& where, const std::vector<std::string>& names);

/// The .tm files a shard list names, in its order, relative paths resolved against the list's
/// folder. InputError when it cannot be read or lists another list.
std::vector<std::filesystem::path> shardListFiles(const std::filesystem::path& list);

/// The same on a stream holding the `size` bytes of a .tm file from its current position (an
/// in-memory file, a fuzzer's input); `where` names the source in errors.
TransportFile readTransport(std::istream& in, uint64_t size, const std::string& where,
                            const std::string& expectedFingerprint = {});

}  // namespace sl
