// NanoFocusNms: the reader of NanoFocus µsurf height images (.nms, "OM_MS_2.0" at byte 32, a
// confocal height image with its intensity image). The layout (little-endian) and what is
// refused: io/HeightmapIO.h. Use loadHeightmap, which recognises the file by its header and then
// applies the height options.
#pragma once

#include <cstddef>
#include <filesystem>

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

}  // namespace sl
