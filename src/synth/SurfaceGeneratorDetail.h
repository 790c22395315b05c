// The surface generator's stages shared by its three files (private to src/synth/):
// SurfaceProcesses.cpp (the tool marks of each machining process, the pocket step, the
// process and test-part tables), SurfaceDefects.cpp (scratches, gouges, dents, chatter bands,
// the burr, cracks, spikes and the truth labels' table) and SurfaceGenerator.cpp (validation,
// roughness, composition and the description). The model and conventions: SurfaceGenerator.h.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "core/Rng.h"
#include "synth/SurfaceGenerator.h"

namespace sl::surfacegen {

constexpr double kPi = 3.14159265358979323846;
constexpr double kInf = std::numeric_limits<double>::infinity();

// Stream keys: each random stage draws from its own PCG32 stream derived from the seed.
constexpr uint64_t kScratchStream = 0x7363726174636831ULL;
constexpr uint64_t kGougeStream = 0x676f756765303031ULL;
constexpr uint64_t kRoughStream = 0x726f756768303031ULL;
constexpr uint64_t kPathStream = 0x7061746873303031ULL;
constexpr uint64_t kDentStream = 0x64656e7473303031ULL;
constexpr uint64_t kBandStream = 0x62616e6473303031ULL;
constexpr uint64_t kBurrStream = 0x6275727273303031ULL;
constexpr uint64_t kTurnStream = 0x7475726e73303031ULL;
constexpr uint64_t kNoiseStream = 0x6e6f697365303031ULL;
constexpr uint64_t kSpikeStream = 0x7370696b65303031ULL;
constexpr uint64_t kGritStream = 0x6772697473303031ULL;
constexpr uint64_t kCrackStream = 0x637261636b303031ULL;       // the cracks' placement
constexpr uint64_t kCrackShapeStream = 0x637261636b736831ULL;  // one crack's shape (crackPaths)

/// Throws the input error of a SurfaceSpec field (its option name) unless `ok`.
void require(bool ok, const std::string& field, const std::string& problem, const std::string& fix);

/// h = R − √(R² − r²) without cancellation; r² < R² required.
inline double sphereRise(double R, double r2) {
    return r2 / (R + std::sqrt(R * R - r2));
}

inline double smoothstep01(double x) {
    x = std::clamp(x, 0.0, 1.0);
    return x * x * (3.0 - 2.0 * x);
}

/// Uniform [0,1) from a hashed key (per-path phases: random access, no stream state).
inline double hashUniform(uint64_t seed, uint64_t stream, int64_t k) {
    uint64_t h = mix64(mix64(seed ^ stream) + static_cast<uint64_t>(k));
    return static_cast<double>(h >> 11) * 0x1p-53;
}

inline double gaussian(Pcg32& rng) {
    double u1 = 1.0 - rng.nextDouble();  // (0, 1]
    double u2 = rng.nextDouble();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * kPi * u2);
}

/// The common geometry of the stages below.
struct Frame {
    int W = 0, H = 0;
    double pitch = 0, cx = 0, cz = 0, extX = 0, extZ = 0;
    bool ball = false;
    explicit Frame(const SurfaceSpec& spec)
        : W(spec.width),
          H(spec.height),
          pitch(spec.pitch),
          cx(0.5 * (spec.width - 1)),
          cz(0.5 * (spec.height - 1)),
          extX((spec.width - 1) * spec.pitch),
          extZ((spec.height - 1) * spec.pitch),
          ball(spec.process == SurfaceSpec::Process::BallEndRaster),
          process(spec.process) {}
    SurfaceSpec::Process process;
};

// ---------------------------------------------------------------------------------------------
// Tool marks.

/// One grit's track (Ground): its centre line across the lay, its extent along it, its depth.
struct GritTrack {
    double p = 0, t0 = 0, t1 = 0, depth = 0;
};

