// X3p: the reader and writer of X3P files (ISO 25178-72; the XML of ISO 5436-2 and binary point
// data in a zip). Which variant is read and what is refused: io/HeightmapIO.h. Use loadHeightmap,
// which dispatches `.x3p` here and then fills invalid points and applies the height options.
#pragma once

#include <filesystem>
#include <vector>

#include "io/HeightmapData.h"

namespace sl {

/// Reads an X3P file: heights in millimetres (NaN marks an invalid point), `pitch` in mm,
/// `format` e.g. "x3p int16". Throws InputError naming the file and the offending field.
HeightmapData readX3p(const std::filesystem::path& file);

/// Writes a W×H height map (mm, row 0 = the first profile) as an X3P file: FeatureType SUR,
/// incremental CX/CY with Increment pitchMm/1000 m, CZ float64 in metres, MD5 checksums of the
/// data and of main.xml. Written atomically (io/AtomicFile.h); throws InputError naming the file.
void writeX3p(const std::filesystem::path& file, int width, int height,
              const std::vector<float>& heightsMm, double pitchMm);

}  // namespace sl
