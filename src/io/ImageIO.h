// ImageIO: reading any image OpenImageIO can read as linear float, and writing EXR and PNG
// files atomically (io/AtomicFile.h).
//
// Colour encoding on read (what Mitsuba 3's Bitmap does before its envmap emitter uses a file):
//   * OpenImageIO's "oiio:ColorSpace" attribute decides when present: "sRGB" -> the sRGB
//     transfer function is inverted (core/Color.h srgbDecode), "Linear"/"linear"/
//     "scene_linear" -> values as stored, "GammaX.Y" (PNG gAMA chunk) -> v^gamma.
//   * without it: PNG and JPEG (any bit depth) and 8-bit files are sRGB, everything else
//     (EXR, HDR, float or 16-bit TIFF, ...) is linear.
//   * integer values are normalised first (v / 255, v / 65535); alpha channels are never
//     decoded.
// Writes: writeExr stores float32 ("Y" or "R","G","B"); writePng stores an 8-bit sRGB-encoded
// preview (clamped); writePng16 stores 16-bit data mapped linearly from [0, 1] (tagged linear,
// gAMA 1.0); writeMaskPng stores 8-bit bytes verbatim (tagged linear).
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "core/Image.h"

namespace sl {

/// Reads the first subimage of any OIIO-readable file as linear float (all channels kept,
/// interleaved, top row first). Throws InputError naming the file.
Image readImage(const std::filesystem::path& file);

/// 32-bit float OpenEXR (zip compressed), 1 channel "Y" or 3 channels "R","G","B" (4: +"A").
/// The name must end in ".exr". Values must be finite.
void writeExr(const std::filesystem::path& file, const Image& img);

/// 8-bit sRGB-encoded PNG preview of a linear image: srgbEncode(clamp(v * exposure, 0, 1)),
/// rounded. 1 or 3 channels (4: alpha written linearly). NaN values are an error.
void writePng(const std::filesystem::path& file, const Image& img, float exposure = 1.0f);

/// 16-bit PNG of data values: round(clamp(v, 0, 1) * 65535), no transfer function. 1 or 3
/// channels. NaN values are an error.
void writePng16(const std::filesystem::path& file, const Image& img);

/// 8-bit gray PNG of `mask` (w*h bytes, row-major, top row first), bytes written verbatim:
/// by convention 0 = outside, 255 = inside.
void writeMaskPng(const std::filesystem::path& file, const std::vector<uint8_t>& mask, int w,
                  int h);

namespace detail {
/// Widens `n` values of type T stored packed at the start of `buf` to float, in place,
/// applying `f(value, index)` (T, size_t -> float). Lets a reader fill a float buffer with
/// narrower pixels and convert them without a second buffer. `buf` must hold n floats.
template <typename T, typename F>
void widenInPlace(float* buf, size_t n, F f);
}  // namespace detail

}  // namespace sl

// --- implementation of the template ---------------------------------------------------------
#include <cstring>

namespace sl::detail {
template <typename T, typename F>
void widenInPlace(float* buf, size_t n, F f) {
    static_assert(sizeof(T) <= sizeof(float));
    // Element i of T lives at byte i*sizeof(T) <= 4i; walking backwards, writing float i only
    // overwrites T elements with index >= i, which have been consumed already.
    unsigned char* bytes = reinterpret_cast<unsigned char*>(buf);
    for (size_t k = n; k-- > 0;) {
        T v;
        std::memcpy(&v, bytes + k * sizeof(T), sizeof(T));
        float out = f(v, k);
        std::memcpy(bytes + k * sizeof(float), &out, sizeof(float));
    }
}
}  // namespace sl::detail