/// The taper of a grit's depth along its track, τ ∈ [0, 1] (see SurfaceGenerator.h).
constexpr double kGritTaper = 0.15;
/// The deepest grit, in units of gritDepth (the exponential's cut).
constexpr double kGritDepthCut = 4.0;

struct ToolMarks {
    SurfaceSpec::Process process = SurfaceSpec::Process::BallEndRaster;
    double R = 0, R2 = 0;   // ball radius (ball-end) or cutter radius (face mill, flat end)
    double rn = 0;          // insert nose radius (face mill, turned)
    double rc = 0, af = 0;  // flat end: corner radius and radius of the flat, R − r_c
    double s = 0, off = 0, f = 0;
    bool feedMarks = false;
    double cosA = 1, sinA = 0;
    double A = 0, omega = 0;
    double maxA = 0;  // the largest chatter amplitude anywhere (bands included)
    double xc = 0, zc = 0, turnPhase = 0, turnChatterPhase = 0;  // turned
    int64_t kMin = 0, kMax = 0;                                  // path table range
    std::vector<double> chatCos, chatSin, toothPhase;
    // Ground: the grit tracks sorted into bins of `gritBin` mm across the lay from `gritLo`
    // (bin b holds grits[gritStart[b] .. gritStart[b + 1]); a track reaches less than a bin).
    std::vector<GritTrack> grits;
    std::vector<uint32_t> gritStart;
    double gritLo = 0, gritBin = 1;

    size_t idx(int64_t k) const { return static_cast<size_t>(std::clamp(k, kMin, kMax) - kMin); }

    // Ball-end raster: MIN over the paths that can reach the point (chatter amplitude amp).
    double ballEnd(double t, double p, double sw, double cw, double amp) const {
        double best = kInf;
        auto k0 = static_cast<int64_t>(std::floor((p - off) / s + 0.5));
        for (int dir = 1; dir >= -1; dir -= 2) {
            for (int64_t k = dir > 0 ? k0 : k0 - 1;; k += dir) {
                double d = p - (off + static_cast<double>(k) * s);
                double d2 = d * d;
                if (d2 >= R2) break;
                if (sphereRise(R, d2) - amp >= best) break;  // farther paths only rise
                size_t n = idx(k);
                double r2 = d2;
                if (feedMarks) {
                    double u = (t - toothPhase[n]) / f;
                    double dt = (u - std::nearbyint(u)) * f;
                    r2 += dt * dt;
                }
                if (r2 >= R2) continue;
                double h = sphereRise(R, r2) + amp * (sw * chatCos[n] + cw * chatSin[n]);
                best = std::min(best, h);
            }
        }
        return std::isfinite(best) ? best : R;  // unreachable after validation
    }

    // Face mill: the last pass covering the point wins; nearest leading-edge tooth arc.
    double faceMill(double t, double p, double sw, double cw, double amp) const {
        // Largest k with p_k < p + R, i.e. the last pass whose swath (|p − p_k| < R) holds p.
        auto k = static_cast<int64_t>(std::ceil((p + R - off) / s)) - 1;
        double q = p - (off + static_cast<double>(k) * s);
        if (q * q >= R2) return rn;  // not covered: unreachable after validation
        size_t n = idx(k);
        double lead = std::sqrt(R2 - q * q);
        double mStar = (t - lead - toothPhase[n]) / f;
        auto m0 = static_cast<int64_t>(std::floor(mStar));
        double best = rn;
        for (int64_t m = m0 - 1; m <= m0 + 2; ++m) {
            double dx = t - (static_cast<double>(m) * f + toothPhase[n]);
            if (dx < 0) continue;  // only the leading half of the cutter cuts (tilted spindle)
            double delta = std::abs(std::hypot(dx, q) - R);
            if (delta >= rn) continue;
            best = std::min(best, sphereRise(rn, delta * delta));
        }
        return best + amp * (sw * chatCos[n] + cw * chatSin[n]);
    }

