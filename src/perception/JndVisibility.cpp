#include "perception/JndVisibility.h"

#include <algorithm>
#include <cmath>
#include <future>
#include <numbers>
#include <stdexcept>

#include "perception/ContrastMasking.h"
#include "perception/ContrastSensitivity.h"

namespace sl {

namespace {

/// σ of band k's finer Gaussian (px); the coarser one is twice it.
double bandSigma(int k) {
    return std::ldexp(0.5, k);
}

/// The peak of the difference of Gaussians σ and 2σ: exp(−2π²σ²f²) − exp(−8π²σ²f²) is
/// largest where exp(6π²σ²f²) = 4, f = sqrt(ln 4 / 6) / (π σ) cycles per pixel.
double bandPeakCyclesPerPixel(double sigma) {
    return std::sqrt(std::log(4.0) / 6.0) / (std::numbers::pi * sigma);
}

std::vector<double> gaussianKernel(double sigma) {
    const int r = std::max(1, static_cast<int>(std::ceil(3.0 * sigma)));
    std::vector<double> k(2 * r + 1);
    double sum = 0;
    for (int i = -r; i <= r; ++i) sum += k[i + r] = std::exp(-0.5 * i * i / (sigma * sigma));
    for (double& v : k) v /= sum;
    return k;
}

/// Separable convolution with zero outside the image.
std::vector<double> convolve(int w, int h, const std::vector<double>& in,
                             const std::vector<double>& kernel) {
    const int r = static_cast<int>(kernel.size() / 2);
    std::vector<double> rows(in.size(), 0.0), out(in.size(), 0.0);
    for (int y = 0; y < h; ++y) {
        const double* src = in.data() + static_cast<size_t>(y) * w;
        double* dst = rows.data() + static_cast<size_t>(y) * w;
        for (int x = 0; x < w; ++x) {
            double s = 0;
            for (int d = std::max(-r, -x); d <= std::min(r, w - 1 - x); ++d)
                s += kernel[d + r] * src[x + d];
            dst[x] = s;
        }
    }
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            double s = 0;
            for (int d = std::max(-r, -y); d <= std::min(r, h - 1 - y); ++d)
                s += kernel[d + r] * rows[static_cast<size_t>(y + d) * w + x];
            out[static_cast<size_t>(y) * w + x] = s;
        }
    return out;
}

}  // namespace

BandContrast::BandContrast(int width, int height, std::span<const double> Ya,
                           std::span<const double> Yb, std::span<const uint8_t> part, double white,
                           const ViewingModel& view)
    : width_(width), height_(height), view_(view) {
    const size_t n = static_cast<size_t>(width) * height;
    if (Ya.size() != n || Yb.size() != n || part.size() != n)
        throw std::invalid_argument("BandContrast: image sizes differ");
    if (!(view.pixelsPerDegree > 0) || !(view.whiteLuminance > 0))
        throw std::invalid_argument("BandContrast: the viewing model needs px/deg and a white");
    double sum = 0;
    size_t count = 0;
    for (size_t p = 0; p < n; ++p)
        if (part[p]) sum += 0.5 * (Ya[p] + Yb[p]), ++count;
    const double partMean = count ? sum / static_cast<double>(count) : 0.0;
    luminance_ = white > 0 ? view.whiteLuminance * std::clamp(partMean / white, 0.0, 1.0) : 0.0;

    // Gaussians of σ_0 .. σ_K (σ_{k+1} = 2σ_k) of each estimate, normalized over the part (the
    // part's own weight convolved once per σ), one task per σ.
    std::vector<double> maskedA(n), maskedB(n), weight(n);
    for (size_t p = 0; p < n; ++p) {
        weight[p] = part[p] ? 1.0 : 0.0;
        maskedA[p] = part[p] ? Ya[p] : 0.0;
        maskedB[p] = part[p] ? Yb[p] : 0.0;
    }
    std::vector<std::vector<double>> ga(kJndBands + 1), gb(kJndBands + 1);
    {
        std::vector<std::future<void>> tasks;
        for (int k = 0; k <= kJndBands; ++k)
            tasks.push_back(std::async(std::launch::async, [&, k] {
                const std::vector<double> kernel = gaussianKernel(bandSigma(k));
                const std::vector<double> den = convolve(width, height, weight, kernel);
                ga[k] = convolve(width, height, maskedA, kernel);
                gb[k] = convolve(width, height, maskedB, kernel);
                for (size_t p = 0; p < n; ++p) {
                    const bool reached = den[p] > 1e-12;
                    ga[k][p] = reached ? ga[k][p] / den[p] : 0.0;
                    gb[k][p] = reached ? gb[k][p] / den[p] : 0.0;
                }
            }));
        for (auto& t : tasks) t.get();
    }
    productAB_.assign(kJndBands, std::vector<double>(n, 0.0));
    // The narrowest local mean: Ȳ's Gaussian of kLocalMeanSigma (σ_4), the mean of the two
    // estimates' (the normalized convolution is linear in the image).
    static_assert(kLocalMeanSigma == 8.0, "σ_4 = 8 px is the narrowest local mean");
    std::vector<double> narrowest(n);
    for (size_t p = 0; p < n; ++p) narrowest[p] = 0.5 * (ga[4][p] + gb[4][p]);
    std::vector<double> wide(n);
    for (int k = 0; k < kJndBands; ++k) {
        // The band's local mean: the Gaussian 2σ_k of Ȳ, at least kLocalMeanSigma wide so that
        // its own noise (shared with both bands) does not bias the product.
        const bool own = 2 * bandSigma(k) >= kLocalMeanSigma;
        if (own)
            for (size_t p = 0; p < n; ++p) wide[p] = 0.5 * (ga[k + 1][p] + gb[k + 1][p]);
        const std::vector<double>& local = own ? wide : narrowest;
        for (size_t p = 0; p < n; ++p) {
            if (!part[p] || !(local[p] > 0)) continue;
            const double ca = (ga[k][p] - ga[k + 1][p]) / local[p];
            const double cb = (gb[k][p] - gb[k + 1][p]) / local[p];
            productAB_[k][p] = ca * cb;
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
        const double j = sens > 0 ? std::numbers::sqrt2 * signal * sens /
                                        thresholdElevation(std::numbers::sqrt2 * mask * sens)
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
