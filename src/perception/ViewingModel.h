// How a person sees the image (README "Visibility in JND"): the angle one image pixel
// subtends at the eye and the luminance of the display's white.
//
// Two ways to say it, each a field of the scene file's "viewing" block (io/SceneFile.cpp):
//   display: the render on a screen of `display_pixel_mm` pixels seen from `distance_mm`
//            (the default: a 0.27 mm pixel, a 24" full-HD monitor, at 600 mm: 38.8 pixels per
//            degree, a white of 200 cd/m²: a person at a bench in front of the tool's images);
//   part:    the part itself seen from `distance_mm` through a loupe of `magnification`, one
//            image pixel covering `mm_per_pixel` of the part (the camera's footprint).
// Luminance: the light E = 1 everywhere (the white furnace) shows the part's mean at the
// display's white; a dimmer light shows dimmer (the scale the brightness floor uses), so a
// light that shows almost nothing is seen at the low luminance it has.
#pragma once

#include <optional>
#include <string>

namespace sl {

struct ViewingModel {
    double pixelsPerDegree = 0;   // image pixels per degree of visual angle
    double whiteLuminance = 200;  // cd/m² of the display's (or the lit part's) white

    /// A w-pixel image shown at `pixelMm` per pixel from `distanceMm`.
    static ViewingModel display(double distanceMm, double pixelMm, double whiteCdM2);
    /// The part seen directly (or through a loupe): one image pixel is `mmPerPixel` of it.
    static ViewingModel part(double distanceMm, double magnification, double mmPerPixel,
                             double whiteCdM2);
    /// One line for logs and reports: "38.8 px/deg, white 200 cd/m²".
    std::string describe() const;
};

/// The default: a monitor at a bench (600 mm, 0.27 mm pixels, 200 cd/m²).
inline constexpr double kViewingDistanceMm = 600.0;
inline constexpr double kDisplayPixelMm = 0.27;
inline constexpr double kDisplayWhiteCdM2 = 200.0;
ViewingModel defaultViewing();

/// The scene file's "viewing" block as written (io/SceneFile.cpp checks its fields):
/// pixels_per_degree given wins; else magnification given: the part through a loupe; else a
/// display. Unset fields take the defaults above.
struct ViewingDesc {
    std::optional<double> pixelsPerDegree;
    double distanceMm = kViewingDistanceMm;
    double displayPixelMm = kDisplayPixelMm;
    std::optional<double> magnification;
    double whiteCdM2 = kDisplayWhiteCdM2;
};
/// The model for an image whose pixel covers `imageMmPerPixel` of the part (used by the
/// magnification form only).
ViewingModel resolveViewing(const ViewingDesc& desc, double imageMmPerPixel);

}  // namespace sl
