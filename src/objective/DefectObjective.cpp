#include "objective/DefectObjective.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/Error.h"

namespace sl {

namespace {

double pairCount(int W, int H, const std::vector<uint8_t>& mask) {
    double n = 0;
    detail::forEachMaskedPair(W, H, mask.data(), [&](size_t, size_t) { n += 1; });
    return n;
}

}  // namespace

std::vector<uint8_t> referenceRegion(int W, int H, const std::vector<uint8_t>& part,
                                     const std::vector<uint8_t>& defects,
                                     const std::vector<uint8_t>& reference) {
    if (reference.empty()) return defectFreeReference(W, H, part, defects, 2);
    std::vector<uint8_t> r(part.size());
    for (size_t k = 0; k < r.size(); ++k) r[k] = part[k] && reference[k] && !defects[k];
    return r;
}

std::vector<uint8_t> defectFreeReference(int W, int H, const std::vector<uint8_t>& part,
                                         const std::vector<uint8_t>& defects, int margin) {
    std::vector<uint8_t> near(part.size(), 0);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            if (!defects[static_cast<size_t>(y) * W + x]) continue;
            for (int v = std::max(0, y - margin); v <= std::min(H - 1, y + margin); ++v)
                for (int u = std::max(0, x - margin); u <= std::min(W - 1, x + margin); ++u)
                    near[static_cast<size_t>(v) * W + u] = 1;
        }
    std::vector<uint8_t> r(part.size());
    for (size_t p = 0; p < r.size(); ++p) r[p] = part[p] && !near[p] ? 1 : 0;
    return r;
}

DefectObjective::DefectObjective(int width, int height, std::vector<uint8_t> part,
                                 std::vector<uint8_t> defects, std::vector<uint8_t> reference,
                                 ObjectiveOptions options, DefectObjectiveOptions defect)
    : base_(width, height, std::move(part), options), d_(defect) {
    const size_t n = static_cast<size_t>(width) * static_cast<size_t>(height);
    if (defects.size() != n)
        throw inputError(option("defects"),
                         "the defect mask has " + std::to_string(defects.size()) +
                             " pixels, the image " + std::to_string(n),
                         "give a mask of the image's size");
    if (!reference.empty() && reference.size() != n)
        throw inputError(option("reference"),
                         "the reference mask has " + std::to_string(reference.size()) +
                             " pixels, the image " + std::to_string(n),
                         "give a mask of the image's size");
    if (options.reg != RegTarget::EnvMap)
        throw inputError(option("reg"), "the defects objective regularises the env map only",
                         "use reg envmap");
    if (!(d_.whiteMean > 0) || !std::isfinite(d_.whiteMean))
        throw std::invalid_argument("DefectObjective: whiteMean must be > 0");
    if (!(d_.darkFloor >= 0 && d_.darkFloor < 1) || !(d_.darkWeight >= 0))
        throw std::invalid_argument("DefectObjective: need 0 <= darkFloor < 1, darkWeight >= 0");
    if (!(d_.low >= 0 && d_.low < d_.high) || !std::isfinite(d_.high))
        throw std::invalid_argument("DefectObjective: need 0 <= low < high");
    const std::vector<uint8_t>& p = mask();
    defects_.resize(n);
    for (size_t k = 0; k < n; ++k) defects_[k] = p[k] ? defects[k] : 0;
    reference_ = referenceRegion(width, height, p, defects_, reference);
    // The labels with a pair of neighbouring pixels of their own are measured.
    std::array<double, 256> pairsOf{};
    detail::forEachMaskedPair(width, height, defects_.data(), [&](size_t a, size_t b) {
        if (defects_[a] == defects_[b]) pairsOf[defects_[a]] += 1;
    });
    labelIndex_.fill(-1);
    for (int v = 1; v < 256; ++v)
        if (pairsOf[v] > 0) {
            labelIndex_[v] = static_cast<int>(labels_.size());
            labels_.push_back(static_cast<uint8_t>(v));
            pairsK_.push_back(pairsOf[v]);
            pairsD_ += pairsOf[v];
        }
    pairsR_ = pairCount(width, height, reference_);
    if (pairsD_ == 0)
        throw inputError(option("defects"), "no two neighbouring defect pixels on the part",
                         "check that the defect mask covers defects the camera sees");
    if (pairsR_ == 0)
        throw inputError(option("reference"),
                         "no two neighbouring defect-free pixels on the part (the defects cover "
                         "it all)",
                         "give a defect mask that leaves some clean surface, or a reference mask");
    for (uint8_t v : p) partPixels_ += v != 0;
}

