#include "perception/ContrastSensitivity.h"

#include <cmath>
#include <numbers>

namespace sl {

double bartenPupilDiameter(double luminance, double x0Deg, double y0Deg) {
    const double a = std::max(luminance * x0Deg * y0Deg, 1e-300) / (40.0 * 40.0);
    return 5.0 - 3.0 * std::tanh(0.4 * std::log10(a));
}

double bartenRetinalIlluminance(double luminance, double pupilMm) {
    const double d = pupilMm;
    const double stilesCrawford = 1.0 - std::pow(d / 9.7, 2) + std::pow(d / 12.4, 4);
    return std::numbers::pi * d * d / 4.0 * luminance * stilesCrawford;
}

BartenCondition bartenCondition(double luminance, double x0Deg, double y0Deg,
                                const BartenConstants& c) {
    BartenCondition cond;
    cond.x0Deg = x0Deg;
    cond.y0Deg = y0Deg;
    if (!(luminance > 0)) return cond;
    const double d = bartenPupilDiameter(luminance, x0Deg, y0Deg);
    cond.sigmaDeg = std::hypot(c.sigma0, c.cAb * d);
    cond.illuminance = bartenRetinalIlluminance(luminance, d);
    return cond;
}

namespace {

/// 1 / X², X = (1/X0² + 1/X_max² + u²/N_max²)^(−1/2): the integration area's side.
double inverseSquaredSide(double u, double side, double xMax, double nMax) {
    return 1.0 / (side * side) + 1.0 / (xMax * xMax) + u * u / (nMax * nMax);
}

}  // namespace

double bartenSensitivity(double u, const BartenCondition& cond, const BartenConstants& c) {
    if (!(u > 0) || !(cond.illuminance > 0) || !(cond.x0Deg > 0) || !(cond.y0Deg > 0)) return 0.0;
    const double pi = std::numbers::pi;
    const double mOpt = std::exp(-2.0 * pi * pi * cond.sigmaDeg * cond.sigmaDeg * u * u);
    const double area = std::sqrt(inverseSquaredSide(u, cond.x0Deg, c.xMax, c.nMax) *
                                  inverseSquaredSide(u, cond.y0Deg, c.xMax, c.nMax));
    const double photonNoise = 1.0 / (c.eta * c.p * cond.illuminance);
    const double neuralNoise = c.phi0 / (1.0 - std::exp(-(u / c.u0) * (u / c.u0)));
    return (mOpt / c.k) / std::sqrt(2.0 / c.T * area * (photonNoise + neuralNoise));
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
