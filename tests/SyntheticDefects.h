// Defects painted into a synthetic height map with exact truth, for the defect-map tests
// (test_laymap, test_selfsim): a paraboloid pit and a V groove on a width × height map.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace sl::test {

/// A paraboloid pit of radius rho and depth d at (cx, cy) on a width-wide map; its truth
/// (within the radius) set to 1 in t.
inline void paintPit(std::vector<float>& h, std::vector<uint8_t>& t, int width, double cx,
                     double cy, double rho, double d) {
    const int height = static_cast<int>(h.size() / static_cast<size_t>(width));
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const double q = std::hypot(x - cx, y - cy) / rho;
            if (q >= 1.0) continue;
            h[static_cast<size_t>(y) * width + x] -= static_cast<float>(d * (1 - q * q));
            t[static_cast<size_t>(y) * width + x] = 1;
        }
}

/// A V groove `grooveWidth` wide and `depth` deep along the segment (x0,y0)–(x1,y1) on a
/// width-wide map; its truth (where it is at least 10 % of its depth) set to 1 in t.
inline void paintGroove(std::vector<float>& h, std::vector<uint8_t>& t, int width, double x0,
                        double y0, double x1, double y1, double grooveWidth, double depth) {
    const int height = static_cast<int>(h.size() / static_cast<size_t>(width));
    const double dx = x1 - x0, dy = y1 - y0, len2 = dx * dx + dy * dy;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const double a = std::clamp(((x - x0) * dx + (y - y0) * dy) / len2, 0.0, 1.0);
            const double dist = std::hypot(x - (x0 + a * dx), y - (y0 + a * dy));
            const double v = 1.0 - 2.0 * dist / grooveWidth;
            if (v <= 0.0) continue;
            h[static_cast<size_t>(y) * width + x] -= static_cast<float>(depth * v);
            if (v >= 0.1) t[static_cast<size_t>(y) * width + x] = 1;
        }
}

}  // namespace sl::test
