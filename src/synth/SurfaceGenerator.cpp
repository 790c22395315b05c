// Synthetic NC-machined surfaces; see SurfaceGenerator.h for the model and conventions.
#include "synth/SurfaceGenerator.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "core/Error.h"
#include "core/Rng.h"
#include "core/Text.h"

namespace sl {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kInf = std::numeric_limits<double>::infinity();

// Stream keys: each random stage draws from its own PCG32 stream derived from the seed.
constexpr uint64_t kScratchStream = 0x7363726174636831ULL;
constexpr uint64_t kGougeStream = 0x676f756765303031ULL;
constexpr uint64_t kRoughStream = 0x726f756768303031ULL;
constexpr uint64_t kPathStream = 0x7061746873303031ULL;

void require(bool ok, const std::string& field, const std::string& problem,
             const std::string& fix) {
    if (!ok) throw inputError("SurfaceSpec." + field, problem, fix);
}

void requireFinite(double v, const std::string& field) {
    require(std::isfinite(v), field, "must be a finite number, got " + formatNumber(v),
            "Set it to a finite value in mm (or degrees for angles)");
}

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

/// Pocket step profile (≤ 0) at signed distance xr from the edge's centre line; see header.
double pocketProfile(double xr, double depth, double r) {
    if (depth <= 0) return 0.0;
    if (r <= 0) return xr < 0 ? 0.0 : -depth;
    double a;  // horizontal extent of each arc
    if (depth <= 2 * r) {
        double c = 1.0 - depth / (2 * r);  // cos θ
        a = r * std::sqrt(std::max(0.0, 1.0 - c * c));
    } else {
        a = r;
    }
    if (xr <= -a) return 0.0;
    if (xr >= a) return -depth;
    if (xr < 0) {  // convex top arc, centre (−a, −r)
        double u = xr + a;
        return -r + std::sqrt(std::max(0.0, r * r - u * u));
    }
    double u = xr - a;  // concave bottom arc, centre (a, −depth + r)
    return -depth + r - std::sqrt(std::max(0.0, r * r - u * u));
}

double pocketHalfWidth(double depth, double r) {
    if (depth <= 0 || r <= 0) return 0.0;
    if (depth > 2 * r) return r;
    double c = 1.0 - depth / (2 * r);
    return r * std::sqrt(std::max(0.0, 1.0 - c * c));
}

void validate(const SurfaceSpec& s) {
    require(s.width >= 2, "width", "must be at least 2 samples, got " + std::to_string(s.width),
            "Use a map of at least 2x2 samples");
    require(s.height >= 2, "height", "must be at least 2 samples, got " + std::to_string(s.height),
            "Use a map of at least 2x2 samples");
    require(static_cast<double>(s.width) * s.height <= 2.0e9, "width",
            "width*height = " + formatNumber(static_cast<double>(s.width) * s.height) +
                " samples is too large",
            "Keep width*height at or below 2e9");
    requireFinite(s.pitch, "pitch");
    require(s.pitch > 0, "pitch", "must be > 0 mm, got " + formatNumber(s.pitch),
            "Set the sample spacing in mm, e.g. 0.01");
    requireFinite(s.toolRadius, "toolRadius");
    require(s.toolRadius > 0, "toolRadius", "must be > 0 mm, got " + formatNumber(s.toolRadius),
            "Set the ball (or face-mill cutter) radius in mm");
    requireFinite(s.stepover, "stepover");
    require(s.stepover > 0, "stepover", "must be > 0 mm, got " + formatNumber(s.stepover),
            "Set the spacing of the tool paths in mm");
    require(s.stepover < 2 * s.toolRadius, "stepover",
            "must be < 2*toolRadius = " + formatNumber(2 * s.toolRadius) + " mm, got " +
                formatNumber(s.stepover),
            "Paths further apart than the tool's diameter leave uncut material");
    requireFinite(s.pathOffset, "pathOffset");
    requireFinite(s.rasterAngleDeg, "rasterAngleDeg");
    requireFinite(s.feedPerTooth, "feedPerTooth");
    require(s.feedPerTooth >= 0, "feedPerTooth",
            "must be >= 0 mm, got " + formatNumber(s.feedPerTooth),
            "Set the feed per tooth in mm (0 disables ball-end feed marks)");
    if (s.process == SurfaceSpec::Process::BallEndRaster && s.ballFeedMarks) {
        double hs = 0.5 * s.stepover, hf = 0.5 * s.feedPerTooth;
        require(hs * hs + hf * hf < s.toolRadius * s.toolRadius, "feedPerTooth",
                "with stepover " + formatNumber(s.stepover) + " mm the ball of radius " +
                    formatNumber(s.toolRadius) + " mm leaves uncut material at feed " +
                    formatNumber(s.feedPerTooth) + " mm",
                "Reduce feedPerTooth or stepover, or set ballFeedMarks = false");
    }
    if (s.process == SurfaceSpec::Process::FaceMillFeed) {
        requireFinite(s.insertNoseRadius, "insertNoseRadius");
        require(s.insertNoseRadius > 0, "insertNoseRadius",
                "must be > 0 mm, got " + formatNumber(s.insertNoseRadius),
                "Typical inserts: 0.4-1.2 mm");
        require(s.feedPerTooth > 0 && s.feedPerTooth < 2 * s.insertNoseRadius, "feedPerTooth",
                "must be in (0, 2*insertNoseRadius = " + formatNumber(2 * s.insertNoseRadius) +
                    ") mm for a face mill, got " + formatNumber(s.feedPerTooth),
                "Typical finishing feeds: 0.05-0.2 mm per tooth");
    }
    requireFinite(s.chatterAmplitude, "chatterAmplitude");
    require(s.chatterAmplitude >= 0, "chatterAmplitude",
            "must be >= 0 mm, got " + formatNumber(s.chatterAmplitude), "Use 0 to disable chatter");
    requireFinite(s.chatterStartFraction, "chatterStartFraction");
    require(s.chatterStartFraction >= 0 && s.chatterStartFraction < 1, "chatterStartFraction",
            "must be in [0, 1), got " + formatNumber(s.chatterStartFraction),
            "Use 0 for chatter everywhere, 0.5 for the right half");
    if (s.chatterAmplitude > 0) {
        requireFinite(s.chatterWavelength, "chatterWavelength");
        require(
            s.chatterWavelength > 0, "chatterWavelength",
            "must be > 0 mm when chatterAmplitude > 0, got " + formatNumber(s.chatterWavelength),
            "Set the chatter wavelength in mm, or chatterAmplitude = 0");
    }
    requireFinite(s.roughnessRms, "roughnessRms");
    require(s.roughnessRms >= 0, "roughnessRms",
            "must be >= 0 mm, got " + formatNumber(s.roughnessRms), "Use 0 to disable roughness");
    if (s.roughnessRms > 0) {
        requireFinite(s.roughnessCorrelation, "roughnessCorrelation");
        require(s.roughnessCorrelation > 0, "roughnessCorrelation",
                "must be > 0 mm when roughnessRms > 0, got " + formatNumber(s.roughnessCorrelation),
                "Set the correlation length in mm, e.g. 0.02");
    }
    if (s.scratches.empty()) {
        require(s.scratchCount >= 0 && s.scratchCount <= 100000, "scratchCount",
                "must be in [0, 100000], got " + std::to_string(s.scratchCount),
                "Use 0 for no scratches");
        if (s.scratchCount > 0) {
            requireFinite(s.scratchDepth, "scratchDepth");
            require(s.scratchDepth >= 0, "scratchDepth",
                    "must be >= 0 mm, got " + formatNumber(s.scratchDepth),
                    "Scratch depths are in mm");
            requireFinite(s.scratchWidth, "scratchWidth");
            require(s.scratchWidth > 0, "scratchWidth",
                    "must be > 0 mm, got " + formatNumber(s.scratchWidth),
                    "Scratch widths are in mm");
        }
    }
    for (size_t n = 0; n < s.scratches.size(); ++n) {
        const ScratchSpec& c = s.scratches[n];
        std::string f = "scratches[" + std::to_string(n) + "]";
        for (double v : {c.x0, c.z0, c.x1, c.z1, c.width, c.depth, c.burr}) requireFinite(v, f);
        require(c.width > 0, f + ".width", "must be > 0 mm, got " + formatNumber(c.width),
                "Scratch widths are in mm");
        require(c.depth >= 0, f + ".depth", "must be >= 0 mm, got " + formatNumber(c.depth),
                "Scratch depths are in mm, positive into the part");
        require(c.burr >= 0, f + ".burr", "must be >= 0, got " + formatNumber(c.burr),
                "The burr is a fraction of the depth");
        require(std::hypot(c.x1 - c.x0, c.z1 - c.z0) > 0, f, "the endpoints coincide",
                "Give a segment of positive length");
    }
    if (s.gouges.empty()) {
        require(s.gougeCount >= 0 && s.gougeCount <= 100000, "gougeCount",
                "must be in [0, 100000], got " + std::to_string(s.gougeCount),
                "Use 0 for no gouges");
        if (s.gougeCount > 0) {
            requireFinite(s.gougeDepth, "gougeDepth");
            require(s.gougeDepth >= 0, "gougeDepth",
                    "must be >= 0 mm, got " + formatNumber(s.gougeDepth), "Gouge depths are in mm");
            requireFinite(s.gougeLength, "gougeLength");
            require(s.gougeLength > 0, "gougeLength",
                    "must be > 0 mm, got " + formatNumber(s.gougeLength),
                    "Gouge lengths are in mm");
        }
    }
    for (size_t n = 0; n < s.gouges.size(); ++n) {
        const GougeSpec& g = s.gouges[n];
        std::string f = "gouges[" + std::to_string(n) + "]";
        for (double v : {g.x0, g.z0, g.x1, g.z1, g.depth}) requireFinite(v, f);
        require(g.depth >= 0, f + ".depth", "must be >= 0 mm, got " + formatNumber(g.depth),
                "Gouge depths are in mm, positive into the part");
        require(std::hypot(g.x1 - g.x0, g.z1 - g.z0) > 0, f, "the endpoints coincide",
                "Give a segment of positive length");
    }
    if (s.pocketEdge) {
        requireFinite(s.pocketDepth, "pocketDepth");
        require(s.pocketDepth >= 0, "pocketDepth",
                "must be >= 0 mm, got " + formatNumber(s.pocketDepth),
                "The pocket floor is pocketDepth below the top");
        requireFinite(s.pocketWallFraction, "pocketWallFraction");
        require(s.pocketWallFraction > 0 && s.pocketWallFraction < 1, "pocketWallFraction",
                "must be in (0, 1), got " + formatNumber(s.pocketWallFraction),
                "It is the fraction of the map width (in +x) that is pocket floor");
        requireFinite(s.cornerRadius, "cornerRadius");
        require(s.cornerRadius >= 0, "cornerRadius",
                "must be >= 0 mm, got " + formatNumber(s.cornerRadius), "Use 0 for a sharp step");
    }
}

// ---------------------------------------------------------------------------------------------
// Tool marks.

struct ToolMarks {
    double R = 0, R2 = 0;  // ball radius (ball-end) or cutter radius (face mill)
    double rn = 0;         // insert nose radius (face mill)
    double s = 0, off = 0, f = 0;
    bool feedMarks = false;
    double cosA = 1, sinA = 0;
    double A = 0, omega = 0;
    int64_t kMin = 0, kMax = 0;  // path table range
    std::vector<double> chatCos, chatSin, toothPhase;

