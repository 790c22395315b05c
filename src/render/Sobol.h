// Sobol' points for the `stratified` sampler (render/PathTracer.h, CONVENTION (direction
// sampling)): the first six dimensions of the Sobol' sequence as 32-bit binary fractions.
// Dimension 0 is van der Corput's; 1..5 use the direction numbers of S. Joe and F. Kuo,
// "Constructing Sobol sequences with better two-dimensional projections" (2008), file
// new-joe-kuo-6.21201 (degree s, coefficients a, initial m_1..m_s: 1 0 1 | 2 1 1 3 | 3 1 1 3 1 |
// 3 2 1 1 1 | 4 1 1 1 3 3), expanded with Bratley and Fox's recurrence. Dimensions 0 and 1 form
// a (0, 2)-sequence: the first 2^m points put one point in every elementary interval of area
// 2^-m (tests/test_sampling.cpp checks it).
#pragma once

#include <cstdint>

namespace sl {

inline constexpr int kSobolDimensions = 6;

/// Point `index` of the Sobol' sequence in dimension dim (0 .. kSobolDimensions−1): the
/// binary fraction x / 2^32 in [0, 1).
uint32_t sobol(uint32_t index, int dim);

}  // namespace sl
