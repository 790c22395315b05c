// A set of samples' (or points') extent on a map: how elongated it is, along which axis, and
// where its centroid lies. Used by the self-similarity map's shape tests (detect/SelfSimMap.h)
// and by the marks' shapes (detect/MarkShapes.h).
#pragma once

#include <cstddef>
#include <span>

namespace sl {

/// The square root of the coordinates' covariance eigenvalues' ratio (each sample a unit square:
/// + 1/12 on both variances, so a single sample or a straight one-sample-wide line is finite),
/// the direction of the long axis (radians from the x axis, in [0, π)) and the centroid.
struct Extent {
    double elongation = 1.0, axis = 0.0, cx = 0.0, cz = 0.0;
};

/// The elongation and the long axis from the coordinates' central second moments (each sample
/// or point a unit square: + 1/12 on both variances); the centroid is left as it is.
void extentFromMoments(Extent& e, double cxx, double czz, double cxz);

/// The extent of samples given by their row-major indices on a map W samples wide (empty: the
/// default Extent).
Extent extentOf(std::span<const size_t> samples, int W);

}  // namespace sl