    size_t idx(int64_t k) const { return static_cast<size_t>(std::clamp(k, kMin, kMax) - kMin); }

    // Ball-end raster: MIN over the paths that can reach the point.
    double ballEnd(double t, double p, double sw, double cw) const {
        double best = kInf;
        auto k0 = static_cast<int64_t>(std::floor((p - off) / s + 0.5));
        for (int dir = 1; dir >= -1; dir -= 2) {
            for (int64_t k = dir > 0 ? k0 : k0 - 1;; k += dir) {
                double d = p - (off + static_cast<double>(k) * s);
                double d2 = d * d;
                if (d2 >= R2) break;
                if (sphereRise(R, d2) - A >= best) break;  // farther paths only rise
                size_t n = idx(k);
                double r2 = d2;
                if (feedMarks) {
                    double u = (t - toothPhase[n]) / f;
                    double dt = (u - std::nearbyint(u)) * f;
                    r2 += dt * dt;
                }
                if (r2 >= R2) continue;
                double h = sphereRise(R, r2) + A * (sw * chatCos[n] + cw * chatSin[n]);
                best = std::min(best, h);
            }
        }
        return std::isfinite(best) ? best : R;  // unreachable after validation
    }

    // Face mill: the last pass covering the point wins; nearest leading-edge tooth arc.
    double faceMill(double t, double p, double sw, double cw) const {
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
        return best + A * (sw * chatCos[n] + cw * chatSin[n]);
    }
};

// ---------------------------------------------------------------------------------------------
// Defects.

struct Segment {
    double ax, az, ux, uz, L;  // start, unit direction, length
    int i0, i1, j0, j1;        // sample bounding box (inclusive), may be empty
};

Segment makeSegment(double x0, double z0, double x1, double z1, double reach, double pitch, int W,
                    int H) {
    Segment g{};
    g.ax = x0;
    g.az = z0;
    g.L = std::hypot(x1 - x0, z1 - z0);
    g.ux = (x1 - x0) / g.L;
    g.uz = (z1 - z0) / g.L;
    double cx = 0.5 * (W - 1), cz = 0.5 * (H - 1);
    auto toIdx = [&](double v, double c, int n, bool lo) {
        double k = lo ? std::floor(v / pitch + c) : std::ceil(v / pitch + c);
        return static_cast<int>(std::clamp(k, -1.0, static_cast<double>(n)));
    };
    g.i0 = std::max(0, toIdx(std::min(x0, x1) - reach, cx, W, true));
    g.i1 = std::min(W - 1, toIdx(std::max(x0, x1) + reach, cx, W, false));
    g.j0 = std::max(0, toIdx(std::min(z0, z1) - reach, cz, H, true));
    g.j1 = std::min(H - 1, toIdx(std::max(z0, z1) + reach, cz, H, false));
    return g;
}

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

/// Scratch height offset at (x, z); sets `cut` when inside the groove (truth).
double scratchOffset(const Scratch& c, double x, double z, bool& cut) {
    const Segment& g = c.seg;
    double px = x - g.ax, pz = z - g.az;
    double along = px * g.ux + pz * g.uz;
    if (along <= 0 || along >= g.L) return 0.0;
    double d = std::abs(-px * g.uz + pz * g.ux);
    double w = c.spec.width;
    double u = 2.0 * d / w;
    if (u >= 2.0) return 0.0;
    double fade = smoothstep01(std::min(along, g.L - along) / c.taper);
    double D = c.spec.depth * fade;
    if (u < 1.0) {
        if (fade >= 0.1) cut = true;
        return c.spec.shape == ScratchSpec::Shape::V ? -D * (1.0 - u) : -D * (1.0 - u * u);
    }
    double v = (u - 1.5) * 2.0;  // lip centred at 0.75·w, half-width 0.25·w
    double b = 1.0 - v * v;
    return c.spec.burr * D * b * b;
}

/// Height of the gouge's swept sphere at (x, z) (relative to the cut plane y = 0), or +inf.
double gougeSurface(const Gouge& gg, double x, double z) {
    const Segment& g = gg.seg;
    constexpr int kSteps = 96;
    double R = gg.radius, R2 = R * R;
    double best = kInf;
    double px = x - g.ax, pz = z - g.az;
    double along = px * g.ux + pz * g.uz;
    double d = -px * g.uz + pz * g.ux;
    double d2 = d * d;
    if (d2 >= R2) return kInf;
    for (int n = 0; n <= kSteps; ++n) {
        double tau = static_cast<double>(n) / kSteps;
        double dt = along - tau * g.L;
        double r2 = dt * dt + d2;
        if (r2 >= R2) continue;
        double h = sphereRise(R, r2) - gg.spec.depth * std::sin(kPi * tau);
        best = std::min(best, h);
    }
    return best;
}

// ---------------------------------------------------------------------------------------------
// Roughness: cubic B-spline interpolation of a Gaussian lattice, renormalised.

struct Roughness {
    double rms = 0;
    int nx = 0, nz = 0;
    std::vector<float> lattice;                     // nz × nx
    std::vector<int> colNode, rowNode;              // first of the 4 nodes for column i / row j
    std::vector<std::array<double, 4>> colW, rowW;  // weights, pre-divided by √(Σw²)

