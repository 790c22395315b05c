// Sdf: the reader of SDF files (ISO 25178-71 / Surfstand "BCR" surface data files, ASCII and
// binary). Which variant is read and what is refused: io/HeightmapIO.h. Use loadHeightmap, which
// dispatches `.sdf` here and then fills invalid points and applies the height options.
#pragma once

#include <filesystem>

#include "io/HeightmapData.h"

namespace sl {

/// Reads an SDF file: heights in millimetres (NaN marks an invalid point), `pitch` in mm,
/// `format` e.g. "sdf binary int16". Throws InputError naming the file and the offending field.
HeightmapData readSdf(const std::filesystem::path& file);

}  // namespace sl
