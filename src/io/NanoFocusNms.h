// NanoFocusNms: the reader of NanoFocus µsurf height images (.nms, "OM_MS_2.0" at byte 32, a
// confocal height image with its intensity image). The layout (little-endian) and what is
// refused: io/HeightmapIO.h. Use loadHeightmap, which recognises the file by its header and then
// applies the height options.
#pragma once

#include <cstddef>
#include <filesystem>
#include <vector>

#include "io/HeightmapData.h"

namespace sl {

/// Where the format's name sits, and its first bytes.
inline constexpr size_t kNmsNameOffset = 32;
inline constexpr char kNmsName[] = "OM_MS_";
inline constexpr size_t kNmsNameLength = sizeof(kNmsName) - 1;

/// Reads an NMS file: heights in millimetres, `pitch` in mm (and `pitchY` when the Y spacing
/// differs), `format` "nanofocus nms uint16". Throws InputError naming the file and the offending
/// field.
HeightmapData readNanoFocusNms(const std::filesystem::path& file);

/// Writes a W×H height map (mm, row 0 first) as an NMS file: the heights' range in µm, each
/// quantised to one of 65536 codes over it, the spacing in nm, and a flat intensity image (what
/// readNanoFocusNms reads back to within a code; `bench read`). Written atomically; throws
/// InputError naming the file.
void writeNanoFocusNms(const std::filesystem::path& file, int width, int height,
                       const std::vector<float>& heightsMm, double pitchMm);

}  // namespace sl