    static std::array<double, 4> bspline(double u) {
        double u2 = u * u, u3 = u2 * u;
        return {(1 - u) * (1 - u) * (1 - u) / 6.0, (3 * u3 - 6 * u2 + 4) / 6.0,
                (-3 * u3 + 3 * u2 + 3 * u + 1) / 6.0, u3 / 6.0};
    }

    void setup(int count, double pitch, double c, std::vector<int>& node,
               std::vector<std::array<double, 4>>& w, int& nodes) {
        double half = 0.5 * (count - 1) * pitch;
        double origin = -half - 2 * c;
        nodes = static_cast<int>(std::ceil((2 * half + 4 * c) / c)) + 4;
        node.resize(static_cast<size_t>(count));
        w.resize(static_cast<size_t>(count));
        for (int i = 0; i < count; ++i) {
            double u = ((i - 0.5 * (count - 1)) * pitch - origin) / c;
            double fl = std::floor(u);
            auto k = static_cast<int>(fl);
            node[static_cast<size_t>(i)] = std::clamp(k - 1, 0, nodes - 4);
            std::array<double, 4> b = bspline(u - fl);
            double norm = std::sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2] + b[3] * b[3]);
            for (double& v : b) v /= norm;
            w[static_cast<size_t>(i)] = b;
        }
    }

    void build(const SurfaceSpec& spec) {
        rms = spec.roughnessRms;
        if (rms <= 0) return;
        double c = std::max(spec.roughnessCorrelation, spec.pitch);
        setup(spec.width, spec.pitch, c, colNode, colW, nx);
        setup(spec.height, spec.pitch, c, rowNode, rowW, nz);
        lattice.assign(static_cast<size_t>(nx) * nz, 0.0f);
        uint64_t key = mix64(spec.seed ^ kRoughStream);
        tbb::parallel_for(tbb::blocked_range<int>(0, nz), [&](const tbb::blocked_range<int>& r) {
            for (int b = r.begin(); b < r.end(); ++b) {
                Pcg32 rng(key, static_cast<uint64_t>(b));
                float* row = lattice.data() + static_cast<size_t>(b) * nx;
                for (int a = 0; a < nx; ++a) row[a] = static_cast<float>(gaussian(rng));
            }
        });
    }

    double at(int i, int j) const {
        if (rms <= 0) return 0.0;
        const auto& wx = colW[static_cast<size_t>(i)];
        const auto& wz = rowW[static_cast<size_t>(j)];
        int a0 = colNode[static_cast<size_t>(i)], b0 = rowNode[static_cast<size_t>(j)];
        double sum = 0;
        for (int b = 0; b < 4; ++b) {
            const float* row = lattice.data() + static_cast<size_t>(b0 + b) * nx + a0;
            double s = wx[0] * row[0] + wx[1] * row[1] + wx[2] * row[2] + wx[3] * row[3];
            sum += wz[static_cast<size_t>(b)] * s;
        }
        return rms * sum;
    }
};

}  // namespace

