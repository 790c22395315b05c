// Writing a generated part to disk: its height map, truth labels with their legend, and a
// scene file that renders it (what `gen-surface` writes, and the parts `bench race` makes).
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>

#include "synth/SurfaceGenerator.h"

namespace sl {

struct PartFileOptions {
    std::filesystem::path scene;  // also write a scene file here ("" = none)
    int imageSize = 0;            // scene camera width = height in pixels (0: the scene default)
    int spp = 64;                 // scene render.spp
    int maxDepth = 4;             // scene render.max_depth
    bool measured = false;        // scene heightmap.measured: true (the map is a measurement's)
    // Members added to the legend file after "labels" (e.g. insert-defects' list of the
    // defects it inserted); readers of the legend read "labels" only.
    nlohmann::ordered_json legendExtra = nlohmann::ordered_json::object();
};

struct PartFiles {
    std::filesystem::path heightmap, truth, legend, scene;
    double lo = 0, hi = 0;  // height range, mm
};

/// The files writePartFiles would write, checked before any work: the height map's extension,
/// a scene file ending in .json, no two of them the same file, none a directory. Throws
/// InputError naming the file and the fix. Fills `heightmap`, `truth`, `legend` and `scene`.
PartFiles checkPartFiles(const std::filesystem::path& heightmap, const PartFileOptions& options);

/// heightmap: .exr (float32 mm), .png (16-bit over [lo, hi], recorded in the scene file) or .x3p
/// (X3P, float64 metres with its pitch; the scene file then gives no pixel_pitch).
/// Truth: <stem>-truth.png (labels, synth/SurfaceGenerator.h) and <stem>-truth.json (legend:
/// truthLegend, every label present).
/// Throws InputError as checkPartFiles. All the files are written under temporary names and
/// renamed into place together at the end: a failure leaves none of them (and the files they
/// would have replaced unchanged).
PartFiles writePartFiles(const GeneratedSurface& g, const std::filesystem::path& heightmap,
                         const PartFileOptions& options);

}  // namespace sl
