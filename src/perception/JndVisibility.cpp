#include "perception/JndVisibility.h"

#include <algorithm>
#include <cmath>
#include <future>
#include <numbers>
#include <stdexcept>

#include "perception/ContrastSensitivity.h"

namespace sl {

BandContrast::BandContrast(int width, int height, std::span<const double> Ya,
                           std::span<const double> Yb, std::span<const uint8_t> part, double white,
                           const ViewingModel& view, GaussianMethod method)
    : BandContrast(Ya, Yb, part, white, view, BandFilterBank(width, height, part, method)) {}

BandContrast::BandContrast(std::span<const double> Ya, std::span<const double> Yb,
                           std::span<const uint8_t> part, double white, const ViewingModel& view,
                           const BandFilterBank& bank)
    : width_(bank.width()), height_(bank.height()), view_(view) {
    const size_t n = static_cast<size_t>(width_) * height_;
    if (Ya.size() != n || Yb.size() != n || part.size() != n)
        throw std::invalid_argument("BandContrast: image sizes differ");
    for (size_t p = 0; p < n; ++p)
        if ((part[p] != 0) != (bank.part()[p] != 0))
            throw std::invalid_argument("BandContrast: the bank was built for another part");
    if (!(view.pixelsPerDegree > 0) || !(view.whiteLuminance > 0))
        throw std::invalid_argument("BandContrast: the viewing model needs px/deg and a white");
    double sum = 0;
    size_t count = 0;
    for (size_t p = 0; p < n; ++p)
        if (part[p]) sum += 0.5 * (Ya[p] + Yb[p]), ++count;
    const double partMean = count ? sum / static_cast<double>(count) : 0.0;
    luminance_ = white > 0 ? view.whiteLuminance * std::clamp(partMean / white, 0.0, 1.0) : 0.0;

    // G_0 .. G_K of each estimate (perception/BandFilters.h), one task per estimate.
    const auto [ga, gb] = bank.gaussians(Ya, Yb);
    productAB_.assign(kJndBands, std::vector<double>(n, 0.0));
    for (int k = 0; k < kJndBands; ++k) {
        const int l = localMeanGaussian(k);
        for (size_t p = 0; p < n; ++p) {
            if (!part[p]) continue;
            productAB_[k][p] = bandProduct(ga[k][p], ga[k + 1][p], gb[k][p], gb[k + 1][p],
                                           0.5 * (ga[l][p] + gb[l][p]));
        }
    }
}

double BandContrast::bandFrequency(int k) const {
    return bandPeakCyclesPerPixel(bandSigma(k)) * view_.pixelsPerDegree;
}

JndScore BandContrast::score(std::span<const uint8_t> region,
                             std::span<const uint8_t> clean) const {
    const size_t n = static_cast<size_t>(width_) * height_;
    if (region.size() != n || clean.size() != n)
        throw std::invalid_argument("BandContrast::score: mask sizes differ");
    JndScore s;
    s.luminance = luminance_;
    size_t inRegion = 0, inClean = 0;
    for (size_t p = 0; p < n; ++p) inRegion += region[p] != 0, inClean += clean[p] != 0;
    if (!inRegion || !inClean || !(luminance_ > 0)) return s;
    // The region's angular size: the side of a square of its area.
    const double sizeDeg = std::sqrt(static_cast<double>(inRegion)) / view_.pixelsPerDegree;
    const BartenCondition eye = bartenCondition(luminance_, sizeDeg, sizeDeg);
    double pooled = 0, signal2 = 0, mask2 = 0, best = 0;
    for (int k = 0; k < kJndBands; ++k) {
        double eR = 0, eF = 0;
        for (size_t p = 0; p < n; ++p) {
            if (region[p]) eR += productAB_[k][p];
            if (clean[p]) eF += productAB_[k][p];
        }
        eR /= static_cast<double>(inRegion);
        eF /= static_cast<double>(inClean);
        const double signal = std::sqrt(std::max(eR - eF, 0.0));
        const double mask = std::sqrt(std::max(eF, 0.0));
        const double sens = bartenSensitivity(bandFrequency(k), eye);
        const double j =
            sens > 0 ? std::pow(jndBandFourth(std::pow(signal, 4.0), mask * mask, sens), 0.25)
                     : 0.0;
        pooled += std::pow(j, kJndPooling);
        signal2 += signal * signal;
        mask2 += mask * mask;
        if (j > best) best = j, s.frequency = bandFrequency(k);
    }
    s.jnd = std::pow(pooled, 1.0 / kJndPooling);
    s.signalContrast = std::sqrt(signal2);
    s.maskContrast = std::sqrt(mask2);
    return s;
}

}  // namespace sl
