// Dual<N>: a forward-mode dual number (a value and N partial derivatives), the few functions
// the lamps' membership (scene/Lamp.h) and the eye's sensitivity as a function of luminance
// (perception/ContrastSensitivity.h, for the JND objective's exact gradient) need. The same
// templates run with ceres::Jet in the tests, so the two differentiations check each other.
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
Dual<N> operator/(double a, const Dual<N>& b) {
    return dual_detail::scaled(a / b.v, b, -a / (b.v * b.v));
}
template <int N>
Dual<N>& operator+=(Dual<N>& a, const Dual<N>& b) {
    return a = a + b;
}
template <int N>
Dual<N>& operator-=(Dual<N>& a, const Dual<N>& b) {
    return a = a - b;
}
template <int N>
Dual<N>& operator*=(Dual<N>& a, const Dual<N>& b) {
    return a = a * b;
}
template <int N>
Dual<N>& operator/=(Dual<N>& a, const Dual<N>& b) {
    return a = a / b;
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

template <int N>
Dual<N> exp(const Dual<N>& x) {
    const double e = std::exp(x.v);
    return dual_detail::scaled(e, x, e);
}
template <int N>
Dual<N> log(const Dual<N>& x) {
    return dual_detail::scaled(std::log(x.v), x, 1.0 / x.v);
}
template <int N>
Dual<N> log10(const Dual<N>& x) {
    return dual_detail::scaled(std::log10(x.v), x, 1.0 / (x.v * std::numbers::ln10));
}
template <int N>
Dual<N> sqrt(const Dual<N>& x) {
    const double r = std::sqrt(x.v);
    return dual_detail::scaled(r, x, 0.5 / r);
}
template <int N>
Dual<N> tanh(const Dual<N>& x) {
    const double t = std::tanh(x.v);
    return dual_detail::scaled(t, x, 1.0 - t * t);
}

template <int N>
bool operator>(const Dual<N>& a, double b) {
    return a.v > b;
}
template <int N>
bool operator<(const Dual<N>& a, double b) {
    return a.v < b;
}

}  // namespace sl
