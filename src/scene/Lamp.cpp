#include "scene/Lamp.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <utility>

#include "core/Dual.h"
#include "core/Error.h"
#include "core/Registry.h"

namespace sl {

namespace {

constexpr LampKindRow kLampKinds[] = {
    {LampKind::Disk, "disk", "a round source: a spot (small) or a dome (large)"},
    {LampKind::Bar, "bar", "a rectangular line light (low-angle dark field), with a roll"},
    {LampKind::Ring, "ring", "a band of elevations all around the part (ring light)"},
};

constexpr double kPi = std::numbers::pi;
constexpr double kReach = 6.5;  // cells farther than kReach·h beyond the lamp are skipped

/// Gauss–Legendre nodes and weights on [0, 1] (weights sum to 1).
void gaussLegendre(int n, std::vector<double>& x, std::vector<double>& w) {
    x.assign(static_cast<size_t>(n), 0.0);
    w.assign(static_cast<size_t>(n), 0.0);
    // P_n(z) by the three-term recurrence, and its derivative P_n'(z).
    auto legendre = [n](double z) {
        double p0 = 1, p1 = z;
        for (int k = 2; k <= n; ++k) {
            const double p2 = ((2.0 * k - 1) * z * p1 - (k - 1.0) * p0) / k;
            p0 = p1;
            p1 = p2;
        }
        return std::pair{p1, n * (z * p1 - p0) / (z * z - 1)};
    };
    for (int i = 0; i < n; ++i) {
        double z = std::cos(kPi * (i + 0.75) / (n + 0.5));  // Newton from Tricomi's guess
        for (int it = 0; it < 100; ++it) {
            const auto [p, dp] = legendre(z);
            const double dz = p / dp;
            z -= dz;
            if (std::abs(dz) < 1e-16) break;
        }
        const double dp = legendre(z).second;
        x[static_cast<size_t>(i)] = 0.5 * (1 - z);
        w[static_cast<size_t>(i)] = 1.0 / ((1 - z * z) * dp * dp);  // 2/((1−z²)P'²) · ½
    }
}

constexpr double kTail = 5.8;  // S is cut to 0 / 1 beyond ±kTail (erfc(5.8)/2 = 1.2e-16)

/// S(t) = ½(1 + erf t) and S'(t) = exp(−t²)/√π on [−kTail, kTail] by Taylor polynomials about
/// the nearest node of a grid of spacing δ = 1/64 (lamp_detail::tabulatedStep): S^(k) at each
/// node, k = 0..6, are S, then S^(k) = (−1)^(k−1) H_(k−1)(t) S'(t) (H the physicists' Hermite
/// polynomials), computed once with std::erfc and std::exp.
struct StepTable {
    static constexpr int kPerUnit = 64;
    static constexpr int kNodes = static_cast<int>(2 * kTail * kPerUnit) + 2;
    std::vector<std::array<double, 7>> c;  // S^(k)(t_n) / k!

