#include "detect/LineValleys.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "detect/Hysteresis.h"
#include "detect/ImageFilters.h"

namespace sl::defectmap {

namespace {

/// The mean of A over a digital segment through every sample, of direction (c, s): along the
/// major axis (x when |c| >= |s|) round(m·|major component|) samples to each side, the minor
/// coordinate following round(major·slope) (a sheared line: one running sum per line, O(1)
/// per sample). Samples past the map's edges are clamped to it.
void segmentMeans(const std::vector<float>& A, int W, int H, double c, double s, int m,
                  std::vector<float>& L) {
    const bool xMajor = std::abs(c) >= std::abs(s);
    const int Nm = xMajor ? W : H, Nn = xMajor ? H : W;  // major / minor lengths
    const size_t sm = xMajor ? 1 : static_cast<size_t>(W), sn = xMajor ? static_cast<size_t>(W) : 1;
    const double slope = xMajor ? s / c : c / s;
    const int half = static_cast<int>(std::lround(m * std::abs(xMajor ? c : s)));
    std::vector<int> r(static_cast<size_t>(Nm));
    for (int i = 0; i < Nm; ++i)
        r[static_cast<size_t>(i)] = static_cast<int>(std::lround(i * slope));
    const int rMin = std::min(r.front(), r.back()), rMax = std::max(r.front(), r.back());
    tbb::parallel_for(-rMax, Nn - rMin, [&](int line) {
        thread_local std::vector<double> prefix;
        prefix.assign(static_cast<size_t>(Nm + 2 * half + 1), 0.0);
        // values along the sheared line, the ends replicated `half` samples beyond the map
        for (int e = -half; e < Nm + half; ++e) {
            const int i = std::clamp(e, 0, Nm - 1);
            const int j = std::clamp(line + r[static_cast<size_t>(i)], 0, Nn - 1);
            prefix[static_cast<size_t>(e + half + 1)] =
                prefix[static_cast<size_t>(e + half)] + A[i * sm + static_cast<size_t>(j) * sn];
        }
        const double inv = 1.0 / (2 * half + 1);
        for (int i = 0; i < Nm; ++i) {
            const int j = line + r[static_cast<size_t>(i)];
            if (j < 0 || j >= Nn) continue;
            L[i * sm + static_cast<size_t>(j) * sn] = static_cast<float>(
                (prefix[static_cast<size_t>(i + 2 * half + 1)] - prefix[static_cast<size_t>(i)]) *
                inv);
        }
    });
}

}  // namespace

std::vector<uint8_t> lineValleyRegions(const std::vector<float>& A, int W, int H,
                                       const DefectMapOptions& o, double* seedUsed,
                                       const std::vector<uint8_t>* skip) {
    constexpr double kPi = 3.14159265358979323846;
    const size_t n = A.size();
    const int m = o.lineLength / 2;
    std::vector<float> L(n), V(n, -std::numeric_limits<float>::infinity());
    for (int k = 0; k < o.lineOrientations; ++k) {
        const double th = kPi * k / o.lineOrientations, c = std::cos(th), s = std::sin(th);
        segmentMeans(A, W, H, c, s, m, L);
        const int nx = static_cast<int>(std::lround(-s * o.lineOffset));
        const int ny = static_cast<int>(std::lround(c * o.lineOffset));
        auto side = [&](int x, int y, int sign) {
            const int xx = std::clamp(x + sign * nx, 0, W - 1);
            const int yy = std::clamp(y + sign * ny, 0, H - 1);
            return L[static_cast<size_t>(yy) * W + xx];
        };
        // σ_θ from both differences at a fixed stride (deterministic)
        std::vector<float> diffs;
        const size_t stride = std::max<size_t>(1, n / (size_t{1} << 17)) | 1;
        diffs.reserve(2 * (n / stride + 1));
        for (size_t q = 0; q < n; q += stride) {
            const int x = static_cast<int>(q % static_cast<size_t>(W));
            const int y = static_cast<int>(q / static_cast<size_t>(W));
            diffs.push_back(side(x, y, 1) - L[q]);
            diffs.push_back(side(x, y, -1) - L[q]);
        }
        const double sigma = 1.4826 * medianAbs(diffs);
        if (!(sigma > 0.0)) continue;
        tbb::parallel_for(0, H, [&](int y) {
            for (int x = 0; x < W; ++x) {
                const size_t q = static_cast<size_t>(y) * W + x;
                const float v = static_cast<float>(
                    std::min(side(x, y, 1) - L[q], side(x, y, -1) - L[q]) / sigma);
                V[q] = std::max(V[q], v);
            }
        });
    }
    L = {};
    tbb::parallel_for(0, H, [&](int y) {
        for (int x = 0; x < W; ++x) {
            const size_t q = static_cast<size_t>(y) * W + x;
            const bool inside = y >= o.border && y < H - o.border && x >= o.border &&
                                x < W - o.border && std::isfinite(V[q]);
            V[q] = inside ? std::max(V[q], 0.0f) : 0.0f;
        }
    });
    std::vector<uint8_t> regions(n, 0);
    const Thresholds t = tailThresholds(V, W, H, o, o.lineSeedSigma, o.lineGrowSigma, skip);
    if (seedUsed) *seedUsed = t.seed;
    hysteresis(V, W, H, t.seed, t.grow, 1, regions);
    for (uint8_t& v : regions) v = v != 0;
    return regions;
}

}  // namespace sl::defectmap