    // Flat end mill: MIN over the passes whose tool reaches the point. Without feed marks the
    // pass's profile (flat, then the corner arc); with them the torus swept by the leading
    // teeth's corners (circle of radius af about each tooth centre, tube radius rc).
    double flatEnd(double t, double p, double sw, double cw, double amp) const {
        double best = kInf;
        auto kLo = static_cast<int64_t>(std::ceil((p - R - off) / s));
        auto kHi = static_cast<int64_t>(std::floor((p + R - off) / s));
        for (int64_t k = kLo; k <= kHi; ++k) {
            double q = p - (off + static_cast<double>(k) * s);
            double aq = std::abs(q);
            if (aq >= R) continue;
            size_t n = idx(k);
            double h = rc;  // above the corner: not cut by this pass
            if (!feedMarks) {
                h = aq <= af ? 0.0 : sphereRise(rc, (aq - af) * (aq - af));
            } else {
                // The leading corner arc crosses the point where hypot(dx, q) = af.
                double dxStar = aq < af ? std::sqrt(af * af - q * q) : 0.0;
                auto m0 = static_cast<int64_t>(std::floor((t - dxStar - toothPhase[n]) / f));
                for (int64_t m = m0 - 1; m <= m0 + 2; ++m) {
                    double dx = t - (static_cast<double>(m) * f + toothPhase[n]);
                    if (dx < 0) continue;  // only the leading half cuts (tilted spindle)
                    double delta = std::abs(std::hypot(dx, q) - af);
                    if (delta >= rc) continue;
                    h = std::min(h, sphereRise(rc, delta * delta));
                }
            }
            best = std::min(best, h + amp * (sw * chatCos[n] + cw * chatSin[n]));
        }
        return std::isfinite(best) ? best : rc;  // unreachable after validation
    }

    // Ground: the MIN of the wheel's envelope (0) and the grit tracks that reach the point,
    // with the wheel's chatter (one phase: sw = sin(ω·t)).
    double ground(double t, double p, double sw, double amp) const {
        double best = 0.0;
        const auto bins = static_cast<int64_t>(gritStart.size()) - 1;
        const auto b = static_cast<int64_t>(std::floor((p - gritLo) / gritBin));
        for (int64_t c = std::max<int64_t>(b - 1, 0); c <= std::min(b + 1, bins - 1); ++c) {
            for (uint32_t n = gritStart[static_cast<size_t>(c)];
                 n < gritStart[static_cast<size_t>(c) + 1]; ++n) {
                const GritTrack& g = grits[n];
                if (t <= g.t0 || t >= g.t1) continue;
                const double q = p - g.p;
                if (q * q >= R2) continue;
                const double rise = sphereRise(R, q * q);
                if (rise >= g.depth) continue;
                const double tau = (t - g.t0) / (g.t1 - g.t0);
                const double w = smoothstep01(std::min(tau, 1.0 - tau) / kGritTaper);
                best = std::min(best, rise - g.depth * w);
            }
        }
        return best + amp * sw;
    }

    // Turned: the nose profile about the spiral's nearest turns; r = distance to the centre,
    // theta = angle about it (radians). Chatter along the spiral when `chatter`.
    double turned(double r, double theta, double amp, bool chatter) const {
        double th = theta / (2.0 * kPi) + turnPhase;
        auto n0 = static_cast<int64_t>(std::nearbyint(r / f - th));
        double best = kInf;
        for (int64_t n = n0 - 1; n <= n0 + 1; ++n) {
            double rho = f * (static_cast<double>(n) + th);
            double d = r - rho;
            if (d * d >= rn * rn) continue;
            double h = sphereRise(rn, d * d);
            if (chatter && amp > 0)
                h += amp * std::sin(omega * kPi * rho * rho / f + turnChatterPhase);
            best = std::min(best, h);
        }
        return std::isfinite(best) ? best : rn;  // unreachable after validation (f < 2·rn)
    }
};

