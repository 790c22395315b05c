// TrueMap: the reader of TrueMap's binary height maps (.tmd, "Binary TrueMap Data File v2.0",
// as TrueMap v6 writes them). The layout (little-endian) and what is refused: io/HeightmapIO.h.
// Use loadHeightmap, which recognises the file by its first bytes and then fills invalid points
// and applies the height options.
#pragma once

#include <cstddef>
#include <filesystem>
#include <vector>

#include "io/HeightmapData.h"

namespace sl {

/// The first bytes of every file this reader reads.
inline constexpr char kTrueMapMagic[] = "Binary TrueMap Data File v2.0";
inline constexpr size_t kTrueMapMagicLength = sizeof(kTrueMapMagic) - 1;

/// Reads a TMD file: heights in millimetres (NaN marks an invalid point), `pitch` in mm (and
/// `pitchY` when the Y spacing differs), `format` "truemap v2.0 float32". Throws InputError
/// naming the file and the offending field.
HeightmapData readTrueMap(const std::filesystem::path& file);

/// Writes a W×H height map (mm, row 0 first) as a TrueMap v2.0 file with lengths W·pitch and
/// H·pitch (what readTrueMap reads back; `bench read`). Written atomically; throws InputError
/// naming the file.
void writeTrueMap(const std::filesystem::path& file, int width, int height,
                  const std::vector<float>& heightsMm, double pitchMm);

}  // namespace sl