double scallopHeight(double stepover, double ballRadius) {
    if (!(std::isfinite(ballRadius) && ballRadius > 0))
        throw inputError("scallopHeight: ballRadius",
                         "must be > 0 mm, got " + formatNumber(ballRadius));
    if (!(std::isfinite(stepover) && stepover >= 0 && stepover <= 2 * ballRadius))
        throw inputError("scallopHeight: stepover",
                         "must be in [0, 2*ballRadius = " + formatNumber(2 * ballRadius) +
                             "] mm, got " + formatNumber(stepover));
    double a = 0.5 * stepover;
    return sphereRise(ballRadius, a * a);
}

namespace {

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
          ball(spec.process == SurfaceSpec::Process::BallEndRaster) {}
};

/// Stage 1: the tool paths that can shape the map, with their chatter and tooth phases.
ToolMarks toolMarks(const SurfaceSpec& spec, const Frame& fr) {
    const bool ball = fr.ball;
    const double extX = fr.extX, extZ = fr.extZ;
    const double angle = spec.rasterAngleDeg * kPi / 180.0;
    ToolMarks tm;
    tm.R = spec.toolRadius;
    tm.R2 = tm.R * tm.R;
    tm.rn = spec.insertNoseRadius;
    tm.s = spec.stepover;
    tm.off = spec.pathOffset;
    tm.f = spec.feedPerTooth;
    tm.feedMarks = ball ? (spec.ballFeedMarks && spec.feedPerTooth > 0) : true;
    tm.cosA = std::cos(angle);
    tm.sinA = std::sin(angle);
    tm.A = spec.chatterAmplitude;
    tm.omega = tm.A > 0 ? 2.0 * kPi / spec.chatterWavelength : 0.0;
    {
        // Paths that can shape a sample: ball-end, those within D* of it, where the ball has
        // risen by more than the worst cusp plus twice the chatter (the search stops there);
        // face mill, the pass indices ceil((p + R − off)/s) − 1 over the map's p range.
        double halfDiag = 0.5 * std::hypot(extX, extZ);
        double lo, hi;
        if (ball) {
            double hs = 0.5 * tm.s, hf = tm.feedMarks ? 0.5 * tm.f : 0.0;
            double need = sphereRise(tm.R, hs * hs + hf * hf) + 2 * tm.A;
            double reach = need >= tm.R ? tm.R : std::sqrt(need * (2 * tm.R - need));
            lo = -halfDiag - reach - 2 * tm.s;
            hi = halfDiag + reach + 2 * tm.s;
        } else {
            lo = -halfDiag + tm.R - 2 * tm.s;
            hi = halfDiag + tm.R + 2 * tm.s;
        }
        double count = (hi - lo) / tm.s;
        require(count < 5.0e7, "stepover",
                "gives " + formatNumber(count) + " tool paths across the map, too many",
                "Use a stepover of at least 1/5e7 of the map's diagonal");
        tm.kMin = static_cast<int64_t>(std::floor((lo - tm.off) / tm.s)) - 1;
        tm.kMax = static_cast<int64_t>(std::ceil((hi - tm.off) / tm.s)) + 1;
        auto n = static_cast<size_t>(tm.kMax - tm.kMin + 1);
        tm.chatCos.resize(n);
        tm.chatSin.resize(n);
        tm.toothPhase.resize(n);
        for (int64_t k = tm.kMin; k <= tm.kMax; ++k) {
            size_t i = tm.idx(k);
            double phi = 2.0 * kPi * hashUniform(spec.seed, kPathStream, 2 * k);
            tm.chatCos[i] = std::cos(phi);
            tm.chatSin[i] = std::sin(phi);
            tm.toothPhase[i] = tm.f * hashUniform(spec.seed, kPathStream, 2 * k + 1);
        }
    }
    return tm;
}

