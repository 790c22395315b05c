// ImageFile: how io/ opens and reads image files, in one place (ImageIO, HeightmapIO and
// MaskIO use it; nothing outside io/ includes it). EXRs that OpenEXR reads exactly as
// OpenImageIO does are read with OpenEXR (io/ExrReader.h), every other file through
// OpenImageIO's module (io/ImageCodec.h), loaded then.
//
//   * Only the reader that the file's extension names is used: a file that reader refuses is
//     refused. (OpenImageIO's own open() would then try every reader it has, so a damaged .exr
//     could be parsed as DICOM, FITS, RAW, ... by any of some thirty format plugins.)
//   * An OpenEXR file's header is walked by checkExrHeader before OpenEXR reads it: every
//     attribute must fit in the file, every channel list (type chlist, whatever its name) must
//     end exactly at its last byte (OpenEXR reads one to its end marker and goes on from
//     there, whatever its size says), the data window must be a box whose chunk-offset table
//     fits in the file, and a chunk (a tile, or up to 256 scanlines however few rows the image
//     has) must pass the size check below. (OpenEXR 3.1 allocates what a header field claims
//     before it reads it: a 300-byte file could ask for gigabytes.)
//   * A PNG file's chunks are walked by checkPngChunks: each must fit in the file (libpng
//     allocated the 1.8 GB a tEXt chunk's length claimed in a 154-byte file).
//   * The image's size is checked against the file's: no supported compression packs more than
//     kMaxDecodedPerFileByte decoded bytes (as float) into one byte of file, so a header that
//     claims more is damaged, and nothing is allocated for it.
//   * checkRead: a read counts only if OpenImageIO reports no error. Its read_image() of a
//     truncated strip TIFF returns true with the missing rows left at 0; only has_error() says
//     that rows are missing.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>

#include "io/ImageCodec.h"

namespace sl::detail {

/// Decoded float bytes per file byte above which an image's header is not believed: 8192.
/// Deflate packs at most 1032 bytes into one (PNG, EXR ZIP, TIFF deflate), so 4128 float bytes
/// for 8-bit samples; TIFF LZW about 1400 (5600 as float); RLE, PackBits and JPEG less.
inline constexpr uint64_t kMaxDecodedPerFileByte = 8192;
/// Images up to this many decoded float bytes pass the ratio check whatever their file size.
inline constexpr uint64_t kMinDecodedLimit = uint64_t(1) << 20;

/// Opens `file` with the reader its extension names, after checking that it is a readable
/// regular file (and, for OpenEXR, its header): OpenEXR's own for the EXRs io/ExrReader.h
/// reads (when `exrDirect`; those readers convert to float only), OpenImageIO's otherwise.
/// Throws InputError naming the file, with `fix` as the fix for an unreadable or damaged file.
std::unique_ptr<ImageReader> openImageFile(const std::filesystem::path& file,
                                           const std::string& fix, bool exrDirect = true);

/// Checks that the opened image's size (W·H·channels float samples, and what a reader buffers
/// at once: a tile, or a TIFF strip) is plausible for the size of its file (see
/// kMaxDecodedPerFileByte). Throws InputError naming the file.
void checkImageSize(const std::filesystem::path& file, const ImageHeader& spec);

/// Reads every pixel of the opened image (all channels, interleaved) band by band of rows: each
/// band is read in the file's own pixel format and converted here to `type` (UINT8, UINT16 or
/// FLOAT, OpenImageIO's conversion: uint8 -> uint16 is v·257, integers -> float are v / max),
/// then handed to sink(y0, y1, values) for rows [y0, y1) (0 = the image's top row). (OpenImageIO
/// 2.4 converts through a buffer of at least 256 scanlines, rounded up to a TIFF's strip height,
/// whatever the image's height: a header could make it allocate gigabytes for one row.) Tiled
/// files are read by bands of whole tile rows. A failed read throws InputError naming the file.
void readBands(ImageReader& in, const std::filesystem::path& file, PixelType type,
               const std::string& fix,
               const std::function<void(int y0, int y1, const void* values)>& sink);

/// Walks an OpenEXR file's headers (exposed for tests). Throws InputError naming the file.
void checkExrHeader(const std::filesystem::path& file);

/// Walks a PNG file's chunks up to IEND: every chunk must fit in the file (libpng allocates what
/// a chunk's length field claims, up to 2 GB, before reading it). Throws InputError naming the
/// file.
void checkPngChunks(const std::filesystem::path& file);

}  // namespace sl::detail
