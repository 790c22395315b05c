// A height map as a reader returns it (HeightmapData) and the size limits of the measured
// formats' headers: what loadHeightmap (io/HeightmapIO.h, which documents every format) and each
// format's reader (io/X3p.h, io/Sdf.h, io/GwyddionReader.h) share, so that none of them includes
// the dispatcher that includes it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace sl {

struct HeightmapData {
    int width = 0, height = 0;
    std::vector<float> heights;   // row-major, row 0 first (width * height values)
    std::string format;           // e.g. "exr float32", "png uint16", "npy float64"
    std::optional<double> pitch;  // measured maps: the sample spacing (mm); unset otherwise
    /// The file's Y spacing (mm) when it differs from its X spacing; after loadHeightmap the map
    /// is square at `pitch` and this is unset (resampling says what was done).
    std::optional<double> pitchY;
    size_t invalidFilled = 0;  // measured maps: invalid points filled (io/HeightmapIO.h)
    /// Per sample, 1 where the height was invented (an invalid point filled, or interpolated
    /// from one); empty when every height is measured. Levelling fits the others only.
    std::vector<uint8_t> invalid;
    std::string resampling;  // "" or how non-square pixels were made square
    /// Files of several channels (and any channel asked for): which one was read and the
    /// others, e.g. `channel 1 "Height" (heights in m), its title names heights; the others:
    /// 0 "Amplitude" (heights in m)` (io/GwyddionReader.h); "" otherwise.
    std::string channel;
    std::vector<std::string> warnings;  // what an imperfect file made the reader assume
    /// An instrument's channel of heights in metres on a grid whose lateral axes carry no
    /// calibration (unit none or pixels): heights in mm, `pitch` unset, so the scene gives
    /// heightmap.pixel_pitch (io/GwyddionReader.h).
    bool uncalibratedLateral = false;
    /// A measured map (X3P, SDF, an instrument format): heights in mm, with its pitch (unless
    /// its lateral axes are uncalibrated).
    bool measured() const { return pitch.has_value() || uncalibratedLateral; }
};

namespace detail {
/// Largest side and sample count an X3P or SDF header may claim (a larger claim is refused).
inline constexpr long long kMaxMetrologySide = 1000000;
inline constexpr long long kMaxMetrologySamples = 400000000;
/// X and Y pitches at most this far apart (relative) are read as square, not interpolated: an
/// instrument's pitch calibration is known to about 0.1 % (io/HeightmapIO.h).
inline constexpr double kSquarePitchTolerance = 1e-3;
}  // namespace detail

}  // namespace sl
