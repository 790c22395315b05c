// Mask files: region masks in image space, masks and truth labels in height-map space.
//
// CONVENTION (truth labels): a truth mask lives in HEIGHT-MAP space (one pixel per height
// sample, as gen-surface's <stem>-truth.png). Its stored 8-bit values are read raw (no colour
// decoding; a 16-bit file is scaled to 8 bits): each distinct nonzero value is one region.
// The legend is the JSON file beside it with the same stem (<stem>-truth.json):
//   {"labels": [{"value": 255, "name": "defect"}, {"value": 128, "name": "chatter"}]}
// Without a legend every value v present is a region named "defect" (v = 255) or "label-v".
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "core/RegionLabel.h"

namespace sl {

/// A region mask from a PNG/EXR in image space, checked against the image size. Read with
/// readImage (linear float, any OIIO format; an 8-bit PNG without a colour-space tag is
/// sRGB-decoded, one written by writeMaskPng is tagged linear and read verbatim), so inside means
/// a byte ≥ 188 under sRGB decoding, ≥ 128 if linear, 1.0 in an EXR; other channels are ignored.
/// Inside = first channel > 0.5 after readImage's decoding (a white-ish PNG pixel, 1.0 in an EXR);
/// the result holds 255 inside, 0 outside. Throws InputError naming the file (also when it is
/// empty).
std::vector<uint8_t> loadImageMask(const std::filesystem::path& file, int width, int height);

/// A mask file in HEIGHT-MAP space: mapWidth×mapHeight pixels, inside = first channel > 0.5
/// after readImage's decoding (the rule of loadImageMask), 255/0. Unlike loadImageMask an empty
/// mask is allowed (a surface without defects). Throws InputError naming the file (unreadable,
/// wrong size).
std::vector<uint8_t> loadHeightMapMask(const std::filesystem::path& file, int mapWidth,
                                       int mapHeight);

struct LabelMask {
    int width = 0, height = 0;
    std::vector<uint8_t> labels;      // width*height, row 0 first
    std::vector<RegionLabel> legend;  // the regions, in the legend's order
};

/// Reads a truth label mask and its legend (see above). Throws InputError naming the file when
/// it cannot be read, is not mapWidth×mapHeight (the height map's size), or the legend is
/// malformed.
LabelMask readLabelMask(const std::filesystem::path& file, int mapWidth, int mapHeight);

}  // namespace sl
