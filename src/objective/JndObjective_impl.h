// JndObjective::value<S>: the loss of JndObjective.h in any scalar type, the same steps as
// evaluate(). Included at the end of JndObjective.h.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "perception/ContrastSensitivity.h"
#include "perception/JndVisibility.h"

namespace sl {

namespace detail {
/// h(Δ) of JndObjective.h.
template <typename S>
S jndSignalFourth(const S& delta) {
    const double d0 = kJndEnergyFloor;
    if (realPart(delta) >= d0) return delta * delta;
    return 2.0 * d0 * delta - d0 * d0;
}
}  // namespace detail

template <typename S>
S JndObjective::luminanceOf(const S& m) const {
    const double lw = o_.view.whiteLuminance, w = o_.band.whiteMean;
    const double lo = kMinJndLuminance / lw;
    const double f = detail::realPart(m) / w;
    if (f <= lo) return S(lw * lo);
    if (f >= 1.0) return S(lw);
    return (lw / w) * m;
}

template <typename S>
S JndObjective::value(std::span<const S> Ya, std::span<const S> Yb, std::span<const S> E) const {
    const size_t n = static_cast<size_t>(width_) * height_;
    std::vector<std::vector<S>> ga(kJndBands + 1), gb(kJndBands + 1);
    for (int j = 0; j <= kJndBands; ++j) {
        ga[j] = bank_.gaussian<S>(j, Ya);
        gb[j] = bank_.gaussian<S>(j, Yb);
    }
    const size_t K = labels_.size();
    std::vector<S> eF(kJndBands, S(0.0)), eK(K * kJndBands, S(0.0));
    const std::vector<uint8_t>& part = base_.mask();
    for (int b = 0; b < kJndBands; ++b) {
        const int l = localMeanGaussian(b);
        for (size_t p = 0; p < n; ++p) {
            if (!part[p] || (!reference_[p] && labelOf_[p] < 0)) continue;
            const S prod = bandProduct(ga[b][p], ga[b + 1][p], gb[b][p], gb[b + 1][p],
                                       S(0.5 * (ga[l][p] + gb[l][p])));
            if (reference_[p]) eF[b] += prod;
            if (labelOf_[p] >= 0) eK[static_cast<size_t>(labelOf_[p]) * kJndBands + b] += prod;
        }
        eF[b] /= referencePixels_;
    }
    S m, clip;
    detail::partBrightness(base_.mask(), partPixels_, Ya, Yb, m, clip);
    const S L = luminanceOf(m);
    std::vector<S> half(K, S(0.0));
    for (size_t k = 0; k < K; ++k) {
        S q(0.0);
        for (int b = 0; b < kJndBands; ++b) {
            const S e = eK[k * kJndBands + b] / labelPixels_[k];
            const S mask = detail::realPart(eF[b]) > 0 ? eF[b] : S(0.0);
            const S sens =
                bartenSensitivityAt(bandFrequency_[b], L, labelSizeDeg_[k], labelSizeDeg_[k]);
            q += jndBandFourth(detail::jndSignalFourth(S(e - eF[b])), mask, sens);
        }
        half[k] = 0.5 * detail::defectLogFloor(q, std::pow(kJndFloor, 4.0));
    }
    S loss = -detail::labelSoftMin(half, kLabelSoftMin) + detail::exposureBand(m, clip, o_.band);
    if (base_.options().lambda != 0) {
        S reg(0.0);
        for (const S& x : E) reg += x * x;
        loss += base_.options().lambda * reg / static_cast<double>(E.size());
    }
    return loss;
}

}  // namespace sl
