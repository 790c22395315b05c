// DefectObjective::value<S>: the loss of DefectObjective.h in any scalar type, the same sums in
// the same order as evaluate(). Included at the end of DefectObjective.h.
#pragma once

#include <cmath>

namespace sl {

namespace detail {
/// φ of DefectObjective.h.
template <typename S>
S defectLogFloor(const S& g, double g0) {
    using std::log;
    if (realPart(g) >= g0) return log(g);
    return S(std::log(g0)) + (g - S(g0)) / g0;
}
template <typename S>
S hingeSquared(const S& x) {
    return realPart(x) > 0 ? x * x : S(0.0);
}
}  // namespace detail

template <typename S>
S DefectObjective::value(std::span<const S> Ya, std::span<const S> Yb, std::span<const S> E) const {
    const int W = width(), H = height();
    S gD(0.0), gR(0.0);
    detail::forEachMaskedPair(W, H, defects_.data(),
                              [&](size_t p, size_t q) { gD += (Ya[q] - Ya[p]) * (Yb[q] - Yb[p]); });
    detail::forEachMaskedPair(W, H, reference_.data(),
                              [&](size_t p, size_t q) { gR += (Ya[q] - Ya[p]) * (Yb[q] - Yb[p]); });
    gD /= pairsD_;
    gR /= pairsR_;
    using std::log;
    S loss = (detail::realPart(gR) >= floor() ? S(log(gR)) : S(std::log(floor()))) -
             detail::defectLogFloor(gD, floor());
    S m(0.0), clip(0.0);
    const std::vector<uint8_t>& part = mask();
    for (size_t p = 0; p < part.size(); ++p) {
        if (!part[p]) continue;
        const S y = (Ya[p] + Yb[p]) * 0.5;
        m += y;
        clip += detail::hingeSquared(S(y - 1.0));
    }
    m /= partPixels_;
    clip /= partPixels_;
    const double w = d_.whiteMean;
    loss += d_.exposureWeight * (detail::hingeSquared(S((d_.low * w - m) / w)) +
                                 detail::hingeSquared(S((m - d_.high * w) / w)) + clip);
    const double floorM = d_.darkFloor * w;
    if (floorM > 0 && detail::realPart(m) < floorM) {
        using std::log;
        const S dark =
            detail::realPart(m) > 1e-12 * w ? S(log(m / floorM)) : S(std::log(1e-12 * w / floorM));
        loss += d_.darkWeight * dark * dark;
    }
    const double cf = d_.contrastFloor;
    if (cf > 0 && detail::realPart(m) > 1e-12 * w) {
        const S gDe = detail::realPart(gD) >= floor() ? gD : S(floor());
        if (detail::realPart(gDe) < cf * cf * detail::realPart(m) * detail::realPart(m)) {
            using std::log;
            const S u = 0.5 * log(gDe / (cf * cf)) - log(m);
            loss += d_.contrastWeight * u * u;
        }
    }
    if (options().lambda != 0) {
        S reg(0.0);
        for (const S& e : E) reg += e * e;
        loss += options().lambda * reg / static_cast<double>(E.size());
    }
    return loss;
}

}  // namespace sl
