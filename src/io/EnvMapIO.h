// EnvMapIO: environment maps in and out, and area-weighted resampling onto the texel grid.
//
// Texel grid (Mitsuba 3's `envmap` emitter, see scene/EnvMapBasis.h): texel (row j, column i)
// of a W×H map sits at θ_j = jπ/(H−1) (row 0 = +Y pole, row H−1 = −Y pole) and u_i = (i+½)/W
// (φ = 2πu, wrapping in u). For resampling, texel (j, i) stands for the cell
//     u ∈ [i/W, (i+1)/W] × θ ∈ [max(0, (j−½)π/(H−1)), min(π, (j+½)π/(H−1))]
// (half-height cells at the poles); the cells partition the sphere.
//
// Input images use the usual pixel-area equirectangular convention: pixel (x, y) of a
// Win×Hin image covers u ∈ [x/Win, (x+1)/Win] × θ ∈ [yπ/Hin, (y+1)π/Hin].
//
// resampleEquirect gives each texel the solid-angle-weighted mean of the input over its cell:
// exact overlaps, length in u times ∫ sinθ dθ = cosθ0 − cosθ1 in θ, separable, O(Win·Hin),
// accumulated in double. Hence Σ texel·cellSolidAngle = ∫ input dω (to rounding).
// Channels: 1-channel output from RGB input is the luminance Y = 0.2126R + 0.7152G + 0.0722B;
// 3-channel output from gray input repeats it; an alpha channel is ignored. Values are not
// clamped (an optimizer's bounds are its own business).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "core/Image.h"
#include "scene/EnvMap.h"

namespace sl {

/// Area-weighted resampling of an equirectangular image (1–4 channels; 2 = gray+alpha,
/// 4 = RGBA) onto a width×height texel grid with `channels` (1 or 3) channels.
/// Requires width >= 1, height >= 2 and finite input; `where` names the source in errors.
EnvMap resampleEquirect(const Image& src, int width, int height, int channels,
                        const std::string& where = "env map image");

/// Negative env-map values down to this fraction of the map's maximum are clamped (loadEnvMap).
inline constexpr double kEnvNegativeTolerance = 1e-4;

/// Reads an env map image (readImage: EXR/HDR linear, PNG/JPEG sRGB-decoded) and resamples it
/// with resampleEquirect. Exception: a file that already has exactly width×height pixels is
/// taken as texels on the grid (what writeEnvMap writes and how Mitsuba reads it), so a saved
/// map loads back unchanged; only its channels are converted. channels == 0: as in the file
/// (1 for gray or gray+alpha, 3 for RGB or RGBA). A file with a NaN or infinite colour value is
/// refused (InputError naming the file and the first such pixel): radiance is finite. Radiance is
/// never negative either, but real HDR photos carry resampling ringing (Blender's HDRIs: −3e-6 to
/// −0.004 against maxima of 55–34 000): negative values down to kEnvNegativeTolerance × the
/// map's largest colour value are clamped to 0 with one warning line (spdlog: how many pixels,
/// the worst); a larger one is refused, naming the worst pixel, the count and the maximum.
EnvMap loadEnvMap(const std::filesystem::path& file, int width, int height, int channels);

/// A light spec, one grammar for every option that takes a light (`where` names it in errors):
///   FILE or envmap:FILE   loadEnvMap(FILE, width, height, channels)
///   const:V               every texel V >= 0 (gray; `channels` 3 gives three equal values)
///   a preset name         scene/EnvMapPresets.h (e.g. studio), unless a file of that name exists
/// channels as loadEnvMap (0: as stored; constants and presets are then gray).
EnvMap lightFromSpec(const std::string& spec, int width, int height, int channels,
                     const std::string& where);
/// "FILE (EXR/HDR/PNG/JPEG, equirectangular) | const:V (V >= 0) | studio", from the presets.
std::string lightSpecForms();

/// Solid angle of every texel's cell, row-major (width*height values), summing to 4π.
std::vector<double> envCellSolidAngles(int width, int height);

/// Writes the env map as float32 EXR ("Y" or "R","G","B"), atomically.
void writeEnvMap(const std::filesystem::path& file, const EnvMap& env);

/// Nearest-neighbour enlargement by `scale` (>= 1) for a readable PNG preview (writePng).
Image envMapPreview(const EnvMap& env, int scale);

}  // namespace sl
