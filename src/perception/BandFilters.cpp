#include "perception/BandFilters.h"

#include <fftw3.h>

#include <future>
#include <mutex>
#include <new>
#include <numbers>
#include <stdexcept>

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

namespace {

/// FFTW's planner is not thread-safe (its execute functions are, on distinct arrays).
std::mutex& plannerMutex() {
    static std::mutex m;
    return m;
}

struct FftwFree {
    void operator()(void* p) const { fftw_free(p); }
};
using RealBuffer = std::unique_ptr<double, FftwFree>;
using ComplexBuffer = std::unique_ptr<fftw_complex, FftwFree>;

RealBuffer realBuffer(size_t n) {
    auto* p = fftw_alloc_real(n);
    if (!p) throw std::bad_alloc();
    return RealBuffer(p);
}
ComplexBuffer complexBuffer(size_t n) {
    auto* p = fftw_alloc_complex(n);
    if (!p) throw std::bad_alloc();
    return ComplexBuffer(p);
}

/// The least even n' ≥ n whose prime factors are 2, 3, 5 and 7 (FFTW's fast sizes; its real-data
/// transforms take a slower path for odd lengths: at 512² + padding the odd 625 = 5⁴ cost
/// 5.4 ms of CPU a transform, the even 630 2.5–3.3 ms, measured side by side).
int fastSize(int n) {
    for (int m = std::max(n + (n & 1), 2);; m += 2) {
        int r = m;
        for (int f : {2, 3, 5, 7})
            while (r % f == 0) r /= f;
        if (r == 1) return m;
    }
}

/// The DFT of the centred symmetric kernel k on a circle of n points, u = 0..count−1:
/// Σ_d k[d]·cos(2πud/n) (real), times `scale`.
std::vector<double> kernelSpectrum(const std::vector<double>& k, int n, int count, double scale) {
    const int r = static_cast<int>(k.size() / 2);
    std::vector<double> s(count);
    for (int u = 0; u < count; ++u) {
        double sum = k[r];
        for (int d = 1; d <= r; ++d) {
            const long long phase = (static_cast<long long>(u) * d) % n;
            sum +=
                2.0 * k[r + d] * std::cos(2.0 * std::numbers::pi * static_cast<double>(phase) / n);
        }
        s[u] = scale * sum;
    }
    return s;
}

}  // namespace

struct BandFilterBank::Fourier {
    int nx = 0, ny = 0, cx = 0;  // the padded grid; cx = nx/2 + 1 complex columns
    fftw_plan forward = nullptr, inverse = nullptr;
    // Per Fourier Gaussian (j − firstFourier_): its spectrum along x (cx values, with the
    // inverse transform's 1/(nx·ny)) and along y (ny values); K̂(u, v) = sx[u]·sy[v].
    std::vector<std::vector<double>> sx, sy;

    Fourier(int width, int height, int radius) {
        nx = fastSize(width + radius);
        ny = fastSize(height + radius);
        cx = nx / 2 + 1;
        const size_t real = static_cast<size_t>(nx) * ny, spec = static_cast<size_t>(ny) * cx;
        RealBuffer in = realBuffer(real);
        ComplexBuffer out = complexBuffer(spec);
        const std::lock_guard<std::mutex> lock(plannerMutex());
        forward = fftw_plan_dft_r2c_2d(ny, nx, in.get(), out.get(), FFTW_ESTIMATE);
        inverse = fftw_plan_dft_c2r_2d(ny, nx, out.get(), in.get(), FFTW_ESTIMATE);
        if (!forward || !inverse) throw std::runtime_error("BandFilterBank: FFTW gave no plan");
    }
    ~Fourier() {
        const std::lock_guard<std::mutex> lock(plannerMutex());
        if (forward) fftw_destroy_plan(forward);
        if (inverse) fftw_destroy_plan(inverse);
    }
    Fourier(const Fourier&) = delete;
    Fourier& operator=(const Fourier&) = delete;

    size_t realSize() const { return static_cast<size_t>(nx) * ny; }
    size_t spectrumSize() const { return static_cast<size_t>(ny) * cx; }

    /// The transform of a width×height image placed at the padded grid's corner.
    ComplexBuffer transform(int width, int height, std::span<const double> x) const {
        RealBuffer in = realBuffer(realSize());
        std::fill(in.get(), in.get() + realSize(), 0.0);
        for (int y = 0; y < height; ++y)
            std::copy_n(x.data() + static_cast<size_t>(y) * width, width,
                        in.get() + static_cast<size_t>(y) * nx);
        ComplexBuffer spectrum = complexBuffer(spectrumSize());
        fftw_execute_dft_r2c(forward, in.get(), spectrum.get());
        return spectrum;
    }
    /// acc (+)= spectrum · K̂_f.
    void multiply(const fftw_complex* spectrum, int f, fftw_complex* acc, bool add) const {
        for (int v = 0; v < ny; ++v) {
            const double ky = sy[f][v];
            const fftw_complex* s = spectrum + static_cast<size_t>(v) * cx;
            fftw_complex* a = acc + static_cast<size_t>(v) * cx;
            for (int u = 0; u < cx; ++u) {
                const double k = ky * sx[f][u];
                a[u][0] = (add ? a[u][0] : 0.0) + k * s[u][0];
                a[u][1] = (add ? a[u][1] : 0.0) + k * s[u][1];
            }
        }
    }
    /// The inverse transform of `spectrum` (destroyed), the width×height corner.
    std::vector<double> inverseCorner(fftw_complex* spectrum, int width, int height) const {
        RealBuffer out = realBuffer(realSize());
        fftw_execute_dft_c2r(inverse, spectrum, out.get());
        std::vector<double> r(static_cast<size_t>(width) * height);
        for (int y = 0; y < height; ++y)
            std::copy_n(out.get() + static_cast<size_t>(y) * nx, width,
                        r.data() + static_cast<size_t>(y) * width);
        return r;
    }
};

