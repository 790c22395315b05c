// Levelling and form removal of a height map, as surface-metrology tools do: a least-squares fit
// of a form on the valid (measured) points, subtracted from every point. Chosen by the scene
// file's heightmap.levelling (io/SceneFile.cpp), applied when the part is loaded.
//
//   none        the heights as read.
//   plane       z ≈ c0 + c1·x + c2·y (the polynomial of degree 1).
//   polynomial  every monomial x^a·y^b with a + b ≤ n (n = degree, 0..10), fitted in the basis of
//               Legendre polynomials P_a(u)·P_b(v) over the map's extent scaled to [−1, 1] (well
//               conditioned), normal equations solved by Cholesky in double precision.
//   cylinder    a cylinder whose axis runs along `axis` (x: along the map's columns' direction
//               +x; y: along its rows' direction, world z), level in height up to a slope b:
//               z ≈ c + σ·√(R² − (s − a)²) + b·t, s the coordinate across the axis, t along it,
//               σ = +1 for a convex surface (a bullet's land), −1 for a concave one. Vertical
//               residuals by Levenberg–Marquardt from an algebraic (Kåsa) circle fit of the
//               mean profile across the axis after the plane's slope along it. Exact: the sums
//               over a column of points are all it needs, so the fit is over every valid point.
//   auto        the default: plane for a measured map (X3P, SDF, an instrument format: the
//               instrument's tilt is not the part), none for EXR, TIFF, PNG and .npy (heights as
//               designed, e.g. gen-surface's parts).
// Coordinates are the world frame's (scene/Heightfield.h): x = (i − (W−1)/2)·p along columns,
// y here = (j − (H−1)/2)·p along rows (world z), heights in scene units.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace sl {

struct LevellingDesc {
    enum class Mode { Auto, None, Plane, Polynomial, Cylinder };
    Mode mode = Mode::Auto;
    int degree = 1;   // polynomial
    char axis = 'y';  // cylinder: the direction its axis runs along, 'x' or 'y'
    static constexpr int kMaxDegree = 10;
};

/// "auto", "none", "plane", "polynomial degree 3", "cylinder along y".
std::string levellingName(const LevellingDesc& d);

struct LevellingResult {
    LevellingDesc applied;   // never Auto
    bool automatic = false;  // chosen by auto
    size_t points = 0;       // valid points the fit used
    double rmsBefore = 0.0;  // RMS of the valid heights about their mean (scene units)
    double rmsAfter = 0.0;   // RMS of the levelled valid heights
    std::vector<double>
        coefficients;     // plane/polynomial: Legendre coefficients; cylinder: a, c, R, b
    double radius = 0.0;  // cylinder: R (scene units); negative: concave
    /// One line, e.g. "plane (auto, measured map): RMS 0.0123 -> 0.0019 mm over 352 511 points".
    std::string text() const;
};

/// Levels `heights` (W×H, row-major) in place; `invalid` (empty or W·H, 1 = invented) marks the
/// points the fit ignores. `measured` resolves auto. Throws InputError (naming `where`) when the
/// form cannot be fitted (too few valid points, a singular fit, no curvature for a cylinder).
LevellingResult levelHeights(std::vector<float>& heights, int width, int height, double pitch,
                             const std::vector<uint8_t>& invalid, const LevellingDesc& desc,
                             bool measured, const std::string& where);

}  // namespace sl