/// Stage 2: the pocket step's height per column (zero without a pocket edge); sets the edge's
/// position and half width in `out`.
std::vector<double> pocketColumns(const SurfaceSpec& spec, const Frame& fr, GeneratedSurface& out) {
    const int W = fr.W;
    const double cx = fr.cx, pitch = fr.pitch, extX = fr.extX;
    std::vector<double> pocket(static_cast<size_t>(W), 0.0);
    out.pocketEdgeX = std::numeric_limits<double>::quiet_NaN();
    out.pocketEdgeHalfWidth = std::numeric_limits<double>::quiet_NaN();
    if (spec.pocketEdge && spec.pocketDepth > 0) {
        out.pocketEdgeX = 0.5 * extX - spec.pocketWallFraction * extX;
        out.pocketEdgeHalfWidth = pocketHalfWidth(spec.pocketDepth, spec.cornerRadius);
        for (int i = 0; i < W; ++i)
            pocket[static_cast<size_t>(i)] = pocketProfile((i - cx) * pitch - out.pocketEdgeX,
                                                           spec.pocketDepth, spec.cornerRadius);
    }

    return pocket;
}

/// Stage 3: the scratches, given or drawn (stratified) from the seed; their specs into `out`.
std::vector<Scratch> placeScratches(const SurfaceSpec& spec, const Frame& fr,
                                    GeneratedSurface& out) {
    const int W = fr.W, H = fr.H;
    const double pitch = fr.pitch, extX = fr.extX, extZ = fr.extZ;
    std::vector<Scratch> scratches;
    if (!spec.scratches.empty()) {
        out.scratches = spec.scratches;
    } else {
        // Centres stratified (Latin hypercube over x and z) so scratches spread over the map.
        Pcg32 rng(mix64(spec.seed ^ kScratchStream), kScratchStream);
        const int count = spec.scratchCount;
        std::vector<int> sx(static_cast<size_t>(count)), sz(static_cast<size_t>(count));
        for (int n = 0; n < count; ++n) sx[static_cast<size_t>(n)] = sz[static_cast<size_t>(n)] = n;
        for (std::vector<int>* perm : {&sx, &sz})
            for (int n = count - 1; n > 0; --n)
                std::swap((*perm)[static_cast<size_t>(n)],
                          (*perm)[rng.nextU32() % static_cast<uint32_t>(n + 1)]);
        double shorter = std::min(extX, extZ);
        for (int n = 0; n < count; ++n) {
            double ux = (sx[static_cast<size_t>(n)] + rng.nextDouble()) / count;
            double uz = (sz[static_cast<size_t>(n)] + rng.nextDouble()) / count;
            double mx = (ux - 0.5) * 0.8 * extX;
            double mz = (uz - 0.5) * 0.8 * extZ;
            double len = (0.15 + 0.35 * rng.nextDouble()) * shorter;
            double th = kPi * rng.nextDouble();
            ScratchSpec c;
            c.depth = spec.scratchDepth * (0.5 + 0.5 * rng.nextDouble());
            c.width = spec.scratchWidth * (0.75 + 0.25 * rng.nextDouble());
            c.shape = rng.nextDouble() < 0.5 ? ScratchSpec::Shape::V : ScratchSpec::Shape::Round;
            c.x0 = mx - 0.5 * len * std::cos(th);
            c.z0 = mz - 0.5 * len * std::sin(th);
            c.x1 = mx + 0.5 * len * std::cos(th);
            c.z1 = mz + 0.5 * len * std::sin(th);
            out.scratches.push_back(c);
        }
    }
    for (const ScratchSpec& c : out.scratches) {
        Scratch sc{makeSegment(c.x0, c.z0, c.x1, c.z1, c.width, pitch, W, H), c, 0.0};
        sc.taper = std::min(0.25 * sc.seg.L, 5.0 * c.width);
        scratches.push_back(sc);
    }

    return scratches;
}

