// GwyChannel: one channel of a .gwy file that io/GwyddionReader.h writeGwy writes (benches, and
// tests of the channel rule); shared by the reader and the Gwyddion module
// (io/GwyddionModule.h), so that neither includes the other.
#pragma once

#include <string>
#include <vector>

namespace sl {

/// Its title (may be empty), its unit of value ("m": `values` are heights in mm; anything
/// else, e.g. "deg" or "V": as they are) and its lateral unit ("m": the grid at the pitch
/// written; anything else, "" for none: one unit per sample, an uncalibrated grid).
struct GwyChannel {
    std::string title;
    std::string unit = "m";
    std::vector<float> values;  // W×H, row 0 first
    std::string lateralUnit = "m";
};

}  // namespace sl
