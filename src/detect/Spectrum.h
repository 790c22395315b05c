// The defect map's spectrum (detect/DefectMap.h, method auto, steps 2–3): the map padded to an
// FFT-friendly size (a mirror cross-faded into its own start), its half spectrum and back.
#pragma once

#include <complex>
#include <span>
#include <vector>

namespace sl::defectmap {

using Complex = std::complex<float>;

struct Padded {
    int W = 0, H = 0, leadX = 0, leadY = 0;
    std::vector<float> data;  // H rows of W
};

Padded padMap(std::span<const float> h, int W, int H, int pad, double mean);

struct Spectrum {
    int W = 0, H = 0, Wh = 0;   // padded size, half width W/2 + 1
    std::vector<Complex> bins;  // H rows of Wh: row kz, column kx
};

Spectrum forward(const Padded& p);

/// Inverse of forward(), cropped to the map (W×H at the padding's lead).
std::vector<float> inverse(Spectrum& s, const Padded& p, int W, int H);

}  // namespace sl::defectmap
