// Black-box gradients: the renderer as a function E → loss, differentiated by finite differences
// (forward / central, per texel) and by SPSA (Spall), and the optimizers that use them
// (`fd-adam`, `spsa`). They are the baselines the exact gradient Tᵀ·dL/dY replaces
// (docs/DESIGN.md "Black-box baselines and validation").
//
// THE BLACK BOX (RenderLoss): E (doubles in [0, 1]) → the renderer's float32 env map →
// Renderer::render(env, seed) (render/Renderer.h: our tracer, POV-Ray or any command) → luminance Y
// of the RGB image → ImageObjective:: evaluate(Y, E).total, with E as the renderer saw it
// (float-rounded) in the regulariser. The objective's mask is fixed (usually the object mask of the
// trace at the base seed, see objectMaskFor; it equals T.objectMask for a T with the same spp and
// seed).
//
// SEEDS: with common random numbers (CRN) every evaluation uses the base seed
// (RenderOptions::seed): the samples are identical, the render is exactly linear in E, and the
// error of a difference quotient comes only from the loss's kinks (|x|), its curvature and float
// rounding. With fresh seeds, evaluation j of stream s uses freshSeed(base, s, j): independent
// Monte Carlo noise in every render, which dominates a difference quotient for small h.
//
// FINITE DIFFERENCES (per texel i, step h; 2N renders central, N+1 forward):
//   central  g_i = (L(E + h e_i) − L(E − h e_i)) / (e⁺ − e⁻)
//   forward  g_i = (L(E + h e_i) − L(E)) / (e⁺ − E_i)
// where e± are the perturbed texel values as float32 (the renderer's env map), so the quotient
// divides by the step the renderer really saw. Near the box: a central difference whose E_i − h
// < 0 becomes forward, one whose E_i + h > 1 backward (the black box is only asked about E in
// [0, 1]). Evaluations run in parallel (each render single-threaded; results in a fixed order).
//
// SPSA (Spall 1992, 1998 "Implementation of the simultaneous perturbation algorithm"):
//   Δ ∈ {±1}ᴺ Rademacher (PCG32 bits),  ĝ = (L(E + cΔ) − L(E − cΔ)) / (2c) · Δ⁻¹   (Δ⁻¹ = Δ)
//   averaged over q independent Δ per step; E ± cΔ is not projected (the render is linear and
//   defined for any E; projecting would bias ĝ). Optimizer: E ← Π_[0,1](E − a_k ĝ_k),
//   a_k = a / (k + 1 + A)^α, c_k = c / (k + 1)^γ, with Spall's α = 0.602, γ = 0.101 and
//   defaults A = 10 % of the iterations (Spall's guideline), c = 0.02 (E units; with CRN the
//   render has no noise, so c only trades the loss's curvature against its kinks), and a
//   calibrated as Spall recommends: a = lr·(A + 1)^α / mean|ĝ_0| from calibrationEstimates
//   estimates at E_0, so the first step moves a texel by about lr (OptimizerOptions::
//   learningRate, 0.02 like Adam's).
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "core/Rng.h"
#include "objective/Objective.h"
#include "optimize/Optimizer.h"
#include "render/PathTracer.h"
#include "render/Renderer.h"

namespace sl {

struct Scene;

/// The object mask of a trace with these options (1 where every camera sample of the pixel hit
/// the part): what render(...).summary.objectMask and a T with the same spp/seed hold.
std::vector<uint8_t> objectMaskFor(const Scene& scene, const RenderOptions& options);

/// Seed of evaluation `index` of stream `stream` when seeds are fresh (never the base seed).
uint64_t freshSeed(uint64_t base, uint64_t stream, uint64_t index);

class RenderLoss {
  public:
    /// The black box for `scene` rendered by our tracer with `options` (spp, max depth, base
    /// seed, threads), scored by `objective` (sized like the camera's image). Keeps references:
    /// scene and objective must outlive it. rgb: E has 3 values per texel (interleaved), else 1.
    /// interruptible: a Ctrl-C throws Interrupted from inside a render (a benchmark that keeps
    /// nothing); by default it does not, and an optimizer stops between its steps instead.
    RenderLoss(const Scene& scene, RenderOptions options, const ImageObjective& objective,
               bool rgb = false, bool interruptible = false);
    /// The black box for any renderer (kept by reference) on an envWidth × envHeight grid, with
    /// `baseSeed` as the common-random-numbers seed.
    RenderLoss(const Renderer& renderer, int envWidth, int envHeight, uint64_t baseSeed,
               const ImageObjective& objective, bool rgb = false);

