// The band filters of the JND model (perception/JndVisibility.h), written once for the judge's
// scores (double) and the JND objective (objective/JndObjective.h: double with a hand-written
// adjoint, and ceres::Jet for its autodiff check).
//
//   Gaussians  G_j = the Gaussian of σ_j = 2^(j−1) px (j = 0..kJndBands), truncated at 3σ,
//              normalized over the part: G_j(Y) = conv(P·Y, K_j) / conv(P, K_j), 0 where the
//              part's own weight conv(P, K_j) is ~0 (zero outside the image)
//   band k     G_k(Y) − G_{k+1}(Y): a difference of Gaussians σ_k and 2σ_k (k = 0..kJndBands−1)
//   local mean the Gaussian 2σ_k of Ȳ = (Y_a + Y_b)/2, at least kLocalMeanSigma wide
//              (G_{localMeanGaussian(k)}), so its own noise does not bias the product
//   product    c_k,a · c_k,b = band_k(Y_a) · band_k(Y_b) / local_k², 0 off the part and where
//              the local mean is not positive
//
// The convolution with a symmetric kernel and zeros outside the image is its own adjoint, so the
// gradient of anything built on G_j(Y) is conv(dG_j / conv(P, K_j), K_j) restricted to the part
// (adjointSum).
//
// Two ways to one operator (GaussianMethod): the direct sums of convolveSeparable (any scalar
// type: the autodiff reference), or, for double, the Gaussians of σ ≥ kFourierMinSigma as
// products in the discrete Fourier domain (FFTW) on a grid padded by the widest kernel's radius
// so that the circular convolution is the zero-padded one exactly: the kernel's spectrum is
// Σ_d K_j[d]·cos(2πud/N) per axis (the same truncated, normalized taps), so the two differ only by
// rounding (~1e-15 of the image's largest value). One forward transform of an image serves every
// Fourier Gaussian; the adjoint sums the Gaussians' spectra before one inverse transform.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <span>
#include <utility>
#include <vector>

namespace sl {

inline constexpr int kJndBands = 6;
inline constexpr double kLocalMeanSigma = 8.0;  // px, the narrowest local mean of a band

/// σ_j of Gaussian j (px): 2^(j−1).
inline double bandSigma(int j) {
    return std::ldexp(0.5, j);
}
/// The index of the Gaussian that is band k's local mean: 2σ_k, at least kLocalMeanSigma.
inline int localMeanGaussian(int band) {
    return std::max(band + 1, 4);
}
static_assert(kLocalMeanSigma == 8.0, "σ_4 = 8 px is the narrowest local mean");

/// Gaussians of σ ≥ this go through the Fourier domain under GaussianMethod::Fourier (below it the
/// direct sums, up to 25 taps, cost less than a transform of the padded grid).
inline constexpr double kFourierMinSigma = 4.0;

/// How BandFilterBank computes its Gaussians (the same operator, rounding apart).
enum class GaussianMethod {
    Direct,   // convolveSeparable for every σ
    Fourier,  // σ ≥ kFourierMinSigma through FFTW, the rest direct
};

/// The peak of the difference of Gaussians σ and 2σ (cycles per pixel).
double bandPeakCyclesPerPixel(double sigma);

/// A normalized Gaussian of σ px, truncated at 3σ (at least one tap each side).
std::vector<double> gaussianKernel(double sigma);

/// Separable convolution with `kernel` (odd length, centred), zero outside the image. Both
/// passes run over whole rows for one tap at a time (contiguous, vectorizable), the same sums for
/// any scalar type.
template <typename S>
std::vector<S> convolveSeparable(int w, int h, std::span<const S> in,
                                 const std::vector<double>& kernel) {
    const int r = static_cast<int>(kernel.size() / 2);
    std::vector<S> rows(in.size(), S(0.0)), out(in.size(), S(0.0));
    for (int y = 0; y < h; ++y) {
        const S* src = in.data() + static_cast<size_t>(y) * w;
        S* dst = rows.data() + static_cast<size_t>(y) * w;
        for (int d = -r; d <= r; ++d) {
            const double k = kernel[d + r];
            const int x0 = std::max(0, -d), x1 = std::min(w, w - d);
            for (int x = x0; x < x1; ++x) dst[x] += k * src[x + d];
        }
    }
    for (int y = 0; y < h; ++y) {
        S* dst = out.data() + static_cast<size_t>(y) * w;
        for (int d = std::max(-r, -y); d <= std::min(r, h - 1 - y); ++d) {
            const double k = kernel[d + r];
            const S* src = rows.data() + static_cast<size_t>(y + d) * w;
            for (int x = 0; x < w; ++x) dst[x] += k * src[x];
        }
    }
    return out;
}

/// The Gaussians G_0..G_kJndBands of one part mask: kernels and the part's own weights.
class BandFilterBank {
  public:
    /// Builds the kernels, the Fourier plans (GaussianMethod::Fourier) and conv(P, K_j).
    BandFilterBank(int width, int height, std::span<const uint8_t> part,
                   GaussianMethod method = GaussianMethod::Fourier);
    ~BandFilterBank();
    BandFilterBank(const BandFilterBank&) = delete;
    BandFilterBank& operator=(const BandFilterBank&) = delete;

