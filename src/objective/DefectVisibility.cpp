#include "objective/DefectVisibility.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

#include "perception/JndVisibility.h"

namespace sl {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// Max filter of radius r along one axis: `count` lines of `length` pixels, consecutive pixels
/// `step` apart, consecutive lines `lineStep` apart.
void maxAlong(const std::vector<uint8_t>& in, std::vector<uint8_t>& out, size_t count,
              size_t lineStep, int length, size_t step, int r) {
    for (size_t l = 0; l < count; ++l)
        for (int i = 0; i < length; ++i) {
            uint8_t m = 0;
            for (int d = std::max(0, i - r); d <= std::min(length - 1, i + r) && !m; ++d)
                m = in[l * lineStep + static_cast<size_t>(d) * step];
            out[l * lineStep + static_cast<size_t>(i) * step] = m;
        }
}

/// Chebyshev dilation of a binary image by r pixels (separable: rows, then columns).
std::vector<uint8_t> dilate(const std::vector<uint8_t>& in, int w, int h, int r) {
    std::vector<uint8_t> rows(in.size()), out(in.size());
    maxAlong(in, rows, static_cast<size_t>(h), static_cast<size_t>(w), w, 1, r);
    maxAlong(rows, out, static_cast<size_t>(w), 1, h, static_cast<size_t>(w), r);
    return out;
}

/// Mean of ΔY_a·ΔY_b over the x and y neighbour pairs with both pixels in `in`.
double meanGradientProduct(int w, int h, std::span<const double> Ya, std::span<const double> Yb,
                           const std::vector<uint8_t>& in) {
    double sum = 0;
    size_t pairs = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const size_t p = static_cast<size_t>(y) * w + x;
            if (!in[p]) continue;
            if (x + 1 < w && in[p + 1]) {
                sum += (Ya[p + 1] - Ya[p]) * (Yb[p + 1] - Yb[p]);
                ++pairs;
            }
            if (y + 1 < h && in[p + w]) {
                sum += (Ya[p + w] - Ya[p]) * (Yb[p + w] - Yb[p]);
                ++pairs;
            }
        }
    return pairs ? sum / static_cast<double>(pairs) : kNaN;
}

double meanOver(std::span<const double> Ya, std::span<const double> Yb,
                const std::vector<uint8_t>& in) {
    double sum = 0;
    size_t n = 0;
    for (size_t p = 0; p < in.size(); ++p)
        if (in[p]) {
            sum += 0.5 * (Ya[p] + Yb[p]);
            ++n;
        }
    return n ? sum / static_cast<double>(n) : kNaN;
}

double rms(double meanSquare) {
    return std::isnan(meanSquare) ? kNaN : std::sqrt(std::max(meanSquare, 0.0));
}

}  // namespace

