// Lamps rasterized into the env-map basis (scene/Lamp.h): the total weight Σ_t E_t Ω_t of a
// lamp of radiance R is R times its solid angle ∫ m dω, checked against 1-D integrals of the
// same membership and the sharp shapes' closed forms; smooth in its parameters (the analytic
// gradient against central differences and ceres::Jet, its hand-written derivatives against
// Dual numbers); the same anywhere (the pole, the
// azimuth seam, a turn by one texel is a shift by one column).
#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "core/Dual.h"
#include "core/Error.h"
#include "scene/Lamp.h"

namespace {

using namespace sl;
constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180;

double totalWeight(const LampRasterizer& r, const Lamp& lamp) {
    std::vector<double> E(static_cast<size_t>(r.basis().texelCount()), 0.0);
    r.add(lamp, E);
    double s = 0;
    for (size_t t = 0; t < E.size(); ++t) s += E[t] * r.texelSolidAngles()[t];
    return s / lamp.radiance;
}

/// ∫ f over [a, b] by composite Simpson with n (even) intervals.
template <class F>
double simpson(F f, double a, double b, int n = 200000) {
    const double h = (b - a) / n;
    double s = f(a) + f(b);
    for (int i = 1; i < n; ++i) s += f(a + i * h) * (i % 2 ? 4 : 2);
    return s * h / 3;
}

/// The exact solid angle of the smooth disk: 2π ∫_{-1}^{1} S((z − cos r)/k) dz, k = h sin r,
/// with ∫ S(t) dt = ½(t + t erf t + e^{−t²}/√π).
double smoothDiskSolidAngle(double r, double h) {
    const double k = h * std::sin(r);
    auto F = [](double t) {
        return 0.5 * (t + t * std::erf(t) + std::exp(-t * t) * std::numbers::inv_sqrtpi);
    };
    return 2 * kPi * k * (F((1 - std::cos(r)) / k) - F((-1 - std::cos(r)) / k));
}

TEST(LampRaster, TexelSolidAnglesPartitionTheSphere) {
    LampRasterizer r(EnvMapBasis(50, 25));
    double s = 0;
    for (double w : r.texelSolidAngles()) {
        EXPECT_GT(w, 0.0);
        s += w;
    }
    EXPECT_NEAR(s, 4 * kPi, 1e-12);
}

TEST(LampRaster, DiskWeightIsItsSolidAngleAnywhere) {
    LampRasterizer r(EnvMapBasis(50, 25));
    const double h = r.options().edge;
    // The pole, the image's seam (azimuth 180°), the bilinear wrap (u = ½ texel: 3.6°), the
    // horizon and below, a texel centre, a dome.
    const double places[][2] = {{0, 90}, {180, 30}, {3.6, 45}, {-179.9, 10},
                                {47, 0}, {90, -40}, {7.2, 60}, {0, 89.5}};
    for (double radius : {3.0, 10.0, 30.0, 85.0})
        for (const auto& p : places) {
            Lamp l;
            l.kind = LampKind::Disk;
            l.radiance = 0.7;
            l.azimuth = p[0] * kDeg;
            l.elevation = p[1] * kDeg;
            l.size = radius * kDeg;
            const double exact = smoothDiskSolidAngle(l.size, h);
            EXPECT_NEAR(totalWeight(r, l), exact, 1e-6 * exact)
                << "r " << radius << " at " << p[0] << "," << p[1];
            EXPECT_NEAR(r.solidAngle(l), exact, 1e-6 * exact);
            // The smooth edge is symmetric in cos(angle): the sharp cap's area, up to erfc tails.
            if (radius >= 10) {
                EXPECT_NEAR(exact, lampSharpSolidAngle(l), 1e-6 * exact);
            }
        }
}

TEST(LampRaster, RingWeightIsItsBandsSolidAngle) {
    LampRasterizer r(EnvMapBasis(50, 25));
    const double h = r.options().edge;
    for (const auto& band : {std::array<double, 2>{10, 5}, {45, 20}, {80, 9}, {-20, 30}}) {
        Lamp l;
        l.kind = LampKind::Ring;
        l.elevation = band[0] * kDeg;
        l.size = band[1] * kDeg;
        l.azimuth = 1.234;  // unused
        auto S = lamp_detail::smoothStep;
        const double exact = simpson(
            [&](double e) {
                return 2 * kPi * std::cos(e) *
                       (S((e - l.elevation + l.size) / h) - S((e - l.elevation - l.size) / h));
            },
            -kPi / 2, kPi / 2);
        EXPECT_NEAR(totalWeight(r, l), exact, 1e-6 * exact) << band[0] << "±" << band[1];
        EXPECT_NEAR(exact, lampSharpSolidAngle(l), 2e-3 * exact);
    }
}

TEST(LampRaster, BarWeightIsItsSolidAngle) {
    LampRasterizer r(EnvMapBasis(50, 25));
    const double h = r.options().edge;
    auto S = lamp_detail::smoothStep;
    const double cases[][5] = {// az, el, half-length, half-width, roll (degrees)
                               {30, 20, 25, 4, 0},
                               {180, 10, 40, 3, 0},
                               {0, 90, 20, 5, 30},
                               {-60, 45, 15, 8, 70},
                               {100, 5, 30, 2.5, -10}};
    for (const auto& c : cases) {
        Lamp l;
        l.kind = LampKind::Bar;
        l.azimuth = c[0] * kDeg;
        l.elevation = c[1] * kDeg;
        l.size = c[2] * kDeg;
        l.width = c[3] * kDeg;
        l.roll = c[4] * kDeg;
        // Separable in the bar's coordinates: dω = cos y dx dy.
        const double ix =
            simpson([&](double x) { return S((l.size - x) / h) * S((l.size + x) / h); }, -kPi, kPi);
        const double iy = simpson(
            [&](double y) { return std::cos(y) * S((l.width - y) / h) * S((l.width + y) / h); },
            -kPi / 2, kPi / 2);
        EXPECT_NEAR(totalWeight(r, l), ix * iy, 1e-6 * ix * iy) << c[0] << "," << c[1];
    }
}

TEST(LampRaster, TurningByOneTexelShiftsOneColumn) {
    const EnvMapBasis basis(50, 25);
    LampRasterizer r(basis);
    for (LampKind kind : {LampKind::Disk, LampKind::Bar}) {
        Lamp l;
        l.kind = kind;
        l.azimuth = 178 * kDeg;  // crosses the seam when turned
        l.elevation = 25 * kDeg;
        l.size = 12 * kDeg;
        l.width = 4 * kDeg;
        Lamp turned = l;
        turned.azimuth += 2 * kPi / basis.width();
        const auto a = r.rasterize(std::span<const Lamp>(&l, 1));
        const auto b = r.rasterize(std::span<const Lamp>(&turned, 1));
        const int W = basis.width();
        for (int j = 0; j < basis.height(); ++j)
            for (int i = 0; i < W; ++i)
                ASSERT_NEAR(b[static_cast<size_t>(j * W + (i + 1) % W)],
                            a[static_cast<size_t>(j * W + i)], 1e-12);
    }
}

TEST(LampRaster, ASmallDiskLightsTheTexelOfItsDirection) {
    // The lamp's direction convention is EnvMapBasis's: a disk centred on the direction of texel
    // (row, col) is brightest there, and EnvMapBasis::weights of its centre name that texel.
    const EnvMapBasis basis(50, 25);
    LampRasterizer r(basis);
    for (const auto& rc : {std::array<int, 2>{3, 0}, {8, 10}, {12, 49}, {20, 33}}) {
        const Vec3d d = basis.texelDirection(rc[0], rc[1]);
        Lamp l;
        l.azimuth = std::atan2(d.x, -d.z);
        l.elevation = std::asin(d.y);
        l.size = 4 * kDeg;
        const auto E = r.rasterize(std::span<const Lamp>(&l, 1));
        const auto best = std::max_element(E.begin(), E.end()) - E.begin();
        EXPECT_EQ(best, rc[0] * basis.width() + rc[1]) << rc[0] << "," << rc[1];
        const TexelWeights w = basis.weights(Vec3f(d));
        const auto k = std::max_element(w.weight.begin(), w.weight.end()) - w.weight.begin();
        EXPECT_EQ(static_cast<long>(w.index[static_cast<size_t>(k)]), best);
    }
}

/// g·E(lamp) for a fixed g.
double project(const LampRasterizer& r, const Lamp& l, const std::vector<double>& g) {
    const auto E = r.rasterize(std::span<const Lamp>(&l, 1));
    double s = 0;
    for (size_t t = 0; t < E.size(); ++t) s += g[t] * E[t];
    return s;
}

TEST(LampRaster, GradientMatchesFiniteDifferences) {
    const EnvMapBasis basis(50, 25);
    LampRasterizer r(basis);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> U(-1, 1);
    std::vector<double> g(static_cast<size_t>(basis.texelCount()));
    for (double& v : g) v = U(rng);
    const double cases[][6] = {{0.8, 30, 20, 12, 0, 0},   {0.5, 180, 40, 8, 0, 0},
                               {0.9, 0, 88, 15, 0, 0},    {0.6, 10, 15, 25, 4, 20},
                               {0.7, -170, 5, 30, 3, -5}, {0.4, 0, 35, 10, 0, 0}};
    const LampKind kinds[] = {LampKind::Disk, LampKind::Disk, LampKind::Disk,
                              LampKind::Bar,  LampKind::Bar,  LampKind::Ring};
    for (size_t c = 0; c < std::size(cases); ++c) {
        Lamp l;
        l.kind = kinds[c];
        std::array<double, kLampParams> p{};
        for (int k = 0; k < kLampParams; ++k)
            p[static_cast<size_t>(k)] = k == 0 ? cases[c][k] : cases[c][k] * kDeg;
        l.setParams(p);
        std::array<double, kLampParams> grad{};
        r.gradient(l, g, grad);
        double scale = 0;
        for (double v : grad) scale = std::max(scale, std::abs(v));
        for (int k = 0; k < kLampParams; ++k) {
            // Richardson-extrapolated central differences (error O(step⁴)).
            auto central = [&](double step) {
                auto q = p;
                q[static_cast<size_t>(k)] += step;
                Lamp a = l;
                a.setParams(q);
                q[static_cast<size_t>(k)] -= 2 * step;
                Lamp b = l;
                b.setParams(q);
                return (project(r, a, g) - project(r, b, g)) / (2 * step);
            };
            const double step = 1e-4;
            const double fd = (4 * central(step / 2) - central(step)) / 3;
            EXPECT_NEAR(grad[static_cast<size_t>(k)], fd, 1e-6 * scale)
                << lampKindName(l.kind) << " case " << c << " param " << k;
            if (!lampUsesParam(l.kind, k)) {
                EXPECT_EQ(grad[static_cast<size_t>(k)], 0.0);
            }
        }
    }
}

TEST(LampRaster, DualDerivativesMatchCeresJet) {
    using J = ceres::Jet<double, 5>;
    using D = Dual<5>;
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> U(-1, 1);
    const double h = 1.5 * kDeg;
    for (LampKind kind : {LampKind::Disk, LampKind::Bar, LampKind::Ring})
        for (int n = 0; n < 200; ++n) {
            const double az = 0.3, el = 0.4, a = 0.25, b = 0.1, roll = 0.2;
            // Directions near the lamp, where m and its derivatives are not negligible.
            const Vec3d c = lampDirection(az, el);
            Vec3d d = c + Vec3d(U(rng), U(rng), U(rng)) * 0.3;
            d = d / std::sqrt(dot(d, d));
            const auto fj = lamp_detail::frame<J>(J(az, 0), J(el, 1), J(roll, 4));
            const J mj = lamp_detail::membership<J>(kind, fj, J(el, 1), J(a, 2), J(b, 3), d, h);
            const auto fd =
                lamp_detail::frame<D>(D::variable(az, 0), D::variable(el, 1), D::variable(roll, 4));
            const D md = lamp_detail::membership<D>(kind, fd, D::variable(el, 1), D::variable(a, 2),
                                                    D::variable(b, 3), d, h);
            ASSERT_NEAR(md.v, mj.a, 1e-14);
            for (int k = 0; k < 5; ++k)
                ASSERT_NEAR(md.d[static_cast<size_t>(k)], mj.v[k], 1e-9 * (1 + std::abs(mj.v[k])));
        }
}

TEST(LampRaster, HandWrittenDerivativesEqualTheDualReference) {
    // jacobian()'s derivatives, written out by hand, against membership<Dual<5>> at every node,
    // on random lamps of every kind anywhere (the pole, the seam, grazing the horizon), on the
    // fit's three quadratures.
    const EnvMapBasis basis(50, 25);
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> U(0, 1);
    const size_t texels = static_cast<size_t>(basis.texelCount());
    for (int subsamples : {8, 12, 16}) {
        LampRasterOptions ro;
        ro.subsamples = subsamples;
        const LampRasterizer r(basis, ro);
        for (int n = 0; n < 60; ++n) {
            Lamp l;
            l.kind = n % 3 == 0 ? LampKind::Disk : (n % 3 == 1 ? LampKind::Bar : LampKind::Ring);
            l.radiance = 0.1 + 0.9 * U(rng);
            l.azimuth = (U(rng) * 720 - 360) * kDeg;
            l.elevation = (U(rng) * 180 - 90) * kDeg;
            if (n % 10 == 3) l.elevation = 89.5 * kDeg;  // at the pole
            if (n % 10 == 6) l.azimuth = 0.01 * kDeg;    // across the seam
            l.size = (4 + 50 * U(rng)) * kDeg;
            l.width = (2 + 18 * U(rng)) * kDeg;
            l.roll = (U(rng) * 360 - 180) * kDeg;
            std::vector<double> J(texels * kLampParams), E(texels), Jr(J.size()), Er(E.size());
            r.jacobian(l, J, E);
            r.jacobianByDual(l, Jr, Er);
            double scale[kLampParams] = {};
            for (size_t t = 0; t < texels; ++t)
                for (size_t k = 0; k < kLampParams; ++k)
                    scale[k] = std::max(scale[k], std::abs(Jr[t * kLampParams + k]));
            for (size_t t = 0; t < texels; ++t) {
                ASSERT_NEAR(E[t], Er[t], 1e-13) << lampKindName(l.kind) << " lamp " << n;
                for (size_t k = 0; k < kLampParams; ++k)
                    ASSERT_NEAR(J[t * kLampParams + k], Jr[t * kLampParams + k],
                                1e-12 * std::max(scale[k], 1.0))
                        << lampKindName(l.kind) << " lamp " << n << " texel " << t << " param "
                        << k;
            }
        }
    }
}

TEST(LampRaster, CullingABarsCellsChangesNoBit) {
    // A bar's cells beyond its cut tails across or along its axis hold only zero nodes: with
    // and without the cull, E, J (hand-written and Dual) and the value-only raster are equal bit
    // for bit, on random bars of every size and roll anywhere, thin and wide, on the fit's three
    // quadratures.
    const EnvMapBasis basis(50, 25);
    std::mt19937 rng(23);
    std::uniform_real_distribution<double> U(0, 1);
    const size_t texels = static_cast<size_t>(basis.texelCount());
    for (int subsamples : {8, 12, 16}) {
        LampRasterOptions on, off;
        on.subsamples = off.subsamples = subsamples;
        off.cullBarCells = false;
        const LampRasterizer culled(basis, on), full(basis, off);
        for (int n = 0; n < 80; ++n) {
            Lamp l;
            l.kind = LampKind::Bar;
            l.radiance = 0.1 + 0.9 * U(rng);
            l.azimuth = (U(rng) * 720 - 360) * kDeg;
            l.elevation = (U(rng) * 180 - 90) * kDeg;
            if (n % 10 == 3) l.elevation = 89.5 * kDeg;  // at the pole
            if (n % 10 == 6) l.azimuth = 0.01 * kDeg;    // across the seam
            if (n % 10 == 8) l.elevation = 0.2 * kDeg;   // on the horizon
            l.size = (4 + 56 * U(rng)) * kDeg;
            l.width = (n % 2 ? 2 + 4 * U(rng) : 2 + 18 * U(rng)) * kDeg;
            l.roll = (U(rng) * 360 - 180) * kDeg;
            std::vector<double> J(texels * kLampParams), E(texels), Jf(J.size()), Ef(E.size());
            culled.jacobian(l, J, E);
            full.jacobian(l, Jf, Ef);
            for (size_t t = 0; t < texels; ++t) ASSERT_EQ(E[t], Ef[t]) << "bar " << n;
            for (size_t i = 0; i < J.size(); ++i) ASSERT_EQ(J[i], Jf[i]) << "bar " << n;
            culled.jacobianByDual(l, J, E);
            full.jacobianByDual(l, Jf, Ef);
            for (size_t i = 0; i < J.size(); ++i) ASSERT_EQ(J[i], Jf[i]) << "bar " << n;
            const std::vector<Lamp> one{l};
            const std::vector<double> a = culled.rasterize(one), b = full.rasterize(one);
            for (size_t t = 0; t < texels; ++t) ASSERT_EQ(a[t], b[t]) << "bar " << n;
            ASSERT_EQ(culled.solidAngle(l), full.solidAngle(l));
        }
    }
}

TEST(LampRaster, TabulatedStepIsErfAndItsSlopeWithinItsBound) {
    // lamp_detail::tabulatedStep against std::erf and std::exp on a grid 1/4096 apart (64 points
    // between two of its nodes, its nodes and midpoints included) over [-6, 6]: within the
    // Taylor remainder it states (3e-17 and 3e-14) plus rounding; 0 / 1 and 0 beyond ±5.8.
    double worstS = 0, worstDs = 0;
    for (int k = -6 * 4096; k <= 6 * 4096; ++k) {
        const double t = k / 4096.0;
        double s, ds;
        lamp_detail::tabulatedStep(t, s, ds);
        if (std::abs(t) > 5.8) {
            ASSERT_EQ(s, t < 0 ? 0.0 : 1.0) << t;
            ASSERT_EQ(ds, 0.0) << t;
            continue;
        }
        worstS = std::max(worstS, std::abs(s - 0.5 * std::erfc(-t)));
        worstDs = std::max(worstDs, std::abs(ds - std::exp(-t * t) / std::sqrt(kPi)));
    }
    EXPECT_LT(worstS, 5e-16);
    EXPECT_LT(worstDs, 5e-14);
    // Cut at ±5.8 as the Dual step is: what is cut is below 1.2e-16.
    EXPECT_LT(0.5 * std::erfc(5.8), 1.2e-16);
}

TEST(LampRaster, KindsParseFromTheirTable) {
    for (const auto& row : lampKindTable()) EXPECT_EQ(parseLampKind(row.name), row.value);
    EXPECT_THROW(parseLampKind("dome"), InputError);
}

}  // namespace
