// Contrast masking: how much a background pattern raises the threshold of a signal seen on it.
//
// Legge & Foley ("Contrast masking in human vision", JOSA 70(12), 1980) measured the threshold
// of a grating on a masking grating over three log units of masker contrast: below the
// masker's own threshold the signal's threshold is unchanged; above it, the threshold grows as
// a power of the masker's contrast with an exponent near 0.6. With m the masker's contrast in
// units of its own detection threshold (contrast × sensitivity), the threshold elevation is
//
//   TE(m) = (1 + m^(b·ε))^(1/b),   ε = 0.6 (Legge & Foley's exponent),
//
// 1 for m ≪ 1 and m^ε for m ≫ 1; b = 4 only sets how sharp the knee between the two is (our
// choice; at m = 1 TE = 2^(1/4) = 1.19). The facilitation ("dipper") at masker contrasts near
// threshold is left out, as masking models for image quality leave it out: a texture never
// makes a defect easier to see here.
#pragma once

#include <cmath>

namespace sl {

inline constexpr double kMaskingExponent = 0.6;  // Legge & Foley 1980
inline constexpr double kMaskingKnee = 4.0;

/// Threshold elevation for a masker at m threshold units (m ≤ 0: no masker, 1).
inline double thresholdElevation(double m) {
    if (!(m > 0)) return 1.0;
    return std::pow(1.0 + std::pow(m, kMaskingKnee * kMaskingExponent), 1.0 / kMaskingKnee);
}

}  // namespace sl
