// Autodiff: the render-to-loss chain written once, templated on the scalar type, and its gradient
// by forward-mode automatic differentiation (ceres::Jet, chunked over texels). It is the
// reference the exact gradient (Tᵀ·dL/dY), finite differences and SPSA are measured against
// (docs/DESIGN.md "Black-box baselines and validation"). Gray env maps (one value per texel).
//
// Two chains, both templated on the scalar S (double, ceres::Jet<double, N>, ...):
//
//   through the recorded paths   Y_p(E) = Σ_paths lum(w_path) · Σ_k b_k E_{i_k}
//       every escaped path of every pixel (PathRecording, a PathSink on the same tracer, same
//       seeds and samples as `render` and `precompute`) with its luminance weight and the four
//       bilinear weights b_k of EnvMapBasis::weights, the one env-map convention. This is the
//       render itself, in double, without the float32 storage of T: the exact gradient through a
//       float T agrees with it to float rounding (~1e-7 relative).
//   through the matrix           Y(E) = T·E, T's float32 entries promoted to S
//       the same numbers the exact gradient multiplies: Tᵀ·dL/dY agrees with it to double
//       rounding (<= 1e-9 relative, tested).
//
// then Loss = ImageObjective::value<S>(Y, E) (same pairs, same order, same |0| sub-gradient as
// ImageObjective::evaluate).
//
// The gradient: texels are split into chunks of kAutodiffChunk (32); chunk c seeds the dual parts
// of its texels (E_i = E_i + ε_{i−c0}) and evaluates the whole chain once in Jet<double, 32>
// arithmetic, which yields dLoss/dE for those 32 texels; chunks run in parallel (TBB) and each
// writes its own slice, so the result does not depend on the number of threads.
// Cost: ceil(N/32) passes, each a full evaluation with 33 numbers per scalar, so use small scenes
// (e.g. 32×32 to 64×64 pixels, a few spp). ceres/jet.h stays inside Autodiff.cpp.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "objective/BothMeasuresObjective.h"
#include "objective/DefectObjective.h"
#include "objective/JndObjective.h"
#include "objective/Objective.h"
#include "render/PathSink.h"
#include "scene/EnvMapBasis.h"
#include "transport/TransportMatrix.h"

namespace sl {

struct Scene;
struct RenderOptions;
struct TraceSummary;

/// Texels per autodiff pass (the Jet's dual dimension).
inline constexpr int kAutodiffChunk = 32;

/// Every escaped path of every pixel, reduced to what the env map sees: the luminance of its
/// throughput (already divided by spp, as EscapedPath::weight) and its four bilinear texel
/// weights. consume() may run concurrently for different pixels (each pixel writes its own slot).
class PathRecording : public PathSink {
  public:
    struct Path {
        double luminance = 0;  // Y of the path's RGB weight, in double (as TransportSink does)
        TexelWeights texels;   // EnvMapBasis::weights(direction)
    };

    PathRecording(const EnvMapBasis& basis, int width, int height);
    void consume(const PixelPaths& pixel) override;

    int width() const { return width_; }
    int height() const { return height_; }
    int texelCount() const { return basis_.texelCount(); }
    size_t pixelCount() const { return paths_.size(); }
    size_t pathCount() const;

    /// The luminance image Y(E) through the recorded paths, in scalar type S.
    template <typename S>
    void image(std::span<const S> E, std::span<S> Y) const;

