// Fitting K physical lamps (scene/Lamp.h) through T: the objective of an optimized env map,
// evaluated on the lamps' rasterization, with its exact gradient by the chain rule
//     dLoss/dθ = (∂E/∂θ)ᵀ · dLoss/dE,   dLoss/dE = Tᵀ·dLoss/dY + dReg/dE  (TransportLoss)
// where θ are the lamps' parameters (LampRasterizer::jacobian).
//
// The box: every parameter is mapped from [0, 1] (the optimizers' box, core/Problem.h) onto its
// range (lampParamRange): radiance [0, 1] (E's range: a lamp's texels never exceed its
// radiance), elevation [minElevation, maxElevation], azimuth [−360°, 360°] (twice round, so the
// seam is no wall), the sizes per kind (a disk's radius 4°–90°, a bar's half-length 4°–60° and
// half-width 2°–20°, a ring's half-height 2°–45°: sizes where the 1.5° soft edge still leaves a
// full-radiance core). A parameter a kind does not use has an
// empty range (it stays put). Forbidden azimuth ranges (camera, fixtures) are a penalty on the
// lamp's centre inside a range (a smooth quadratic in the depth of the intrusion, weighted so a
// lamp there loses any gain), not a hole in the box; so is a centre within the margin of the
// camera's direction (LampFitOptions::camera). Only the centre is kept out: a disk's or
// bar's edge may reach into a range, and a ring (all azimuths) is not refused: drop `ring` from
// the kinds when a range matters. Overlapping lamps must keep E within E*'s box [0, 1]: the
// excess above 1 is a penalty 1e3·Σ_t Ω_t (E_t − 1)², so lamps get the light budget E* had
// (without it the fit stacks lamps into one brighter than any texel of E* may be).
//
// Greedy K: lamps are added one at a time. The k-th lamp starts, for each allowed kind, at the
// brightest directions of the residual max(E* − E_lamps, 0) (E* the optimized env map; up to
// residualPeaks peaks at least 20° apart) and at the direction where dLoss/dE is most negative
// (where light helps most); each candidate is screened: optimized jointly with the k−1 lamps
// before it for candidateIterations on a coarse quadrature (screenSubsamples nodes per cell and
// axis, 4× fewer than the default 16²; the candidates in parallel). The `polished` best screened
// sets are then polished (in parallel) on a finer one (polishSubsamples, 12: its solid angles are
// within 2e-5 of the exact ones, scene/Lamp.h) for finalIterations and the lowest polished loss
// is kept (candidates in a fixed order, ties to the better screen: deterministic),
// unless the k−1 lamps with the k-th switched off score better on the same problem (then the
// k-th lamp stays off). The steps' E and loss are on the full quadrature (raster.subsamples).
// The loss after every k is reported, so the user sees what each extra lamp buys.
#pragma once

#include <array>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "objective/TransportLoss.h"
#include "optimize/Optimizer.h"
#include "scene/Lamp.h"

namespace sl {

struct LampFitOptions {
    int count = 3;  // K: lamps at most (1..8)
    std::vector<LampKind> kinds{LampKind::Disk, LampKind::Bar, LampKind::Ring};
    double minElevation = 0, maxElevation = 1.5707963267948966;  // radians
    /// Azimuth ranges no lamp's centre may sit in, radians [from, to] (from > to wraps).
    std::vector<std::pair<double, double>> forbiddenAzimuth;
    /// The camera, as seen from the part's centre (azimuth, elevation in radians; unset: no
    /// camera). No disk's or bar's centre may sit within cameraMargin of it, the same penalty
    /// as a forbidden azimuth (a lamp there would stand in the camera's view or shine into
    /// the lens); a ring, all around, is not kept out.
    std::optional<std::array<double, 2>> camera;
    double cameraMargin = 0.17453292519943295;  // 10°
    /// L-BFGS with the box; iterations per candidate and for the final polish. 8 screening
    /// iterations (15 before issue 32's tenth pass: the screen was 3/4 of the fit's
    /// evaluations) found lamps as good by the judge on three measured parts held out from the
    /// choice, their training loss within 0.1 % (docs/RESEARCH.md).
    OptimizerMethod method = OptimizerMethod::Lbfgs;
    int candidateIterations = 8, finalIterations = 200;
    /// Candidates are screened on a quadrature of this many nodes per cell and axis (at most
    /// raster.subsamples), then the `polished` best are polished on the full one.
    int screenSubsamples = 8, polished = 2;
    int polishSubsamples = 12;        // the polish's quadrature (the reported E and loss: raster's)
    int residualPeaks = 3;            // residual peaks (at least 20° apart) a new lamp is tried at
    double relativeTolerance = 1e-5;  // stop when the loss changes by less than this fraction
    /// Products over the lamps' texels only (transport/TransportColumns.h); false: over all of
    /// T (the baseline `bench lamps` measures it against).
    bool columnProducts = true;
    LampRasterOptions raster;
};

/// The range [lo, hi] of parameter p of a lamp of `kind` under the options.
std::array<double, 2> lampParamRange(LampKind kind, int p, const LampFitOptions& options);

struct LampFitStep {
    int count = 0;
    std::vector<Lamp> lamps;
    double loss = 0;      // the objective (training T) under these lamps
    double seconds = 0;   // since the fit started
    int evaluations = 0;  // of the loss and its gradient for this k (all candidates)
};

struct LampFitResult {
    std::vector<LampFitStep> steps;  // k = 1..K
    double targetLoss = 0;           // the objective under E*
    std::vector<double> envMap;      // E of the last step's lamps
    double seconds = 0;
    double cpuSeconds = 0;  // CPU seconds of the process (all threads) during the fit
};

/// The lamps' problem through `loss` for lamps of the given kinds (their parameters in x,
/// kLampParams per lamp, each in [0, 1] as above).
class LampProblem {
  public:
    /// columns (optional, a TransportColumns of loss's matrix): the products read only the
    /// texels the lamps touch (TransportLoss::evaluateOnColumns); the same loss and gradient.
    LampProblem(const TransportLoss& loss, const LampRasterizer& raster,
                std::vector<LampKind> kinds, const LampFitOptions& options,
                const TransportColumns* columns = nullptr);
    size_t dimension() const { return kinds_.size() * kLampParams; }
    /// The loss at x (and the gradient when grad is non-empty).
    double evaluate(std::span<const double> x, std::span<double> grad) const;
    std::vector<Lamp> lamps(std::span<const double> x) const;
    std::vector<double> encode(std::span<const Lamp> lamps) const;
    Problem problem() const;

  private:
    const TransportLoss& loss_;
    const LampRasterizer& raster_;
    std::vector<LampKind> kinds_;
    LampFitOptions options_;
    const TransportColumns* columns_;
};

/// InputError naming the option when the options are out of range (count 1..8, a kind, an
/// elevation range within [−90°, 90°]).
void checkLampFitOptions(const LampFitOptions& options);

/// Fits lamps k = 1..options.count to the objective `loss` starting from E* (`target`, one value
/// per texel of the rasterizer's basis). Throws InputError for bad options.
LampFitResult fitLamps(const TransportLoss& loss, std::span<const double> target,
                       const LampFitOptions& options);

}  // namespace sl
