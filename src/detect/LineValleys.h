// The defect map's line valleys (detect/DefectMap.h, method auto, step 7a): long, straight,
// narrow grooves, lower than the surface on both sides.
#pragma once

#include <cstdint>
#include <vector>

#include "detect/DefectMap.h"

namespace sl::defectmap {

/// Step 7a, the line-valley score: a scratch is a long, straight, narrow groove, lower than the
/// surface on both of its sides. For each of `lineOrientations` directions θ = πk/K, L_θ = the
/// mean of A over a segment about `lineLength` samples long along θ (segmentMeans), and
/// V_θ = min(L_θ(p + o·n) − L_θ(p), L_θ(p − o·n) − L_θ(p)) / σ_θ with n the normal,
/// o = `lineOffset` (rounded to samples) and σ_θ = 1.4826 × the median of both differences'
/// magnitudes. V = max over θ of V_θ, 0 within `border`. Returns 1 on the regions of
/// V ≥ lineGrowSigma (8-connected) that reach V ≥ lineSeedSigma (both raised by step 7b, its
/// tail without the samples `skip` holds, when given), 0 elsewhere.
std::vector<uint8_t> lineValleyRegions(const std::vector<float>& A, int W, int H,
                                       const DefectMapOptions& o, double* seedUsed,
                                       const std::vector<uint8_t>* skip = nullptr);

}  // namespace sl::defectmap
