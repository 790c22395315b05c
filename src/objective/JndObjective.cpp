#include "objective/JndObjective.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include "core/Dual.h"
#include "core/Error.h"

namespace sl {

JndObjective::JndObjective(int width, int height, std::vector<uint8_t> part,
                           std::vector<uint8_t> defects, std::vector<uint8_t> reference,
                           ObjectiveOptions options, JndObjectiveOptions jnd)
    : width_(width),
      height_(height),
      base_(width, height, std::move(part), options),
      bank_(width, height, base_.mask(), jnd.gaussians),
      o_(jnd) {
    const size_t n = static_cast<size_t>(width) * height;
    if (defects.size() != n) throw inputError(option("defects"), "has the wrong size", "");
    if (!reference.empty() && reference.size() != n)
        throw inputError(option("reference"), "has the wrong size", "");
    if (!(o_.band.whiteMean > 0))
        throw std::invalid_argument("JndObjective: the white furnace's mean must be > 0");
    if (!(o_.view.pixelsPerDegree > 0) || !(o_.view.whiteLuminance > 0))
        throw std::invalid_argument("JndObjective: the viewing model needs px/deg and a white");
    if (!(o_.band.low >= 0 && o_.band.low < o_.band.high) || !std::isfinite(o_.band.high))
        throw std::invalid_argument("JndObjective: need 0 <= low < high");
    const std::vector<uint8_t>& p = base_.mask();
    std::vector<uint8_t> onPart(n);
    for (size_t k = 0; k < n; ++k) onPart[k] = p[k] ? defects[k] : 0;
    reference_ = referenceRegion(width, height, p, onPart, reference);
    std::array<double, 256> count{};
    for (size_t k = 0; k < n; ++k) count[onPart[k]] += onPart[k] ? 1 : 0;
    std::array<int, 256> index{};
    index.fill(-1);
    for (int v = 1; v < 256; ++v)
        if (count[v] > 0) {
            index[v] = static_cast<int>(labels_.size());
            labels_.push_back(static_cast<uint8_t>(v));
            labelPixels_.push_back(count[v]);
            labelSizeDeg_.push_back(std::sqrt(count[v]) / o_.view.pixelsPerDegree);
        }
    labelOf_.assign(n, -1);
    for (size_t k = 0; k < n; ++k)
        if (onPart[k]) labelOf_[k] = index[onPart[k]];
    for (size_t k = 0; k < n; ++k) referencePixels_ += reference_[k], partPixels_ += p[k] != 0;
    if (labels_.empty())
        throw inputError(option("defects"), "no defect pixel on the part",
                         "check that the defect mask covers defects the camera sees");
    if (referencePixels_ == 0)
        throw inputError(option("reference"),
                         "no defect-free pixel on the part (the defects cover it all)",
                         "give a defect mask that leaves some clean surface, or a reference mask");
    for (int b = 0; b < kJndBands; ++b)
        bandFrequency_.push_back(bandPeakCyclesPerPixel(bandSigma(b)) * o_.view.pixelsPerDegree);
}

LossParts JndObjective::evaluate(std::span<const double> Ya, std::span<const double> Yb,
                                 std::span<const double> E, std::span<double> dLdYa,
                                 std::span<double> dLdYb, std::span<double> dLdE) const {
    const size_t n = static_cast<size_t>(width_) * height_;
    if (Ya.size() != n || Yb.size() != n)
        throw std::invalid_argument("JndObjective: half images must have width*height values");
    if ((!dLdYa.empty() && dLdYa.size() != n) || (!dLdYb.empty() && dLdYb.size() != n) ||
        (!dLdE.empty() && dLdE.size() != E.size()) || E.empty())
        throw std::invalid_argument("JndObjective: spans have the wrong size");
    detail::checkFinite(Ya, "Ya", "evaluate");
    detail::checkFinite(Yb, "Yb", "evaluate");
    detail::checkFinite(E, "E", "evaluate");

    // Forward: the Gaussians of both estimates, one task per σ.
    const auto [ga, gb] = bank_.gaussians(Ya, Yb);
    const size_t K = labels_.size();
    const std::vector<uint8_t>& part = base_.mask();
    auto counted = [&](size_t p) { return part[p] && (reference_[p] || labelOf_[p] >= 0); };
    std::vector<double> eF(kJndBands, 0.0), eK(K * kJndBands, 0.0);
    for (int b = 0; b < kJndBands; ++b) {
        const int l = localMeanGaussian(b);
        for (size_t p = 0; p < n; ++p) {
            if (!counted(p)) continue;
            const double prod = bandProduct(ga[b][p], ga[b + 1][p], gb[b][p], gb[b + 1][p],
                                            0.5 * (ga[l][p] + gb[l][p]));
            if (reference_[p]) eF[b] += prod;
            if (labelOf_[p] >= 0) eK[static_cast<size_t>(labelOf_[p]) * kJndBands + b] += prod;
        }
        eF[b] /= referencePixels_;
    }
    double m = 0, clip = 0;
    detail::partBrightness(base_.mask(), partPixels_, Ya, Yb, m, clip);
    // L(m), m a variable: the sensitivities below carry dS/dm.
    const Dual<1> L = luminanceOf(Dual<1>::variable(m, 0));

    // Per label: q_k and the derivatives of q_k by its parts (core/Dual.h, variables h, e_F, S).
    const double q0 = std::pow(kJndFloor, 4.0);
    std::vector<double> half(K), dHalfDq(K);
    struct BandPartials {
        double dh = 0, dMask = 0, dSens = 0, dSensDm = 0, dDelta = 0;
    };
    std::vector<BandPartials> partial(K * kJndBands);
    double worstJnd = 0;
    for (size_t k = 0; k < K; ++k) {
        double q = 0;
        for (int b = 0; b < kJndBands; ++b) {
            const double delta = eK[k * kJndBands + b] / labelPixels_[k] - eF[b];
            const double mask = eF[b] > 0 ? eF[b] : 0.0;
            // S_kb and dS_kb/dm at once.
            const Dual<1> sens =
                bartenSensitivityAt(bandFrequency_[b], L, labelSizeDeg_[k], labelSizeDeg_[k]);
            const Dual<3> qb =
                jndBandFourth(Dual<3>::variable(detail::jndSignalFourth(delta), 0),
                              Dual<3>::variable(mask, 1), Dual<3>::variable(sens.v, 2));
            q += qb.v;
            BandPartials& bp = partial[k * kJndBands + b];
            bp.dh = qb.d[0];
            bp.dMask = eF[b] > 0 ? qb.d[1] : 0.0;
            bp.dSens = qb.d[2];
            bp.dSensDm = sens.d[0];
            bp.dDelta = delta >= kJndEnergyFloor ? 2.0 * delta : 2.0 * kJndEnergyFloor;
        }
        half[k] = 0.5 * detail::defectLogFloor(q, q0);
        dHalfDq[k] = 0.5 / std::max(q, q0);
        const double jnd = q > 0 ? std::pow(q, 0.25) : 0.0;
        worstJnd = k == 0 ? jnd : std::min(worstJnd, jnd);
    }
    std::vector<double> weight;
    const double M = detail::labelSoftMin(half, kLabelSoftMin, &weight);
    const Dual<1> exposure = detail::exposureBand(Dual<1>::variable(m, 0), Dual<1>(clip), o_.band);

    LossParts r;
    r.lGrad = -M;
    r.G = worstJnd;
    double mask2 = 0;
    for (double e : eF) mask2 += std::max(e, 0.0);
    r.S = std::sqrt(mask2);
    r.clamped = worstJnd < kJndFloor;
    r.lReg = base_.envMapRegulariser(E, dLdE);
    r.total = r.lGrad + exposure.v + base_.options().lambda * r.lReg;
    if (dLdYa.empty() || dLdYb.empty()) return r;

    // Backward: dLoss/de_b(D_k), dLoss/de_b(F) and dLoss/dm (the exposure band's and through L).
    std::vector<double> gEK(K * kJndBands, 0.0), gEF(kJndBands, 0.0);
    double gm = exposure.d[0];
    for (size_t k = 0; k < K; ++k) {
        const double gq = -weight[k] * dHalfDq[k];
        for (int b = 0; b < kJndBands; ++b) {
            const BandPartials& bp = partial[k * kJndBands + b];
            const double gDelta = gq * bp.dh * bp.dDelta;
            gEK[k * kJndBands + b] += gDelta / labelPixels_[k];
            gEF[b] += -gDelta + gq * bp.dMask;
            gm += gq * bp.dSens * bp.dSensDm;
        }
    }
    // The band products' adjoint into the Gaussians' (dG_j of both estimates).
    std::vector<std::vector<double>> dga(kJndBands + 1, std::vector<double>(n, 0.0)),
        dgb(kJndBands + 1, std::vector<double>(n, 0.0));
    for (int b = 0; b < kJndBands; ++b) {
        const int l = localMeanGaussian(b);
        const double aF = gEF[b] / referencePixels_;
        for (size_t p = 0; p < n; ++p) {
            if (!counted(p)) continue;
            const double local = 0.5 * (ga[l][p] + gb[l][p]);
            if (!(local > 0)) continue;
            double a = reference_[p] ? aF : 0.0;
            if (labelOf_[p] >= 0) a += gEK[static_cast<size_t>(labelOf_[p]) * kJndBands + b];
            if (a == 0) continue;
            const double A = ga[b][p] - ga[b + 1][p], B = gb[b][p] - gb[b + 1][p];
            const double inv2 = 1.0 / (local * local);
            const double dA = a * B * inv2, dB = a * A * inv2;
            const double dLocal = -2.0 * a * A * B * inv2 / local;
            dga[b][p] += dA;
            dga[b + 1][p] -= dA;
            dgb[b][p] += dB;
            dgb[b + 1][p] -= dB;
            dga[l][p] += 0.5 * dLocal;
            dgb[l][p] += 0.5 * dLocal;
        }
    }
    const auto [da, db] = bank_.adjointSums(dga, dgb);
    const double kappa = o_.band.exposureWeight;
    for (size_t p = 0; p < n; ++p) {
        double sa = da[p], sb = db[p];
        if (part[p]) {
            // m = mean_P (Y_a + Y_b)/2; the clip term per pixel (exposureBand's κ·clip).
            const double y = 0.5 * (Ya[p] + Yb[p]);
            const double dy =
                gm * 0.5 / partPixels_ + (y > 1 ? kappa * (y - 1) / partPixels_ : 0.0);
            sa += dy;
            sb += dy;
        }
        dLdYa[p] = sa;
        dLdYb[p] = sb;
    }
    return r;
}

}  // namespace sl
