#include "detect/ScratchMap.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "core/Error.h"
#include "core/Stopwatch.h"

namespace sl {

double ScratchMap::markedFraction() const {
    if (map.empty()) return 0.0;
    size_t n = 0;
    for (uint8_t v : map) n += v != 0;
    return static_cast<double>(n) / static_cast<double>(map.size());
}

namespace {

// Horizontal box sums of one row of (h − mean): out[i] = Σ_{c ∈ [i−lo, i+hi] ∩ [0, W)}.
void rowBoxSums(const float* row, int W, int lo, int hi, double mean, std::vector<double>& prefix,
                std::vector<double>& out) {
    prefix[0] = 0.0;
    for (int c = 0; c < W; ++c) prefix[c + 1] = prefix[c] + (static_cast<double>(row[c]) - mean);
    for (int i = 0; i < W; ++i) {
        int a = std::max(0, i - lo), b = std::min(W - 1, i + hi);
        out[i] = prefix[b + 1] - prefix[a];
    }
}

// The detrending pass (steps 1 of the header) for bands of `bandRows` rows, in parallel:
// fn(y, drow) receives each row's D values (W doubles) once; rows of one band in order.
template <typename Fn>
void forEachDetrendedRow(std::span<const float> heights, int W, int H, int kernel, int bandRows,
                         Fn&& fn) {
    const size_t n = static_cast<size_t>(W) * H;
    double sum = 0.0;
    for (size_t k = 0; k < n; ++k) {
        if (!std::isfinite(heights[k]))
            throw inputError("scratch map", "height at row " + std::to_string(k / W) + ", column " +
                                                std::to_string(k % W) + " is not finite");
        sum += heights[k];
    }
    const double mean = sum / static_cast<double>(n);
    const int lo = (kernel - 1) / 2, hi = kernel / 2;
    const int bands = (H + bandRows - 1) / bandRows;
    tbb::parallel_for(0, bands, [&](int band) {
        const int y0 = band * bandRows, y1 = std::min(H, y0 + bandRows);
        std::vector<double> prefix(W + 1), hrow(W), colSum(W, 0.0), cntX(W), drow(W);
        for (int i = 0; i < W; ++i)
            cntX[i] = static_cast<double>(std::min(W - 1, i + hi) - std::max(0, i - lo) + 1);
        auto addRow = [&](int row, double sign) {
            rowBoxSums(heights.data() + static_cast<size_t>(row) * W, W, lo, hi, mean, prefix,
                       hrow);
            for (int i = 0; i < W; ++i) colSum[i] += sign * hrow[i];
        };
        for (int row = std::max(0, y0 - lo); row <= std::min(H - 1, y0 + hi); ++row)
            addRow(row, 1.0);
        for (int y = y0; y < y1; ++y) {
            if (y > y0) {  // slide the window from y − 1 to y
                if (y - 1 - lo >= 0) addRow(y - 1 - lo, -1.0);
                if (y + hi < H) addRow(y + hi, 1.0);
            }
            const double cntY =
                static_cast<double>(std::min(H - 1, y + hi) - std::max(0, y - lo) + 1);
            const float* hr = heights.data() + static_cast<size_t>(y) * W;
            for (int i = 0; i < W; ++i)
                drow[i] = (static_cast<double>(hr[i]) - mean) - colSum[i] / (cntX[i] * cntY);
            fn(y, drow.data());
        }
    });
}

void checkOptions(const ScratchMapOptions& o) {
    if (o.kernel < 1)
        throw inputError(option("kernel"), "must be >= 1 (got " + std::to_string(o.kernel) + ")",
                         "The paper uses 21");
    if (o.patch < 1)
        throw inputError(option("patch"), "must be >= 1 (got " + std::to_string(o.patch) + ")",
                         "The paper uses 40");
    if (!(o.threshold >= 0.0 && o.threshold <= 1.0))
        throw inputError(option("threshold"),
                         "must be in [0, 1] (got " + std::to_string(o.threshold) + ")",
                         "It applies to the detrended map scaled to [0, 1]; the paper uses 0.03");
}

void checkSize(std::span<const float> heights, int width, int height) {
    if (width < 1 || height < 1)
        throw inputError("scratch map", "height map has no samples (" + std::to_string(width) +
                                            "x" + std::to_string(height) + ")");
    if (heights.size() != static_cast<size_t>(width) * height)
        throw inputError("scratch map", "height map has " + std::to_string(heights.size()) +
                                            " values, expected " + std::to_string(width) + "x" +
                                            std::to_string(height));
}

}  // namespace

std::vector<double> detrendHeights(std::span<const float> heights, int width, int height,
                                   int kernel) {
    checkOptions({kernel, 1, 0.0});
    checkSize(heights, width, height);
    std::vector<double> d(static_cast<size_t>(width) * height);
    forEachDetrendedRow(heights, width, height, kernel, 64, [&](int y, const double* row) {
        std::copy(row, row + width, d.begin() + static_cast<std::ptrdiff_t>(y) * width);
    });
    return d;
}

ScratchMap computeScratchMap(std::span<const float> heights, int width, int height,
                             const ScratchMapOptions& o) {
    const Stopwatch clock;
    checkOptions(o);
    checkSize(heights, width, height);
    const size_t n = static_cast<size_t>(width) * height;
    const int W = width, H = height, P = o.patch;
    ScratchMap r;
    r.width = W;
    r.height = H;
    r.patchesX = (W + P - 1) / P;
    r.patchesY = (H + P - 1) / P;
    const size_t tiles = static_cast<size_t>(r.patchesX) * r.patchesY;
    std::vector<double> tmin(tiles, std::numeric_limits<double>::infinity());
    std::vector<double> tmax(tiles, -std::numeric_limits<double>::infinity());
    // Bands of P rows: each band owns one row of tiles.
    forEachDetrendedRow(heights, W, H, o.kernel, P, [&](int y, const double* d) {
        double* mn = tmin.data() + static_cast<size_t>(y / P) * r.patchesX;
        double* mx = tmax.data() + static_cast<size_t>(y / P) * r.patchesX;
        for (int i = 0; i < W; ++i) {
            const int tx = i / P;
            mn[tx] = std::min(mn[tx], d[i]);
            mx[tx] = std::max(mx[tx], d[i]);
        }
    });

    r.detrendedMin = *std::min_element(tmin.begin(), tmin.end());
    r.detrendedMax = *std::max_element(tmax.begin(), tmax.end());
    const double range = r.detrendedMax - r.detrendedMin;
    r.map.assign(n, 0);
    if (range > 0.0) {
        for (int ty = 0; ty < r.patchesY; ++ty)
            for (int tx = 0; tx < r.patchesX; ++tx) {
                size_t t = static_cast<size_t>(ty) * r.patchesX + tx;
                if ((tmax[t] - tmin[t]) / range < o.threshold) continue;
                ++r.patchesMarked;
                for (int y = ty * P; y < std::min(H, ty * P + P); ++y)
                    std::fill_n(r.map.begin() + static_cast<std::ptrdiff_t>(y) * W + tx * P,
                                std::min(W, tx * P + P) - tx * P, uint8_t{255});
            }
    }
    r.seconds = clock.seconds();
    return r;
}

}  // namespace sl
