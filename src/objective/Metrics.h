// Visibility metrics (the quantitative evaluation the paper's §6 asks for), computed on a render
// I = T·E (or a path-traced image) and its env map E. Every summary.json and report carries them.
//
// Definitions (Y = luminance of I: I itself for 1 channel, 0.2126R + 0.7152G + 0.0722B for 3):
//  * mean luminance gradient of a region R: the mean over COUNTED PAIRS of |ΔY|, a pair being a
//    pixel and its right or lower neighbour with BOTH pixels in R (the pair rule of the
//    objective, objective/Objective.h, so gradientInside = G / pairs for the loss mask M).
//      gradientInside   R = the optimization (loss) mask M
//      gradientOutside  R = object-mask pixels NOT in M (NaN when that region has no pair, e.g.
//                       when M is the whole object mask)
//      gradientRatio    gradientInside / gradientOutside (NaN when either is NaN or outside = 0)
//  * clippedFraction: fraction of object-mask pixels that are clipped: Y ≥ 1 for a 1-channel
//    image, ANY channel ≥ 1 for an RGB image (what a display clips).
//  * envSparsity: fraction of the env map's values (all texels × channels) below 1e-3.
//  * envMeanChroma: mean over texels of the CIE 1976 LUV chroma C*_uv / 100 of the texel's
//    linear Rec.709 RGB (white Y = 1, white point = RGB (1, 1, 1), i.e. D65), so gray texels are
//    exactly 0 and sRGB red (1, 0, 0) is 1.7908 (XYZ by core/Color.h rgbToXyz, IEC 61966-2-1's
//    matrix); a 1-channel (gray) E gives 0.
//  * truth (only with a ground-truth defect mask projected into the image, objective/
//    ImageSpace.h): the object-mask pairs are split into DEFECT pairs (at least one pixel in the
//    truth mask) and BACKGROUND pairs (neither pixel in it):
//      defectGradient / backgroundGradient  their mean |ΔY|
//      gradientRatio  defectGradient / backgroundGradient: how much more the image changes
//                     across true defects than elsewhere on the part (> 1: defects stand out)
//      weberContrast  (mean Y over defect pixels − mean Y over the other object pixels) / the
//                     latter: signed; near 0 when a defect's bright and dark flanks cancel
//    NaN when a side has no pair / pixel (e.g. no defect is visible).
// NaN is written as JSON null.
#pragma once

#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>

namespace sl {

struct MetricsInput {
    int width = 0, height = 0, channels = 1;  // image; channels 1 or 3
    std::span<const double> image;            // width*height*channels, linear, interleaved
    std::span<const uint8_t> objectMask;      // width*height, nonzero = the part
    std::span<const uint8_t> lossMask;        // width*height, nonzero = in M (empty: = object)
    std::span<const double> envmap;           // E: texels × envChannels (may be empty)
    int envChannels = 1;                      // 1 (gray) or 3 (RGB interleaved)
    std::span<const uint8_t> truthMask;       // width*height image-space truth (empty: none)
};

struct TruthMetrics {
    double defectGradient = 0, backgroundGradient = 0, gradientRatio = 0, weberContrast = 0;
    size_t defectPairs = 0, backgroundPairs = 0, defectPixels = 0;
};

struct VisibilityMetrics {
    double gradientInside = 0, gradientOutside = 0, gradientRatio = 0;
    size_t pairsInside = 0, pairsOutside = 0;
    double clippedFraction = 0;
    size_t objectPixels = 0;
    double envSparsity = 0;
    double envMeanChroma = 0;
    std::optional<TruthMetrics> truth;
};

/// Computes the metrics. Throws std::invalid_argument on inconsistent sizes.
VisibilityMetrics computeVisibilityMetrics(const MetricsInput& in);

/// CIE 1976 LUV chroma C*_uv / 100 of a linear Rec.709 colour (white Y = 1, D65 white).
double chromaUv01(double r, double g, double b);

/// JSON object with snake_case keys (gradient_inside, ..., truth: {...} or null); NaN → null.
nlohmann::json toJson(const VisibilityMetrics& m);

}  // namespace sl
