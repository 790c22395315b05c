// Label masks: an 8-bit image whose values name regions (0 = none), with an optional legend.
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
#include <string>
#include <vector>

namespace sl {

struct RegionLabel {
    uint8_t value = 255;
    std::string name = "defect";
};

struct LabelMask {
    int width = 0, height = 0;
    std::vector<uint8_t> labels;      // width*height, row 0 first
    std::vector<RegionLabel> legend;  // the regions, in the legend's order
};

/// Reads a label mask and its legend. Throws InputError naming the file when it cannot be
/// read, is not mapWidth×mapHeight (the height map's size), or the legend is malformed.
LabelMask readLabelMask(const std::filesystem::path& file, int mapWidth, int mapHeight);

}  // namespace sl
