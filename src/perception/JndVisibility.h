// Visibility in just-noticeable differences (README "Visibility in JND"): how many times over
// its threshold a person sees a region's pattern, given how the image is viewed
// (perception/ViewingModel.h), the eye's contrast sensitivity at the image's luminance
// (perception/ContrastSensitivity.h, Barten 1999) and the masking by the part's own texture
// (perception/ContrastMasking.h, Legge & Foley 1980).
//
// From two independent estimates Y_a, Y_b of the same image (disjoint samples):
//   bands     difference-of-Gaussian octaves (σ_k = 2^(k−1) px, k = 0..5, Gaussians of σ_k and
//             2σ_k, normalized over the part: perception/BandFilters.h), the band's peak
//             frequency f_k = 0.153/σ_k
//             cycles/pixel → u_k = f_k · pixels per degree;
//   contrast  Peli's band-limited local contrast (JOSA A 7(10), 1990):
//             c_k = band_k / the Gaussian 2σ_k mean of Ȳ (at least 8 px wide, so that the
//             mean's own noise, shared by both estimates' bands, stays negligible), per
//             estimate: c_k,a and c_k,b;
//   energy    e_k(X) = mean over X of c_k,a · c_k,b: an estimate of the mean squared noise-free
//             band contrast in X whose noise terms cancel in expectation (as the judge's
//             gradients: objective/DefectVisibility.h);
//   signal    s_k = sqrt(max(e_k(R) − e_k(F), 0)): the contrast a region R adds over the
//             defect-free surface F (the texture); mask m_k = sqrt(max(e_k(F), 0));
//   threshold in modulation (a sinusoid of modulation M has RMS contrast M/√2):
//             t_k = TE(√2·m_k·S_k) / S_k, S_k = Barten's S(u_k, L, X0, Y0), L the part's mean
//             luminance on the display, X0 = Y0 = the region's angular size (sqrt of its area);
//   JND       J_k = √2·s_k / t_k, pooled over bands by a Minkowski sum of exponent β = 4
//             (probability summation over channels): J = (Σ J_k^β)^(1/β).
// J = 0: nothing to see; J = 1: at threshold (half of observers notice it); the J of a
// pattern grows linearly with its contrast on a flat background and slower (exponent 0.4) on a
// texture that masks it.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "perception/BandFilters.h"
#include "perception/ContrastMasking.h"
#include "perception/ViewingModel.h"

namespace sl {

inline constexpr double kJndPooling = 4.0;

/// J_k⁴ of one band, from the signal's contrast energy s_k² = e_k(R) − e_k(F) (≥ 0), the
/// mask's m_k² = e_k(F) (≥ 0) and the sensitivity S_k, in any scalar type:
///   J_k⁴ = (√2·s_k·S_k)⁴ / TE(√2·m_k·S_k)⁴ = 4·s_k⁴·S_k⁴ / (1 + (2·m_k²·S_k²)^(b·ε/2))
/// (TE of perception/ContrastMasking.h). The JND objective passes a floored s_k⁴ (its h(Δ)).
template <typename S>
S jndBandFourth(const S& signalFourth, const S& maskEnergy, const S& sensitivity) {
    using std::exp;
    using std::log;
    const S s2 = sensitivity * sensitivity;
    const S x = 2.0 * maskEnergy * s2;
    const S elevation4 =
        maskEnergy > 0.0 ? S(1.0 + exp(0.5 * kMaskingKnee * kMaskingExponent * log(x))) : S(1.0);
    return 4.0 * signalFourth * s2 * s2 / elevation4;
}

struct JndScore {
    double jnd = 0;             // pooled over bands
    double signalContrast = 0;  // RMS band contrast the region adds (bands in quadrature)
    double maskContrast = 0;    // the texture's RMS band contrast (bands in quadrature)
    double frequency = 0;       // c/deg of the band with the largest J_k (0 when J = 0)
    double luminance = 0;       // cd/m², the part's mean on the display
};

/// The band contrasts of one image pair, computed once, scored for any region.
class BandContrast {
  public:
    /// white: the image value shown at the display's white (the white furnace's part mean);
    /// method: how the band filters are computed (the same operator, rounding apart).
    BandContrast(int width, int height, std::span<const double> Ya, std::span<const double> Yb,
                 std::span<const uint8_t> part, double white, const ViewingModel& view,
                 GaussianMethod method = GaussianMethod::Fourier);
    /// The same on a bank built once for this part (bank.part() nonzero where `part` is): the
    /// same numbers, without building its kernels, plans and part weights again (the judge's
    /// bootstrap replicates share one). Throws std::invalid_argument for another part or size.
    BandContrast(std::span<const double> Ya, std::span<const double> Yb,
                 std::span<const uint8_t> part, double white, const ViewingModel& view,
                 const BandFilterBank& bank);

    /// The JND of `region` (nonzero pixels) over the defect-free surface `clean`.
    JndScore score(std::span<const uint8_t> region, std::span<const uint8_t> clean) const;

    /// The band's peak frequency in cycles/degree.
    double bandFrequency(int k) const;

  private:
    int width_, height_;
    ViewingModel view_;
    double luminance_ = 0;
    std::vector<std::vector<double>> productAB_;  // c_k,a · c_k,b per band (0 off the part)
};

}  // namespace sl
