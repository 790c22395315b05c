// `scratchlight bench regions`: what tracing only what a scene needs saves (issue 16, item 2).
// T is precomputed four ways on one scene, interleaved, `repeats` times (median seconds):
//   every pixel        the baseline: every pixel's camera samples traced (no culling)
//   footprint          the default: pixels outside the part's footprint skipped
//                      (render/Footprint.h); T is checked to be the baseline's, bit for bit
//   mask only          footprint + only the loss mask's pixels (`optimize --trace-mask-only`,
//                      here the paper's scratch map as the mask)
//   max_depth auto     footprint + the path length autoMaxDepth measures (its measurement's
//                      seconds included)
// For each: rays, camera rays, T's non-zeros and bytes, seconds, and ratios to the baseline.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace sl {

struct RegionBenchOptions {
    std::filesystem::path scene;              // empty: the bundled default scene (app/host/Plot.h)
    std::vector<std::string> sceneOverrides;  // -D key=value on the scene (io/SceneFile.h)
    int resolution = 512, spp = 16;           // image N×N, samples per pixel (two halves)
    int repeats = 3;                          // interleaved runs (median seconds)
    int threads = 0;
};

struct RegionBenchRow {
    std::string name, detail;
    uint64_t rays = 0, cameraRays = 0, pixels = 0;  // pixels: those whose samples were traced
    size_t nnz = 0, bytes = 0;
    int maxDepth = 0;
    double seconds = 0;           // median
    bool sameAsBaseline = false;  // T bit for bit the baseline's (footprint only)
};

struct RegionBenchResult {
    RegionBenchOptions options;
    int width = 0, height = 0;
    std::vector<RegionBenchRow> rows;  // the baseline first
    std::string csv() const;
};

/// Runs the benchmark. Throws InputError for a bad scene or option.
RegionBenchResult runRegionBench(const RegionBenchOptions& options);

}  // namespace sl
