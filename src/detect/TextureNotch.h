// The defect map's texture model (detect/DefectMap.h, method auto, steps 1–3): the macro shape
// (a separable running median) and the periodic tool-path texture (the spectral notch).
#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include "detect/DefectMap.h"

namespace sl::defectmap {

/// What steps 1–3 are asked for beyond R and the macro shape, and where they start.
struct TextureRequest {
    bool texture = false;      // the texture T (textureSectors == 1)
    bool sectors = false;      // T split by orientation (textureSectors > 1)
    bool period = false;       // the dominant period of h − macro (the ring model's pitch)
    bool levelDelta = false;   // with levelWiener: what step 4 adds to the level
    std::vector<float> prior;  // a texture found before: every pass starts from h minus it
    int passes = 0;            // 0: o.passes
};

/// The notch's statistics: the spectrum's bins notched of all, the padded FFT's size.
struct NotchStats {
    size_t notchedBins = 0, spectrumBins = 0;
    int fftWidth = 0, fftHeight = 0;
};

/// Steps 1–3's results (W×H each; a field not requested stays empty, or 0).
struct TextureResidual {
    std::vector<float> residual;              // R = h − macro − texture
    std::vector<float> macro;                 // the macro shape
    std::vector<float> texture;               // T (request.texture)
    std::vector<std::vector<float>> sectors;  // T by orientation, their sum T (request.sectors)
    double period = 0;                        // samples (request.period)
    std::vector<float> levelDelta;            // the Wiener estimate's level minus A
    NotchStats notch;                         // the last pass's notch
};

/// Steps 1–3: R = h − macro − texture, with what `request` asks for, and the notch's
/// statistics.
TextureResidual textureResidual(std::span<const float> h, int W, int H, const DefectMapOptions& o,
                                TextureRequest request = {});

}  // namespace sl::defectmap
