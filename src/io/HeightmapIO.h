// HeightmapIO: loading height maps (the world frame of scene/Heightfield.h: sample (row j,
// column i) of a W×H map sits at x = (i − (W−1)/2)·p, z = (j − (H−1)/2)·p; row 0 is the file's
// first row). For X3P and SDF, row j is the file's profile j (Y index j, the first profile
// stored is row 0) and column i is X index i (the first point of a profile is column 0).
//
// Formats and how values become heights (scene units, millimetres by default):
//   * float maps — OpenEXR and TIFF float32/float16 (float64 TIFF is read as float32), .npy
//     float32/float64: height = value · heightScale. heightmap.height_range must not be given.
//   * integer maps — 16-bit PNG and TIFF (uint16), 8-bit PNG and TIFF (uint8), .npy uint16:
//     t = v / 65535 (v / 255 for 8-bit) in [0, 1], height = min + (max − min)·t with the
//     REQUIRED heightmap.height_range [min, max]. No sRGB decoding: the numbers are data.
//     heightmap.height_scale must stay 1 (put the scale into height_range).
//   * one channel; a multi-channel file is accepted only if every colour channel equals the
//     first (gray stored as RGB) and any alpha channel is fully opaque.
//   * surface-metrology maps (io/X3p.h, io/Sdf.h) — physical heights in metres, converted to
//     millimetres: height = 1000 · z[m] · heightScale, whatever the stored type (like float
//     maps, heightmap.height_range must not be given). They carry their sample spacing:
//     HeightmapData::pitch (mm); the scene uses it when heightmap.pixel_pitch is not given
//     (io/SceneFile.h). When the X and Y spacings differ (by more than 1e-6, relative) the map
//     is resampled onto a square grid at the finer of the two (see "Non-square pixels" below).
//       - X3P (.x3p, ISO 25178-72 / ISO 5436-2 XML in a zip): Record1/FeatureType SUR, CX and
//         CY incremental (AxisType I, Increment in m), CZ absolute (AxisType A) with DataType
//         I (int16), L (int32), F (float32) or D (float64), z = value · CZ/Increment (default 1)
//         + CZ/Offset (default 0); Record3/MatrixDimension SizeX × SizeY with SizeZ 1; binary
//         little-endian data (Record3/DataLink/PointDataLink, usually bindata/data.bin) X
//         fastest, then Y. Invalid points: NaN or ±Inf (float types; Alicona's export writes
//         +Inf) and the optional valid-points
//         mask (Record3/DataLink/ValidPointsLink, 1 bit per point, LSB first, 0 = invalid).
//         MD5 checksums are verified when given (Record3/DataLink/MD5ChecksumPointData and
//         MD5ChecksumValidPoints; main.xml against the Record4/ChecksumFile member when that
//         member exists); libzip checks every member's CRC-32. Refused: FCM/PRF feature types,
//         absolute CX/CY axes, SizeZ > 1, XML point lists (no PointDataLink), a missing member,
//         other data types, a data member whose length is not SizeX·SizeY·bytes, a checksum
//         mismatch of the point data or the valid-points mask. main.xml's own checksum (the
//         Record4/ChecksumFile member) that does not match is a warning when the point data's
//         MD5 is given and matches (x3ptools edits main.xml after writing its checksum). The
//         members may sit in one folder inside the zip (`sample-land/main.xml`, as x3ptools
//         and zips made on a Mac write them); links in main.xml are then relative to that
//         folder, and macOS's `__MACOSX/` entries are ignored. The root element may be
//         <ISO5436_2> (any namespace prefix) or x3ptools' <ISO5436>.
//         (io/X3p.h writeX3p writes this variant, float64; `gen-surface OUT.x3p`.)
//       - SDF (.sdf, ISO 25178-71 / Surfstand "BCR"): ASCII (first line aBCR-1.0, aBCR-0.0 or
//         aISO-1.0, then `Key = value` lines, `*`, NumPoints·NumProfiles whitespace-separated
//         values, optionally `*` and a trailer) or binary (bBCR-1.0 / bISO-1.0: an 81-byte
//         little-endian header — 8 version, 10 ManufacID, 12 CreateDate, 12 ModDate, uint16
//         NumPoints, uint16 NumProfiles, float64 Xscale, Yscale, Zscale, Zresolution, uint8
//         Compression, DataType, CheckType — then the values, then an optional trailer).
//         Profile after profile, NumPoints values each. DataType (Gwyddion's codes): 0 uint8,
//         1 uint16, 2 uint32, 3 float32, 4 int8, 5 int16, 6 int32, 7 float64; z = value ·
//         Zscale; Xscale/Yscale are the spacing in m. Invalid points: NaN (float types; "nan"
//         in ASCII) and Gwyddion's sentinels 65535 (uint16), 4294967295 (uint32), −32768
//         (int16), −2147483648 (int32). Compression ≠ 0 is refused; CheckType is ignored (the
//         checksum is not verified).
//       - TrueMap (.tmd, "Binary TrueMap Data File v2.0", io/TrueMap.h): an 80-byte
//         little-endian header — 32 bytes of name (the magic, "\r\n\0"), 24 of comment, uint32
//         width and height, float32 length X and Y (mm, the whole side) and offset X and Y —
//         then width·height float32 heights in mm, X fastest. Pitch = length / samples per
//         axis. NaN is an invalid point. Other versions, a size that does not match the
//         header, non-positive lengths are refused. (Gwyddion 2.62 has no TrueMap module.)
//       - NanoFocus µsurf (.nms, "OM_MS_" at byte 32, io/NanoFocusNms.h): a 3468-byte
//         little-endian header of which we read float64 z min and max (µm) at byte 16, uint32
//         points X and Y at 1368, float64 spacing X and Y (nm) at 1376; then X·Y uint16 codes,
//         X fastest, and optionally as many uint8 intensities (ignored). z = z min + code /
//         65535 · (z max − z min). No code is known to mark an invalid point (every code is
//         read as a height). The layout is reverse-engineered (surfalize reads it so; Gwyddion
//         2.62's modules do not read these files: its Quesant module claims them and fails).
//         A size other than header + 2 or 3 bytes per point is refused.
//       - instrument formats (Wyko OPD, Sensofar PLU, Digital Surf SUR, Zygo DAT, NanoFocus,
//         Gwyddion's .gwy and whatever else Gwyddion's file modules read): through Gwyddion
//         (io/GwyddionReader.h; the build option SCRATCHLIGHT_GWYDDION), heights and spacing in
//         metres, invalid points from the channel's mask; format "gwyddion <module>"; of a
//         file of several channels the height channel, or the one heightmap.channel names
//         (HeightmapData::channel says which).
//     Non-square pixels (X spacing px ≠ Y spacing py): the map is resampled onto the finer pitch
//     p = min(px, py) by linear interpolation along the coarser axis (the finer axis keeps its
//     samples): W' = ⌊(W−1)·px/p⌋ + 1 columns, H' = ⌊(H−1)·py/p⌋ + 1 rows, new sample k at
//     k·p from the first. HeightmapData::resampling says so; a new sample is invalid when a
//     source sample it weights is. Pitches more than 1000-fold apart are refused (a damaged
//     header: a 124-byte file would become gigabytes); one row or column is not resampled.
//     Pitches a hair apart (at most 0.1 %, an instrument's calibration: Alicona's 2.27998 x
//     2.27979 µm) are not interpolated, which would only blur the map: its samples are kept at
//     p, and `resampling` says "read as square" with the pitches' difference in per cent.
//     Any non-finite height of a measured map (NaN, ±Inf) is an invalid point.
//     Invalid points are filled, deterministically, layer by layer from the valid region: each
//     pass gives every invalid point that has a valid 4-neighbour the mean of those neighbours,
//     all at once, then counts them valid. HeightmapData::invalidFilled counts them (and the
//     format string says so). A map more than half invalid is first cropped to the bounding
//     box of its valid points (the rows and columns at its border that hold none: a part
//     smaller than the field), with a warning naming the rows and columns kept. Refused: no
//     valid point, or more than half the points invalid within that box.
// Which reader: by content (the first bytes: .npy's magic, a zip = X3P, SDF's version line,
// TrueMap's name, NMS's name at byte 32, EXR/PNG/TIFF/JPEG magic), then by extension for what the
// content does not say (a damaged file keeps its format's error), then Gwyddion's file modules (by
// content and name), then OpenImageIO. X3P and SDF use our own readers, also when Gwyddion is
// built: they read the X3P files whose members sit in a folder (Gwyddion refuses them) and are
// faster (README "Instrument files"). Checks: file exists and decodes, at least 2×2 samples, every
// height finite (the error names the first bad row and column).
//
// Memory: one float buffer of W·H values (plus a strip of rows for multi-channel files); a
// single-channel file is decoded straight into it. X3P and SDF also hold the file's data
// (X3P: the uncompressed data member) while converting.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "io/HeightmapData.h"

namespace sl {

struct HeightmapOptions {
    std::optional<std::array<double, 2>> heightRange;  // integer maps: [min, max], scene units
    /// Integer maps without heightRange use this range instead of being refused. For what
    /// depends only on the map's shape, invariant to an affine change of the heights (the
    /// scratch and defect maps read an integer map as [0, 1]); unset for anything rendered.
    std::optional<std::array<double, 2>> defaultIntegerRange;
    double heightScale = 1.0;  // float maps: multiplier
    /// heightmap.channel: the channel of an instrument file read through Gwyddion, by number or
    /// title (io/GwyddionReader.h); "" the height channel its rule finds. A file one of our
    /// own readers reads holds one height channel and is refused with a channel asked for.
    std::string channel;
};

/// Which reader loadHeightmap uses: the one the content says, or Gwyddion's file modules for
/// any file (benches compare our X3P and SDF readers with Gwyddion's).
enum class HeightmapReader { Auto, Gwyddion };

HeightmapData loadHeightmap(const std::filesystem::path& file, const HeightmapOptions& opt,
                            HeightmapReader reader = HeightmapReader::Auto);

}  // namespace sl
