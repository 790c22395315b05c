// EnvMapBasis: the ONE place that maps directions to env-map texels.
//
// CONVENTION (env map) — Mitsuba 3's `envmap` emitter, checked against Mitsuba 3.8.0
// src/emitters/envmap.cpp (direction_to_uv / eval_spectrum / half_texel):
//   * a world direction d (the direction a path travels when it escapes) maps to
//       u = atan2(d.x, -d.z) / 2π,   v = acos(d.y) / π          (row 0 = +Y, top of the image)
//   * lookup is bilinear on a W×H texel grid whose rows sit at θ_j = jπ/(H−1) (first and last
//     rows exactly at the poles) and whose columns sit at u_i = (i + ½)/W, wrapping in u
//     (Mitsuba pads the image with a copy of column 0 and shifts u by half a texel, 0.5/W).
//   * so: x = frac(u − 0.5/W)·W, y = v·(H−1); i0 = min(floor(x), W−1), j0 = min(floor(y), H−2);
//     weights (1−fx)(1−fy), fx(1−fy), (1−fx)fy, fx·fy on (i0,j0), (i0+1 mod W,j0), (i0,j0+1),
//     (i0+1 mod W,j0+1).
// Early Mitsuba 3 versions had no half-texel shift in u. Another convention (nearest texel,
// area-integrated texels) is a change to this class only: every renderer, sink and exporter
// reads the env map through `weights()`.
#pragma once

#include <array>
#include <cstdint>

#include "core/Vec3.h"

namespace sl {

struct TexelWeights {
    std::array<uint32_t, 4> index{};  // texel index j*W + i
    std::array<float, 4> weight{};    // bilinear weights, sum to 1
};

/// An env map's texel grid: width × height texels (columns in u, rows in v).
struct EnvMapGrid {
    int width, height;
};

/// The default grid, wherever neither the scene file (`envmap.width/height`) nor a traced T
/// names one: the paper's 25 rows of 50 texels (Motegi et al.). The one place these numbers
/// are written.
inline constexpr EnvMapGrid kDefaultEnvMapGrid{50, 25};

class EnvMapBasis {
  public:
    EnvMapBasis(int width = kDefaultEnvMapGrid.width, int height = kDefaultEnvMapGrid.height);

    int width() const { return width_; }
    int height() const { return height_; }
    int texelCount() const { return width_ * height_; }

    /// Mitsuba's direction_to_uv: u in (-½, ½], v in [0, 1].
    static std::array<double, 2> directionToUv(const Vec3d& d);
    /// Inverse of directionToUv (uv_to_direction in Mitsuba).
    static Vec3d uvToDirection(double u, double v);

    /// Bilinear texel weights of the (unit) direction d.
    TexelWeights weights(const Vec3f& d) const;

    /// Direction of the centre of texel (row j, column i): θ = jπ/(H−1), u = (i+½)/W.
    Vec3d texelDirection(int row, int col) const;

  private:
    int width_, height_;
};

}  // namespace sl
