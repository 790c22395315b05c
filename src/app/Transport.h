// Getting a transport matrix: compute it from a scene (optionally cached by fingerprint) or read
// it from a .tm file.
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <string>

#include "render/PathTracer.h"
#include "transport/TransportFile.h"

namespace sl {

struct PrecomputeOptions {
    std::optional<int> spp, maxDepth;
    std::optional<uint64_t> seed;
    bool rgb = false;
    int sampleSets = 1;  // 2: store the halves T_a, T_b (noise-unbiased objective, held-out)
    int threads = 0;
    std::function<void(double)> progress;
};

struct TransportSource {
    TransportFile file;          // the matrix and its provenance
    std::filesystem::path path;  // where it is stored (empty if not stored)
    bool cacheHit = false;       // read from the cache instead of traced
    double secondsTrace = 0;     // path tracing (0 on a cache hit)
    double secondsTotal = 0;     // scene load + trace + build + write, or the file read
    TraceSummary trace;          // the trace's summary (empty on a cache hit)
};

/// Traces `scene` into T and writes it to `out` (atomic). Returns what was built.
TransportSource precomputeToFile(const std::filesystem::path& scene,
                                 const PrecomputeOptions& options,
                                 const std::filesystem::path& out);

/// T for a scene, from cacheDir/transport-<fingerprint>.tm when it is there and valid,
/// otherwise traced and stored there.
TransportSource transportForScene(const std::filesystem::path& scene,
                                  const PrecomputeOptions& options,
                                  const std::filesystem::path& cacheDir);

/// The held-out estimate for a training T: the same scene traced with another seed
/// (training seed + kHeldOutSeedOffset), two sample sets, `spp` samples (0: the training spp),
/// cached like transportForScene. The scene is the training T's recorded scene file (or
/// `sceneOverride`); its inputs must match the training T's apart from the sampling.
TransportSource heldOutFor(const TransportFile& training, int spp,
                           const std::filesystem::path& cacheDir,
                           const std::filesystem::path& sceneOverride = {});

/// True if `input` names a transport-matrix file (by extension .tm).
bool isTransportFile(const std::filesystem::path& input);

}  // namespace sl
