#include "objective/BothMeasuresObjective.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "core/Error.h"
#include "objective/TransportLoss.h"

namespace sl {

BothMeasuresObjective::BothMeasuresObjective(int width, int height, std::vector<uint8_t> part,
                                             std::vector<uint8_t> defects,
                                             std::vector<uint8_t> reference,
                                             ObjectiveOptions options, JndObjectiveOptions jnd)
    : jnd_(width, height, part, defects, reference, options, jnd),
      ratio_(width, height, std::move(part), std::move(defects), std::move(reference), options,
             jnd.band) {}

namespace {

/// softmax_τ(a, b) and the weight of a (b's is 1 − w).
std::pair<double, double> softMax2(double a, double b) {
    const double top = std::max(a, b);
    const double ea = std::exp((a - top) / kLabelSoftMin), eb = std::exp((b - top) / kLabelSoftMin);
    return {top + kLabelSoftMin * std::log(0.5 * (ea + eb)), ea / (ea + eb)};
}

}  // namespace

LossParts BothMeasuresObjective::evaluate(std::span<const double> Ya, std::span<const double> Yb,
                                          std::span<const double> E, std::span<double> dLdYa,
                                          std::span<double> dLdYb, std::span<double> dLdE) const {
    const bool grad = !dLdYa.empty() || !dLdYb.empty() || !dLdE.empty();
    std::vector<double> ja, jb, je, ra, rb, re;
    if (grad) {
        ja.assign(Ya.size(), 0), jb.assign(Yb.size(), 0), je.assign(dLdE.size(), 0);
        ra.assign(Ya.size(), 0), rb.assign(Yb.size(), 0), re.assign(dLdE.size(), 0);
    }
    const LossParts j = jnd_.evaluate(Ya, Yb, E, ja, jb, je);
    const LossParts r = ratio_.evaluate(Ya, Yb, E, ra, rb, re);
    const auto [total, w] = softMax2(j.total - anchors_.jnd, r.total - anchors_.ratio);
    LossParts p;
    p.total = total;
    p.lGrad = softMax2(j.lGrad - anchors_.jnd, r.lGrad - anchors_.ratio).first;
    p.lReg = j.lReg;
    p.G = std::exp(-p.lGrad / 2);
    p.S = j.G;
    p.clamped = j.clamped || r.clamped;
    const auto mix = [w = w](std::span<double> out, const std::vector<double>& a,
                             const std::vector<double>& b) {
        for (size_t k = 0; k < out.size(); ++k) out[k] = w * a[k] + (1 - w) * b[k];
    };
    if (!dLdYa.empty()) mix(dLdYa, ja, ra);
    if (!dLdYb.empty()) mix(dLdYb, jb, rb);
    if (!dLdE.empty()) mix(dLdE, je, re);
    return p;
}

MeasureAnchors measureAnchors(const TransportMatrix& t, const BothMeasuresObjective& objective,
                              std::span<const double> anchor, bool rgb, const RowShard& shard) {
    if (anchor.size() != t.cols() * (rgb ? 3 : 1))
        throw inputError(option("defects-measure"),
                         "'both' needs the user's lamp as the light its gains are over (" +
                             std::to_string(anchor.size()) + " values given, " +
                             std::to_string(t.cols()) + " texels)",
                         "give the lamp (" + option("compare") + "), or measure 'jnd' alone");
    MeasureAnchors a;
    TransportLoss jnd(t, objective.jnd(), rgb), ratio(t, objective.ratio(), rgb);
    jnd.distribute(shard);
    ratio.distribute(shard);
    // lGrad = −2·log J (objective/JndObjective.h), so J ≥ kGainFloorJnd is lGrad ≤ its value.
    a.jnd = std::min(jnd.evaluate(anchor, {}).lGrad, -2.0 * std::log(kGainFloorJnd));
    a.ratio = ratio.evaluate(anchor, {}).lGrad;
    return a;
}

}  // namespace sl