/// Stage 4: the gouges (tool digs), given or drawn from the seed off the pocket edge.
std::vector<Gouge> placeGouges(const SurfaceSpec& spec, const Frame& fr, const ToolMarks& tm,
                               GeneratedSurface& out) {
    const int W = fr.W, H = fr.H;
    const double pitch = fr.pitch, extX = fr.extX, extZ = fr.extZ;
    const bool ball = fr.ball;
    std::vector<Gouge> gouges;
    const double gougeRadius = ball ? spec.toolRadius : spec.insertNoseRadius;
    if (!spec.gouges.empty()) {
        out.gouges = spec.gouges;
    } else {
        // Kept off the pocket edge (redrawn up to 64 times), so that defects and the macro edge
        // stay apart and a detector's hits on either can be told apart.
        Pcg32 rng(mix64(spec.seed ^ kGougeStream), kGougeStream);
        const double keepOut = std::isfinite(out.pocketEdgeX)
                                   ? out.pocketEdgeHalfWidth + 0.5 * spec.gougeLength +
                                         std::sqrt(2.0 * gougeRadius * spec.gougeDepth) +
                                         0.5 * spec.stepover + 0.1
                                   : -1.0;
        for (int n = 0; n < spec.gougeCount; ++n) {
            double mx = 0, mz = 0;
            for (int attempt = 0; attempt < 64; ++attempt) {
                mx = (rng.nextDouble() - 0.5) * 0.6 * extX;
                mz = (rng.nextDouble() - 0.5) * 0.6 * extZ;
                if (!(std::abs(mx - out.pocketEdgeX) < keepOut)) break;
            }
            double t = mx * tm.cosA + mz * tm.sinA;
            double p = -mx * tm.sinA + mz * tm.cosA;
            if (ball) p = tm.off + std::nearbyint((p - tm.off) / tm.s) * tm.s;  // on a path
            double h = 0.5 * spec.gougeLength;
            GougeSpec g;
            g.depth = spec.gougeDepth;
            g.x0 = (t - h) * tm.cosA - p * tm.sinA;
            g.z0 = (t - h) * tm.sinA + p * tm.cosA;
            g.x1 = (t + h) * tm.cosA - p * tm.sinA;
            g.z1 = (t + h) * tm.sinA + p * tm.cosA;
            out.gouges.push_back(g);
        }
    }
    for (const GougeSpec& g : out.gouges) {
        // The crater ends where the sphere has risen above the lowest tool mark (−chatter):
        // rise(r) = D + A, i.e. r² = e·(2R − e) with e = D + A.
        double e = std::min(g.depth + tm.A, gougeRadius);
        double reach = std::min(std::sqrt(e * (2 * gougeRadius - e)) + 2 * pitch, gougeRadius);
        gouges.push_back({makeSegment(g.x0, g.z0, g.x1, g.z1, reach, pitch, W, H), g, gougeRadius});
    }

    return gouges;
}

