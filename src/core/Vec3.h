// Small 3-vector value type used for geometry and RGB throughputs.
#pragma once

#include <algorithm>
#include <cmath>

namespace sl {

template <typename T>
struct Vec3T {
    T x{}, y{}, z{};

    constexpr Vec3T() = default;
    constexpr Vec3T(T x_, T y_, T z_) : x(x_), y(y_), z(z_) {}
    constexpr explicit Vec3T(T s) : x(s), y(s), z(s) {}
    template <typename U>
    constexpr explicit Vec3T(const Vec3T<U>& o)
        : x(static_cast<T>(o.x)), y(static_cast<T>(o.y)), z(static_cast<T>(o.z)) {}

    constexpr T operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
    constexpr T& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }

    constexpr Vec3T operator+(const Vec3T& o) const { return {x + o.x, y + o.y, z + o.z}; }
    constexpr Vec3T operator-(const Vec3T& o) const { return {x - o.x, y - o.y, z - o.z}; }
    constexpr Vec3T operator*(const Vec3T& o) const { return {x * o.x, y * o.y, z * o.z}; }
    constexpr Vec3T operator/(const Vec3T& o) const { return {x / o.x, y / o.y, z / o.z}; }
    constexpr Vec3T operator*(T s) const { return {x * s, y * s, z * s}; }
    constexpr Vec3T operator/(T s) const { return {x / s, y / s, z / s}; }
    constexpr Vec3T operator-() const { return {-x, -y, -z}; }
    constexpr Vec3T& operator+=(const Vec3T& o) {
        x += o.x;
        y += o.y;
        z += o.z;
        return *this;
    }
    constexpr Vec3T& operator*=(const Vec3T& o) {
        x *= o.x;
        y *= o.y;
        z *= o.z;
        return *this;
    }
    constexpr Vec3T& operator*=(T s) {
        x *= s;
        y *= s;
        z *= s;
        return *this;
    }
    constexpr bool operator==(const Vec3T& o) const = default;
};

template <typename T>
constexpr Vec3T<T> operator*(T s, const Vec3T<T>& v) {
    return v * s;
}
template <typename T>
constexpr T dot(const Vec3T<T>& a, const Vec3T<T>& b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
template <typename T>
constexpr Vec3T<T> cross(const Vec3T<T>& a, const Vec3T<T>& b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <typename T>
inline T length(const Vec3T<T>& v) {
    return std::sqrt(dot(v, v));
}
template <typename T>
inline Vec3T<T> normalize(const Vec3T<T>& v) {
    return v / length(v);
}
template <typename T>
constexpr T maxComponent(const Vec3T<T>& v) {
    return std::max(v.x, std::max(v.y, v.z));
}

using Vec3f = Vec3T<float>;
using Vec3d = Vec3T<double>;
/// Linear Rec.709 RGB (see core/Color.h for the colour conventions).
using Rgb = Vec3T<float>;

/// Orthonormal frame (s, t, n): local z is the normal. Local coordinates are
/// (dot(v,s), dot(v,t), dot(v,n)), as Mitsuba's Frame3f.
struct Frame {
    Vec3f s, t, n;
    Vec3f toLocal(const Vec3f& v) const { return {dot(v, s), dot(v, t), dot(v, n)}; }
    Vec3f toWorld(const Vec3f& v) const { return s * v.x + t * v.y + n * v.z; }
};

}  // namespace sl