    StepTable() : c(static_cast<size_t>(kNodes)) {
        constexpr double kInvSqrtPi = 0.5641895835477562869;
        for (int n = 0; n < kNodes; ++n) {
            const double t = -kTail + static_cast<double>(n) / kPerUnit;
            const double g = kInvSqrtPi * std::exp(-t * t);
            double hm = 1, h = 2 * t;  // H_0, H_1
            std::array<double, 7>& a = c[static_cast<size_t>(n)];
            a[0] = t < 0 ? 0.5 * std::erfc(-t) : 1 - 0.5 * std::erfc(t);
            a[1] = g;
            double factorial = 1, sign = -1;
            for (int k = 2; k <= 6; ++k) {
                factorial *= k;
                a[static_cast<size_t>(k)] = sign * h * g / factorial;  // H_(k−1) S' / k!
                const double next = 2 * t * h - 2 * (k - 1) * hm;      // H_k
                hm = h;
                h = next;
                sign = -sign;
            }
        }
    }
    void eval(double t, double& s, double& ds) const {
        const double x = (t + kTail) * kPerUnit;
        const auto n = static_cast<size_t>(x + 0.5);
        const double u = t - (-kTail + static_cast<double>(n) / kPerUnit);
        const double* a = c[n].data();
        s = a[0] + u * (a[1] + u * (a[2] + u * (a[3] + u * (a[4] + u * (a[5] + u * a[6])))));
        ds =
            a[1] + u * (2 * a[2] + u * (3 * a[3] + u * (4 * a[4] + u * (5 * a[5] + u * 6 * a[6]))));
    }
};

const StepTable& stepTable() {
    static const StepTable table;
    return table;
}

/// S(t) with its tails cut where they are below 1.2e-16 (no erf there).
double stepFast(double t) {
    if (t < -kTail) return 0.0;
    if (t > kTail) return 1.0;
    double s, ds;
    stepTable().eval(t, s, ds);
    return s;
}

/// The lamp's membership as membership<double>, with early outs far from the edges (the hot
/// loop: most nodes of a touched cell are well inside or outside).
struct QuickMembership {
    LampKind kind;
    lamp_detail::Frame<double> f;
    double h, cosR = 0, hSinR = 1, sinYLimit = 2, a = 0, b = 0, lo = 0, hi = 0;

    QuickMembership(const Lamp& l, double edge)
        : kind(l.kind),
          f(lamp_detail::frame<double>(l.azimuth, l.elevation, l.roll)),
          h(edge),
          a(l.size),
          b(l.width),
          lo(l.elevation - l.size),
          hi(l.elevation + l.size) {
        cosR = std::cos(l.size);
        hSinR = edge * std::sin(l.size);
        const double yMax = l.width + kTail * edge;
        sinYLimit = yMax < std::numbers::pi / 2 ? std::sin(yMax) : 2.0;
    }
    double operator()(const Vec3d& d, double elevation) const {
        switch (kind) {
            case LampKind::Disk:
                return stepFast((lamp_detail::dotd(f.c, d) - cosR) / hSinR);
            case LampKind::Bar: {
                const double r = lamp_detail::dotd(f.e2, d);
                if (std::abs(r) >= sinYLimit) return 0.0;
                const double y = std::asin(r);
                const double sy = stepFast((b - y) / h) * stepFast((b + y) / h);
                if (sy == 0) return 0.0;
                const double x = std::atan2(lamp_detail::dotd(f.e1, d), lamp_detail::dotd(f.c, d));
                return sy * stepFast((a - x) / h) * stepFast((a + x) / h);
            }
            case LampKind::Ring:
                return stepFast((elevation - lo) / h) - stepFast((elevation - hi) / h);
        }
        return 0.0;
    }
};

/// The membership's value and its five derivatives ∂m/∂(φ, ε, a, b, ρ) at a node, written out
/// by hand (the chain rule through S' (t) = exp(−t²)/√π and the frame's derivatives), with
/// the same early outs as QuickMembership: the hot loop of a lamp fit. It equals
/// membership<Dual<5>> to rounding (tests/test_lamps.cpp); S' is cut where S is (|t| > kTail),
/// as the Dual step is.
struct NodeDerivatives {
    LampKind kind;
    double h, a, b, lo, hi, cosA, sinA, hSinA, cotA, sinYLimit;
    lamp_detail::Frame<double> f;
    // Reciprocals (a multiply where a division stalled the loop), and a bar's reach along its
    // axis as the tangent of |x| beyond which both its x factors are 0 (−1: no such limit).
    double invH, invHSinA, tanXLimit;
    // ∂c, ∂e1, ∂e2 by (φ, ε, ρ) (vectors), from frame<Dual<3>>.
    double dc[3][3], de1[3][3], de2[3][3];
    // The step's table, held (no static guard checked at every node).
    const StepTable& table = stepTable();

