// Previews a person looks at: a render written as data with its PNG preview, a render exposed
// for a PNG, and the same with labelled regions outlined in one colour per label (the judge's
// report, optimize's regions.png).
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <vector>

#include "core/Image.h"

namespace sl {

/// Writes `image` (width×height, 1 or 3 channels, double) as EXR + PNG preview.
void writeRender(const std::filesystem::path& exr, const std::vector<double>& image, int width,
                 int height, int channels);

/// The exposure of a preview: the 99th percentile of the part's pixels (all pixels when `part`
/// is empty) maps to 0.8; 1 when that is not positive.
double exposureScale(const std::vector<double>& y, const std::vector<uint8_t>& part);

/// The outline colour of a label value (linear RGB) and its name for captions: 255 red,
/// 224 orange, 192 magenta, 160 yellow, 144 cyan, 128 blue (gen-surface's truth values,
/// synth/SurfaceGenerator.h), any other value white.
struct OutlineColour {
    uint8_t value;
    float r, g, b;
    const char* name;
};
const OutlineColour& outlineOf(uint8_t value);
/// Every value with a colour of its own, in that order (red 255 first).
std::span<const OutlineColour> outlineColours();

/// A w×h luminance render as an RGB preview (exposureScale), gray, with the boundary pixels of
/// every labelled region (a pixel of the region with a 4-neighbour outside it; `labels` empty:
/// none) drawn in the region's colour.
Image outlinedRender(const std::vector<double>& y, int w, int h, const std::vector<uint8_t>& part,
                     const std::vector<uint8_t>& labels);

/// A height map as a person looks at it: hill-shaded, lit from the top left (row 0 at the top)
/// at 45° elevation, the slopes measured in units of their robust spread (1.4826 × the median
/// |central difference|, the mean |difference| when that is 0; over every sample, or a regular
/// subset of a million on a larger map), so that a texture of any height shows; w×h luminance
/// in [0, 1]; a flat map is uniform.
std::vector<double> hillShade(std::span<const float> heights, int w, int h);

/// A defect map's preview (defectmap's <stem>-preview.png): the hill-shaded heights, the marks
/// (map != 0) outlined red, the regions the map could not judge (unjudged == kUnjudgedRegion,
/// detect/DefectMap.h) outlined blue (outlineOf(128)) and the border it never marks (unjudged
/// == kUnjudgedBorder) at half brightness; `unjudged` empty: none.
Image defectMapPreview(std::span<const float> heights, int w, int h,
                       const std::vector<uint8_t>& map, const std::vector<uint8_t>& unjudged);

}  // namespace sl
