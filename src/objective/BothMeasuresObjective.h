// The defects objective on both of the judge's measures at once (`--defects-measure both`): make
// the defects stand out of the texture more than under the user's lamp by the visibility ratio
// (objective/DefectObjective.h) AND be seen more than under it in JND (objective/JndObjective.h),
// by raising the worse of the two gains over the lamp.
//
// Why: the JND measure alone raises the texture's contrast along with the defects' (the eye's
// masking grows slower than the contrast), so its optimum can show the defects more in JND while
// they stand out of the texture less than under the lamp; the ratio measure alone can flatten the
// image until the eye sees less. Each measure's loss is −2·log of its visibility plus the same
// exposure terms; with c_j, c_r the two visibility terms (lGrad) of the lamp's light on the same
// estimate (the anchor),
//
//   a_j   = Loss_jnd − c_j   = −2·log(J / J_lamp)     + penalties + λ·mean(E²)
//   a_r   = Loss_ratio − c_r = −2·log(ratio / ratio_lamp) + penalties + λ·mean(E²)
//   Loss  = softmax_τ(a_j, a_r) = τ·log((exp(a_j/τ) + exp(a_r/τ)) / 2),  τ = kLabelSoftMin
//
// The JND anchor is the lamp's JND or 1 JND, whichever is larger (kGainFloorJnd): under a lamp
// that shows the defects less than just noticeably, a gain over the lamp's JND is a gain over
// nothing (its JND can be 0, its φ on the floor's tangent, and every light's JND gain unbounded),
// so the JND gain is counted from the threshold of seeing; the softmax then weighs both measures
// where the lamp shows nothing, instead of the ratio alone.
//
// between max(a_j, a_r) − τ·log 2 and max(a_j, a_r): the optimizer works on the measure whose gain
// over the lamp is the smaller (weights w_i = exp(a_i/τ)/Σ, summing to 1, so the shared exposure
// terms and the regulariser keep their weight). Loss < 0 where both gains are above 1 (up to the
// penalties). LossParts: lGrad = softmax_τ of the two visibility terms less their anchors (so
// exp(−lGrad/2) is the smaller gain over the lamp, softly: the noise rule's gap reads it as either
// measure's visibility), lReg = mean(E²), G = that gain, S = the JND measure's G (the worst label's
// JND), clamped when either measure's is.
//
// evaluate() is exact (the weighted sum of the two exact adjoints); value<S>() is the autodiff
// reference (objective/Autodiff.h).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "objective/DefectObjective.h"
#include "objective/HalfImageObjective.h"
#include "objective/JndObjective.h"
#include "transport/TransportMatrix.h"

namespace sl {

/// The least JND a gain over the lamp is counted from (BothMeasuresObjective's JND anchor, the
/// answer's gain merit, pipeline/Answer.h): the threshold of seeing.
inline constexpr double kGainFloorJnd = 1.0;

/// The two measures' visibility terms (LossParts::lGrad) of the anchor light (the user's lamp) on
/// the estimate the objective is evaluated on.
struct MeasureAnchors {
    double jnd = 0, ratio = 0;
};

class BothMeasuresObjective final : public HalfImageObjective {
  public:
    /// The same regions and options as the two measures' objectives (JndObjective's `jnd.band` is
    /// the ratio measure's options too). Throws InputError as they do.
    BothMeasuresObjective(int width, int height, std::vector<uint8_t> part,
                          std::vector<uint8_t> defects, std::vector<uint8_t> reference,
                          ObjectiveOptions options, JndObjectiveOptions jnd);

    /// Sets c_j, c_r (default 0: the gains are over a light of visibility 1 in each measure).
    void setAnchors(MeasureAnchors anchors) { anchors_ = anchors; }
    const MeasureAnchors& anchors() const { return anchors_; }
    const JndObjective& jnd() const { return jnd_; }
    const DefectObjective& ratio() const { return ratio_; }

    LossParts evaluate(std::span<const double> Ya, std::span<const double> Yb,
                       std::span<const double> E, std::span<double> dLdYa = {},
                       std::span<double> dLdYb = {}, std::span<double> dLdE = {}) const override;
    int imageWidth() const override { return jnd_.width(); }
    int imageHeight() const override { return jnd_.height(); }
    int width() const { return jnd_.width(); }
    int height() const { return jnd_.height(); }

    /// The same loss in scalar type S (double, ceres::Jet): the autodiff reference.
    template <typename S>
    S value(std::span<const S> Ya, std::span<const S> Yb, std::span<const S> E) const {
        using std::exp, std::log, std::max;
        const S aj = jnd_.template value<S>(Ya, Yb, E) - anchors_.jnd;
        const S ar = ratio_.template value<S>(Ya, Yb, E) - anchors_.ratio;
        const S top = aj > ar ? aj : ar;
        return top + kLabelSoftMin * log(0.5 * (exp((aj - top) / kLabelSoftMin) +
                                                exp((ar - top) / kLabelSoftMin)));
    }

  private:
    JndObjective jnd_;
    DefectObjective ratio_;
    MeasureAnchors anchors_;
};

/// The anchors of `objective` on T's halves: the two measures' visibility terms of the light
/// `anchor` (E, as T's columns; with `rgb`, three values per texel), the JND's taken at
/// kGainFloorJnd where the light shows the defects less. Throws InputError (option
/// 'defects-measure') when `anchor` is empty or has the wrong size.
MeasureAnchors measureAnchors(const TransportMatrix& t, const BothMeasuresObjective& objective,
                              std::span<const double> anchor, bool rgb, const RowShard& shard = {});

}  // namespace sl
