// `scratchlight bench render`: renderer rays/s next to bare Embree closest-hit rays/s on the same
// height field in the same run (render/Benchmark.h), on every pixel and on the part's footprint
// only, and the height field's build time and memory, for an optional scene file and synthetic
// height maps of several sizes.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "render/Benchmark.h"
#include "scene/Heightfield.h"

namespace sl {

struct RenderBenchOptions {
    std::filesystem::path scene;              // also measure this scene (optional)
    std::vector<std::string> sceneOverrides;  // -D key=value on the scene (io/SceneFile.h)
    std::vector<int> sizes{1024, 5000};  // synthetic N×N height maps (a 10 mm part at every N)
    int resolution = 256, spp = 16;      // image N×N, samples per pixel
    int threads = 0;                     // 0: all cores
    int repeats = 3;                     // interleaved runs per measurement (median)
    std::function<void(const std::string&)> log;  // progress lines (optional)
};

struct RenderBenchRow {
    std::string map;        // scene file name or "NxN"
    double genSeconds = 0;  // generating the synthetic map (0 for a scene file)
    HeightfieldStats heightfield;
    ThroughputRow renderer, bare;  // every pixel's rays; median over the repeats
    // The same on the part's footprint only (render/Footprint.h: the pixels the tracer, the
    // precompute and the renderer trace by default); a background pixel's ray misses the part
    // at once, cheap for both loops, which lifts the every-pixel ratio.
    ThroughputRow rendererFootprint, bareFootprint;
    double ratio() const;           // renderer rays/s over bare rays/s, every pixel
    double footprintRatio() const;  // the same on the footprint's pixels
};

struct RenderBenchResult {
    RenderBenchOptions options;
    std::vector<RenderBenchRow> rows;
    std::string csv() const;  // header + one line per row
};

/// Runs the benchmark. Throws InputError for a bad scene or option.
RenderBenchResult runRenderBench(const RenderBenchOptions& options);

/// The median of repeated measurements of the same rays: the first row's workload and ray count
/// with the median seconds (core/Stats.h). Empty input gives an empty row.
ThroughputRow medianThroughput(const std::vector<ThroughputRow>& rows);

}  // namespace sl
