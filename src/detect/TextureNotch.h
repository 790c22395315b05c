// The defect map's texture model (detect/DefectMap.h, method auto, steps 1–3): the macro shape
// (a separable running median) and the periodic tool-path texture (the spectral notch).
#pragma once

#include <span>
#include <vector>

#include "detect/DefectMap.h"

namespace sl::defectmap {

/// Steps 1–3: returns R = h − macro − texture; `macroOut` and `textureOut` (if given) receive
/// the macro shape and the texture T, `periodOut` the dominant period of h − macro,
/// `levelDeltaOut` (with levelWiener) what step 4 adds to the level for the Wiener estimate.
/// With `prior` (a texture found before), `passes` passes (default o.passes) all start from h
/// minus the texture found so far.
std::vector<float> textureResidual(std::span<const float> h, int W, int H,
                                   const DefectMapOptions& o, DefectMap* info,
                                   std::vector<float>* macroOut = nullptr,
                                   std::vector<float>* textureOut = nullptr,
                                   std::vector<std::vector<float>>* sectorsOut = nullptr,
                                   double* periodOut = nullptr,
                                   std::vector<float>* levelDeltaOut = nullptr,
                                   std::vector<float>* prior = nullptr, int passes = 0);

}  // namespace sl::defectmap
