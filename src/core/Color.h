// CONVENTION (colour): all radiance is linear Rec.709 RGB. Luminance
// Y = 0.2126 R + 0.7152 G + 0.0722 B. A grayscale env map drives all three channels.
// An RGB map becomes a gray initial E by CIE L* (LUV lightness) / 100, as the paper does.
// CIE XYZ (the metrics' chroma): IEC 61966-2-1's matrix, its Y row the luminance above.
// PNG previews are sRGB-encoded (IEC 61966-2-1) after clamping to [0, 1].
#pragma once

#include <algorithm>
#include <cmath>

#include "core/Vec3.h"

namespace sl {

inline constexpr float kLumR = 0.2126f, kLumG = 0.7152f, kLumB = 0.0722f;

template <typename T>
constexpr T luminance(T r, T g, T b) {
    return T(0.2126) * r + T(0.7152) * g + T(0.0722) * b;
}
inline float luminance(const Rgb& c) {
    return luminance(c.x, c.y, c.z);
}

/// Linear Rec.709 RGB (sRGB primaries, D65 white) to CIE XYZ: the matrix of IEC 61966-2-1
/// (sRGB), whose middle row is the luminance above, so the luminance weights are written once
/// and white (1, 1, 1) has Y = 1 exactly. (The seven-digit matrix derived from the primaries'
/// chromaticities has the Y row 0.2126729, 0.7151522, 0.0721750; its chroma differs by < 0.05 %.)
inline void rgbToXyz(double r, double g, double b, double& X, double& Y, double& Z) {
    X = 0.4124 * r + 0.3576 * g + 0.1805 * b;
    Y = luminance(r, g, b);
    Z = 0.0193 * r + 0.1192 * g + 0.9505 * b;
}

/// sRGB transfer function, linear -> encoded, input clamped to [0, 1].
inline float srgbEncode(float v) {
    v = std::clamp(v, 0.0f, 1.0f);
    return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}
/// sRGB transfer function, encoded -> linear.
inline float srgbDecode(float v) {
    return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

/// CIE L* of a linear Rec.709 colour relative to white Y = 1, scaled to [0, 1]
/// (L*/100). L* depends only on Y, so CIE LUV and CIE Lab share it.
inline double lightnessLStar01(double r, double g, double b) {
    double y = std::max(0.0, luminance(r, g, b));
    constexpr double eps = 216.0 / 24389.0, kappa = 24389.0 / 27.0;
    double l = y > eps ? 116.0 * std::cbrt(y) - 16.0 : kappa * y;
    return l / 100.0;
}

}  // namespace sl