// ---------------------------------------------------------------------------------------------
// Defects.

struct Segment {
    double ax, az, ux, uz, L;  // start, unit direction, length
    int i0, i1, j0, j1;        // sample bounding box (inclusive), may be empty
};

struct Scratch {
    Segment seg;
    ScratchSpec spec;
    double taper;
};

struct Gouge {
    Segment seg;
    GougeSpec spec;
    double radius;
};

/// Scratch height offset at (x, z); sets `cut` when inside the groove (truth), `lip` where the
/// lip is ≥ 10% of its height.
double scratchOffset(const Scratch& c, double x, double z, bool& cut, bool& lip);

/// Height of the gouge's swept sphere at (x, z) (relative to the cut plane y = 0), or +inf.
double gougeSurface(const Gouge& gg, double x, double z);

/// A dent's bounding box in samples and its reach² (where the sphere has risen by its depth).
struct Dent {
    DentSpec spec;
    double reach2 = 0;
    int i0 = 0, i1 = -1, j0 = 0, j1 = -1;
};

/// Dent height offset (≤ 0) at (x, z); sets `hit` where it lowers by ≥ 10% of the depth.
double dentOffset(const Dent& d, double x, double z, bool& hit);

/// A crack placed on the map: its spec, its pieces (crackPaths) and its sample bounding box.
struct Crack {
    CrackSpec spec;
    std::vector<CrackPath> paths;
    int i0 = 0, i1 = -1, j0 = 0, j1 = -1;
};

/// The pocket-edge burr: its profile across the edge per column and its height along it per
/// row (both 0 without a burr).
struct Burr {
    std::vector<double> across, along;
};

// ---------------------------------------------------------------------------------------------
// The stages (SurfaceProcesses.cpp: 1, 2; SurfaceDefects.cpp: 3, 4, 4b, 4c, 4d, 4e, 6b).

/// Stage 1: the tool paths that can shape the map, with their chatter and tooth phases.
ToolMarks toolMarks(const SurfaceSpec& spec, const Frame& fr);

/// Stage 2: the pocket step's height per column (zero without a pocket edge); sets the edge's
/// position and half width in `out`.
std::vector<double> pocketColumns(const SurfaceSpec& spec, const Frame& fr, GeneratedSurface& out);

/// Stage 3: the scratches, given or drawn (stratified) from the seed; their specs into `out`.
std::vector<Scratch> placeScratches(const SurfaceSpec& spec, const Frame& fr,
                                    GeneratedSurface& out);

/// Stage 4: the gouges (tool digs), given or drawn from the seed off the pocket edge.
std::vector<Gouge> placeGouges(const SurfaceSpec& spec, const Frame& fr, const ToolMarks& tm,
                               GeneratedSurface& out);

/// Stage 4b: the dents, given or drawn from the seed (uniform over the inner 80% of the map,
/// off the pocket edge).
std::vector<Dent> placeDents(const SurfaceSpec& spec, const Frame& fr, GeneratedSurface& out);

/// Stage 4e: the cracks, drawn from the seed (centres uniform over the inner 60% of the map, off
/// the pocket edge; see SurfaceSpec).
std::vector<Crack> placeCracks(const SurfaceSpec& spec, const Frame& fr, GeneratedSurface& out);

/// Stage 4c: the chatter bands' centres (across-path coordinate), uniform over the map's range.
std::vector<double> placeChatterBands(const SurfaceSpec& spec, const Frame& fr,
                                      const ToolMarks& tm);

/// Stage 4d: the burr on the pocket's top edge (see the header).
Burr placeBurr(const SurfaceSpec& spec, const Frame& fr, const GeneratedSurface& out);

/// Stage 6b: measurement spikes at random samples (after everything).
void addSpikes(const SurfaceSpec& spec, GeneratedSurface& out);

}  // namespace sl::surfacegen
