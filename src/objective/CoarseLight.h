// CoarseLight: the light searched on a coarser grid of nodes than the env map's, E = P·θ.
//
// The noise of a Monte Carlo estimate of T is a property of each of its columns (each texel's
// image); an optimizer with one free value per texel can combine a few columns whose noise
// happens to serve its objective, and the optimum then fits the estimate rather than the part
// (docs/DESIGN.md "Noise is the trap"). Searching a light with fewer degrees of freedom fits
// less noise: the resolution is the second knob of the noise rule (app/pipeline/TrainingNoise.h) beside
// the samples per pixel.
//
// The nodes sit on a coarse env-map grid of the same convention (scene/EnvMapBasis.h: rows at
// θ = kπ/(h−1), columns at u = (k+½)/w, wrapping in u), and each texel of the W×H map takes
// the bilinear weights of its centre direction on that grid. So P ≥ 0 and every row of P sums
// to 1: θ ∈ [0, 1] gives E ∈ [0, 1] (the optimizers' box), a constant θ gives the same constant
// E, and the coarse grid at W×H is the identity. With RGB lights (3 values per texel) each
// channel is interpolated on its own.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/Problem.h"

namespace sl {

/// The grid a light is searched on: width × height nodes, or (0 × 0) one value per texel of
/// the env map.
struct LightGrid {
    int width = 0, height = 0;
    bool perTexel() const { return width <= 0 || height <= 0; }
    /// "W×H nodes" as printed, or "texels".
    std::string name() const;
    bool operator==(const LightGrid&) const = default;
};

/// "WxH" (W ≥ 1, H ≥ 2) or "texels"; InputError naming option 'light-grid' otherwise.
LightGrid parseLightGrid(std::string_view text);

class CoarseLight {
  public:
    /// The coarse grid `width`×`height` (2 ≤ height, 1 ≤ width; at most the env map's) onto
    /// the env map `envWidth`×`envHeight` with `channels` values per texel (1 or 3).
    CoarseLight(int envWidth, int envHeight, int width, int height, int channels = 1);

    int width() const { return width_; }
    int height() const { return height_; }
    int channels() const { return channels_; }
    /// θ's size: nodes × channels.
    size_t parameters() const { return static_cast<size_t>(width_) * height_ * channels_; }
    /// E's size: texels × channels.
    size_t envValues() const { return rows_.size() * static_cast<size_t>(channels_); }
    /// True when the grid is the env map's own (P = identity).
    bool identity() const { return identity_; }

    /// E = P·θ.
    std::vector<double> prolong(std::span<const double> theta) const;
    /// Pᵀ·g: the gradient in θ of a loss whose gradient in E is g.
    std::vector<double> gradientInNodes(std::span<const double> g) const;
    /// θ whose P·θ is near E: each node the weighted mean of the texels it touches (the
    /// weights of P's column). Exact for a constant E; a start for the search, no more.
    std::vector<double> project(std::span<const double> e) const;

    /// The same problem in θ: f(θ) = fine.evaluate(P·θ), ∇θ = Pᵀ·∇E. `fine`'s box carries
    /// over (P's rows are convex combinations).
    Problem over(Problem fine) const;

    /// "W×H" as printed and recorded.
    std::string name() const;

  private:
    struct Row {
        uint32_t node[4];
        float weight[4];
    };
    int width_, height_, channels_;
    bool identity_;
    std::vector<Row> rows_;          // one per texel
    std::vector<double> columnSum_;  // Σ of each node's weights over the texels
};

}  // namespace sl
