// Dual<N>: a forward-mode dual number (a value and N partial derivatives), the few functions
// the lamps' membership needs (scene/Lamp.h). The same templates run with ceres::Jet in the
// tests, so the two differentiations check each other.
#pragma once

#include <array>
#include <cmath>
#include <numbers>

namespace sl {

template <int N>
struct Dual {
    double v = 0;
    std::array<double, N> d{};

    Dual() = default;
    Dual(double value) : v(value) {}  // NOLINT: a constant
    static Dual variable(double value, int i) {
        Dual x(value);
        x.d[static_cast<size_t>(i)] = 1;
        return x;
    }
};

namespace dual_detail {
template <int N>
Dual<N> scaled(double value, const Dual<N>& x, double k) {
    Dual<N> r(value);
    for (size_t i = 0; i < static_cast<size_t>(N); ++i) r.d[i] = k * x.d[i];
    return r;
}
}  // namespace dual_detail

template <int N>
Dual<N> operator+(const Dual<N>& a, const Dual<N>& b) {
    Dual<N> r(a.v + b.v);
    for (size_t i = 0; i < static_cast<size_t>(N); ++i) r.d[i] = a.d[i] + b.d[i];
    return r;
}
template <int N>
Dual<N> operator-(const Dual<N>& a, const Dual<N>& b) {
    Dual<N> r(a.v - b.v);
    for (size_t i = 0; i < static_cast<size_t>(N); ++i) r.d[i] = a.d[i] - b.d[i];
    return r;
}
template <int N>
Dual<N> operator-(const Dual<N>& a) {
    return dual_detail::scaled(-a.v, a, -1.0);
}
template <int N>
Dual<N> operator*(const Dual<N>& a, const Dual<N>& b) {
    Dual<N> r(a.v * b.v);
    for (size_t i = 0; i < static_cast<size_t>(N); ++i) r.d[i] = a.d[i] * b.v + a.v * b.d[i];
    return r;
}
template <int N>
Dual<N> operator/(const Dual<N>& a, const Dual<N>& b) {
    Dual<N> r(a.v / b.v);
    const double inv = 1.0 / b.v;
    for (size_t i = 0; i < static_cast<size_t>(N); ++i) r.d[i] = (a.d[i] - r.v * b.d[i]) * inv;
    return r;
}
template <int N>
Dual<N> operator+(const Dual<N>& a, double b) {
    Dual<N> r = a;
    r.v += b;
    return r;
}
template <int N>
Dual<N> operator+(double a, const Dual<N>& b) {
    return b + a;
}
template <int N>
Dual<N> operator-(const Dual<N>& a, double b) {
    return a + (-b);
}
template <int N>
Dual<N> operator-(double a, const Dual<N>& b) {
    return dual_detail::scaled(a - b.v, b, -1.0);
}
template <int N>
Dual<N> operator*(const Dual<N>& a, double b) {
    return dual_detail::scaled(a.v * b, a, b);
}
template <int N>
Dual<N> operator*(double a, const Dual<N>& b) {
    return b * a;
}
template <int N>
Dual<N> operator/(const Dual<N>& a, double b) {
    return a * (1.0 / b);
}
template <int N>
Dual<N> sin(const Dual<N>& x) {
    return dual_detail::scaled(std::sin(x.v), x, std::cos(x.v));
}
template <int N>
Dual<N> cos(const Dual<N>& x) {
    return dual_detail::scaled(std::cos(x.v), x, -std::sin(x.v));
}
template <int N>
Dual<N> asin(const Dual<N>& x) {
    return dual_detail::scaled(std::asin(x.v), x, 1.0 / std::sqrt(1.0 - x.v * x.v));
}
template <int N>
Dual<N> atan2(const Dual<N>& y, const Dual<N>& x) {
    const double r2 = x.v * x.v + y.v * y.v;
    Dual<N> r(std::atan2(y.v, x.v));
    for (size_t i = 0; i < static_cast<size_t>(N); ++i) r.d[i] = (x.v * y.d[i] - y.v * x.d[i]) / r2;
    return r;
}
template <int N>
Dual<N> erf(const Dual<N>& x) {
    return dual_detail::scaled(std::erf(x.v), x,
                               2.0 * std::numbers::inv_sqrtpi * std::exp(-x.v * x.v));
}

}  // namespace sl
