// The defect map's ring model of a rotational texture (detect/DefectMap.h, method auto, step 4b).
#pragma once

#include <span>
#include <vector>

#include "detect/DefectMap.h"

namespace sl::defectmap {

struct RingFit {
    double cx = 0, cz = 0;  // centre (samples: x = column, z = row)
    double pitch = 0;       // samples per revolution (0: circles)
    int hand = 1;           // the spiral's radius grows by hand·pitch per turn of +angle
    double isotropy = 0, residual = 1;
};

/// Step 4b's fit and decision on d = h − macro (fitRings); fills info's ring fields.
RingFit ringFit(std::span<const float> h, const std::vector<float>& macro, int W, int H,
                const DefectMapOptions& o, double pitch, DefectMap& info);

/// Step 4b where the rings are used (info.ringUsed): A (the level) becomes A_ring = d −
/// grooveMedian(d), d = h − macro, at samples with |A| >= growSigma·σ_A and |A_ring| <=
/// ringRatio·|A|, no smaller in magnitude than the median of |A| (so σ_A stays as it was).
void ringLevel(std::span<const float> h, const std::vector<float>& macro, std::vector<float>& A,
               int W, int H, const DefectMapOptions& o, double floorSigma, const RingFit& f,
               DefectMap& info);

}  // namespace sl::defectmap
