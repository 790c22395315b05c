// The path length a scene needs (Mitsuba's max_depth, render/PathTracer.h): issue 16, item 2's
// rule. The scene is rendered under a white light (E = 1, the most any E in [0, 1] can gather) at
// max_depth 1, 2, … with one seed: a sample draws the same numbers at each vertex whatever the
// path length, so image(d+1) − image(d) is exactly what bounce d+1 adds for these samples; the
// chosen length is the first whose next bounce adds less than a threshold (0.1 %) of the image.
// What `render --auto-depth` and `precompute`/`optimize --max-depth auto` use (app/pipeline/
// Transport.h); `bench depth` (app/bench/DepthBench.h) prints the whole table.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace sl {

struct Scene;
struct RenderOptions;
struct TraceSummary;

struct DepthChoice {
    int maxDepth = 0;
    std::string reason;
};

/// The smallest max_depth d >= 2 for which going to d + 1 adds less than `threshold` of the
/// image at d + 1; energy[d] is the image's energy at max_depth d (energy[0] unused). When no
/// measured d qualifies, the longest measured one, saying so. Exposed for tests.
DepthChoice chooseMaxDepth(const std::vector<double>& energy, double threshold);

/// Σ luminance of the scene's image under E = 1 at max_depth `depth` (the other settings from
/// `ro`), and the trace summary when `summary` is given.
double whiteEnergy(const Scene& scene, RenderOptions ro, int depth, TraceSummary* summary);

/// How autoMaxDepth measures: spp samples at each of about `pixels` pixels (a regular lattice
/// over the image: the energy per bounce is a sum over the image, and a lattice estimates its
/// shares as well as every pixel at a fraction of the rays), up to `limit` path lengths.
struct AutoDepthOptions {
    int spp = 16;
    int pixels = 16384;
    int limit = 16;
    double threshold = 0.001;  // "the next bounce adds less than this share of the image"
    int threads = 0;
};

/// The lattice of about `count` pixels autoMaxDepth traces: every k-th pixel of every k-th row,
/// k = max(1, floor(sqrt(width·height / count))); width·height flags (RenderOptions::pixels).
std::vector<uint8_t> pixelLattice(int width, int height, int count);

/// The rule applied to a scene as it is (its camera, material and seed): renders under E = 1
/// with max_depth 1, 2, … on the lattice and stops at the first depth whose next bounce adds
/// less than `threshold` of the image (at most limit − 1 reflections measured). What
/// `render --auto-depth` and `precompute`/`optimize --max-depth auto` use; the choice's reason
/// says what was measured and the seconds spent.
DepthChoice autoMaxDepth(const Scene& scene, const AutoDepthOptions& options = {});

}  // namespace sl
