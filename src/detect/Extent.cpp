#include "detect/Extent.h"

#include <cmath>

namespace sl {

void extentFromMoments(Extent& e, double cxx, double czz, double cxz) {
    constexpr double kPi = 3.14159265358979323846;
    cxx += 1.0 / 12.0;
    czz += 1.0 / 12.0;
    const double half = 0.5 * (cxx + czz),
                 root = std::sqrt(0.25 * (cxx - czz) * (cxx - czz) + cxz * cxz);
    e.elongation = std::sqrt((half + root) / (half - root));
    e.axis = 0.5 * std::atan2(2.0 * cxz, cxx - czz);
    if (e.axis < 0.0) e.axis += kPi;
}

Extent extentOf(std::span<const size_t> samples, int W) {
    Extent e;
    if (samples.empty()) return e;
    double sx = 0.0, sz = 0.0;
    for (const size_t i : samples) {
        sx += static_cast<double>(i % W);
        sz += static_cast<double>(i / W);
    }
    const double m = static_cast<double>(samples.size()), mx = sx / m, mz = sz / m;
    e.cx = mx;
    e.cz = mz;
    double cxx = 0.0, czz = 0.0, cxz = 0.0;
    for (const size_t i : samples) {
        const double dx = static_cast<double>(i % W) - mx, dz = static_cast<double>(i / W) - mz;
        cxx += dx * dx;
        czz += dz * dz;
        cxz += dx * dz;
    }
    extentFromMoments(e, cxx / m, czz / m, cxz / m);
    return e;
}

}  // namespace sl