    NodeDerivatives(const Lamp& l, double edge)
        : kind(l.kind),
          h(edge),
          a(l.size),
          b(l.width),
          lo(l.elevation - l.size),
          hi(l.elevation + l.size),
          cosA(std::cos(l.size)),
          sinA(std::sin(l.size)),
          hSinA(edge * std::sin(l.size)),
          cotA(std::cos(l.size) / std::sin(l.size)),
          sinYLimit(l.width + kTail * edge < kPi / 2 ? std::sin(l.width + kTail * edge) : 2.0),
          f(lamp_detail::frame<double>(l.azimuth, l.elevation, l.roll)),
          invH(1 / edge),
          invHSinA(1 / (edge * std::sin(l.size))),
          tanXLimit(l.size + kTail * edge < kPi / 2 ? std::tan(l.size + kTail * edge) : -1.0) {
        using D3 = Dual<3>;
        const auto fd = lamp_detail::frame<D3>(
            D3::variable(l.azimuth, 0), D3::variable(l.elevation, 1), D3::variable(l.roll, 2));
        for (size_t p = 0; p < 3; ++p)
            for (int k = 0; k < 3; ++k) {
                dc[p][k] = fd.c[k].d[p];
                de1[p][k] = fd.e1[k].d[p];
                de2[p][k] = fd.e2[k].d[p];
            }
    }
    static double dot3(const double v[3], const Vec3d& d) {
        return v[0] * d.x + v[1] * d.y + v[2] * d.z;
    }
    /// S and S' at t (0 beyond the tails, as stepFast).
    void stepAndSlope(double t, double& s, double& ds) const {
        if (t < -kTail) {
            s = 0;
            ds = 0;
        } else if (t > kTail) {
            s = 1;
            ds = 0;
        } else {
            table.eval(t, s, ds);
        }
    }
    /// m and, into g, ∂m/∂(φ, ε, a, b, ρ) (zero where m is exactly 0 or 1).
    double operator()(const Vec3d& d, double elevation, double g[5]) const {
        switch (kind) {
            case LampKind::Disk: {
                const double t = (dot3(f.c, d) - cosA) * invHSinA;
                double s, ds;
                stepAndSlope(t, s, ds);
                const double k = ds * invHSinA;
                g[0] = k * dot3(dc[0], d);
                g[1] = k * dot3(dc[1], d);
                g[2] = ds * (invH - t * cotA);
                g[3] = 0;
                g[4] = k * dot3(dc[2], d);
                return s;
            }
            case LampKind::Bar: {
                const double r = dot3(f.e2, d);
                for (int k = 0; k < 5; ++k) g[k] = 0;
                if (std::abs(r) >= sinYLimit) return 0.0;  // across the bar, beyond its edge
                // Along the axis beyond a + kTail·h (|x| past atan of tanXLimit, or behind the
                // centre's hemisphere) both x factors and their slopes are 0: no atan2.
                const double p = dot3(f.e1, d), q = dot3(f.c, d);
                if (tanXLimit > 0 && (q <= 0 || std::abs(p) > q * tanXLimit)) return 0.0;
                const double y = std::asin(r);
                double sb1, db1, sb2, db2;
                stepAndSlope((b - y) * invH, sb1, db1);
                stepAndSlope((b + y) * invH, sb2, db2);
                const double sb = sb1 * sb2;
                if (sb == 0) return 0.0;
                const double x = std::atan2(p, q);
                double sa1, da1, sa2, da2;
                stepAndSlope((a - x) * invH, sa1, da1);
                stepAndSlope((a + x) * invH, sa2, da2);
                const double sa = sa1 * sa2;
                const double mx = (-da1 * sa2 + sa1 * da2) * sb * invH;
                const double my = sa * (-db1 * sb2 + sb1 * db2) * invH;
                const double invPq = 1 / (p * p + q * q), ry = 1 / std::sqrt(1 - r * r);
                double dm[3];
                for (int k = 0; k < 3; ++k) {
                    const double dx = (q * dot3(de1[k], d) - p * dot3(dc[k], d)) * invPq;
                    const double dy = dot3(de2[k], d) * ry;
                    dm[k] = mx * dx + my * dy;
                }
                g[0] = dm[0];
                g[1] = dm[1];
                g[2] = (da1 * sa2 + sa1 * da2) * sb * invH;
                g[3] = sa * (db1 * sb2 + sb1 * db2) * invH;
                g[4] = dm[2];
                return sa * sb;
            }
            case LampKind::Ring: {
                double s1, d1, s2, d2;
                stepAndSlope((elevation - lo) * invH, s1, d1);
                stepAndSlope((elevation - hi) * invH, s2, d2);
                g[0] = 0;
                g[1] = (-d1 + d2) * invH;
                g[2] = (d1 + d2) * invH;
                g[3] = 0;
                g[4] = 0;
                return s1 - s2;
            }
        }
        for (int k = 0; k < 5; ++k) g[k] = 0;
        return 0.0;
    }
};

}  // namespace

namespace lamp_detail {
void tabulatedStep(double t, double& s, double& ds) {
    if (t < -kTail || t > kTail) {
        s = t < 0 ? 0.0 : 1.0;
        ds = 0;
        return;
    }
    stepTable().eval(t, s, ds);
}
}  // namespace lamp_detail

std::span<const LampKindRow> lampKindTable() {
    return kLampKinds;
}

LampKind parseLampKind(std::string_view name, const std::string& where) {
    return parseRegistryName(lampKindTable(), name, where).value;
}

const char* lampKindName(LampKind kind) {
    return registryRow(lampKindTable(), kind).name;
}

bool lampUsesParam(LampKind kind, int p) {
    switch (kind) {
        case LampKind::Disk:
            return p <= kSize;
        case LampKind::Bar:
            return true;
        case LampKind::Ring:
            return p == kRadiance || p == kElevation || p == kSize;
    }
    return false;
}

Vec3d lampDirection(double azimuth, double elevation) {
    return {std::sin(azimuth) * std::cos(elevation), std::sin(elevation),
            -std::cos(azimuth) * std::cos(elevation)};
}

double lampSharpSolidAngle(const Lamp& lamp) {
    switch (lamp.kind) {
        case LampKind::Disk:
            return 2 * kPi * (1 - std::cos(lamp.size));
        case LampKind::Bar:
            return 2 * lamp.size * 2 * std::sin(lamp.width);
        case LampKind::Ring: {
            const double lo = std::max(lamp.elevation - lamp.size, -kPi / 2);
            const double hi = std::min(lamp.elevation + lamp.size, kPi / 2);
            return hi > lo ? 2 * kPi * (std::sin(hi) - std::sin(lo)) : 0.0;
        }
    }
    return 0;
}

LampRasterizer::LampRasterizer(const EnvMapBasis& basis, LampRasterOptions options)
    : basis_(basis), options_(options) {
    if (options.subsamples < 1 || options.subsamples > 64)
        throw inputError(option("lamp-subsamples"),
                         "must be between 1 and 64, not " + std::to_string(options.subsamples),
                         "use 12 (the default)");
    if (!(options.edge > 0) || options.edge > 0.2)
        throw inputError(option("lamp-edge"), "the edge width must be in (0, 0.2] radians",
                         "use 1 degree (the default)");
    const int W = basis.width(), H = basis.height(), N = options.subsamples;
    std::vector<double> x, w;
    gaussLegendre(N, x, w);
    n_ = N * N;
    std::vector<double> wxy(static_cast<size_t>(n_));
    for (int a = 0; a < N; ++a)
        for (int b = 0; b < N; ++b) {
            gx_.push_back(x[static_cast<size_t>(a)]);
            gy_.push_back(x[static_cast<size_t>(b)]);
            wxy[static_cast<size_t>(a * N + b)] =
                w[static_cast<size_t>(a)] * w[static_cast<size_t>(b)];
            const double fx = x[static_cast<size_t>(a)], fy = x[static_cast<size_t>(b)];
            for (double v : {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy})
                wt_.push_back(v);
        }
    const size_t cells = static_cast<size_t>(W) * (H - 1);
    dir_.resize(cells * n_);
    dw_.resize(cells * n_);
    elev_.resize(cells * n_);
    cellCentre_.resize(cells);
    cellRadius_.resize(cells);
    cellCosRadius_.resize(cells);
    cellSinRadius_.resize(cells);
    cellElLo_.resize(cells);
    cellElHi_.resize(cells);
    omega_.assign(static_cast<size_t>(W) * H, 0.0);
    const double cellArea = (kPi / (H - 1)) * (2 * kPi / W);
    for (int j = 0; j < H - 1; ++j)
        for (int i = 0; i < W; ++i) {
            const size_t cell = static_cast<size_t>(j) * W + i;
            const Vec3d centre = EnvMapBasis::uvToDirection((i + 1.0) / W, (j + 0.5) / (H - 1));
            cellCentre_[cell] = centre;
            // The cell's radius: the largest angle from its centre to a corner, an edge's middle
            // or a node, as the acos of the smallest cosine (one acos a cell, not one a node).
            double minCos = 1;
            for (double fy : {0.0, 1.0})
                for (double fx : {0.0, 0.5, 1.0})
                    minCos =
                        std::min(minCos, dot(centre, EnvMapBasis::uvToDirection(
                                                         (i + 0.5 + fx) / W, (j + fy) / (H - 1))));
            cellElHi_[cell] = kPi / 2 - kPi * j / (H - 1);
            cellElLo_[cell] = kPi / 2 - kPi * (j + 1) / (H - 1);
            const uint32_t t00 = static_cast<uint32_t>(j * W + i),
                           t01 = static_cast<uint32_t>(j * W + (i + 1) % W);
            const uint32_t t10 = t00 + static_cast<uint32_t>(W),
                           t11 = t01 + static_cast<uint32_t>(W);
            for (int s = 0; s < n_; ++s) {
                const double fx = gx_[static_cast<size_t>(s)], fy = gy_[static_cast<size_t>(s)];
                const double v = (j + fy) / (H - 1);
                const Vec3d d = EnvMapBasis::uvToDirection((i + 0.5 + fx) / W, v);
                minCos = std::min(minCos, dot(centre, d));
                const double dw = std::sin(kPi * v) * cellArea * wxy[static_cast<size_t>(s)];
                dir_[cell * n_ + s] = d;
                elev_[cell * n_ + s] = std::asin(std::clamp(d.y, -1.0, 1.0));
                dw_[cell * n_ + s] = dw;
                omega_[t00] += (1 - fx) * (1 - fy) * dw;
                omega_[t01] += fx * (1 - fy) * dw;
                omega_[t10] += (1 - fx) * fy * dw;
                omega_[t11] += fx * fy * dw;
            }
            const double radius = std::acos(std::clamp(minCos, -1.0, 1.0));
            cellRadius_[cell] = radius;
            cellCosRadius_[cell] = std::cos(radius);
            cellSinRadius_[cell] = std::sin(radius);
        }
}

LampRasterizer::Reach LampRasterizer::reach(const Lamp& lamp) const {
    const double margin = kReach * options_.edge;
    Reach r;
    switch (lamp.kind) {
        case LampKind::Disk:
            r.angle = lamp.size + margin;
            break;
        case LampKind::Bar: {
            r.angle = std::abs(lamp.size) + std::abs(lamp.width) + margin;
            if (!options_.cullBarCells) break;
            // A node is exactly 0 when |y| >= yMax (the early out on |d·e2| >= sin yMax), or
            // when |x| > xMax (x's factors and slopes are 0 beyond a + kTail·h); y = asin(d·e2)
            // is the signed angle to the great circle across e2, and asin(d·n±) that to the
            // meridian at x = ±xMax (d·n± = ±cos y sin(x ∓ xMax), n+ = −sin xMax c + cos xMax
            // e1, n− = −sin xMax c − cos xMax e1): both move by at most the angle moved, so a
            // cell whose centre is more than its radius beyond either holds no non-zero node.
            const auto f = lamp_detail::frame<double>(lamp.azimuth, lamp.elevation, lamp.roll);
            const Vec3d c{f.c[0], f.c[1], f.c[2]}, e1{f.e1[0], f.e1[1], f.e1[2]};
            r.e2 = {f.e2[0], f.e2[1], f.e2[2]};
            const double yMax = lamp.width + kTail * options_.edge;
            if (yMax > 0 && yMax < kPi / 2) {
                r.acrossCut = true;
                r.yMax = yMax;
                r.sinY = std::sin(yMax);
                r.cosY = std::cos(yMax);
            }
            const double xMax = lamp.size + kTail * options_.edge;
            if (lamp.size > 0 && xMax < kPi / 2) {
                r.alongCut = true;
                const double sx = std::sin(xMax), cx = std::cos(xMax);
                r.nPlus = c * (-sx) + e1 * cx;
                r.nMinus = c * (-sx) - e1 * cx;
            }
            break;
        }
        case LampKind::Ring:
            r.lo = lamp.elevation - lamp.size - margin;
            r.hi = lamp.elevation + lamp.size + margin;
            return r;
    }
    r.cosAngle = std::cos(r.angle);
    r.sinAngle = std::sin(r.angle);
    return r;
}

bool LampRasterizer::cellMayTouch(const Lamp& lamp, const Vec3d& centre, const Reach& reach,
                                  int cell) const {
    const size_t c = static_cast<size_t>(cell);
    if (lamp.kind == LampKind::Ring) return cellElHi_[c] >= reach.lo && cellElLo_[c] <= reach.hi;
    // The angle between the lamp's and the cell's centres is at most reach + the cell's
    // radius: cos(angle) >= cos(reach + radius), unless that sum passes π (every cell).
    if (reach.angle + cellRadius_[c] >= kPi) return true;
    if (dot(centre, cellCentre_[c]) <
        reach.cosAngle * cellCosRadius_[c] - reach.sinAngle * cellSinRadius_[c])
        return false;
    // A bar's cell beyond a cut great circle by more than its radius R (and a margin far above
    // rounding): sin(yMax + R) < |centre·e2|, or sin R < centre·n±.
    constexpr double kMargin = 1e-9;
    const Vec3d& cc = cellCentre_[c];
    const double cosR = cellCosRadius_[c], sinR = cellSinRadius_[c];
    if (reach.acrossCut && reach.yMax + cellRadius_[c] < kPi / 2 &&
        std::abs(dot(cc, reach.e2)) > reach.sinY * cosR + reach.cosY * sinR + kMargin)
        return false;
    if (reach.alongCut &&
        (dot(cc, reach.nPlus) > sinR + kMargin || dot(cc, reach.nMinus) > sinR + kMargin))
        return false;
    return true;
}

void LampRasterizer::coverage(const Lamp& lamp, std::vector<double>& c, std::vector<double>* dc,
                              bool byDual) const {
    using D = Dual<5>;
    const int W = basis_.width(), H = basis_.height();
    const double h = options_.edge;
    c.assign(static_cast<size_t>(W) * H, 0.0);
    if (dc) dc->assign(c.size() * 5, 0.0);
    const Vec3d centre = lampDirection(lamp.azimuth, lamp.elevation);
    const QuickMembership quick(lamp, h);
    const NodeDerivatives fast(lamp, h);
    const D az = D::variable(lamp.azimuth, 0), el = D::variable(lamp.elevation, 1),
            a = D::variable(lamp.size, 2), b = D::variable(lamp.width, 3),
            roll = D::variable(lamp.roll, 4);
    const auto fj = lamp_detail::frame<D>(az, el, roll);
    const Reach reach = this->reach(lamp);
    for (int j = 0; j < H - 1; ++j)
        for (int i = 0; i < W; ++i) {
            const int cell = j * W + i;
            if (!cellMayTouch(lamp, centre, reach, cell)) continue;
            const size_t t[4] = {static_cast<size_t>(j * W + i),
                                 static_cast<size_t>(j * W + (i + 1) % W),
                                 static_cast<size_t>((j + 1) * W + i),
                                 static_cast<size_t>((j + 1) * W + (i + 1) % W)};
            double cs[4] = {0, 0, 0, 0}, gs[4][5] = {};
            for (int s = 0; s < n_; ++s) {
                const size_t k = static_cast<size_t>(cell) * n_ + s;
                // With derivatives asked for, the hand-written ones give the value too (one erf
                // per factor for both).
                double g[5] = {0, 0, 0, 0, 0};
                const double mv =
                    dc && !byDual ? fast(dir_[k], elev_[k], g) : quick(dir_[k], elev_[k]);
                // Far outside (m < 1e-15) or deep inside (m > 1 − 1e-15) the edge the
                // derivatives are below 1e-13 of the edge's: the value alone.
                if (mv < 1e-15) continue;
                const double* wt = wt_.data() + static_cast<size_t>(s) * 4;
                if (!dc || mv > 1 - 1e-15) {
                    for (int q = 0; q < 4; ++q) cs[q] += wt[q] * dw_[k] * mv;
                    continue;
                }
                double m = mv;
                if (byDual) {
                    const D md = lamp_detail::membership<D>(lamp.kind, fj, el, a, b, dir_[k], h);
                    m = md.v;
                    for (size_t p = 0; p < 5; ++p) g[p] = md.d[p];
                }
                for (int q = 0; q < 4; ++q) {
                    const double f = wt[q] * dw_[k];
                    cs[q] += f * m;
                    for (size_t p = 0; p < 5; ++p) gs[q][p] += f * g[p];
                }
            }
            for (int q = 0; q < 4; ++q) {
                c[t[q]] += cs[q];
                if (dc)
                    for (size_t p = 0; p < 5; ++p) (*dc)[t[q] * 5 + p] += gs[q][p];
            }
        }
}

void LampRasterizer::add(const Lamp& lamp, std::span<double> E) const {
    std::vector<double> c;
    coverage(lamp, c, nullptr);
    for (size_t t = 0; t < c.size(); ++t) E[t] += lamp.radiance * c[t] / omega_[t];
}

std::vector<double> LampRasterizer::rasterize(std::span<const Lamp> lamps) const {
    std::vector<double> E(static_cast<size_t>(basis_.texelCount()), 0.0);
    for (const Lamp& l : lamps) add(l, E);
    return E;
}

void LampRasterizer::gradient(const Lamp& lamp, std::span<const double> dLdE,
                              std::span<double> dLdp, std::span<double> E) const {
    std::vector<double> c, dc;
    coverage(lamp, c, &dc);
    std::fill(dLdp.begin(), dLdp.end(), 0.0);
    for (size_t t = 0; t < c.size(); ++t) {
        const double g = dLdE[t] / omega_[t];
        if (!E.empty()) E[t] += lamp.radiance * c[t] / omega_[t];
        dLdp[0] += g * c[t];
        for (size_t p = 0; p < 5; ++p) dLdp[p + 1] += lamp.radiance * g * dc[t * 5 + p];
    }
}

void LampRasterizer::jacobian(const Lamp& lamp, std::span<double> J, std::span<double> E) const {
    jacobianOf(lamp, J, E, false);
}

void LampRasterizer::jacobianByDual(const Lamp& lamp, std::span<double> J,
                                    std::span<double> E) const {
    jacobianOf(lamp, J, E, true);
}

void LampRasterizer::jacobianOf(const Lamp& lamp, std::span<double> J, std::span<double> E,
                                bool byDual) const {
    std::vector<double> c, dc;
    coverage(lamp, c, &dc, byDual);
    for (size_t t = 0; t < c.size(); ++t) {
        E[t] = lamp.radiance * c[t] / omega_[t];
        J[t * kLampParams] = c[t] / omega_[t];
        for (size_t p = 0; p < 5; ++p)
            J[t * kLampParams + p + 1] = lamp.radiance * dc[t * 5 + p] / omega_[t];
    }
}

double LampRasterizer::solidAngle(const Lamp& lamp) const {
    std::vector<double> c;
    coverage(lamp, c, nullptr);
    double s = 0;
    for (double v : c) s += v;
    return s;
}

}  // namespace sl
