#include "core/WildBootstrap.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/Rng.h"

namespace sl {

double robustSpread(std::vector<double> v, int replicates) {
    std::erase_if(v, [](double x) { return !std::isfinite(x); });
    if (v.size() < 2 || 2 * v.size() < static_cast<size_t>(std::max(replicates, 0)))
        return std::numeric_limits<double>::quiet_NaN();
    auto median = [](std::vector<double>& x) {
        std::sort(x.begin(), x.end());
        const size_t m = x.size();
        return m % 2 ? x[m / 2] : 0.5 * (x[m / 2 - 1] + x[m / 2]);
    };
    const double m = median(v);
    for (double& x : v) x = std::abs(x - m);
    return 1.4826 * median(v);
}

std::vector<double> wildBootstrapErrors(std::span<const HalfImages> images, uint64_t seed,
                                        int replicates, const ReplicateScores& scores) {
    if (images.empty()) throw std::invalid_argument("wildBootstrapErrors: no image");
    const size_t n = images.front().a.size();
    for (const HalfImages& h : images)
        if (h.a.size() != n || h.b.size() != n)
            throw std::invalid_argument("wildBootstrapErrors: images of different sizes");
    // d_p/√2 per image and pixel.
    std::vector<std::vector<double>> d(images.size(), std::vector<double>(n));
    for (size_t k = 0; k < images.size(); ++k)
        for (size_t p = 0; p < n; ++p) d[k][p] = (images[k].a[p] - images[k].b[p]) * std::sqrt(0.5);
    std::vector<HalfImages> r(images.size(),
                              HalfImages{std::vector<double>(n), std::vector<double>(n)});
    std::vector<std::vector<double>> values;  // [score][replicate]
    for (int rep = 0; rep < replicates; ++rep) {
        Pcg32 rng(mix64(seed ^ 0x5345ULL), static_cast<uint64_t>(rep));
        for (size_t p = 0; p < n; ++p) {
            const uint32_t bits = rng.nextU32();
            const double sa = bits & 1u ? 1.0 : -1.0, sb = bits & 2u ? 1.0 : -1.0;
            for (size_t k = 0; k < images.size(); ++k) {
                r[k].a[p] = images[k].a[p] + sa * d[k][p];
                r[k].b[p] = images[k].b[p] + sb * d[k][p];
            }
        }
        const std::vector<double> s = scores(r);
        if (values.empty()) values.resize(s.size());
        if (s.size() != values.size())
            throw std::invalid_argument("wildBootstrapErrors: a replicate gave another count");
        for (size_t j = 0; j < s.size(); ++j) values[j].push_back(s[j]);
    }
    std::vector<double> se;
    se.reserve(values.size());
    for (std::vector<double>& v : values) se.push_back(robustSpread(std::move(v), replicates));
    return se;
}

}  // namespace sl
