// Getting a transport matrix: compute it from a scene (optionally cached by fingerprint) or read
// it from a .tm file.
#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "app/pipeline/AutoDepth.h"
#include "core/Communicator.h"
#include "io/TransportFile.h"
#include "render/PathTracer.h"

namespace sl {

struct Scene;

struct PrecomputeOptions {
    std::optional<int> spp, maxDepth;
    /// maxDepth from the measured energy per bounce (app/pipeline/AutoDepth.h autoMaxDepth) instead
    /// of the scene's; resolveMaxDepth replaces it by the number before the trace.
    bool autoMaxDepth = false;
    std::optional<Sampling> sampling;  // overrides render.sampling
    /// spp from the measured noise of the objective's gradient (resolveSpp) instead of the
    /// scene's: the fewest samples whose gradient's relative noise is at most sppTolerance.
    bool autoSpp = false;
    double sppTolerance = 0.05;
    /// The pixels traced (RenderOptions::pixels): empty, all; else width·height flags, e.g. a
    /// loss mask's region: T's other rows are empty.
    std::vector<uint8_t> pixels;
    /// Per-pixel sample multipliers (RenderOptions::sppScale): empty, spp everywhere.
    std::vector<uint8_t> sppScale;
    std::optional<uint64_t> seed;
    bool rgb = false;
    int sampleSets = 1;  // 2: store the halves T_a, T_b (noise-unbiased objective, held-out)
    int threads = 0;
    /// Image rows [rowBegin, rowEnd) only (both 0: all): a shard (io/TransportFile.h SHARDS).
    int rowBegin = 0, rowEnd = 0;
    /// What the trace's progress (core/Progress.h) is called; the image size and spp follow.
    std::string label = "precompute";
};

/// What resolveSpp measured and chose.
struct SppChoice {
    int spp = 0;
    int pilotSpp = 0;
    double pilotNoise = 0;   // relative noise of the gradient at pilotSpp
    double chosenNoise = 0;  // ... predicted at spp (∝ 1/√spp)
    std::string reason;
};

struct TransportSource {
    TransportFile file;                    // the matrix and its provenance
    std::filesystem::path path;            // where it is stored (empty if not stored)
    bool cacheHit = false;                 // read from the cache instead of traced
    double secondsTrace = 0;               // path tracing (0 on a cache hit)
    double secondsTotal = 0;               // scene load + trace + build + write, or the file read
    TraceSummary trace;                    // the trace's summary (empty on a cache hit)
    std::optional<DepthChoice> autoDepth;  // max_depth auto: what was measured and chosen
    std::optional<SppChoice> autoSpp;      // spp auto: what was measured and chosen
};

/// With options.autoMaxDepth: measures the scene's path length (autoMaxDepth), sets
/// options.maxDepth to it and clears the flag; returns the choice and its reason. Otherwise
/// nothing. Called before the trace, so the fingerprint records the number.
std::optional<DepthChoice> resolveMaxDepth(const Scene& scene, PrecomputeOptions& options);

/// The pilot trace of spp auto: samples per pixel (two halves).
inline constexpr int kSppAutoPilot = 8;
/// The most samples spp auto chooses.
inline constexpr int kSppAutoMax = 4096;

/// With options.autoSpp: traces a pilot T at kSppAutoPilot spp in two independent halves (the
/// options' other settings; cached in cacheDir like transportForScene), takes the gradient
/// g = Tᵀ·dL_grad/dY of eq. 2's image-gradient term (the term every objective builds on) at
/// E = 0.5 on `region` (image space, nonzero inside; empty: the part) from each half, g_a and
/// g_b, and estimates the relative noise of the gradient at n spp as
/// r(n) = ‖g_a − g_b‖ / ‖g_a + g_b‖ (the halves' difference has four times the variance of
/// their mean). Noise falls as 1/√spp, so it picks the smallest power of two N >= the pilot
/// with r(pilot)·√(pilot/N) <= sppTolerance (at most kSppAutoMax, saying so), sets
/// options.spp = N and clears the flag. Otherwise returns nothing.
std::optional<SppChoice> resolveSpp(const Scene& scene, PrecomputeOptions& options,
                                    const std::vector<uint8_t>& region,
                                    const std::filesystem::path& cacheDir);

/// The RenderOptions a precompute of `scene` uses: the scene's `render` section with the
/// options' overrides.
RenderOptions traceOptions(const Scene& scene, const PrecomputeOptions& options);
/// The same from the scene's render section (render/Render.h renderOptionsFor) and image height.
RenderOptions traceOptions(const RenderOptions& sceneRender, int imageHeight,
                           const PrecomputeOptions& options);

/// What transportForScene reads from `cacheDir` for these options, found without the scene: from
/// the scene's share of T's inputs (io/TransportFile.h transportSceneInputs, or a .tm's
/// sceneInputsOfTransport) and its render section. nullopt when it is not cached (or cacheDir is
/// empty): then transportForScene traces it from the scene.
std::optional<TransportSource> cachedTransport(const nlohmann::json& sceneInputs,
                                               const RenderOptions& sceneRender,
                                               const PrecomputeOptions& options,
                                               const std::filesystem::path& cacheDir);

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
/// estimates the stochastic optimizers cycle through (estimate 0 is the usual T).
std::vector<TransportSource> transportSetForScene(const Scene& scene,
                                                  const PrecomputeOptions& options, int count,
                                                  const std::filesystem::path& cacheDir);

/// Two independent estimates of the same T at the same spp (same image, grid, channels and
/// planes) as one at twice the spp: each entry the mean of the two (plane by plane, so two
/// halves stay two halves, each from its own samples); a pixel is on the part where both say
/// so. Stored as chooseStorage picks.
TransportMatrix meanOfEstimates(const TransportMatrix& a, const TransportMatrix& b);

/// The seed of the chunk that takes an estimate of seed `seed` from `spp` to 2·spp
/// (transportInDoublings): a mix of both, so no two chunks of one estimate share samples, and
/// none is a training seed (small numbers), the validation seed or the judge's.
uint64_t doublingSeed(uint64_t seed, int spp);

/// An estimate extended instead of traced anew (the judge's rounds): at options.spp = base·2^k,
/// k >= 1, the estimate at options.spp/2 (the same way) and an independent chunk of
/// options.spp/2 samples (seed doublingSeed(seed, options.spp/2); the other options the same),
/// averaged by meanOfEstimates; at base, or at an spp of no such form, transportForScene. A
/// round at 2n thus traces n more samples where a new trace took 2n, and the same options give
/// the same numbers however the rounds got there. Every chunk and the result are cached in
/// cacheDir (the result's fingerprint over its pieces'); provenance: options.spp, the first
/// chunk's seed and path length.
TransportSource transportInDoublings(const Scene& scene, const PrecomputeOptions& options, int base,
                                     const std::filesystem::path& cacheDir);

/// The scene a transport matrix records (its "scene_file"), checked against T's image size.
/// `purpose` names what needs it, for the error message when the file records none.
std::unique_ptr<Scene> sceneOfTransport(const TransportFile& t, const std::string& purpose);

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
