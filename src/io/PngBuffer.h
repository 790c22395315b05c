// PngBuffer: a PNG encoded in memory with zlib directly (no row filter), so that the
// compression level can be traded for time: level 1 encodes a 2048² gray image in tens of
// milliseconds (the viewer's images, sent over HTTP). Values are stored verbatim (the caller
// applies exposure and sRGB encoding); io/ImageIO.h's PNG files are written with it too, so
// that writing them does not load OpenImageIO (io/ImageCodec.h).
#pragma once

#include <cstdint>
#include <span>
#include <string>

namespace sl {

/// PNG bytes of a width×height image with `channels` 8-bit channels per pixel (1 gray, 2 gray
/// + alpha, 3 RGB, 4 RGBA), row-major, top row first. `level`: zlib level 0..9.
/// Throws std::invalid_argument for a size that does not match.
std::string encodePng8(std::span<const uint8_t> pixels, int width, int height, int channels,
                       int level = 1);

/// The colour tag of a PNG: none, sRGB (sRGB, gAMA and cHRM chunks, as OpenImageIO wrote) or
/// linear (a gAMA chunk of 1.0); OpenImageIO reads them as "sRGB" and "Linear" (io/ImageIO.h).
enum class PngColour { None, Srgb, Linear };

/// PNG bytes of `pixels` (width·height·channels values of `bitDepth` 8 (uint8_t) or 16
/// (uint16_t, native order; stored big-endian), row-major, top row first), tagged `colour`.
/// Throws std::invalid_argument for a bad size, depth or level.
std::string encodePng(const void* pixels, int width, int height, int channels, int bitDepth,
                      PngColour colour, int level);

}  // namespace sl
