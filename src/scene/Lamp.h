// Lamps: the few physical area sources an inspection booth is built from (a disk: a spot or a
// dome; a bar: a low-angle line light; a ring: a band of elevation around +Y), each a radiance,
// a direction and a shape, and their rasterization into the env-map basis (scene/EnvMapBasis.h)
// with its exact derivative in the lamp's parameters.
//
// DIRECTION (the part's frame, as the report's plots): azimuth φ, elevation ε;
//     d(φ, ε) = (sin φ cos ε, sin ε, −cos φ cos ε)
// so φ = 0 points toward −z, φ = 90° toward +x, ε = 90° is +Y: EnvMapBasis's u = φ/2π,
// v = ½ − ε/π (uvToDirection).
//
// SHAPE: a smooth membership m(d) ∈ [0, 1] with an edge of width h (options.edge, radians):
// S(t) = ½(1 + erf t) of a signed distance to the edge over h.
//   disk  centre c = d(φ, ε), angular radius r:  m = S((d·c − cos r) / (h sin r)); the ½ level
//         is exactly the cap of radius r and the edge's slope is that of (r − angle)/h.
//   bar   a spherical rectangle about c: along-axis e₁ = cos ρ e_φ + sin ρ e_ε, across
//         e₂ = −sin ρ e_φ + cos ρ e_ε (e_φ the horizontal tangent toward growing φ, e_ε the
//         tangent toward the zenith, ρ the roll); coordinates x = atan2(d·e₁, d·c),
//         y = asin(d·e₂), and m = S((a−x)/h)·S((a+x)/h)·S((b−y)/h)·S((b+y)/h) for half-length
//         a and half-width b. The area element in (x, y) is cos y dx dy.
//   ring  the band of elevations [ε − a, ε + a] all around +Y (φ unused):
//         m = S((e − ε + a)/h) − S((e − ε − a)/h), e = asin(d.y).
//
// RASTERIZATION AND "WEIGHT = SOLID ANGLE". The renderer sees L(d) = Σ_t E_t w_t(d), w_t the
// bilinear hat of texel t (EnvMapBasis: a partition of unity, Σ_t w_t = 1). A lamp of radiance
// R gives each texel
//     E_t = R · c_t / Ω_t,   c_t = ∫ w_t(d) m(d) dω,   Ω_t = ∫ w_t(d) dω,
// so ∫ L dω = Σ_t E_t Ω_t = R · Σ_t c_t = R · ∫ m dω: the light's power is the lamp's power
// exactly (the "lumped mass" projection onto the basis, which keeps E_t ≤ R). Its total weight
// Σ_t E_t Ω_t / R is the lamp's solid angle ∫ m dω. The integrals are one fixed quadrature:
// each bilinear cell (between texel rows j, j+1 and columns i, i+1 in the half-texel-shifted u)
// is sampled at N×N Gauss–Legendre nodes in (u, v) with dω = sin θ dθ dφ, and Ω_t uses the same
// nodes, so the identity holds to rounding whatever N is, and the result is a smooth function of
// the lamp's parameters (m is). The quadrature's own error against the exact ∫ m dω depends on
// N against h: measured worst relative error over disks of 3°–10° at the pole, the seam and the
// horizon: N 12: 4e-4 (h 1°), 2e-5 (h 1.5°); N 16: 6e-6 (h 1°), 4e-8 (h 1.5°); N 20: 9e-8 (h 1°).
// The default N 16, h 1.5° keeps it below 1e-6 (tests/test_lamps.cpp: disks anywhere, at the
// pole, across the seam, rings, bars, against 1-D integrals of the same m). Cells farther than 7h
// beyond the lamp's extent are skipped (m < 1e-22 there).
//
// DERIVATIVES: m is written once as a template (membership), run on Dual<5> (core/Dual.h) for
// ∂m/∂(φ, ε, a, b, ρ) by jacobianByDual and the tests, also on ceres::Jet and against finite
// differences. The fit's jacobian() writes the same derivatives out by hand (S'(t) =
// exp(−t²)/√π times the frame's derivatives, reusing the value's erf): equal to the Dual ones
// to 1e-12 on random lamps. That cut the fit's rasterization by only ~10 % per evaluation
// (perf, `lamps part.tm --count 3` on the bundled part at 256²: 2.3 → 2.0 ms of CPU an
// evaluation): most of it was libm's erf, exp, atan2 and asin at the nodes of the edges' soft
// band (±5.8 h), which both paths evaluate. So S and S' are tabulated (lamp_detail::
// tabulatedStep: Taylor polynomials on a grid, within 3e-14 of erf and exp); the Dual
// reference keeps std::erf. Which cells a lamp can touch is one dot product per cell against
// cos(reach + the cell's radius).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/Dual.h"
#include "core/Vec3.h"
#include "scene/EnvMapBasis.h"

