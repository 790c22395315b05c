// Least-squares surfaces on a grid: the one fit of a bivariate polynomial to a height map that
// scene/Levelling (form removal), detect/SelfSimMap (the quadratic under the texture) and
// synth/DefectInsert (the texture's Sq) share, and the Cholesky solve beneath it.
//
// The basis is Legendre's: the terms P_a(u)·P_b(v) with a + b <= degree, u = 2i/(w−1) − 1 along
// the columns and v = 2j/(h−1) − 1 along the rows (0 along an axis of one sample), in the order
// (total degree, then a descending): 1, u, v, u², uv, v², … The normal equations of this basis
// on a regular grid are nearly diagonal (Legendre polynomials are orthogonal on [−1, 1]), so
// Cholesky keeps the digits that monomials in pixel coordinates (entries from the sample count
// to ~1e60 at degree 10 on 1024 samples) would lose: on a 1024 × 768 grid at degree 10, with a
// large offset, the fit of an exact polynomial leaves only the samples' own float rounding
// (tests/test_polynomial_fit.cpp). A term of degree a >= w along u (b >= h along
// v) is left out: on w samples it equals a combination of lower ones, so the fitted surface is
// the same and the system stays regular (a map one or two samples wide).
//
// The sums are accumulated per image row (the sums over a row of P_a(u)·P_c(u) combined with
// the row's P_b(v)·P_d(v): (degree+1)² work per sample, not K²), in double.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

namespace sl {

/// Solves the symmetric positive definite system A·x = b (K×K, row-major) by Cholesky; x
/// replaces b. False when A is not positive definite to working precision (a pivot at most
/// 1e-13 × A's largest diagonal entry).
bool solveSpd(std::vector<double> a, std::vector<double>& b, size_t k);

/// A fitted polynomial surface on a width × height grid (the header's basis).
struct PolynomialSurface {
    int degree = 0;
    size_t width = 0, height = 0;
    std::vector<std::array<int, 2>> terms;  // (a, b): P_a(u)·P_b(v), in the header's order
    std::vector<double> coefficients;       // one per term
    std::vector<double> pu, pv;             // P_0..P_degree at each column's u, at each row's v

    /// The surface's values along row j (width of them) into `out`.
    void row(size_t j, std::vector<double>& out) const;
};

/// The least-squares polynomial surface of total degree `degree` (>= 0) through the samples
/// of z (width × height, row-major) that `invalid` does not exclude (empty: all samples; else
/// one byte per sample, nonzero = left out). Nothing when the valid samples do not determine
/// it (too few, or all on a line).
std::optional<PolynomialSurface> fitPolynomialSurface(std::span<const float> z, size_t width,
                                                      size_t height, int degree,
                                                      std::span<const uint8_t> invalid = {});

}  // namespace sl
