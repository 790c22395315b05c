#include "perception/ContrastSensitivity.h"

#include <cmath>
#include <numbers>

namespace sl {

double bartenPupilDiameter(double luminance, double x0Deg, double y0Deg) {
    return bartenPupilDiameterOf(std::max(luminance * x0Deg * y0Deg, 1e-300) / (x0Deg * y0Deg),
                                 x0Deg, y0Deg);
}

double bartenRetinalIlluminance(double luminance, double pupilMm) {
    return bartenRetinalIlluminanceOf(luminance, pupilMm);
}

BartenCondition bartenCondition(double luminance, double x0Deg, double y0Deg,
                                const BartenConstants& c) {
    BartenCondition cond;
    cond.x0Deg = x0Deg;
    cond.y0Deg = y0Deg;
    if (!(luminance > 0)) return cond;
    const double d = bartenPupilDiameter(luminance, x0Deg, y0Deg);
    cond.sigmaDeg =
        std::sqrt(c.sigma0 * c.sigma0 + (c.cAb * d) * (c.cAb * d));  // as bartenSensitivityAt
    cond.illuminance = bartenRetinalIlluminance(luminance, d);
    return cond;
}

double bartenSensitivity(double u, const BartenCondition& cond, const BartenConstants& c) {
    if (!(u > 0) || !(cond.illuminance > 0) || !(cond.x0Deg > 0) || !(cond.y0Deg > 0)) return 0.0;
    return bartenSensitivityOf(u, cond.sigmaDeg, cond.illuminance, cond.x0Deg, cond.y0Deg, c);
}

double bartenSensitivity(double u, double luminance, double x0Deg, double y0Deg,
                         const BartenConstants& c) {
    return bartenSensitivity(u, bartenCondition(luminance, x0Deg, y0Deg, c), c);
}

SensitivityPeak bartenPeak(const BartenCondition& cond, const BartenConstants& c) {
    // S is unimodal in log u: golden-section search.
    double lo = std::log(0.05), hi = std::log(60.0);
    const double g = (std::sqrt(5.0) - 1.0) / 2.0;
    double a = hi - g * (hi - lo), b = lo + g * (hi - lo);
    double fa = bartenSensitivity(std::exp(a), cond, c),
           fb = bartenSensitivity(std::exp(b), cond, c);
    for (int i = 0; i < 100 && hi - lo > 1e-10; ++i) {
        if (fa < fb) {
            lo = a;
            a = b;
            fa = fb;
            b = lo + g * (hi - lo);
            fb = bartenSensitivity(std::exp(b), cond, c);
        } else {
            hi = b;
            b = a;
            fb = fa;
            a = hi - g * (hi - lo);
            fa = bartenSensitivity(std::exp(a), cond, c);
        }
    }
    const double u = std::exp(0.5 * (lo + hi));
    return {u, bartenSensitivity(u, cond, c)};
}

}  // namespace sl
