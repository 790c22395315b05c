// HeightmapIO: loading height maps (the world frame of scene/Heightfield.h: sample (row j,
// column i) of a W×H map sits at x = (i − (W−1)/2)·p, z = (j − (H−1)/2)·p; row 0 is the file's
// first row).
//
// Formats and how values become heights (scene units, millimetres by default):
//   * float maps — OpenEXR and TIFF float32/float16 (float64 TIFF is read as float32), .npy
//     float32/float64: height = value · heightScale. heightmap.height_range must not be given.
//   * integer maps — 16-bit PNG and TIFF (uint16), 8-bit PNG and TIFF (uint8), .npy uint16:
//     t = v / 65535 (v / 255 for 8-bit) in [0, 1], height = min + (max − min)·t with the
//     REQUIRED heightmap.height_range [min, max]. No sRGB decoding: the numbers are data.
//     heightmap.height_scale must stay 1 (put the scale into height_range).
//   * one channel; a multi-channel file is accepted only if every colour channel equals the
//     first (gray stored as RGB) and any alpha channel is fully opaque.
// Checks: file exists and decodes, at least 2×2 samples, every height finite (the error names
// the first bad row and column).
//
// Memory: one float buffer of W·H values (plus a strip of rows for multi-channel files); a
// single-channel file is decoded straight into it.
#pragma once

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace sl {

struct HeightmapOptions {
    std::optional<std::array<double, 2>> heightRange;  // integer maps: [min, max], scene units
    /// Integer maps without heightRange use this range instead of being refused. For what
    /// depends only on the map's shape, invariant to an affine change of the heights (the
    /// scratch and defect maps read an integer map as [0, 1]); unset for anything rendered.
    std::optional<std::array<double, 2>> defaultIntegerRange;
    double heightScale = 1.0;  // float maps: multiplier
};

struct HeightmapData {
    int width = 0, height = 0;
    std::vector<float> heights;  // row-major, row 0 first (width * height values)
    std::string format;          // e.g. "exr float32", "png uint16", "npy float64"
};

HeightmapData loadHeightmap(const std::filesystem::path& file, const HeightmapOptions& opt);

}  // namespace sl