std::vector<RegionVisibility> defectVisibility(int w, int h, std::span<const double> Ya,
                                               std::span<const double> Yb,
                                               std::span<const uint8_t> partMask,
                                               std::span<const uint8_t> labels,
                                               const std::vector<RegionLabel>& legend,
                                               std::span<const uint8_t> reference,
                                               const JndViewing* viewing) {
    const size_t n = static_cast<size_t>(w) * h;
    if (Ya.size() != n || Yb.size() != n || partMask.size() != n || labels.size() != n)
        throw std::invalid_argument("defectVisibility: image sizes differ");

    std::vector<RegionLabel> regions = legend;
    std::vector<uint8_t> any(n, 0);
    bool present[256] = {};
    for (size_t p = 0; p < n; ++p) {
        any[p] = labels[p] != 0;
        if (partMask[p] && labels[p]) present[labels[p]] = true;
    }
    for (int v = 1; v < 256; ++v) {
        const bool listed = std::any_of(regions.begin(), regions.end(),
                                        [&](const RegionLabel& r) { return r.value == v; });
        if (present[v] && !listed)
            regions.push_back({static_cast<uint8_t>(v), "label-" + std::to_string(v)});
    }

    const std::vector<uint8_t> near = dilate(any, w, h, kCleanMargin);
    std::vector<uint8_t> clean(n, 0);
    for (size_t p = 0; p < n; ++p)
        clean[p] = partMask[p] && !near[p] && (reference.empty() || reference[p]);
    const double cleanRms = rms(meanGradientProduct(w, h, Ya, Yb, clean));
    std::vector<uint8_t> part(n, 0);
    for (size_t p = 0; p < n; ++p) part[p] = partMask[p] != 0;
    const double partMean = meanOver(Ya, Yb, part);
    std::optional<BandContrast> bands;
    if (viewing && viewing->bank)
        bands.emplace(Ya, Yb, partMask, viewing->white, viewing->view, *viewing->bank);
    else if (viewing)
        bands.emplace(w, h, Ya, Yb, partMask, viewing->white, viewing->view);

    std::vector<RegionVisibility> out;
    for (const RegionLabel& r : regions) {
        RegionVisibility v;
        v.label = r;
        std::vector<uint8_t> in(n, 0);
        for (size_t p = 0; p < n; ++p) {
            in[p] = partMask[p] && labels[p] == r.value;
            v.pixels += in[p];
        }
        v.cleanRmsGradient = cleanRms;
        v.rmsGradient = rms(meanGradientProduct(w, h, Ya, Yb, in));
        v.visibility = cleanRms > 0 ? v.rmsGradient / cleanRms : kNaN;
        v.contrast = partMean > 0 ? v.rmsGradient / partMean : kNaN;
        const std::vector<uint8_t> ring = dilate(in, w, h, kWeberRing);
        std::vector<uint8_t> background(n, 0);
        for (size_t p = 0; p < n; ++p) background[p] = ring[p] && partMask[p] && !any[p];
        const double mIn = meanOver(Ya, Yb, in), mBg = meanOver(Ya, Yb, background);
        v.weber = mBg > 0 ? (mIn - mBg) / mBg : kNaN;
        if (bands && v.pixels > 0) {
            const JndScore j = bands->score(in, clean);
            v.jnd = j.jnd;
            v.jndFrequency = j.jnd > 0 ? j.frequency : kNaN;
            v.maskContrast = j.maskContrast;
            v.luminance = j.luminance;
        }
        out.push_back(v);
    }
    return out;
}

namespace {

/// sqrt(Σ pixels·x² / Σ pixels) of one field over the regions with pixels and a finite value.
double pooledRms(std::span<const RegionVisibility> regions, double RegionVisibility::*field) {
    double sum = 0, pixels = 0;
    for (const RegionVisibility& r : regions)
        if (std::isfinite(r.*field) && r.pixels > 0) {
            sum += static_cast<double>(r.pixels) * (r.*field) * (r.*field);
            pixels += static_cast<double>(r.pixels);
        }
    return pixels > 0 ? std::sqrt(sum / pixels) : kNaN;
}

}  // namespace

double combinedVisibility(std::span<const RegionVisibility> regions) {
    return pooledRms(regions, &RegionVisibility::visibility);
}

double combinedContrast(std::span<const RegionVisibility> regions) {
    return pooledRms(regions, &RegionVisibility::contrast);
}

double combinedJnd(std::span<const RegionVisibility> regions) {
    double sum = 0;
    bool any = false;
    for (const RegionVisibility& r : regions)
        if (std::isfinite(r.jnd) && r.pixels > 0) {
            sum += std::pow(r.jnd, kJndPooling);
            any = true;
        }
    return any ? std::pow(sum, 1.0 / kJndPooling) : kNaN;
}

double leastVisibleJnd(std::span<const RegionVisibility> regions, size_t* which) {
    double least = kNaN;
    for (size_t k = 0; k < regions.size(); ++k) {
        const RegionVisibility& r = regions[k];
        if (r.pixels == 0 || !std::isfinite(r.jnd) || r.jnd >= least) continue;
        least = r.jnd;
        if (which) *which = k;
    }
    return least;
}

}  // namespace sl
