#include "core/PolynomialFit.h"

#include <algorithm>
#include <cmath>

namespace sl {

namespace {

/// P_0..P_n at u (Legendre, by the three-term recurrence).
void legendre(double u, int n, double* out) {
    out[0] = 1.0;
    if (n >= 1) out[1] = u;
    for (int m = 2; m <= n; ++m)
        out[m] = ((2.0 * m - 1.0) * u * out[m - 1] - (m - 1.0) * out[m - 2]) / m;
}

/// Samples 0..n−1 scaled to [−1, 1] (all 0 for n = 1).
double unit(size_t i, size_t n) {
    return n < 2 ? 0.0 : 2.0 * static_cast<double>(i) / static_cast<double>(n - 1) - 1.0;
}

}  // namespace

bool solveSpd(std::vector<double> a, std::vector<double>& b, size_t k) {
    double scale = 0.0;
    for (size_t i = 0; i < k; ++i) scale = std::max(scale, std::abs(a[i * k + i]));
    if (!(scale > 0)) return false;
    for (size_t j = 0; j < k; ++j) {
        double d = a[j * k + j];
        for (size_t m = 0; m < j; ++m) d -= a[j * k + m] * a[j * k + m];
        if (!(d > 1e-13 * scale)) return false;
        const double l = std::sqrt(d);
        a[j * k + j] = l;
        for (size_t i = j + 1; i < k; ++i) {
            double s = a[i * k + j];
            for (size_t m = 0; m < j; ++m) s -= a[i * k + m] * a[j * k + m];
            a[i * k + j] = s / l;
        }
    }
    for (size_t i = 0; i < k; ++i) {  // L·y = b
        double s = b[i];
        for (size_t m = 0; m < i; ++m) s -= a[i * k + m] * b[m];
        b[i] = s / a[i * k + i];
    }
    for (size_t i = k; i-- > 0;) {  // Lᵀ·x = y
        double s = b[i];
        for (size_t m = i + 1; m < k; ++m) s -= a[m * k + i] * b[m];
        b[i] = s / a[i * k + i];
    }
    return true;
}

void PolynomialSurface::row(size_t j, std::vector<double>& out) const {
    const size_t np = static_cast<size_t>(degree) + 1;
    const double* q = &pv[j * np];
    // the fit along this row as a polynomial in u: Σ_a (Σ_b c_ab P_b(v)) P_a(u)
    std::vector<double> fu(np, 0.0);
    for (size_t r = 0; r < terms.size(); ++r)
        fu[static_cast<size_t>(terms[r][0])] +=
            coefficients[r] * q[static_cast<size_t>(terms[r][1])];
    out.resize(width);
    for (size_t i = 0; i < width; ++i) {
        const double* p = &pu[i * np];
        double f = 0.0;
        for (size_t a = 0; a < np; ++a) f += fu[a] * p[a];
        out[i] = f;
    }
}

std::optional<PolynomialSurface> fitPolynomialSurface(std::span<const float> z, size_t width,
                                                      size_t height, int degree,
                                                      std::span<const uint8_t> invalid) {
    if (width == 0 || height == 0 || z.size() != width * height ||
        (!invalid.empty() && invalid.size() != z.size()))
        return std::nullopt;
    PolynomialSurface s;
    s.degree = std::max(degree, 0);
    s.width = width;
    s.height = height;
    const int n = s.degree;
    // terms of a degree along an axis the axis' samples cannot tell from lower ones: left out
    const auto maxU = static_cast<int>(std::min<size_t>(static_cast<size_t>(n), width - 1));
    const auto maxV = static_cast<int>(std::min<size_t>(static_cast<size_t>(n), height - 1));
    for (int tot = 0; tot <= n; ++tot)
        for (int a = tot; a >= 0; --a)
            if (a <= maxU && tot - a <= maxV) s.terms.push_back({a, tot - a});
    const size_t k = s.terms.size();
    const size_t np = static_cast<size_t>(n) + 1;
    s.pu.resize(width * np);
    s.pv.resize(height * np);
    for (size_t i = 0; i < width; ++i) legendre(unit(i, width), n, &s.pu[i * np]);
    for (size_t j = 0; j < height; ++j) legendre(unit(j, height), n, &s.pv[j * np]);
    std::vector<double> ata(k * k, 0.0), atz(k, 0.0);
    // Per image row: the sums over its valid points of P_a(u)·P_c(u) (and ·z) are combined with
    // the row's P_b(v)·P_d(v), so the cost per point is (n+1)² not K².
    std::vector<double> su(np * np), sz(np);
    for (size_t j = 0; j < height; ++j) {
        std::fill(su.begin(), su.end(), 0.0);
        std::fill(sz.begin(), sz.end(), 0.0);
        bool any = false;
        for (size_t i = 0; i < width; ++i) {
            const size_t idx = j * width + i;
            if (!invalid.empty() && invalid[idx]) continue;
            any = true;
            const double* p = &s.pu[i * np];
            const double zv = z[idx];
            for (size_t a = 0; a < np; ++a) {
                sz[a] += p[a] * zv;
                for (size_t c = a; c < np; ++c) su[a * np + c] += p[a] * p[c];
            }
        }
        if (!any) continue;
        const double* q = &s.pv[j * np];
        for (size_t r = 0; r < k; ++r) {
            const auto a = static_cast<size_t>(s.terms[r][0]),
                       b = static_cast<size_t>(s.terms[r][1]);
            atz[r] += sz[a] * q[b];
            for (size_t c2 = r; c2 < k; ++c2) {
                const auto c = static_cast<size_t>(s.terms[c2][0]),
                           e = static_cast<size_t>(s.terms[c2][1]);
                const double uu = a <= c ? su[a * np + c] : su[c * np + a];
                ata[r * k + c2] += uu * q[b] * q[e];
            }
        }
    }
    for (size_t r = 0; r < k; ++r)
        for (size_t c = 0; c < r; ++c) ata[r * k + c] = ata[c * k + r];
    s.coefficients = atz;
    if (!solveSpd(ata, s.coefficients, k)) return std::nullopt;
    return s;
}

}  // namespace sl