namespace sl {

enum class LampKind { Disk, Bar, Ring };

struct LampKindRow {
    LampKind value;
    const char* name;
    const char* help;
};
std::span<const LampKindRow> lampKindTable();
/// The kind named `name`; InputError naming `where` and listing the table otherwise.
LampKind parseLampKind(std::string_view name, const std::string& where = "lamp kind");
const char* lampKindName(LampKind kind);

/// The parameters of a lamp, in this order in params(): radiance, azimuth, elevation, size,
/// width, roll (angles in radians). Which of them a kind uses: lampUsesParam.
inline constexpr int kLampParams = 6;
enum LampParam { kRadiance = 0, kAzimuth, kElevation, kSize, kWidth, kRoll };

struct Lamp {
    LampKind kind = LampKind::Disk;
    double radiance = 1;
    double azimuth = 0, elevation = 0;  // the centre (ring: the band's middle elevation)
    double size = 0.1;    // disk: angular radius; bar: half-length; ring: half-height of the band
    double width = 0.05;  // bar: half-width
    double roll = 0;      // bar: turn about its centre direction (0: along the horizon)

    std::array<double, kLampParams> params() const {
        return {radiance, azimuth, elevation, size, width, roll};
    }
    void setParams(std::span<const double> p) {
        radiance = p[0];
        azimuth = p[1];
        elevation = p[2];
        size = p[3];
        width = p[4];
        roll = p[5];
    }
};

/// Whether parameter `p` changes a lamp of `kind` (a disk has no width nor roll, a ring no
/// azimuth, width nor roll).
bool lampUsesParam(LampKind kind, int p);

/// The unit direction of azimuth φ and elevation ε (radians; the convention above).
Vec3d lampDirection(double azimuth, double elevation);

/// The exact solid angle of the sharp-edged shape (h → 0): disk 2π(1 − cos r), bar
/// 2a·2 sin b, ring 2π(sin(ε+a) − sin(ε−a)) (clipped to the sphere).
double lampSharpSolidAngle(const Lamp& lamp);

namespace lamp_detail {

inline double smoothStep(double t) {
    return 0.5 * (1.0 + std::erf(t));
}

/// S(t) and S'(t) as the rasterizer evaluates them (the hot loop of a lamp fit): 0 / 1 and 0
/// beyond |t| > 5.8 (erfc(5.8)/2 = 1.2e-16), inside it degree-6 (S) and degree-5 (S') Taylor
/// polynomials about the nearest node of a grid of spacing δ = 1/64 whose coefficients are
/// S's derivatives there (S^(k+1) = (−1)^k H_k(t) S'(t)), computed once with std::erfc and
/// std::exp. The Taylor remainder, |u| ≤ δ/2 and max|S^(7)| = max|H_6 e^(−t²)|/√π = 120/√π:
/// |S − Ŝ| ≤ 67.7·(1/128)^7/7! < 3e-17 and |S' − Ŝ'| ≤ 67.7·(1/128)^6/6! < 3e-14, plus
/// rounding (tests/test_lamps.cpp checks both against std::erf and std::exp on a dense grid).
/// It costs a few multiply-adds where erf and exp cost ~10× that.
void tabulatedStep(double t, double& s, double& ds);

/// The lamp's frame from its angles: centre c, along-axis e1, across e2 (see above).
template <class T>
struct Frame {
    T c[3], e1[3], e2[3];
};

template <class T>
Frame<T> frame(const T& az, const T& el, const T& roll) {
    using std::cos;
    using std::sin;
    const T sa = sin(az), ca = cos(az), se = sin(el), ce = cos(el), sr = sin(roll), cr = cos(roll);
    const T ephi[3] = {ca, T(0.0), sa};
    const T eel[3] = {-(sa * se), ce, ca * se};
    Frame<T> f;
    f.c[0] = sa * ce;
    f.c[1] = se;
    f.c[2] = -(ca * ce);
    for (int k = 0; k < 3; ++k) {
        f.e1[k] = cr * ephi[k] + sr * eel[k];
        f.e2[k] = cr * eel[k] - sr * ephi[k];
    }
    return f;
}

template <class T>
T dotd(const T v[3], const Vec3d& d) {
    return v[0] * d.x + v[1] * d.y + v[2] * d.z;
}

template <class T>
T step(const T& t) {
    using std::erf;
    return 0.5 * (erf(t) + 1.0);
}
/// The same on Dual numbers, constant where the tails are below 1.2e-16 (no erf, no exp).
template <int N>
Dual<N> step(const Dual<N>& t) {
    if (t.v < -5.8) return Dual<N>(0.0);
    if (t.v > 5.8) return Dual<N>(1.0);
    return 0.5 * (erf(t) + 1.0);
}

/// m(d) for a lamp with the frame f, elevation el, size a, width b, edge h (see above).
template <class T>
T membership(LampKind kind, const Frame<T>& f, const T& el, const T& a, const T& b, const Vec3d& d,
             double h) {
    using std::asin;
    using std::atan2;
    using std::cos;
    using std::sin;
    switch (kind) {
        case LampKind::Disk:
            return step((dotd(f.c, d) - cos(a)) / (h * sin(a)));
        case LampKind::Bar: {
            const T x = atan2(dotd(f.e1, d), dotd(f.c, d));
            const T y = asin(dotd(f.e2, d));
            return step((a - x) / h) * step((a + x) / h) * step((b - y) / h) * step((b + y) / h);
        }
        case LampKind::Ring: {
            const double e = std::asin(std::clamp(d.y, -1.0, 1.0));
            return step((e - el + a) / h) - step((e - el - a) / h);
        }
    }
    return T(0.0);
}

}  // namespace lamp_detail

struct LampRasterOptions {
    int subsamples = 16;                         // N: Gauss–Legendre nodes per cell and axis
    double edge = 1.5 * 3.14159265358979 / 180;  // h, radians
    /// Skip a bar's cells that lie wholly beyond its cut tails across or along its axis (every
    /// node there is exactly 0, so the result is the same bit for bit; off only for the test
    /// that shows it).
    bool cullBarCells = true;
};

/// Rasterizes lamps into E on one basis (the quadrature is built once).
class LampRasterizer {
  public:
    explicit LampRasterizer(const EnvMapBasis& basis, LampRasterOptions options = {});