    int width() const { return width_; }
    int height() const { return height_; }
    const std::vector<uint8_t>& part() const { return part_; }

    GaussianMethod method() const { return method_; }

    /// G_j(Y) of the header for an image Y (width*height; values off the part are ignored), by
    /// the direct sums in any scalar type (the autodiff reference of gaussians()).
    template <typename S>
    std::vector<S> gaussian(int j, std::span<const S> y) const {
        const size_t n = part_.size();
        std::vector<S> masked(n, S(0.0));
        for (size_t p = 0; p < n; ++p)
            if (part_[p]) masked[p] = y[p];
        std::vector<S> g = convolveSeparable<S>(width_, height_, masked, kernels_[j]);
        for (size_t p = 0; p < n; ++p) g[p] = reached(j, p) ? S(g[p] / weight_[j][p]) : S(0.0);
        return g;
    }
    /// G_0..G_kJndBands of one image, by the bank's method.
    std::vector<std::vector<double>> gaussians(std::span<const double> y) const;
    /// G_0..G_kJndBands of two images (two estimates), one task each: {G(Y_a), G(Y_b)}.
    std::pair<std::vector<std::vector<double>>, std::vector<std::vector<double>>> gaussians(
        std::span<const double> ya, std::span<const double> yb) const;
    /// The adjoint of Y ↦ (G_0(Y)..G_kJndBands(Y)): d/dY (on the part, 0 off it) of
    /// Σ_j Σ_p dG_j[p]·G_j(Y)[p]; dG holds kJndBands + 1 images.
    std::vector<double> adjointSum(const std::vector<std::vector<double>>& dG) const;
    /// The same for two images' dG at once, one task each.
    std::pair<std::vector<double>, std::vector<double>> adjointSums(
        const std::vector<std::vector<double>>& dGa,
        const std::vector<std::vector<double>>& dGb) const;

  private:
    struct Fourier;  // FFTW plans and the kernels' spectra (BandFilters.cpp)
    bool reached(int j, size_t p) const { return weight_[j][p] > 1e-12; }
    bool inFourier(int j) const { return fourier_ && j >= firstFourier_; }
    /// conv(x, K_j) of every j at once (x: width*height, zero off the part): the raw sums.
    std::vector<std::vector<double>> convolveAll(std::span<const double> x) const;
    int width_, height_;
    GaussianMethod method_;
    std::vector<uint8_t> part_;                 // 0/1
    std::vector<std::vector<double>> kernels_;  // K_j
    std::vector<std::vector<double>> weight_;   // conv(P, K_j)
    int firstFourier_ = kJndBands + 1;          // the first j through the Fourier domain
    std::unique_ptr<Fourier> fourier_;          // null: every Gaussian direct
};

/// c_k,a · c_k,b at one pixel from the band's Gaussians of both estimates and its local mean
/// (the header's product); 0 when the local mean is not positive.
template <typename S>
S bandProduct(const S& gaK, const S& gaK1, const S& gbK, const S& gbK1, const S& local) {
    if (!(local > 0.0)) return S(0.0);
    return (gaK - gaK1) * (gbK - gbK1) / (local * local);
}

}  // namespace sl
