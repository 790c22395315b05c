// The contrast sensitivity of the human eye: Barten's model (P. G. J. Barten, "Contrast
// Sensitivity of the Human Eye and Its Effects on Image Quality", SPIE 1999, ch. 3; the same
// model as his "Formula for the contrast sensitivity of the human eye", Proc. SPIE 5294, 2004).
//
// Sensitivity S = 1 / modulation threshold of a sinusoidal grating (50 % detection), as a
// function of its spatial frequency u (cycles/degree), the mean luminance L (cd/m²) and the
// angular size X0 × Y0 (degrees) of the grating's field:
//
//   S(u) = M_opt(u)/k / sqrt( (2/T) · (1/X² + ...)(u) · ( 1/(η·p·E) + Φ0 / (1 − exp(−(u/u0)²)) ) )
//
//   M_opt(u) = exp(−2π² σ² u²)                   the eye's optics, σ = sqrt(σ0² + (C_ab·d)²)
//   1/(X·Y)  with X = (1/X0² + 1/X_max² + u²/N_max²)^(−1/2), Y likewise: spatial integration
//   d        = 5 − 3·tanh(0.4·log10(L·X0·Y0/40²))  the pupil (mm)
//   E        = π d²/4 · L · (1 − (d/9.7)² + (d/12.4)⁴)   retinal illuminance (Td), Stiles–Crawford
//
// with Barten's standard constants (BartenConstants). Valid for photopic luminance (≳ 0.1
// cd/m²), foveal, static viewing. The tests hold the formula against its published values.
#pragma once

#include <cmath>
#include <numbers>

namespace sl {

struct BartenConstants {
    double k = 3.0;            // signal-to-noise ratio at threshold
    double T = 0.1;            // integration time of the eye (s)
    double xMax = 12.0;        // maximum angular size of the integration area (deg)
    double nMax = 15.0;        // maximum number of cycles integrated
    double eta = 0.03;         // quantum efficiency of the eye
    double p = 1.2274e6;       // photon conversion factor (photons/s/deg²/Td)
    double phi0 = 3e-8;        // spectral density of the neural noise (s·deg²)
    double u0 = 7.0;           // spatial frequency above which lateral inhibition ceases (c/deg)
    double sigma0 = 0.5 / 60;  // σ of the optics' line spread at small pupils (deg)
    double cAb = 0.08 / 60;    // its growth with the pupil diameter (deg/mm)
};

/// The pupil diameter (mm) for luminance L (cd/m²) seen over X0 × Y0 degrees.
double bartenPupilDiameter(double luminance, double x0Deg, double y0Deg);
/// Retinal illuminance (Td) for luminance L and pupil d, with the Stiles–Crawford correction.
double bartenRetinalIlluminance(double luminance, double pupilMm);

/// The eye's state for one viewing condition: what the sensitivity needs besides u.
struct BartenCondition {
    double sigmaDeg = 0;     // σ of the optical line spread (deg)
    double illuminance = 0;  // retinal illuminance E (Td)
    double x0Deg = 0, y0Deg = 0;
};
/// The condition at luminance L over a field of X0 × Y0 degrees (pupil from Barten's formula).
BartenCondition bartenCondition(double luminance, double x0Deg, double y0Deg,
                                const BartenConstants& c = {});

/// Contrast sensitivity S(u) (1 / threshold modulation) at u cycles/degree; 0 at u ≤ 0 (no
/// pattern) and for a dark field (L ≤ 0).
double bartenSensitivity(double u, const BartenCondition& cond, const BartenConstants& c = {});
double bartenSensitivity(double u, double luminance, double x0Deg, double y0Deg,
                         const BartenConstants& c = {});

/// The frequency (c/deg) where S peaks for this condition, and S there (golden-section search
/// on log u over [0.05, 60]).
struct SensitivityPeak {
    double frequency = 0;
    double sensitivity = 0;
};
SensitivityPeak bartenPeak(const BartenCondition& cond, const BartenConstants& c = {});

// --- the formulas, in any scalar type S (double, core/Dual.h, ceres::Jet) --------------------
// The JND objective (objective/JndObjective.h) differentiates them with respect to the
// luminance; the double functions above are these with S = double. The caller keeps L > 0.

/// d(L) of bartenPupilDiameter.
template <typename S>
S bartenPupilDiameterOf(const S& luminance, double x0Deg, double y0Deg) {
    using std::log10;
    using std::tanh;
    return 5.0 - 3.0 * tanh(0.4 * log10(luminance * (x0Deg * y0Deg / (40.0 * 40.0))));
}
/// E(L, d) of bartenRetinalIlluminance.
template <typename S>
S bartenRetinalIlluminanceOf(const S& luminance, const S& d) {
    const S a = d / 9.7, b = d / 12.4;
    const S stilesCrawford = 1.0 - a * a + (b * b) * (b * b);
    return (std::numbers::pi / 4.0) * d * d * luminance * stilesCrawford;
}
/// S(u) at σ (deg) and E (Td) of bartenSensitivity; u > 0, E > 0, X0, Y0 > 0.
template <typename S>
S bartenSensitivityOf(double u, const S& sigmaDeg, const S& illuminance, double x0Deg, double y0Deg,
                      const BartenConstants& c = {}) {
    using std::exp;
    using std::sqrt;
    const double pi = std::numbers::pi;
    const S mOpt = exp(-2.0 * pi * pi * u * u * sigmaDeg * sigmaDeg);
    const auto inverseSquaredSide = [&](double side) {
        return 1.0 / (side * side) + 1.0 / (c.xMax * c.xMax) + u * u / (c.nMax * c.nMax);
    };
    const double area = std::sqrt(inverseSquaredSide(x0Deg) * inverseSquaredSide(y0Deg));
    const S photonNoise = 1.0 / (c.eta * c.p * illuminance);
    const double neuralNoise = c.phi0 / (1.0 - std::exp(-(u / c.u0) * (u / c.u0)));
    return (mOpt / c.k) / sqrt(2.0 / c.T * area * (photonNoise + neuralNoise));
}
/// S(u) at luminance L > 0 over X0 × Y0 degrees (pupil, optics, illuminance from L).
template <typename S>
S bartenSensitivityAt(double u, const S& luminance, double x0Deg, double y0Deg,
                      const BartenConstants& c = {}) {
    using std::sqrt;
    const S d = bartenPupilDiameterOf(luminance, x0Deg, y0Deg);
    const S sigma = sqrt(c.sigma0 * c.sigma0 + (c.cAb * d) * (c.cAb * d));
    return bartenSensitivityOf(u, sigma, bartenRetinalIlluminanceOf(luminance, d), x0Deg, y0Deg, c);
}

}  // namespace sl