BandFilterBank::BandFilterBank(int width, int height, std::span<const uint8_t> part,
                               GaussianMethod method)
    : width_(width), height_(height), method_(method), part_(part.size()) {
    if (width < 1 || height < 1 || part.size() != static_cast<size_t>(width) * height)
        throw std::invalid_argument("BandFilterBank: the part mask is not width*height");
    for (size_t p = 0; p < part.size(); ++p) part_[p] = part[p] ? 1 : 0;
    kernels_.resize(kJndBands + 1);
    for (int j = 0; j <= kJndBands; ++j) kernels_[j] = gaussianKernel(bandSigma(j));
    if (method == GaussianMethod::Fourier) {
        firstFourier_ = kJndBands + 1;
        for (int j = kJndBands; j >= 0 && bandSigma(j) >= kFourierMinSigma; --j) firstFourier_ = j;
        if (firstFourier_ <= kJndBands) {
            const int radius = static_cast<int>(kernels_[kJndBands].size() / 2);
            fourier_ = std::make_unique<Fourier>(width, height, radius);
            const double scale = 1.0 / static_cast<double>(fourier_->realSize());
            for (int j = firstFourier_; j <= kJndBands; ++j) {
                fourier_->sx.push_back(
                    kernelSpectrum(kernels_[j], fourier_->nx, fourier_->cx, scale));
                fourier_->sy.push_back(kernelSpectrum(kernels_[j], fourier_->ny, fourier_->ny, 1));
            }
        }
    }
    const std::vector<double> ones(part_.begin(), part_.end());
    weight_ = convolveAll(ones);
}

BandFilterBank::~BandFilterBank() = default;

std::vector<std::vector<double>> BandFilterBank::convolveAll(std::span<const double> x) const {
    std::vector<std::vector<double>> r(kJndBands + 1);
    for (int j = 0; j <= kJndBands; ++j)
        if (!inFourier(j)) r[j] = convolveSeparable<double>(width_, height_, x, kernels_[j]);
    if (!fourier_) return r;
    const ComplexBuffer spectrum = fourier_->transform(width_, height_, x);
    ComplexBuffer product = complexBuffer(fourier_->spectrumSize());
    for (int j = firstFourier_; j <= kJndBands; ++j) {
        fourier_->multiply(spectrum.get(), j - firstFourier_, product.get(), false);
        r[j] = fourier_->inverseCorner(product.get(), width_, height_);
    }
    return r;
}

std::vector<std::vector<double>> BandFilterBank::gaussians(std::span<const double> y) const {
    const size_t n = part_.size();
    if (y.size() != n) throw std::invalid_argument("BandFilterBank: image is not width*height");
    std::vector<double> masked(n, 0.0);
    for (size_t p = 0; p < n; ++p)
        if (part_[p]) masked[p] = y[p];
    std::vector<std::vector<double>> g = convolveAll(masked);
    for (int j = 0; j <= kJndBands; ++j)
        for (size_t p = 0; p < n; ++p) g[j][p] = reached(j, p) ? g[j][p] / weight_[j][p] : 0.0;
    return g;
}

std::pair<std::vector<std::vector<double>>, std::vector<std::vector<double>>>
BandFilterBank::gaussians(std::span<const double> ya, std::span<const double> yb) const {
    auto a = std::async(std::launch::async, [&] { return gaussians(ya); });
    std::vector<std::vector<double>> gb = gaussians(yb);
    return {a.get(), std::move(gb)};
}

std::vector<double> BandFilterBank::adjointSum(const std::vector<std::vector<double>>& dG) const {
    const size_t n = part_.size();
    if (dG.size() != static_cast<size_t>(kJndBands + 1))
        throw std::invalid_argument("BandFilterBank::adjointSum: need one image per Gaussian");
    std::vector<double> sum(n, 0.0), scaled(n);
    ComplexBuffer acc;
    for (int j = 0; j <= kJndBands; ++j) {
        if (dG[j].size() != n)
            throw std::invalid_argument("BandFilterBank::adjointSum: image is not width*height");
        for (size_t p = 0; p < n; ++p) scaled[p] = reached(j, p) ? dG[j][p] / weight_[j][p] : 0.0;
        if (!inFourier(j)) {
            const std::vector<double> d =
                convolveSeparable<double>(width_, height_, scaled, kernels_[j]);
            for (size_t p = 0; p < n; ++p) sum[p] += d[p];
            continue;
        }
        const ComplexBuffer spectrum = fourier_->transform(width_, height_, scaled);
        if (!acc) acc = complexBuffer(fourier_->spectrumSize());
        fourier_->multiply(spectrum.get(), j - firstFourier_, acc.get(), j > firstFourier_);
    }
    if (acc) {
        const std::vector<double> d = fourier_->inverseCorner(acc.get(), width_, height_);
        for (size_t p = 0; p < n; ++p) sum[p] += d[p];
    }
    for (size_t p = 0; p < n; ++p)
        if (!part_[p]) sum[p] = 0.0;
    return sum;
}

std::pair<std::vector<double>, std::vector<double>> BandFilterBank::adjointSums(
    const std::vector<std::vector<double>>& dGa,
    const std::vector<std::vector<double>>& dGb) const {
    auto a = std::async(std::launch::async, [&] { return adjointSum(dGa); });
    std::vector<double> b = adjointSum(dGb);
    return {a.get(), std::move(b)};
}

}  // namespace sl
