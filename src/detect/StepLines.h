// The defect map's tool-change steps (detect/DefectMap.h, method auto, step 4a): the centre
// lines of steps in h − T, their ramps and bands.
#pragma once

#include <cstdint>
#include <vector>

#include "detect/DefectMap.h"

namespace sl::defectmap {

/// One point of a detected step's centre line.
struct StepPoint {
    float x, z;    // the centre (samples, sub-sample along the detector's direction)
    float nx, nz;  // unit normal, pointing to the side that is higher by `jump`
    float jump;    // > 0, height units
};

struct StepModel {
    std::vector<StepPoint> points;
    std::vector<uint8_t> ramp;  // the samples within stepRampHalf of a centre line
    std::vector<uint8_t> band;  // the samples within stepBand of a centre line
};

/// Step 4a's lines on G = h − T (DefectMap.h): their points, ramps and bands.
StepModel detectSteps(const std::vector<float>& G, int W, int H, const DefectMapOptions& o,
                      double floorSigma);

}  // namespace sl::defectmap
