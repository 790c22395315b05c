#include "scene/Levelling.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>

#include "core/Error.h"
#include "core/PolynomialFit.h"

namespace sl {

namespace {

using Matrix = std::vector<double>;  // K×K row-major

struct Grid {
    const std::vector<float>& z;
    size_t w, h;
    const std::vector<uint8_t>& invalid;
    bool valid(size_t k) const { return invalid.empty() || !invalid[k]; }
};

std::string fixFor(const LevellingDesc& d) {
    return d.mode == LevellingDesc::Mode::Cylinder
               ? "use \"levelling\": \"plane\" (or \"none\") for this map"
               : "use a lower degree, or \"levelling\": \"none\"";
}

/// Polynomial of degree n (plane: 1) in the Legendre basis (core/PolynomialFit.h); returns the
/// coefficients.
std::vector<double> levelPolynomial(const Grid& g, std::vector<float>& z, int n,
                                    const std::string& where, const LevellingDesc& d) {
    const std::optional<PolynomialSurface> s = fitPolynomialSurface(g.z, g.w, g.h, n, g.invalid);
    if (!s)
        throw inputError(where,
                         "heightmap.levelling " + levellingName(d) +
                             ": the valid points do not determine the fit (too few, or all on "
                             "a line)",
                         fixFor(d));
    std::vector<double> f;
    for (size_t j = 0; j < g.h; ++j) {
        s->row(j, f);
        for (size_t i = 0; i < g.w; ++i) {
            float& zz = z[j * g.w + i];
            zz = static_cast<float>(static_cast<double>(zz) - f[i]);
        }
    }
    return s->coefficients;
}

/// Cylinder along `axis`; returns {a, c, R·σ, b}.
std::vector<double> levelCylinder(const Grid& g, std::vector<float>& z, double pitch, char axis,
                                  const std::string& where, const LevellingDesc& d) {
    const bool alongY = axis == 'y';  // axis along rows' direction: s = x (columns)
    const size_t ns = alongY ? g.w : g.h, nt = alongY ? g.h : g.w;
    const auto coord = [&](size_t i, size_t n) {
        return (static_cast<double>(i) - (static_cast<double>(n) - 1.0) / 2.0) * pitch;
    };
    // Per line across s (a column for axis y): the sums over its valid points.
    std::vector<double> n(ns, 0), st(ns, 0), stt(ns, 0), sz(ns, 0), szt(ns, 0), szz(ns, 0);
    for (size_t j = 0; j < g.h; ++j)
        for (size_t i = 0; i < g.w; ++i) {
            const size_t idx = j * g.w + i;
            if (!g.valid(idx)) continue;
            const size_t si = alongY ? i : j, ti = alongY ? j : i;
            const double t = coord(ti, nt), zv = g.z[idx];
            n[si] += 1;
            st[si] += t;
            stt[si] += t * t;
            sz[si] += zv;
            szt[si] += zv * t;
            szz[si] += zv * zv;
        }
    const auto fail = [&](const std::string& why) {
        throw inputError(where, "heightmap.levelling " + levellingName(d) + ": " + why, fixFor(d));
    };
    // Plane z = c + α·s + b·t for the slope b along the axis.
    {
        Matrix a(9, 0.0);
        std::vector<double> r(3, 0.0);
        for (size_t i = 0; i < ns; ++i) {
            if (n[i] == 0) continue;
            const double s = coord(i, ns);
            const double v[3] = {1.0, s, 0.0};
            (void)v;
            a[0] += n[i];
            a[1] += n[i] * s;
            a[2] += st[i];
            a[4] += n[i] * s * s;
            a[5] += s * st[i];
            a[8] += stt[i];
            r[0] += sz[i];
            r[1] += s * sz[i];
            r[2] += szt[i];
        }
        a[3] = a[1];
        a[6] = a[2];
        a[7] = a[5];
        if (!solveSpd(a, r, 3)) fail("the valid points do not determine a plane");
        // r[2] is b
        std::vector<double>& bInit = r;
        // Kåsa circle fit of the mean profile p(s) = (Σz − b·Σt)/n, weighted by n.
        Matrix k(9, 0.0);
        std::vector<double> rhs(3, 0.0);
        double pMean = 0.0, nTot = 0.0;
        for (size_t i = 0; i < ns; ++i) {
            if (n[i] == 0) continue;
            const double s = coord(i, ns), p = (sz[i] - bInit[2] * st[i]) / n[i];
            const double row[3] = {s, p, 1.0}, y = -(s * s + p * p);
            for (int u = 0; u < 3; ++u) {
                rhs[static_cast<size_t>(u)] += n[i] * row[u] * y;
                for (int v = 0; v < 3; ++v)
                    k[static_cast<size_t>(u * 3 + v)] += n[i] * row[u] * row[v];
            }
            pMean += n[i] * p;
            nTot += n[i];
        }
        pMean /= nTot;
        if (!solveSpd(k, rhs, 3))
            fail(
                "no circle fits the profile across the axis (too few lines of valid points, or a "
                "flat profile)");
        const double ca = -rhs[0] / 2, cc = -rhs[1] / 2, r2 = ca * ca + cc * cc - rhs[2];
        if (!(r2 > 0) || !std::isfinite(r2)) fail("no circle fits the profile across the axis");
        double R = std::sqrt(r2);
        const double sigma = cc < pMean ? 1.0 : -1.0;  // centre below the surface: convex
        double sMax = 0.0, sMin = 0.0;
        for (size_t i = 0; i < ns; ++i)
            if (n[i] > 0) {
                sMax = std::max(sMax, coord(i, ns));
                sMin = std::min(sMin, coord(i, ns));
            }
        // Levenberg–Marquardt on θ = (a, c, R, b) with vertical residuals.
        std::array<double, 4> th = {ca, cc, R, bInit[2]};
        const auto feasible = [&](const std::array<double, 4>& t) {
            return t[2] > 0 && std::abs(sMax - t[0]) < t[2] && std::abs(sMin - t[0]) < t[2];
        };
        const auto cost = [&](const std::array<double, 4>& t) {
            double c = 0.0;
            for (size_t i = 0; i < ns; ++i) {
                if (n[i] == 0) continue;
                const double s = coord(i, ns), q = std::sqrt(t[2] * t[2] - (s - t[0]) * (s - t[0]));
                const double f = t[1] + sigma * q;
                c += szz[i] - 2 * f * sz[i] - 2 * t[3] * szt[i] + n[i] * f * f +
                     2 * t[3] * f * st[i] + t[3] * t[3] * stt[i];
            }
            return c;
        };
        if (!feasible(th)) fail("the fitted circle is narrower than the map");
        double lambda = 1e-3, cur = cost(th);
        for (int it = 0; it < 200; ++it) {
            Matrix jtj(16, 0.0);
            std::vector<double> jtr(4, 0.0);
            for (size_t i = 0; i < ns; ++i) {
                if (n[i] == 0) continue;
                const double s = coord(i, ns), ds = s - th[0];
                const double q = std::sqrt(th[2] * th[2] - ds * ds);
                const double f = th[1] + sigma * q;
                const double gi[3] = {sigma * ds / q, 1.0, sigma * th[2] / q};  // ∂f/∂(a, c, R)
                const double rsum = sz[i] - n[i] * f - th[3] * st[i];           // Σ r
                const double rt = szt[i] - f * st[i] - th[3] * stt[i];          // Σ r·t
                for (int u = 0; u < 3; ++u) {
                    jtr[static_cast<size_t>(u)] += gi[u] * rsum;
                    for (int v = 0; v < 3; ++v)
                        jtj[static_cast<size_t>(u * 4 + v)] += n[i] * gi[u] * gi[v];
                    jtj[static_cast<size_t>(u * 4 + 3)] += gi[u] * st[i];
                }
                jtr[3] += rt;
                jtj[15] += stt[i];
            }
            for (int u = 0; u < 3; ++u)
                jtj[static_cast<size_t>(12 + u)] = jtj[static_cast<size_t>(u * 4 + 3)];
            bool improved = false;
            for (int tries = 0; tries < 30 && !improved; ++tries) {
                Matrix m = jtj;
                for (int u = 0; u < 4; ++u) m[static_cast<size_t>(u * 5)] *= 1.0 + lambda;
                std::vector<double> step = jtr;
                if (solveSpd(m, step, 4)) {
                    std::array<double, 4> next = th;
                    for (int u = 0; u < 4; ++u)
                        next[static_cast<size_t>(u)] += step[static_cast<size_t>(u)];
                    if (feasible(next)) {
                        const double c = cost(next);
                        if (c <= cur) {
                            const double gain = cur - c;
                            th = next;
                            cur = c;
                            lambda = std::max(lambda / 10, 1e-12);
                            improved = true;
                            if (gain <= 1e-14 * std::max(cur, 1e-300)) it = 1000;  // converged
                            break;
                        }
                    }
                }
                lambda *= 10;
            }
            if (!improved) break;
        }
        R = th[2];
        // Subtract the form from every point.
        for (size_t j = 0; j < g.h; ++j)
            for (size_t i = 0; i < g.w; ++i) {
                const size_t si = alongY ? i : j, ti = alongY ? j : i;
                const double s = coord(si, ns), t = coord(ti, nt), ds = s - th[0];
                const double q = std::sqrt(std::max(0.0, R * R - ds * ds));
                float& zz = z[j * g.w + i];
                zz = static_cast<float>(static_cast<double>(zz) - (th[1] + sigma * q + th[3] * t));
            }
        return {th[0], th[1], sigma * R, th[3]};
    }
}

std::string groupDigits(size_t v) {
    std::string s = std::to_string(v), out;
    for (size_t i = 0; i < s.size(); ++i) {
        if (i > 0 && (s.size() - i) % 3 == 0) out += ' ';
        out += s[i];
    }
    return out;
}

}  // namespace

std::string levellingName(const LevellingDesc& d) {
    using M = LevellingDesc::Mode;
    switch (d.mode) {
        case M::Auto:
            return "auto";
        case M::None:
            return "none";
        case M::Plane:
            return "plane";
        case M::Polynomial:
            return "polynomial degree " + std::to_string(d.degree);
        case M::Cylinder:
            return std::string("cylinder along ") + d.axis;
    }
    return "?";
}

std::string LevellingResult::text() const {
    std::string t = levellingName(applied);
    if (automatic)
        t += applied.mode == LevellingDesc::Mode::None ? " (auto: heights as designed)"
                                                       : " (auto: a measured map)";
    if (applied.mode == LevellingDesc::Mode::None) return t;
    char b[160];
    std::snprintf(b, sizeof b, ": RMS %.4g -> %.4g over %s valid points", rmsBefore, rmsAfter,
                  groupDigits(points).c_str());
    t += b;
    if (applied.mode == LevellingDesc::Mode::Cylinder) {
        std::snprintf(b, sizeof b, ", radius %.4g (%s)", std::abs(radius),
                      radius >= 0 ? "convex" : "concave");
        t += b;
    }
    return t;
}

LevellingResult levelHeights(std::vector<float>& heights, int width, int height, double pitch,
                             const std::vector<uint8_t>& invalid, const LevellingDesc& desc,
                             bool measured, const std::string& where) {
    using M = LevellingDesc::Mode;
    LevellingResult res;
    res.applied = desc;
    if (desc.mode == M::Auto) {
        res.automatic = true;
        res.applied.mode = measured ? M::Plane : M::None;
    }
    if (res.applied.mode == M::Plane) res.applied.degree = 1;
    const Grid g{heights, static_cast<size_t>(width), static_cast<size_t>(height), invalid};
    const auto rms = [&] {
        double s = 0, s2 = 0;
        size_t n = 0;
        for (size_t k = 0; k < heights.size(); ++k)
            if (g.valid(k)) {
                s += heights[k];
                s2 += static_cast<double>(heights[k]) * heights[k];
                ++n;
            }
        res.points = n;
        if (n == 0) return 0.0;
        const double m = s / static_cast<double>(n);
        return std::sqrt(std::max(0.0, s2 / static_cast<double>(n) - m * m));
    };
    if (res.applied.mode == M::None) return res;
    res.rmsBefore = rms();
    switch (res.applied.mode) {
        case M::Plane:
        case M::Polynomial:
            res.coefficients = levelPolynomial(g, heights, res.applied.degree, where, res.applied);
            break;
        case M::Cylinder:
            res.coefficients =
                levelCylinder(g, heights, pitch, res.applied.axis, where, res.applied);
            res.radius = res.coefficients[2];
            break;
        default:
            break;
    }
    res.rmsAfter = rms();
    return res;
}

}  // namespace sl