    const EnvMapBasis& basis() const { return basis_; }
    const LampRasterOptions& options() const { return options_; }
    /// Ω_t of every texel (the quadrature's; they sum to 4π up to the quadrature's error).
    const std::vector<double>& texelSolidAngles() const { return omega_; }

    /// E += the lamp's texels (E has basis().texelCount() values).
    void add(const Lamp& lamp, std::span<double> E) const;
    /// The texels of all the lamps (their sum).
    std::vector<double> rasterize(std::span<const Lamp> lamps) const;
    /// dLoss/dparams (kLampParams values, params() order) of the lamp given dLoss/dE: the
    /// vector–Jacobian product (∂E/∂params)ᵀ·dLdE. Optionally also adds the lamp into E.
    void gradient(const Lamp& lamp, std::span<const double> dLdE, std::span<double> dLdp,
                  std::span<double> E = {}) const;
    /// The Jacobian ∂E_t/∂p, texel-major (texelCount × kLampParams), and E.
    void jacobian(const Lamp& lamp, std::span<double> J, std::span<double> E) const;

    /// The same Jacobian with every edge node's derivatives by membership<Dual<5>>: the
    /// reference the hand-written derivatives of jacobian() are tested against.
    void jacobianByDual(const Lamp& lamp, std::span<double> J, std::span<double> E) const;

    /// The lamp's solid angle as the quadrature sees it: Σ over nodes of m dω (= Σ_t c_t).
    double solidAngle(const Lamp& lamp) const;

  private:
    EnvMapBasis basis_;
    LampRasterOptions options_;
    int n_ = 0;                    // nodes per cell (N²)
    std::vector<double> gx_, gy_;  // node offsets in the cell, N² each
    std::vector<double> wt_;       // ... and their 4 bilinear weights (N² × 4)
    std::vector<Vec3d> dir_;       // cells × N² directions
    std::vector<double> dw_;       // ... and their dω
    std::vector<double> elev_;     // ... and their elevation asin(d.y)
    std::vector<Vec3d> cellCentre_;
    std::vector<double> cellRadius_, cellCosRadius_, cellSinRadius_, cellElLo_, cellElHi_;
    std::vector<double> omega_;

    /// c_t (texels) and, when dc is non-empty, ∂c_t/∂(φ, ε, a, b, ρ) (texels × 5): by the
    /// hand-written derivatives, or membership<Dual<5>> (byDual, the reference).
    void coverage(const Lamp& lamp, std::vector<double>& c, std::vector<double>* dc,
                  bool byDual = false) const;
    /// How far from its centre a lamp can touch a cell (a disk or bar: an angle, with its
    /// cosine and sine; a ring: an elevation band). A bar also: the great circles its nodes
    /// cannot cross (its axis' e2 at y = ±yMax, and the meridians about e2 at x = ±xMax, by
    /// their normals), yMax and xMax where its factors' tails are cut (b, a + 5.8 h).
    struct Reach {
        double angle = 0, cosAngle = 1, sinAngle = 0, lo = 0, hi = 0;
        bool acrossCut = false, alongCut = false;
        Vec3d e2, nPlus, nMinus;
        double yMax = 0, sinY = 0, cosY = 1;
    };
    Reach reach(const Lamp& lamp) const;
    void jacobianOf(const Lamp& lamp, std::span<double> J, std::span<double> E, bool byDual) const;
    bool cellMayTouch(const Lamp& lamp, const Vec3d& centre, const Reach& reach, int cell) const;
};

}  // namespace sl