/// Stage 5: every sample's height and truth label, row-parallel (each a pure function of the
/// spec).
void compose(const SurfaceSpec& spec, const Frame& fr, const ToolMarks& tm,
             const std::vector<double>& pocket, const std::vector<Scratch>& scratches,
             const std::vector<Gouge>& gouges, const Roughness& rough, GeneratedSurface& out) {
    const int W = fr.W, H = fr.H;
    const double pitch = fr.pitch, cx = fr.cx, cz = fr.cz;
    const bool ball = fr.ball;
    const size_t N = static_cast<size_t>(W) * H;
    const int chatterStart = static_cast<int>(std::ceil(spec.chatterStartFraction * W));
    const bool labelChatter = spec.chatterStartFraction > 0 && spec.chatterAmplitude > 0;
    out.heights.assign(N, 0.0f);
    out.truth.assign(N, 0);
    tbb::parallel_for(tbb::blocked_range<int>(0, H), [&](const tbb::blocked_range<int>& r) {
        std::vector<double> row(static_cast<size_t>(W));
        std::vector<uint8_t> cut(static_cast<size_t>(W));
        for (int j = r.begin(); j < r.end(); ++j) {
            const double z = (j - cz) * pitch;
            std::fill(cut.begin(), cut.end(), uint8_t{0});
            for (int i = 0; i < W; ++i) {
                double x = (i - cx) * pitch;
                double t = x * tm.cosA + z * tm.sinA;
                double p = -x * tm.sinA + z * tm.cosA;
                double sw = 0, cw = 0;
                if (tm.A > 0 && i >= chatterStart) {
                    sw = std::sin(tm.omega * t);
                    cw = std::cos(tm.omega * t);
                }
                row[static_cast<size_t>(i)] =
                    ball ? tm.ballEnd(t, p, sw, cw) : tm.faceMill(t, p, sw, cw);
            }
            for (const Gouge& g : gouges) {
                if (j < g.seg.j0 || j > g.seg.j1) continue;
                for (int i = g.seg.i0; i <= g.seg.i1; ++i) {
                    double hg = gougeSurface(g, (i - cx) * pitch, z);
                    double& h = row[static_cast<size_t>(i)];
                    if (hg < h) {
                        if (h - hg >= 0.1 * g.spec.depth && g.spec.depth > 0)
                            cut[static_cast<size_t>(i)] = 1;
                        h = hg;
                    }
                }
            }
            if (rough.rms > 0)
                for (int i = 0; i < W; ++i) row[static_cast<size_t>(i)] += rough.at(i, j);
            for (const Scratch& c : scratches) {
                if (j < c.seg.j0 || j > c.seg.j1) continue;
                for (int i = c.seg.i0; i <= c.seg.i1; ++i) {
                    bool inGroove = false;
                    row[static_cast<size_t>(i)] += scratchOffset(c, (i - cx) * pitch, z, inGroove);
                    if (inGroove && c.spec.depth > 0) cut[static_cast<size_t>(i)] = 1;
                }
            }
            float* dst = out.heights.data() + static_cast<size_t>(j) * W;
            uint8_t* tr = out.truth.data() + static_cast<size_t>(j) * W;
            for (int i = 0; i < W; ++i) {
                auto k = static_cast<size_t>(i);
                dst[i] = static_cast<float>(row[k] + pocket[k]);
                tr[i] = cut[k]                              ? kTruthDefect
                        : labelChatter && i >= chatterStart ? kTruthChatter
                                                            : uint8_t{0};
            }
        }
    });
}

