// Small statistics for benchmark tables (medians over repeats or seeds).
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

namespace sl {

/// Median (mean of the two middle values for an even count); NaN for an empty sample.
inline double median(std::vector<double> v) {
    if (v.empty()) return std::nan("");
    std::sort(v.begin(), v.end());
    const size_t m = v.size() / 2;
    return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

}  // namespace sl
