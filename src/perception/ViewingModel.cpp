#include "perception/ViewingModel.h"

#include <cmath>
#include <numbers>
#include <stdexcept>

#include "core/Text.h"

namespace sl {

namespace {

/// Pixels per degree when one pixel spans `sizeMm` at `distanceMm` (centred on the line of
/// sight: 2·atan(s/2d)).
double perDegree(double sizeMm, double distanceMm) {
    if (!(sizeMm > 0) || !(distanceMm > 0) || !std::isfinite(sizeMm) || !std::isfinite(distanceMm))
        throw std::invalid_argument("ViewingModel: sizes and distances must be positive");
    const double deg = 2.0 * std::atan(sizeMm / (2.0 * distanceMm)) * 180.0 / std::numbers::pi;
    return 1.0 / deg;
}

}  // namespace

ViewingModel ViewingModel::display(double distanceMm, double pixelMm, double whiteCdM2) {
    if (!(whiteCdM2 > 0) || !std::isfinite(whiteCdM2))
        throw std::invalid_argument("ViewingModel: the white luminance must be positive");
    return {perDegree(pixelMm, distanceMm), whiteCdM2};
}

ViewingModel ViewingModel::part(double distanceMm, double magnification, double mmPerPixel,
                                double whiteCdM2) {
    if (!(magnification > 0) || !std::isfinite(magnification))
        throw std::invalid_argument("ViewingModel: the magnification must be positive");
    return display(distanceMm, mmPerPixel * magnification, whiteCdM2);
}

std::string ViewingModel::describe() const {
    return formatNumber(pixelsPerDegree, 3) + " px/deg, white " + formatNumber(whiteLuminance, 3) +
           " cd/m²";
}

ViewingModel resolveViewing(const ViewingDesc& d, double imageMmPerPixel) {
    if (d.pixelsPerDegree) {
        if (!(*d.pixelsPerDegree > 0) || !std::isfinite(*d.pixelsPerDegree) || !(d.whiteCdM2 > 0) ||
            !std::isfinite(d.whiteCdM2))
            throw std::invalid_argument(
                "ViewingModel: pixels per degree and white must be positive");
        return {*d.pixelsPerDegree, d.whiteCdM2};
    }
    if (d.magnification)
        return ViewingModel::part(d.distanceMm, *d.magnification, imageMmPerPixel, d.whiteCdM2);
    return ViewingModel::display(d.distanceMm, d.displayPixelMm, d.whiteCdM2);
}

ViewingModel defaultViewing() {
    return ViewingModel::display(kViewingDistanceMm, kDisplayPixelMm, kDisplayWhiteCdM2);
}

}  // namespace sl
