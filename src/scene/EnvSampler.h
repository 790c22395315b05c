// EnvSampler: a density over directions for sampling the env map (the emitter), defined on the
// bilinear grid of EnvMapBasis (the one direction <-> texel convention) from one non-negative
// guide value per texel (a given E, or 1 everywhere: "by solid angle").
//
// Definition. In the bilinear lookup's grid coordinates (x, y) in [0, W) × [0, H−1]
// (EnvMapBasis.h: x = frac(u − ½/W)·W, y = v·(H−1)), the density is the bilinear interpolation
// of the grid values g_t = guide_t · sin θ_j (θ_j = jπ/(H−1), the texel's row), normalised:
//     p_xy(x, y) = Σ_k w_k(x, y) g_{t_k} / Z,   Z = Σ over the W·(H−1) cells of the mean of its
//                                                  four corners' g (each cell has unit area),
// with w_k, t_k exactly the bilinear weights and texels of EnvMapBasis::weights(). Since
// dω = sin θ dθ dφ = 2π² sin θ du dv and du dv = dx dy / (W (H−1)), its solid-angle density is
//     p(ω) = p_xy · W (H−1) / (2π² sin θ).
// p integrates to 1 over the sphere (p_xy does over the grid), it is bounded at the poles (g
// and sin θ both vanish linearly there), and with guide = 1 it is within a few % of uniform
// (the bilinear chord of sin θ). With guide = E it is nearly proportional to E's radiance.
// Sampling is exact: a cell by its share of Z, then y in the cell from its linear marginal,
// then x from the linear conditional.
#pragma once

#include <span>
#include <vector>

#include "core/Vec3.h"
#include "scene/EnvMapBasis.h"

namespace sl {

class EnvSampler {
  public:
    /// guide: basis.texelCount() non-negative finite values, or empty for 1 everywhere.
    /// Throws std::invalid_argument for a wrong size, a negative value, or an all-zero guide.
    explicit EnvSampler(const EnvMapBasis& basis, std::span<const float> guide = {});

    struct Sample {
        Vec3f direction;  // unit world direction (toward the env map)
        float pdf = 0;    // solid-angle density of direction, as pdf(direction)
    };
    /// A direction from two uniform numbers in [0, 1).
    Sample sample(float u1, float u2) const;
    /// Solid-angle density of the (unit) direction d.
    float pdf(const Vec3f& d) const;

  private:
    const EnvMapBasis& basis_;
    int W_, H_;
    std::vector<float> g_;     // per texel: guide · sin θ_j
    std::vector<double> cdf_;  // cumulative cell masses, W·(H−1) + 1 entries, last = 1
    double scale_ = 0;         // W (H−1) / (2π² Z)
};

}  // namespace sl
