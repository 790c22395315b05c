// PngBuffer: an 8-bit PNG encoded in memory (the viewer's images, sent over HTTP), written with
// zlib directly so that the compression level can be traded for time: level 1 with no row
// filter encodes a 2048² gray image in tens of milliseconds. Bytes are stored verbatim (the
// caller applies exposure and sRGB encoding; io/ImageIO.h writePng writes files).
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

}  // namespace sl