    size_t dimension() const { return dimension_; }
    uint64_t baseSeed() const { return baseSeed_; }
    const ImageObjective& objective() const { return objective_; }
    const Renderer& renderer() const { return *renderer_; }

    /// The loss parts at E rendered with `seed`. threads: render threads (< 0: the options').
    /// Throws std::invalid_argument for a wrong size or non-finite E.
    LossParts evaluate(std::span<const double> E, uint64_t seed, int threads = -1) const;
    /// The luminance image the black box scores (for tests and reports).
    std::vector<double> image(std::span<const double> E, uint64_t seed, int threads = -1) const;

    /// Renders so far (every evaluate/image call), for cost accounting.
    long renders() const { return renders_.load(); }

  private:
    void checkObjective() const;
    std::unique_ptr<BuiltinRenderer> owned_;
    const Renderer* renderer_ = nullptr;
    int envWidth_ = 0, envHeight_ = 0;
    uint64_t baseSeed_ = 0;
    int threads_ = 0;
    const ImageObjective& objective_;
    bool rgb_;
    size_t dimension_;
    mutable std::atomic<long> renders_{0};
};

struct FdOptions {
    bool central = true;
    double h = 1e-3;                  // step in E units (> 0)
    bool commonRandomNumbers = true;  // same seed in every render (else fresh seeds)
    std::vector<uint32_t> texels;     // texels to differentiate (empty: all); others get 0
    int threads = 0;                  // parallel renders (0: all cores)
};

struct SpsaOptions {
    double a = 0;                         // step gain; <= 0: calibrated (see the header comment)
    double c = 0.02;                      // perturbation size (E units)
    double A = -1;                        // stability constant; < 0: 10 % of the iterations
    double alpha = 0.602, gamma = 0.101;  // Spall's exponents
    int q = 1;                            // estimates averaged per gradient
    int calibrationEstimates = 4;         // for a <= 0
    bool commonRandomNumbers = true;      // same seed in every render (else fresh seeds)
    uint64_t seed = 1;                    // the perturbations' generator
    int threads = 0;                      // parallel renders (0: all cores)
};

/// A gradient estimate and what it cost.
struct GradientEstimate {
    std::vector<double> gradient;
    double loss = 0;      // FD: L(E) (the base evaluation); SPSA: mean of (L⁺ + L⁻)/2
    int evaluations = 0;  // renders
    double seconds = 0;
};

/// Finite-difference gradient at E (in [0, 1]). stream: fresh-seed stream (ignored with CRN).
GradientEstimate finiteDifferenceGradient(const RenderLoss& loss, std::span<const double> E,
                                          const FdOptions& options, uint64_t stream = 0);

/// SPSA gradient at E with perturbation size c, averaged over q estimates; Δ from `rng`
/// (advanced), seeds from `stream` when fresh. `estimates` (optional) receives the q single
/// estimates, row by row (q × N), e.g. for variance estimates.
GradientEstimate spsaGradient(const RenderLoss& loss, std::span<const double> E, double c, int q,
                              Pcg32& rng, bool commonRandomNumbers, uint64_t stream = 0,
                              int threads = 0, std::vector<double>* estimates = nullptr);

struct BlackBoxOptions {
    FdOptions fd;      // fd-adam
    SpsaOptions spsa;  // spsa
};

/// Minimizes the black-box loss over [0, 1]^N from E (in/out), method = options.method:
///   fd-adam  sl::minimize's Adam (options.learningRate, beta1, beta2, epsilon, iterations,
///            callback) on the finite-difference gradient (bb.fd); each step costs 2N renders
///            (central) + 1 for the loss, or N + 1 (forward). History losses are the black
///            box's L(E) at each iterate (base seed with CRN).
///   spsa     projected SPSA (bb.spsa), `iterations` steps of 2q renders each; history[0] and
///            the final record are exact L(E) (base seed), the records in between the free
///            estimate (L⁺ + L⁻)/2 = L(E_k) + O(c²) of the step's own evaluations.
/// Returns the summary in the shape of sl::minimize's (method, history, evaluations = renders,
/// termination, settings). Throws InputError for an unknown method or bad options (naming the
/// option); std::runtime_error when a render gives a non-finite loss.
OptimizerSummary minimizeBlackBox(const RenderLoss& loss, std::vector<double>& E,
                                  const OptimizerOptions& options, const BlackBoxOptions& blackBox);

}  // namespace sl
