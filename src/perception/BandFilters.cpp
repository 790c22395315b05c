#include "perception/BandFilters.h"

#include <future>
#include <numbers>

namespace sl {

double bandPeakCyclesPerPixel(double sigma) {
    // exp(−2π²σ²f²) − exp(−8π²σ²f²) is largest where exp(6π²σ²f²) = 4.
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

BandFilterBank::BandFilterBank(int width, int height, std::span<const uint8_t> part)
    : width_(width), height_(height), part_(part.size()) {
    for (size_t p = 0; p < part.size(); ++p) part_[p] = part[p] ? 1 : 0;
    kernels_.resize(kJndBands + 1);
    weight_.resize(kJndBands + 1);
    std::vector<double> ones(part_.begin(), part_.end());
    std::vector<std::future<void>> tasks;
    for (int j = 0; j <= kJndBands; ++j)
        tasks.push_back(std::async(std::launch::async, [&, j] {
            kernels_[j] = gaussianKernel(bandSigma(j));
            weight_[j] = convolveSeparable<double>(width_, height_, ones, kernels_[j]);
        }));
    for (auto& t : tasks) t.get();
}

std::pair<std::vector<std::vector<double>>, std::vector<std::vector<double>>>
BandFilterBank::gaussians(std::span<const double> ya, std::span<const double> yb) const {
    std::vector<std::vector<double>> ga(kJndBands + 1), gb(kJndBands + 1);
    std::vector<std::future<void>> tasks;
    for (int j = 0; j <= kJndBands; ++j)
        tasks.push_back(std::async(std::launch::async, [&, j] {
            ga[j] = gaussian<double>(j, ya);
            gb[j] = gaussian<double>(j, yb);
        }));
    for (auto& t : tasks) t.get();
    return {std::move(ga), std::move(gb)};
}

std::vector<double> BandFilterBank::gaussianAdjoint(int j, std::span<const double> dG) const {
    const size_t n = part_.size();
    std::vector<double> scaled(n, 0.0);
    for (size_t p = 0; p < n; ++p)
        if (reached(j, p)) scaled[p] = dG[p] / weight_[j][p];
    std::vector<double> d = convolveSeparable<double>(width_, height_, scaled, kernels_[j]);
    for (size_t p = 0; p < n; ++p)
        if (!part_[p]) d[p] = 0.0;
    return d;
}

}  // namespace sl
