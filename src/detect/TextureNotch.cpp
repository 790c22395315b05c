#include "detect/TextureNotch.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "detect/ImageFilters.h"
#include "detect/Spectrum.h"

namespace sl::defectmap {

namespace {

/// Step 3's notch on the spectrum in place; returns the number of bins shrunk. With `wiener`
/// (the same size as s, zero-filled), each notched bin's F·(B²/|F|² − B/|F|) goes there: the
/// level's Wiener estimate minus the shrunk bin (header, step 4).
size_t notchTexture(Spectrum& s, const DefectMapOptions& o, Spectrum* wiener = nullptr) {
    const size_t n = s.bins.size();
    std::vector<float> mag(n);
    for (size_t k = 0; k < n; ++k) mag[k] = std::abs(s.bins[k]);
    // the background on the 2×2-pooled magnitude (windows halved): a quarter of the work
    int W2 = 0, H2 = 0;
    const std::vector<float> pooled = pool2(mag.data(), s.Wh, s.H, W2, H2);
    const int w = std::max(3, (o.spectrumWindow / 2) | 1);
    std::vector<float> medX(pooled.size()), medZ(pooled.size());
    rowMedians(pooled.data(), W2, H2, w, medX.data());
    columnMedians(pooled.data(), W2, H2, w, true, medZ.data());
    // the radial median: along the ray from DC through the cell, w cells centred on it (a
    // straight feature of the map puts its energy on such a ray, through DC)
    // Only where a bin could be notched: a bin with |F| <= notchGrow·max(med_x, med_z) is never
    // texture whatever med_r is (B only grows with it), so med_r is needed in the other cells
    // alone (the same result, a fraction of the work).
    std::vector<float> medR(pooled.size(), 0.0f);
    if (o.radial) {
        std::vector<uint8_t> needed(pooled.size(), 0);
        for (int y = 0; y < s.H; ++y)
            for (int kx = 0; kx < s.Wh; ++kx) {
                const size_t q = static_cast<size_t>(y / 2) * W2 + kx / 2;
                if (mag[static_cast<size_t>(y) * s.Wh + kx] >
                    o.notchGrow * std::max(medX[q], medZ[q]))
                    needed[q] = 1;
            }
        const int half = w / 2;
        tbb::parallel_for(0, H2, [&](int py) {
            thread_local std::vector<float> vals;
            const int y0 = 2 * py;
            const double kz = (y0 <= s.H / 2 ? y0 : y0 - s.H) + 0.5;
            for (int px = 0; px < W2; ++px) {
                if (!needed[static_cast<size_t>(py) * W2 + px]) continue;
                const double kx = 2.0 * px + 0.5, rho = std::hypot(kx, kz);
                const double ux = kx / rho, uz = kz / rho;
                vals.clear();
                for (int t = -half; t <= half; ++t) {
                    double qx = kx + 2.0 * t * ux, qz = kz + 2.0 * t * uz;
                    if (qx < 0) {  // Hermitian symmetry: |F(−k)| = |F(k)|
                        qx = -qx;
                        qz = -qz;
                    }
                    const int bx = static_cast<int>(qx), bz = static_cast<int>(std::floor(qz));
                    if (bx >= s.Wh || bz <= -s.H / 2 || bz > s.H / 2) continue;
                    const int yy = bz >= 0 ? bz : bz + s.H;
                    vals.push_back(pooled[static_cast<size_t>(yy / 2) * W2 + bx / 2]);
                }
                if (vals.empty()) continue;
                auto mid = vals.begin() + static_cast<std::ptrdiff_t>(vals.size() / 2);
                std::nth_element(vals.begin(), mid, vals.end());
                medR[static_cast<size_t>(py) * W2 + px] = *mid;
            }
        });
    }
    const double keep2 = static_cast<double>(o.keepLowBins) * o.keepLowBins;
    std::vector<float> b(n);
    std::vector<uint8_t> seed(n, 0), near(n, 0);
    for (int y = 0; y < s.H; ++y) {
        const int kz = y <= s.H / 2 ? y : y - s.H;
        for (int kx = 0; kx < s.Wh; ++kx) {
            const size_t k = static_cast<size_t>(y) * s.Wh + kx;
            const size_t q = static_cast<size_t>(y / 2) * W2 + kx / 2;
            b[k] = std::max({medX[q], medZ[q], medR[q]});
            const bool low = static_cast<double>(kx) * kx + static_cast<double>(kz) * kz <= keep2;
            seed[k] = !low && mag[k] > o.notchRatio * b[k];
        }
    }
    // bins within notchSpread of a seed (box; periodic along k_z, clamped along k_x)
    const int r = o.notchSpread;
    tbb::parallel_for(0, s.H, [&](int y) {
        const size_t off = static_cast<size_t>(y) * s.Wh;
        int count = 0;
        for (int kx = 0; kx <= std::min(r, s.Wh - 1); ++kx) count += seed[off + kx];
        for (int kx = 0; kx < s.Wh; ++kx) {
            if (kx > 0) {
                if (kx - 1 - r >= 0) count -= seed[off + kx - 1 - r];
                if (kx + r < s.Wh) count += seed[off + kx + r];
            }
            near[off + kx] = count > 0;
        }
    });
    std::vector<uint8_t> near2(n, 0);
    tbb::parallel_for(0, s.Wh, [&](int kx) {
        for (int y = 0; y < s.H; ++y) {
            bool any = false;
            for (int d = -r; d <= r && !any; ++d)
                any = near[static_cast<size_t>(((y + d) % s.H + s.H) % s.H) * s.Wh + kx] != 0;
            near2[static_cast<size_t>(y) * s.Wh + kx] = any;
        }
    });
    size_t notched = 0;
    for (int y = 0; y < s.H; ++y) {
        const int kz = y <= s.H / 2 ? y : y - s.H;
        for (int kx = 0; kx < s.Wh; ++kx) {
            const size_t k = static_cast<size_t>(y) * s.Wh + kx;
            if (static_cast<double>(kx) * kx + static_cast<double>(kz) * kz <= keep2) continue;
            if (seed[k] || (near2[k] && mag[k] > o.notchGrow * b[k])) {
                const float ratio = b[k] / mag[k];
                if (wiener) wiener->bins[k] = s.bins[k] * (ratio * ratio - ratio);
                s.bins[k] *= ratio;
                ++notched;
            }
        }
    }
    return notched;
}

/// The orientation sector (0 … sectors−1) of bin (kx, kz): sectors of π/sectors of the
/// wave-vector's orientation θ = atan2(kz, kx) ∈ [0, π), sector 0 centred on the k_x axis.
int sectorOf(int kx, int kz, int sectors) {
    constexpr double kPi = 3.14159265358979323846;
    double theta = std::atan2(static_cast<double>(kz), static_cast<double>(kx));
    if (theta < 0) theta += kPi;
    const double width = kPi / sectors;
    return static_cast<int>(std::floor(theta / width + 0.5)) % sectors;
}

/// The period (samples) of the bin of most gradient power |k|²·|F|² among periods below
/// maxPeriod, 0 when there is none: the ring model's pitch (step 4b). The weight keeps what the
/// macro median left at long wavelengths from outweighing the texture.
double dominantPeriod(const Spectrum& s, double maxPeriod) {
    double best = -1.0, period = 0.0;
    for (int y = 0; y < s.H; ++y) {
        const int kz = y <= s.H / 2 ? y : y - s.H;
        for (int kx = 0; kx < s.Wh; ++kx) {
            const double fx = static_cast<double>(kx) / s.W, fz = static_cast<double>(kz) / s.H;
            const double fr = std::hypot(fx, fz);
            if (!(fr * maxPeriod > 1.0)) continue;
            const double m = fr * fr * std::norm(s.bins[static_cast<size_t>(y) * s.Wh + kx]);
            if (m > best) {
                best = m;
                period = 1.0 / fr;
            }
        }
    }
    return period;
}

/// One notch pass: the periodic texture of d (W×H). With `sectorsOut`, also the texture split
/// by the orientation of its wave-vector into textureSectors parts (their sum is the texture);
/// with `periodOut`, d's dominantPeriod below macroWindow/2 (from the same spectrum); with
/// `levelDeltaOut` (and levelWiener), the level's Wiener residual minus d − texture (step 4).
/// `stats`: the notch's statistics.
std::vector<float> notchPass(const std::vector<float>& d, int W, int H, const DefectMapOptions& o,
                             NotchStats& stats, std::vector<std::vector<float>>* sectorsOut,
                             double* periodOut, std::vector<float>* levelDeltaOut) {
    const Padded p = padMap(d, W, H, o.pad, 0.0);
    Spectrum s = forward(p);
    if (periodOut) *periodOut = dominantPeriod(s, 0.5 * o.macroWindow);
    // the texture alone: the spectrum minus its shrunk version
    Spectrum kept = s;
    Spectrum wiener;
    const bool wantWiener = levelDeltaOut && o.levelWiener;
    if (wantWiener) {
        wiener.W = s.W;
        wiener.H = s.H;
        wiener.Wh = s.Wh;
        wiener.bins.assign(s.bins.size(), Complex(0.0f, 0.0f));
    }
    const size_t notched = notchTexture(kept, o, wantWiener ? &wiener : nullptr);
    if (wantWiener) {
        *levelDeltaOut = inverse(wiener, p, W, H);
        wiener = {};
    }
    for (size_t k = 0; k < s.bins.size(); ++k) s.bins[k] -= kept.bins[k];
    kept = {};
    stats.notchedBins = notched;
    stats.spectrumBins = s.bins.size();
    stats.fftWidth = p.W;
    stats.fftHeight = p.H;
    if (!sectorsOut || o.textureSectors < 2) return inverse(s, p, W, H);
    // sectors 0 … K−2 from their bins; the last is the texture minus them (one FFT fewer)
    sectorsOut->clear();
    for (int c = 0; c + 1 < o.textureSectors; ++c) {
        Spectrum part = s;
        for (int y = 0; y < s.H; ++y) {
            const int kz = y <= s.H / 2 ? y : y - s.H;
            for (int kx = 0; kx < s.Wh; ++kx)
                if ((kx != 0 || kz != 0 ? sectorOf(kx, kz, o.textureSectors) : 0) != c)
                    part.bins[static_cast<size_t>(y) * s.Wh + kx] = 0;
        }
        sectorsOut->push_back(inverse(part, p, W, H));
    }
    std::vector<float> texture = inverse(s, p, W, H);
    std::vector<float> last = texture;
    for (const std::vector<float>& t : *sectorsOut)
        for (size_t k = 0; k < last.size(); ++k) last[k] -= t[k];
    sectorsOut->push_back(std::move(last));
    return texture;
}

}  // namespace

TextureResidual textureResidual(std::span<const float> h, int W, int H, const DefectMapOptions& o,
                                TextureRequest request) {
    const size_t n = h.size();
    const int passes = request.passes > 0 ? request.passes : o.passes;
    TextureResidual res;
    std::vector<float> macro(h.begin(), h.end()), d(n), texture = std::move(request.prior);
    for (int pass = 0; pass < passes; ++pass) {
        // the macro shape: the separable running median of h minus the texture found so far
        if (!texture.empty())
            for (size_t k = 0; k < n; ++k) macro[k] = h[k] - texture[k];
        macro = separableMedian(macro, W, H, o.macroWindow);
        for (size_t k = 0; k < n; ++k) d[k] = h[k] - macro[k];
        const bool last = pass + 1 == passes;
        texture = notchPass(d, W, H, o, res.notch, last && request.sectors ? &res.sectors : nullptr,
                            last && request.period ? &res.period : nullptr,
                            last && request.levelDelta ? &res.levelDelta : nullptr);
    }
    if (request.texture) res.texture = texture;
    for (size_t k = 0; k < n; ++k) texture[k] = d[k] - texture[k];
    res.residual = std::move(texture);
    res.macro = std::move(macro);
    return res;
}

}  // namespace sl::defectmap