  private:
    const EnvMapBasis& basis_;
    int width_, height_;
    std::vector<std::vector<Path>> paths_;
};

/// Traces the scene once and records its paths (the same samples as render(scene, ., options)).
/// `summary` (optional) receives the trace's summary (object mask included).
PathRecording recordPaths(const Scene& scene, const RenderOptions& options,
                          TraceSummary* summary = nullptr);

/// Loss(E) through the recorded paths: Y = paths(E), then objective.value<S>(Y, E).
template <typename S>
S lossThroughPaths(const PathRecording& paths, const ImageObjective& objective,
                   std::span<const S> E);

/// Loss(E) through a gray transport matrix (channels == 1, planes == 1): Y = T·E with T's
/// float entries promoted to S, then objective.value<S>(Y, E).
template <typename S>
S lossThroughMatrix(const TransportMatrix& t, const ImageObjective& objective,
                    std::span<const S> E);

/// Loss(E) of a half-image objective (DefectObjective, JndObjective, BothMeasuresObjective) through
/// the halves of a gray T (channels 1, planes 2): Y_a = T_a·E, Y_b = T_b·E with T's float entries
/// promoted to S, then objective.value<S>.
template <typename S, typename HalfObjective>
S lossThroughHalves(const TransportMatrix& t, const HalfObjective& objective, std::span<const S> E);

struct AutodiffGradient {
    double loss = 0;
    std::vector<double> gradient;  // dLoss/dE, one value per texel
    int passes = 0;                // Jet evaluations (chunks)
    double seconds = 0;            // wall time
};

/// dLoss/dE by forward-mode autodiff (ceres::Jet<double, kAutodiffChunk>) through the recorded
/// paths / through T. threads: 0 = all cores. Throws std::invalid_argument on size mismatches.
AutodiffGradient autodiffThroughPaths(const PathRecording& paths, const ImageObjective& objective,
                                      std::span<const double> E, int threads = 0);
AutodiffGradient autodiffThroughMatrix(const TransportMatrix& t, const ImageObjective& objective,
                                       std::span<const double> E, int threads = 0);
AutodiffGradient autodiffThroughHalves(const TransportMatrix& t, const DefectObjective& objective,
                                       std::span<const double> E, int threads = 0);
AutodiffGradient autodiffThroughHalves(const TransportMatrix& t, const JndObjective& objective,
                                       std::span<const double> E, int threads = 0);
AutodiffGradient autodiffThroughHalves(const TransportMatrix& t,
                                       const BothMeasuresObjective& objective,
                                       std::span<const double> E, int threads = 0);

/// Gradient comparison: relative L2 error ‖g − ref‖/‖ref‖ and cosine similarity g·ref/(‖g‖‖ref‖)
/// (NaN when a norm is 0).
struct GradientError {
    double relativeL2 = 0;
    double cosine = 0;
};
GradientError compareGradients(std::span<const double> g, std::span<const double> ref);

// --- templates --------------------------------------------------------------------------------

template <typename S>
void PathRecording::image(std::span<const S> E, std::span<S> Y) const {
    for (size_t p = 0; p < paths_.size(); ++p) {
        S y(0.0);
        for (const Path& path : paths_[p]) {
            S r(0.0);
            for (int k = 0; k < 4; ++k) {
                if (path.texels.weight[k] == 0.0f) continue;
                r += S(static_cast<double>(path.texels.weight[k])) * E[path.texels.index[k]];
            }
            y += S(path.luminance) * r;
        }
        Y[p] = y;
    }
}

template <typename S>
S lossThroughPaths(const PathRecording& paths, const ImageObjective& objective,
                   std::span<const S> E) {
    std::vector<S> Y(paths.pixelCount(), S(0.0));
    paths.image<S>(E, Y);
    return objective.value<S>(std::span<const S>(Y), E);
}

template <typename S>
S lossThroughMatrix(const TransportMatrix& t, const ImageObjective& objective,
                    std::span<const S> E) {
    std::vector<S> Y(t.rows(), S(0.0));
    const size_t cols = t.cols();
    for (size_t r = 0; r < t.rows(); ++r) {
        S acc(0.0);
        if (t.storage == TransportStorage::Sparse) {
            for (uint64_t e = t.rowPtr[r]; e < t.rowPtr[r + 1]; ++e)
                acc += S(static_cast<double>(t.values[e])) * E[t.colIdx[e]];
        } else {
            const float* row = t.values.data() + r * cols;
            for (size_t c = 0; c < cols; ++c)
                if (row[c] != 0.0f) acc += S(static_cast<double>(row[c])) * E[c];
        }
        Y[r] = acc;
    }
    return objective.value<S>(std::span<const S>(Y), E);
}

template <typename S, typename HalfObjective>
S lossThroughHalves(const TransportMatrix& t, const HalfObjective& objective,
                    std::span<const S> E) {
    std::vector<S> Ya(t.rows(), S(0.0)), Yb(t.rows(), S(0.0));
    const size_t cols = t.cols();
    for (size_t r = 0; r < t.rows(); ++r) {
        S a(0.0), b(0.0);
        if (t.storage == TransportStorage::Sparse) {
            for (uint64_t e = t.rowPtr[r]; e < t.rowPtr[r + 1]; ++e) {
                a += S(static_cast<double>(t.values[2 * e])) * E[t.colIdx[e]];
                b += S(static_cast<double>(t.values[2 * e + 1])) * E[t.colIdx[e]];
            }
        } else {
            const float* row = t.values.data() + 2 * r * cols;
            for (size_t c = 0; c < cols; ++c) {
                a += S(static_cast<double>(row[2 * c])) * E[c];
                b += S(static_cast<double>(row[2 * c + 1])) * E[c];
            }
        }
        Ya[r] = a;
        Yb[r] = b;
    }
    return objective.template value<S>(std::span<const S>(Ya), std::span<const S>(Yb), E);
}

}  // namespace sl
