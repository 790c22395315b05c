// Getting a transport matrix: compute it from a scene (optionally cached by fingerprint) or read
// it from a .tm file.
#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/Communicator.h"
#include "io/TransportFile.h"
#include "render/PathTracer.h"

namespace sl {

struct Scene;

struct PrecomputeOptions {
    std::optional<int> spp, maxDepth;
    std::optional<uint64_t> seed;
    bool rgb = false;
    int sampleSets = 1;  // 2: store the halves T_a, T_b (noise-unbiased objective, held-out)
    int threads = 0;
    /// Image rows [rowBegin, rowEnd) only (both 0: all): a shard (io/TransportFile.h SHARDS).
    int rowBegin = 0, rowEnd = 0;
    /// What the trace's progress (core/Progress.h) is called; the image size and spp follow.
    std::string label = "precompute";
};

struct TransportSource {
    TransportFile file;          // the matrix and its provenance
    std::filesystem::path path;  // where it is stored (empty if not stored)
    bool cacheHit = false;       // read from the cache instead of traced
    double secondsTrace = 0;     // path tracing (0 on a cache hit)
    double secondsTotal = 0;     // scene load + trace + build + write, or the file read
    TraceSummary trace;          // the trace's summary (empty on a cache hit)
};

/// The RenderOptions a precompute of `scene` uses: the scene's `render` section with the
/// options' overrides.
RenderOptions traceOptions(const Scene& scene, const PrecomputeOptions& options);

/// Traces `scene` into T and writes it to `out` (atomic). Returns what was built.
TransportSource precomputeToFile(const std::filesystem::path& scene,
                                 const PrecomputeOptions& options, const std::filesystem::path& out,
                                 const std::vector<std::string>& sceneOverrides = {});

/// T for a loaded scene, from cacheDir/transport-<fingerprint>.tm when it is there and valid,
/// otherwise traced and stored there (cacheDir empty: traced, not stored).
TransportSource transportForScene(const Scene& scene, const PrecomputeOptions& options,
                                  const std::filesystem::path& cacheDir);

/// `count` independent estimates of T: the same trace with seeds seed + k, k = 0..count−1
/// (seed: options.seed or the scene's render.seed), each cached like transportForScene. The
/// sample-set planes the stochastic optimizers cycle through (estimate 0 is the usual T).
std::vector<TransportSource> transportSetForScene(const Scene& scene,
                                                  const PrecomputeOptions& options, int count,
                                                  const std::filesystem::path& cacheDir);

/// The scene a transport matrix records (its "scene_file"), checked against T's image size.
/// `purpose` names what needs it, for the error message when the file records none.
std::unique_ptr<Scene> sceneOfTransport(const TransportFile& t, const std::string& purpose);

/// The judge's estimate (app/Judge.h) for a training T of `scene`: the same scene and path
/// length traced with the judge's seed, two sample sets, `spp` samples (0: the judge's
/// default), cached like transportForScene. The scene's inputs must match the training T's
/// apart from the sampling.
TransportSource judgeEstimateFor(const TransportFile& training, const Scene& scene, int spp,
                                 const std::filesystem::path& cacheDir);

/// "transport matrix 512x512 px x 50x25 texels, gray T, CSR, nnz ... MB", and on a second line
/// the trace's rays and seconds when it was traced (not on a cache hit or a file read).
std::string describeTransport(const TransportSource& source);

/// T over MPI ranks (docs/CLUSTER.md): rank r of N reads the r-th shard of the .shards list
/// `list`, which must name N shards. The ranks check together that their shards are one trace
/// (the same inputs, every image row in exactly one) and put the object mask together, so each
/// rank's matrix holds its rows of T, the whole image's object mask and the merged T's
/// provenance; `rows` (optional) receives the rows it holds. With one rank: the whole list,
/// merged (readTransportFile), all its rows.
TransportFile readShardOfRank(const std::filesystem::path& list, const Communicator& ranks,
                              RowShard* rows = nullptr);

/// True if `input` names a transport-matrix file (by extension: .tm, or a .shards list).
bool isTransportFile(const std::filesystem::path& input);

}  // namespace sl
