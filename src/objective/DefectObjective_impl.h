// DefectObjective::value<S>: the loss of DefectObjective.h in any scalar type, the same sums in
// the same order as evaluate(). Included at the end of DefectObjective.h.
#pragma once

#include <cmath>
#include <span>
#include <vector>

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
/// M of DefectObjective.h: the soft-min over labels, −τ·log((1/K)·Σ exp(−φ_k/τ)), shifted by
/// the smallest φ for range; one label: φ itself. weights (optional): dM/dφ_k.
template <typename S>
S labelSoftMin(const std::vector<S>& phi, double tau, std::vector<double>* weights = nullptr) {
    using std::exp;
    using std::log;
    if (weights) weights->assign(phi.size(), 1.0);
    if (phi.size() == 1) return phi.front();
    size_t lo = 0;
    for (size_t k = 1; k < phi.size(); ++k)
        if (realPart(phi[k]) < realPart(phi[lo])) lo = k;
    S sum(0.0);
    for (const S& f : phi) sum += exp(-(f - phi[lo]) / tau);
    if (weights)
        for (size_t k = 0; k < phi.size(); ++k)
            (*weights)[k] = std::exp(-(realPart(phi[k]) - realPart(phi[lo])) / tau) / realPart(sum);
    return phi[lo] - tau * log(sum / static_cast<double>(phi.size()));
}
/// m = the mean over the part of Ȳ = (Y_a + Y_b)/2 and clip = the mean of max(0, Ȳ − 1)², the
/// exposure band's inputs (`pixels`: the part's pixel count).
template <typename S>
void partBrightness(const std::vector<uint8_t>& part, double pixels, std::span<const S> Ya,
                    std::span<const S> Yb, S& m, S& clip) {
    m = S(0.0);
    clip = S(0.0);
    for (size_t p = 0; p < part.size(); ++p) {
        if (!part[p]) continue;
        const S y = (Ya[p] + Yb[p]) * 0.5;
        m += y;
        clip += hingeSquared(S(y - 1.0));
    }
    m /= pixels;
    clip /= pixels;
}
/// L_exp + L_dark of DefectObjective.h at the part's mean brightness m and mean squared
/// clipping `clip` (the JND objective keeps the same band and floor: objective/JndObjective.h).
template <typename S>
S exposureBand(const S& m, const S& clip, const DefectObjectiveOptions& d) {
    const double w = d.whiteMean;
    S loss = d.exposureWeight *
             (hingeSquared(S((d.low * w - m) / w)) + hingeSquared(S((m - d.high * w) / w)) + clip);
    const double floorM = d.darkFloor * w;
    if (floorM > 0 && realPart(m) < floorM) {
        using std::log;
        const S dark =
            realPart(m) > 1e-12 * w ? S(log(m / floorM)) : S(std::log(1e-12 * w / floorM));
        loss += d.darkWeight * dark * dark;
    }
    return loss;
}
}  // namespace detail

template <typename F>
void DefectObjective::forEachLabelPair(F&& f) const {
    detail::forEachMaskedPair(width(), height(), defects_.data(), [&](size_t p, size_t q) {
        const uint8_t v = defects_[p];
        if (v != defects_[q]) return;
        const int k = labelIndex_[v];
        if (k >= 0) f(static_cast<size_t>(k), p, q);
    });
}

template <typename S>
S DefectObjective::value(std::span<const S> Ya, std::span<const S> Yb, std::span<const S> E) const {
    const int W = width(), H = height();
    std::vector<S> gK(labels_.size(), S(0.0));
    S gR(0.0);
    forEachLabelPair(
        [&](size_t k, size_t p, size_t q) { gK[k] += (Ya[q] - Ya[p]) * (Yb[q] - Yb[p]); });
    detail::forEachMaskedPair(W, H, reference_.data(),
                              [&](size_t p, size_t q) { gR += (Ya[q] - Ya[p]) * (Yb[q] - Yb[p]); });
    std::vector<S> phi(gK.size(), S(0.0));
    for (size_t k = 0; k < gK.size(); ++k)
        phi[k] = detail::defectLogFloor(S(gK[k] / pairsK_[k]), floor());
    gR /= pairsR_;
    // g(D), the pooled defect energy, as evaluate() forms LossParts::G (for L_con).
    S gD(0.0);
    for (const S& g : gK) gD += g;
    gD = gK.size() == 1 ? S(gK[0] / pairsK_[0]) : S(gD / pairsD_);
    using std::log;
    S loss = (detail::realPart(gR) >= floor() ? S(log(gR)) : S(std::log(floor()))) -
             detail::labelSoftMin(phi, kLabelSoftMin);
    S m, clip;
    detail::partBrightness(mask(), partPixels_, Ya, Yb, m, clip);
    const double w = d_.whiteMean;
    loss += detail::exposureBand(m, clip, d_);
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
