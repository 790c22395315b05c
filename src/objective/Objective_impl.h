// Implementation of ImageObjective::value<T> and the helpers it shares with Objective.cpp's
// double path (pair traversal, |x|), so both compute the same sums in the same order.
// Included at the end of objective/Objective.h; do not include it directly.
// The definitions (pair mask, borders, G floor, |0|, smooth |x|) are in Objective.cpp's header.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <type_traits>

namespace sl::detail {

/// Calls f(p, q) for every counted pair of pixels whose first pixel p lies in rows [y0, y1)
/// (default: all rows), in row-major order of p, the x-pair (p, p+1) before the y-pair
/// (p, p+width). A pair counts when both pixels lie in the image and both are inside the mask
/// (nonzero). The difference of a pair is Y[q] − Y[p].
template <typename F>
inline void forEachMaskedPair(int width, int height, const uint8_t* mask, F&& f, int y0 = 0,
                              int y1 = -1) {
    const size_t w = static_cast<size_t>(width);
    if (y1 < 0 || y1 > height) y1 = height;
    for (int y = y0; y < y1; ++y) {
        const size_t row = static_cast<size_t>(y) * w;
        for (int x = 0; x < width; ++x) {
            const size_t p = row + static_cast<size_t>(x);
            if (!mask[p]) continue;
            if (x + 1 < width && mask[p + 1]) f(p, p + 1);
            if (y + 1 < height && mask[p + w]) f(p, p + w);
        }
    }
}

/// The real part of a scalar: itself for arithmetic types, `.a` (recursively) for
/// ceres::Jet-like types, `.v` for core/Dual.h.
template <typename T>
inline double realPart(const T& x) {
    if constexpr (std::is_arithmetic_v<T>) {
        return static_cast<double>(x);
    } else if constexpr (requires { x.a; }) {
        return realPart(x.a);
    } else {
        return x.v;  // core/Dual.h
    }
}

/// |d| as the objective defines it. Non-smooth: d, −d or exactly 0 by the sign of the real
/// part (so a Jet's derivative at d = 0 is the sub-gradient 0). Smooth: sqrt(d² + ε²) − ε,
/// evaluated as d² / (sqrt(d² + ε²) + ε) (the same value, without cancellation near 0).
template <typename T>
inline T objectiveAbs(const T& d, bool smooth, double eps) {
    using std::abs;
    using std::sqrt;
    if (smooth) {
        const T d2 = d * d;
        return d2 / (sqrt(d2 + T(eps * eps)) + T(eps));
    }
    const double r = realPart(d);
    if (r == 0.0) return T(0.0);
    return abs(d);
}

/// Throws std::invalid_argument if any entry's real part is not finite.
template <typename T>
inline void checkFinite(std::span<const T> v, const char* name, const char* who) {
    for (size_t i = 0; i < v.size(); ++i) {
        if (!std::isfinite(realPart(v[i]))) {
            throw std::invalid_argument(std::string("ImageObjective::") + who + ": " + name + "[" +
                                        std::to_string(i) + "] is not finite (" +
                                        std::to_string(realPart(v[i])) + ")");
        }
    }
}

}  // namespace sl::detail

namespace sl {

template <typename T>
T ImageObjective::value(std::span<const T> Y, std::span<const T> E) const {
    checkSizes(Y.size(), E.size(), "value");
    detail::checkFinite(Y, "Y", "value");
    detail::checkFinite(E, "E", "value");

    T G(0.0);
    const bool smooth = opt_.smoothAbs;
    const double eps = opt_.smoothEps;
    detail::forEachMaskedPair(width_, height_, mask_.data(), [&](size_t p, size_t q) {
        G += detail::objectiveAbs<T>(Y[q] - Y[p], smooth, eps);
    });
    // Branch on the real part exactly as evaluate() does: below the floor L_grad is a constant.
    const T lGradT = detail::realPart(G) < gFloor() ? T(S_ / gFloor()) : T(S_) / G;

    T reg(0.0);
    if (opt_.reg == RegTarget::EnvMap) {
        for (const T& e : E) reg += e * e;
        reg /= T(static_cast<double>(E.size()));
    } else {
        for (const T& y : Y) reg += y * y;
        reg /= T(static_cast<double>(Y.size()));
    }
    const T total = lGradT + T(opt_.lambda) * reg;
    if (!std::isfinite(detail::realPart(total))) {
        throw std::range_error("ImageObjective::value: the loss is not finite (G = " +
                               std::to_string(detail::realPart(G)) +
                               "); are Y or E extremely large?");
    }
    return total;
}

}  // namespace sl
