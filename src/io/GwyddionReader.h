// GwyddionReader: height maps read through Gwyddion's file modules (Gwyddion 2.x, Debian
// `gwyddion` and `libgwyddion20-dev`; GPL-2+, see README "Licence"), built with the CMake option
// SCRATCHLIGHT_GWYDDION (default ON). Without it gwyddionBuilt() is false, gwyddionDetect() finds
// nothing and readGwyddion()/writeGwy() throw an InputError that names the option.
//
// Gwyddion is not linked into the program: its calls live in a module loaded the first time a
// file needs it (io/GwyddionModule.h, libscratchlight-gwyddion.so beside the executable), which
// initialises Gwyddion once, headless as its own gwyddion-thumbnailer does: the widget types, the
// gradient resources, then only the file modules (`<libdir>/gwyddion/modules/file`; the other
// module kinds need a display). Gwyddion is not thread-safe: every call into it holds one lock.
//
// What is read (loadHeightmap dispatches here for a file whose content none of our own readers
// claims, io/HeightmapIO.h): one channel (/N/data) of heights in metres whose lateral unit is
// metres, or none (or px: a grid without calibration, below) --
//   - the one `channel` names (heightmap.channel): its number N, its title (/N/data/title, any
//     case), or a part of the title that names no other channel; a channel not in metres, or
//     none, is refused naming heightmap.channel and listing the file's channels;
//   - else the lowest-numbered channel in metres whose title names heights ("height", "topo",
//     any case): an AFM file's Height beside an Amplitude (error) channel also in metres;
//   - else the lowest-numbered channel in metres.
// Heights become millimetres (×1000), NaN where the channel's mask (/N/mask, the file module's
// invalid points) is set or the value is not finite. pitch = dx, pitchY = dy (mm); on a grid
// without lateral calibration, pitch is unset and uncalibratedLateral set, with a warning: the
// scene gives heightmap.pixel_pitch, or it is refused saying so. `channel` of
// the result says which channel was read and lists the others when the file holds several. A
// file with no channel is refused saying what it holds instead: point clouds (/xyz/N), volume
// data (/brick/N) or graphs (profiles, spectra).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "io/GwyChannel.h"
#include "io/HeightmapData.h"

namespace sl {

/// Whether this build reads files through Gwyddion.
bool gwyddionBuilt();

/// The Gwyddion file module that claims `file` by its content (and name), e.g. "opdfile",
/// "sensofar"; "" when none does or Gwyddion is not built. Initialises Gwyddion.
std::string gwyddionDetect(const std::filesystem::path& file);

/// Reads `file` through Gwyddion (see above): heights in mm, NaN for invalid points, `pitch` and
/// `pitchY` in mm, `format` "gwyddion <module>". `channel` "" reads the height channel the rule
/// above finds. Throws InputError naming the file (or heightmap.channel).
HeightmapData readGwyddion(const std::filesystem::path& file, const std::string& channel = "");

/// Writes a W×H height map (mm, row 0 first) with square pitch pitchMm as Gwyddion's own .gwy
/// file (heights and lateral units in metres). For benches and tests.
void writeGwy(const std::filesystem::path& file, int width, int height,
              const std::vector<float>& heightsMm, double pitchMm);
/// ... and several channels, numbered 0, 1, ... in order (tests of the channel rule).
void writeGwy(const std::filesystem::path& file, int width, int height,
              const std::vector<GwyChannel>& channels, double pitchMm);

}  // namespace sl