/// Stage 6: the one-line description of what was generated.
std::string describe(const SurfaceSpec& spec, const Frame& fr, const ToolMarks& tm,
                     const GeneratedSurface& out) {
    const int W = fr.W, H = fr.H;
    const double pitch = fr.pitch, extX = fr.extX, extZ = fr.extZ;
    const bool ball = fr.ball;
    const bool labelChatter = spec.chatterStartFraction > 0 && spec.chatterAmplitude > 0;
    char buf[768];
    const double R = spec.toolRadius, s = spec.stepover;
    std::string marks;
    if (ball) {
        std::snprintf(buf, sizeof buf,
                      "ball-end raster R=%.4g mm, stepover %.4g mm at %.4g deg: scallop height "
                      "%.4g um (s^2/8R = %.4g um)%s",
                      R, s, spec.rasterAngleDeg, 1e3 * out.scallop, 1e3 * s * s / (8 * R),
                      tm.feedMarks ? "" : ", no feed marks");
        marks = buf;
        if (tm.feedMarks) {
            std::snprintf(buf, sizeof buf, ", feed marks %.4g mm (%.3g um)", tm.f,
                          1e3 * scallopHeight(tm.f, R));
            marks += buf;
        }
    } else {
        std::snprintf(buf, sizeof buf,
                      "face mill R=%.4g mm, pass spacing %.4g mm at %.4g deg, feed %.4g mm/tooth, "
                      "nose r=%.4g mm: feed-mark height %.4g um on the pass centre line",
                      R, s, spec.rasterAngleDeg, spec.feedPerTooth, spec.insertNoseRadius,
                      1e3 * out.scallop);
        marks = buf;
    }
    std::string chatterWhere;
    if (labelChatter) {
        std::snprintf(buf, sizeof buf, " on the last %.3g%% of the width in +x",
                      100.0 * (1.0 - spec.chatterStartFraction));
        chatterWhere = buf;
    }
    std::string pocketText = "no pocket edge";
    if (std::isfinite(out.pocketEdgeX)) {
        std::snprintf(buf, sizeof buf, "pocket step %.4g mm (r=%.4g mm) at x=%.4g mm",
                      spec.pocketDepth, spec.cornerRadius, out.pocketEdgeX);
        pocketText = buf;
    }
    std::snprintf(buf, sizeof buf,
                  "synthetic %dx%d @ %.4g mm (%.4g x %.4g mm): %s; chatter %.3g um / %.4g mm%s; "
                  "roughness %.3g um rms; %zu scratch(es), %zu gouge(s); %s; seed %llu",
                  W, H, pitch, extX, extZ, marks.c_str(), 1e3 * spec.chatterAmplitude,
                  spec.chatterWavelength, chatterWhere.c_str(), 1e3 * spec.roughnessRms,
                  out.scratches.size(), out.gouges.size(), pocketText.c_str(),
                  static_cast<unsigned long long>(spec.seed));
    return buf;
}

}  // namespace

GeneratedSurface generateSurface(const SurfaceSpec& spec) {
    validate(spec);
    const Frame fr(spec);
    GeneratedSurface out;
    out.width = spec.width;
    out.height = spec.height;
    out.pitch = spec.pitch;
    const ToolMarks tm = toolMarks(spec, fr);
    out.scallop = fr.ball ? scallopHeight(spec.stepover, spec.toolRadius)
                          : scallopHeight(spec.feedPerTooth, spec.insertNoseRadius);
    const std::vector<double> pocket = pocketColumns(spec, fr, out);
    const std::vector<Scratch> scratches = placeScratches(spec, fr, out);
    const std::vector<Gouge> gouges = placeGouges(spec, fr, tm, out);
    Roughness rough;
    rough.build(spec);
    compose(spec, fr, tm, pocket, scratches, gouges, rough, out);
    out.description = describe(spec, fr, tm, out);
    return out;
}

}  // namespace sl
