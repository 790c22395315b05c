// `scratchlight bench depth`: how much each further bounce adds to the image, and the path length
// (Mitsuba's max_depth, render/PathTracer.h) after which the next bounce adds less than a
// threshold (0.1 %) of the image: issue 16, item 2's rule (app/pipeline/AutoDepth.h, which
// `render` and `optimize` apply).
// The scene is rendered under a white light (E = 1, the most any E in [0, 1] can gather) at
// max_depth 1, 2, … with one seed: a sample draws the same numbers at each vertex whatever the
// path length, so image(d+1) − image(d) is exactly what bounce d+1 adds for these samples.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "app/pipeline/AutoDepth.h"

namespace sl {

struct DepthBenchOptions {
    std::filesystem::path scene;              // empty: the bundled default scene (app/host/Plot.h)
    std::vector<std::string> sceneOverrides;  // -D key=value on the scene (io/SceneFile.h)
    int resolution = 128, spp = 16;           // image N×N, samples per pixel
    int maxDepth = 12;                        // the longest path length measured
    double threshold = 0.001;                 // "the next bounce adds less than this share"
    int threads = 0;
};

struct DepthBenchRow {
    int maxDepth = 0;
    double energy = 0;  // Σ luminance over the image at this max_depth under E = 1
    double added = 0;   // (energy − energy at max_depth − 1) / energy: this bounce's share
    double seconds = 0;
    uint64_t rays = 0;
};

struct DepthBenchResult {
    DepthBenchOptions options;
    std::vector<DepthBenchRow> rows;
    DepthChoice choice;
    int sceneMaxDepth = 0;  // the scene's own render.max_depth, for comparison
    std::string csv() const;
};

/// Runs the benchmark. Throws InputError for a bad scene or option.
DepthBenchResult runDepthBench(const DepthBenchOptions& options);

}  // namespace sl