LossParts DefectObjective::evaluate(std::span<const double> Ya, std::span<const double> Yb,
                                    std::span<const double> E, std::span<double> dLdYa,
                                    std::span<double> dLdYb, std::span<double> dLdE) const {
    const int W = width(), H = height();
    const size_t n = static_cast<size_t>(W) * static_cast<size_t>(H);
    if (Ya.size() != n || Yb.size() != n)
        throw std::invalid_argument("DefectObjective: half images must have width*height values");
    if ((!dLdYa.empty() && dLdYa.size() != n) || (!dLdYb.empty() && dLdYb.size() != n) ||
        (!dLdE.empty() && dLdE.size() != E.size()) || E.empty())
        throw std::invalid_argument("DefectObjective: spans have the wrong size");
    detail::checkFinite(Ya, "Ya", "evaluate");
    detail::checkFinite(Yb, "Yb", "evaluate");
    detail::checkFinite(E, "E", "evaluate");

    LossParts r;
    const size_t K = labels_.size();
    std::vector<double> gK(K, 0.0), phi(K), dPhi(K), weight;
    forEachLabelPair(
        [&](size_t k, size_t p, size_t q) { gK[k] += (Ya[q] - Ya[p]) * (Yb[q] - Yb[p]); });
    double sumD = 0;
    for (size_t k = 0; k < K; ++k) {
        sumD += gK[k];
        gK[k] /= pairsK_[k];
        phi[k] = detail::defectLogFloor(gK[k], floor());
        dPhi[k] = 1.0 / std::max(gK[k], floor());
        r.clamped = r.clamped || gK[k] < floor();  // a label shows no gradient
    }
    r.G = K == 1 ? gK[0] : sumD / pairsD_;
    double gR = 0;
    detail::forEachMaskedPair(W, H, reference_.data(),
                              [&](size_t p, size_t q) { gR += (Ya[q] - Ya[p]) * (Yb[q] - Yb[p]); });
    r.S = gR / pairsR_;
    const double phiD = detail::labelSoftMin(phi, kLabelSoftMin, &weight),
                 phiR = std::log(std::max(r.S, floor()));
    const double dPhiR = r.S >= floor() ? 1.0 / r.S : 0.0;
    r.lGrad = phiR - phiD;

    const std::vector<uint8_t>& part = mask();
    double m = 0, clip = 0;
    for (size_t p = 0; p < n; ++p) {
        if (!part[p]) continue;
        const double y = (Ya[p] + Yb[p]) * 0.5;
        m += y;
        clip += y > 1 ? (y - 1) * (y - 1) : 0.0;
    }
    m /= partPixels_;
    clip /= partPixels_;
    const double w = d_.whiteMean, k = d_.exposureWeight;
    const double under = std::max(0.0, (d_.low * w - m) / w),
                 over = std::max(0.0, (m - d_.high * w) / w);
    const double floorM = d_.darkFloor * w, mEff = std::max(m, 1e-12 * w);
    const double darkLog = floorM > 0 && m < floorM ? std::log(mEff / floorM) : 0.0;
    // L_con: u = ½·log(g(D)/(f_c·c0)²) − log m, negative when the contrast is under the floor.
    const double cf = d_.contrastFloor;
    const double gDe = std::max(r.G, floor());
    const double u = cf > 0 && m > 1e-12 * w && gDe < cf * cf * m * m
                         ? 0.5 * std::log(gDe / (cf * cf)) - std::log(m)
                         : 0.0;
    const double exposure = k * (under * under + over * over + clip) +
                            d_.darkWeight * darkLog * darkLog + d_.contrastWeight * u * u;
    r.lReg = base_.envMapRegulariser(E, dLdE);
    r.total = r.lGrad + exposure + options().lambda * r.lReg;

    if (dLdYa.empty() || dLdYb.empty()) return r;
    std::fill(dLdYa.begin(), dLdYa.end(), 0.0);
    std::fill(dLdYb.begin(), dLdYb.end(), 0.0);
    auto addPair = [&](double scale, size_t p, size_t q) {
        const double da = Ya[q] - Ya[p], db = Yb[q] - Yb[p];
        dLdYa[q] += scale * db;
        dLdYa[p] -= scale * db;
        dLdYb[q] += scale * da;
        dLdYb[p] -= scale * da;
    };
    const double scaleR = dPhiR / pairsR_;
    detail::forEachMaskedPair(W, H, reference_.data(),
                              [&](size_t p, size_t q) { addPair(scaleR, p, q); });
    // L_con through g(D), the pooled defect energy: dG per label pair as r.G was formed.
    const double dConD = u != 0 && r.G >= floor() ? d_.contrastWeight * u / r.G : 0.0;
    std::vector<double> scaleK(K);
    for (size_t j = 0; j < K; ++j)
        scaleK[j] = -weight[j] * dPhi[j] / pairsK_[j] + dConD / (K == 1 ? pairsK_[0] : pairsD_);
    forEachLabelPair([&](size_t label, size_t p, size_t q) { addPair(scaleK[label], p, q); });
    // d/dm of the band terms, then dm/dY = 1/(2·|P|) per half; the clip term per pixel.
    const double dDark = darkLog != 0 && m > 1e-12 * w ? 2.0 * d_.darkWeight * darkLog / m : 0.0;
    const double dCon = u != 0 ? -2.0 * d_.contrastWeight * u / m : 0.0;
    const double dm =
        (k * (-2.0 * under / w + 2.0 * over / w) + dDark + dCon) / (2.0 * partPixels_);
    for (size_t p = 0; p < n; ++p) {
        if (!part[p]) continue;
        const double y = (Ya[p] + Yb[p]) * 0.5;
        const double dy = dm + (y > 1 ? k * 2.0 * (y - 1) * 0.5 / partPixels_ : 0.0);
        dLdYa[p] += dy;
        dLdYb[p] += dy;
    }
    return r;
}

double whiteFurnaceMean(const TransportMatrix& t, const std::vector<uint8_t>& mask,
                        const RowShard& shard) {
    const std::vector<double> one(t.cols(), 1.0);
    std::vector<double> y(t.rows());
    t.applyLuminance(one, y);
    shard.gatherImage(y, t.width);
    double sum = 0, n = 0;
    for (size_t p = 0; p < y.size(); ++p)
        if (mask[p]) sum += y[p], n += 1;
    return n > 0 ? sum / n : 0.0;
}

}  // namespace sl
