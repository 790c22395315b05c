// Synthetic NC-machined surfaces; see SurfaceGenerator.h for the model and conventions.
#include "synth/SurfaceGenerator.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "core/Error.h"
#include "core/Interrupt.h"
#include "core/Progress.h"
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
constexpr uint64_t kDentStream = 0x64656e7473303031ULL;
constexpr uint64_t kBandStream = 0x62616e6473303031ULL;
constexpr uint64_t kBurrStream = 0x6275727273303031ULL;
constexpr uint64_t kTurnStream = 0x7475726e73303031ULL;
constexpr uint64_t kNoiseStream = 0x6e6f697365303031ULL;
constexpr uint64_t kSpikeStream = 0x7370696b65303031ULL;

/// A SurfaceSpec field's option name: its dash-separated lower-case form (toolRadius:
/// 'tool-radius'; core/Error.h option()).
std::string optionName(const std::string& field) {
    std::string name;
    for (const char c : field) {
        if (std::isupper(static_cast<unsigned char>(c))) {
            name += '-';
            name += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
        } else {
            name += c;
        }
    }
    return name;
}

void require(bool ok, const std::string& field, const std::string& problem,
             const std::string& fix) {
    if (!ok) throw inputError(option(optionName(field)), problem, fix);
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
    // An insert of nose radius r cuts crescents only for a feed in (0, 2r) per tooth or turn.
    auto requireInsert = [&](const std::string& inserts, const std::string& feedIs,
                             const std::string& typicalFeeds) {
        requireFinite(s.insertNoseRadius, "insertNoseRadius");
        require(s.insertNoseRadius > 0, "insertNoseRadius",
                "must be > 0 mm, got " + formatNumber(s.insertNoseRadius), "Typical " + inserts);
        require(s.feedPerTooth > 0 && s.feedPerTooth < 2 * s.insertNoseRadius, "feedPerTooth",
                "must be in (0, 2*insertNoseRadius = " + formatNumber(2 * s.insertNoseRadius) +
                    ") mm " + feedIs + ", got " + formatNumber(s.feedPerTooth),
                "Typical finishing feeds: " + typicalFeeds);
    };
    if (s.process == SurfaceSpec::Process::FaceMillFeed)
        requireInsert("inserts: 0.4-1.2 mm", "for a face mill", "0.05-0.2 mm per tooth");
    if (s.process == SurfaceSpec::Process::FlatEndPocket) {
        requireFinite(s.toolCornerRadius, "toolCornerRadius");
        require(s.toolCornerRadius > 0 && s.toolCornerRadius <= s.toolRadius, "toolCornerRadius",
                "must be in (0, toolRadius = " + formatNumber(s.toolRadius) + "] mm, got " +
                    formatNumber(s.toolCornerRadius),
                "Typical corner radii: 0.1-0.5 mm");
        require(s.feedPerTooth < 2 * s.toolCornerRadius, "feedPerTooth",
                "must be < 2*toolCornerRadius = " + formatNumber(2 * s.toolCornerRadius) +
                    " mm for a flat end mill, got " + formatNumber(s.feedPerTooth),
                "Typical finishing feeds: 0.02-0.1 mm per tooth (0: no feed marks)");
        double hs = 0.5 * s.stepover;
        require(std::hypot(hs, s.feedPerTooth) < s.toolRadius, "feedPerTooth",
                "with stepover " + formatNumber(s.stepover) + " mm the flat end mill of radius " +
                    formatNumber(s.toolRadius) + " mm leaves uncut material at feed " +
                    formatNumber(s.feedPerTooth) + " mm",
                "Reduce feedPerTooth or stepover");
    }
    if (s.process == SurfaceSpec::Process::Turned) {
        requireInsert("turning inserts: 0.2-1.6 mm", "per revolution for turning",
                      "0.05-0.2 mm per revolution");
        requireFinite(s.turnCentreX, "turnCentreX");
        requireFinite(s.turnCentreZ, "turnCentreZ");
    }
    requireFinite(s.chatterAmplitude, "chatterAmplitude");
    require(s.chatterAmplitude >= 0, "chatterAmplitude",
            "must be >= 0 mm, got " + formatNumber(s.chatterAmplitude), "Use 0 to disable chatter");
    requireFinite(s.chatterStartFraction, "chatterStartFraction");
    require(s.chatterStartFraction >= 0 && s.chatterStartFraction < 1, "chatterStartFraction",
            "must be in [0, 1), got " + formatNumber(s.chatterStartFraction),
            "Use 0 for chatter everywhere, 0.5 for the right half");
    require(s.chatterBands >= 0 && s.chatterBands <= 10000, "chatterBands",
            "must be in [0, 10000], got " + std::to_string(s.chatterBands),
            "Use 0 for no chatter bands");
    if (s.chatterBands > 0) {
        requireFinite(s.chatterBandWidth, "chatterBandWidth");
        require(s.chatterBandWidth > 0, "chatterBandWidth",
                "must be > 0 mm, got " + formatNumber(s.chatterBandWidth),
                "Set the width of a chatter band across the paths in mm, e.g. 0.8");
        requireFinite(s.chatterBandAmplitude, "chatterBandAmplitude");
        require(s.chatterBandAmplitude > 0, "chatterBandAmplitude",
                "must be > 0 mm, got " + formatNumber(s.chatterBandAmplitude),
                "Set the chatter amplitude inside the bands in mm, or chatterBands = 0");
    }
    if (s.chatterAmplitude > 0 || s.chatterBands > 0) {
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
        for (auto [v, field] :
             {std::pair{s.scratchDepthMin, "scratchDepthMin"},
              std::pair{s.scratchWidthMin, "scratchWidthMin"},
              std::pair{s.scratchDirectionDeg, "scratchDirectionDeg"},
              std::pair{s.scratchDirectionSpreadDeg, "scratchDirectionSpreadDeg"}})
            requireFinite(v, field);
        require(s.scratchDepthMin >= 0 && s.scratchDepthMin <= 1, "scratchDepthMin",
                "must be in [0, 1], got " + formatNumber(s.scratchDepthMin),
                "It is the shallowest random scratch as a fraction of scratchDepth");
        require(s.scratchWidthMin > 0 && s.scratchWidthMin <= 1, "scratchWidthMin",
                "must be in (0, 1], got " + formatNumber(s.scratchWidthMin),
                "It is the narrowest random scratch as a fraction of scratchWidth");
        require(s.scratchDirectionSpreadDeg >= 0 && s.scratchDirectionSpreadDeg <= 180,
                "scratchDirectionSpreadDeg",
                "must be in [0, 180] degrees, got " + formatNumber(s.scratchDirectionSpreadDeg),
                "Use 180 for any direction, 0 for all along scratchDirectionDeg");
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
    if (s.dents.empty()) {
        require(s.dentCount >= 0 && s.dentCount <= 100000, "dentCount",
                "must be in [0, 100000], got " + std::to_string(s.dentCount), "Use 0 for no dents");
        if (s.dentCount > 0) {
            requireFinite(s.dentDepth, "dentDepth");
            requireFinite(s.dentRadius, "dentRadius");
            require(s.dentRadius > 0, "dentRadius",
                    "must be > 0 mm, got " + formatNumber(s.dentRadius),
                    "The indenter's radius in mm, e.g. 0.5");
            require(s.dentDepth >= 0 && s.dentDepth <= s.dentRadius, "dentDepth",
                    "must be in [0, dentRadius = " + formatNumber(s.dentRadius) + "] mm, got " +
                        formatNumber(s.dentDepth),
                    "Dent depths are in mm, e.g. 0.005");
        }
    }
    for (size_t n = 0; n < s.dents.size(); ++n) {
        const DentSpec& d = s.dents[n];
        std::string f = "dents[" + std::to_string(n) + "]";
        for (double v : {d.x, d.z, d.depth, d.radius}) requireFinite(v, f);
        require(d.radius > 0, f + ".radius", "must be > 0 mm, got " + formatNumber(d.radius),
                "The indenter's radius in mm");
        require(d.depth >= 0 && d.depth <= d.radius, f + ".depth",
                "must be in [0, radius] mm, got " + formatNumber(d.depth),
                "Dent depths are in mm, positive into the part");
    }
    requireFinite(s.pocketBurrHeight, "pocketBurrHeight");
    require(s.pocketBurrHeight >= 0, "pocketBurrHeight",
            "must be >= 0 mm, got " + formatNumber(s.pocketBurrHeight), "Use 0 for no burr");
    if (s.pocketBurrHeight > 0) {
        require(s.pocketEdge && s.pocketDepth > 0, "pocketBurrHeight",
                "a burr sits on the pocket edge, and there is none",
                "Keep the pocket edge (pocketEdge = true, pocketDepth > 0) or set it to 0");
        requireFinite(s.pocketBurrWidth, "pocketBurrWidth");
        require(s.pocketBurrWidth > 0, "pocketBurrWidth",
                "must be > 0 mm, got " + formatNumber(s.pocketBurrWidth),
                "The burr's width across the edge in mm, e.g. 0.04");
    }
    requireFinite(s.toolChangeStep, "toolChangeStep");
    if (s.toolChangeStep != 0) {
        requireFinite(s.toolChangeAt, "toolChangeAt");
        requireFinite(s.toolChangeWidth, "toolChangeWidth");
        require(s.toolChangeWidth >= 0, "toolChangeWidth",
                "must be >= 0 mm, got " + formatNumber(s.toolChangeWidth),
                "The width of the step's ramp in mm (at least 2 samples are used)");
    }
    requireFinite(s.noiseRms, "noiseRms");
    require(s.noiseRms >= 0, "noiseRms", "must be >= 0 mm, got " + formatNumber(s.noiseRms),
            "Use 0 for no measurement noise");
    require(s.spikeCount >= 0 && s.spikeCount <= 1000000, "spikeCount",
            "must be in [0, 1000000], got " + std::to_string(s.spikeCount), "Use 0 for no spikes");
    if (s.spikeCount > 0) {
        requireFinite(s.spikeHeight, "spikeHeight");
        require(s.spikeHeight >= 0, "spikeHeight",
                "must be >= 0 mm, got " + formatNumber(s.spikeHeight),
                "It is the largest spike's height; each spike's sign is random");
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

/// Scratch height offset at (x, z); sets `cut` when inside the groove (truth), `lip` where the
/// lip is ≥ 10% of its height.
double scratchOffset(const Scratch& c, double x, double z, bool& cut, bool& lip) {
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
    if (fade >= 0.1 && b * b >= 0.1) lip = true;
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

double flatEndRidgeHeight(double stepover, double toolRadius, double cornerRadius) {
    if (!(std::isfinite(toolRadius) && toolRadius > 0))
        throw inputError("flatEndRidgeHeight: toolRadius",
                         "must be > 0 mm, got " + formatNumber(toolRadius));
    if (!(std::isfinite(cornerRadius) && cornerRadius > 0 && cornerRadius <= toolRadius))
        throw inputError("flatEndRidgeHeight: cornerRadius",
                         "must be in (0, toolRadius] mm, got " + formatNumber(cornerRadius));
    if (!(std::isfinite(stepover) && stepover >= 0 && stepover <= 2 * toolRadius))
        throw inputError("flatEndRidgeHeight: stepover",
                         "must be in [0, 2*toolRadius = " + formatNumber(2 * toolRadius) +
                             "] mm, got " + formatNumber(stepover));
    double e = 0.5 * stepover - (toolRadius - cornerRadius);
    return e > 0 ? sphereRise(cornerRadius, e * e) : 0.0;
}

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
          ball(spec.process == SurfaceSpec::Process::BallEndRaster),
          process(spec.process) {}
    SurfaceSpec::Process process;
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
    tm.maxA = tm.A;
    tm.process = spec.process;
    if (spec.chatterBands > 0) {
        tm.maxA = std::max(tm.A, spec.chatterBandAmplitude);
        tm.omega = 2.0 * kPi / spec.chatterWavelength;
    }
    if (spec.process == SurfaceSpec::Process::FlatEndPocket) {
        tm.rc = spec.toolCornerRadius;
        tm.af = tm.R - tm.rc;
        tm.feedMarks = spec.feedPerTooth > 0;
    }
    if (spec.process == SurfaceSpec::Process::Turned) {
        // No path table: one spiral, its phase and the chatter's phase from the seed.
        tm.xc = spec.turnCentreX;
        tm.zc = spec.turnCentreZ;
        tm.turnPhase = hashUniform(spec.seed, kTurnStream, 0);
        tm.turnChatterPhase = 2.0 * kPi * hashUniform(spec.seed, kTurnStream, 1);
        tm.chatCos.assign(1, 1.0);
        tm.chatSin.assign(1, 0.0);
        tm.toothPhase.assign(1, 0.0);
        return tm;
    }
    {
        // Paths that can shape a sample: ball-end, those within D* of it, where the ball has
        // risen by more than the worst cusp plus twice the chatter (the search stops there);
        // face mill, the pass indices ceil((p + R − off)/s) − 1 over the map's p range.
        double halfDiag = 0.5 * std::hypot(extX, extZ);
        double lo, hi;
        if (ball) {
            double hs = 0.5 * tm.s, hf = tm.feedMarks ? 0.5 * tm.f : 0.0;
            double need = sphereRise(tm.R, hs * hs + hf * hf) + 2 * tm.maxA;
            double reach = need >= tm.R ? tm.R : std::sqrt(need * (2 * tm.R - need));
            lo = -halfDiag - reach - 2 * tm.s;
            hi = halfDiag + reach + 2 * tm.s;
        } else if (spec.process == SurfaceSpec::Process::FlatEndPocket) {
            lo = -halfDiag - tm.R - 2 * tm.s;
            hi = halfDiag + tm.R + 2 * tm.s;
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
            const double uth = rng.nextDouble();
            // Spread 180°: any direction (the draw of before the spread existed, bit for bit).
            const double th =
                spec.scratchDirectionSpreadDeg >= 180
                    ? kPi * uth
                    : (spec.scratchDirectionDeg + spec.scratchDirectionSpreadDeg * (uth - 0.5)) *
                          kPi / 180.0;
            const double dMin = spec.scratchDepthMin, wMin = spec.scratchWidthMin;
            ScratchSpec c;
            c.depth = spec.scratchDepth * (dMin + (1.0 - dMin) * rng.nextDouble());
            c.width = spec.scratchWidth * (wMin + (1.0 - wMin) * rng.nextDouble());
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
    const double gougeRadius = ball ? spec.toolRadius
                               : fr.process == SurfaceSpec::Process::FlatEndPocket
                                   ? spec.toolCornerRadius
                                   : spec.insertNoseRadius;
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
        double e = std::min(g.depth + tm.maxA, gougeRadius);
        double reach = std::min(std::sqrt(e * (2 * gougeRadius - e)) + 2 * pitch, gougeRadius);
        gouges.push_back({makeSegment(g.x0, g.z0, g.x1, g.z1, reach, pitch, W, H), g, gougeRadius});
    }

    return gouges;
}

/// A dent's bounding box in samples and its reach² (where the sphere has risen by its depth).
struct Dent {
    DentSpec spec;
    double reach2 = 0;
    int i0 = 0, i1 = -1, j0 = 0, j1 = -1;
};

/// Dent height offset (≤ 0) at (x, z); sets `hit` where it lowers by ≥ 10% of the depth.
double dentOffset(const Dent& d, double x, double z, bool& hit) {
    double dx = x - d.spec.x, dz = z - d.spec.z;
    double r2 = dx * dx + dz * dz;
    if (r2 >= d.reach2) return 0.0;
    double lower = d.spec.depth - sphereRise(d.spec.radius, r2);
    if (lower <= 0) return 0.0;
    if (lower >= 0.1 * d.spec.depth) hit = true;
    return -lower;
}

/// Stage 4b: the dents, given or drawn from the seed (uniform over the inner 80% of the map,
/// off the pocket edge).
std::vector<Dent> placeDents(const SurfaceSpec& spec, const Frame& fr, GeneratedSurface& out) {
    if (!spec.dents.empty()) {
        out.dents = spec.dents;
    } else if (spec.dentCount > 0) {
        Pcg32 rng(mix64(spec.seed ^ kDentStream), kDentStream);
        const double R = spec.dentRadius, D = spec.dentDepth;
        const double keepOut = std::isfinite(out.pocketEdgeX)
                                   ? out.pocketEdgeHalfWidth + std::sqrt(D * (2 * R - D)) + 0.1
                                   : -1.0;
        for (int n = 0; n < spec.dentCount; ++n) {
            DentSpec d;
            for (int attempt = 0; attempt < 64; ++attempt) {
                d.x = (rng.nextDouble() - 0.5) * 0.8 * fr.extX;
                d.z = (rng.nextDouble() - 0.5) * 0.8 * fr.extZ;
                if (!(std::abs(d.x - out.pocketEdgeX) < keepOut)) break;
            }
            d.depth = D * (0.5 + 0.5 * rng.nextDouble());
            d.radius = R;
            out.dents.push_back(d);
        }
    }
    std::vector<Dent> dents;
    for (const DentSpec& d : out.dents) {
        Dent dt;
        dt.spec = d;
        dt.reach2 = d.depth * (2 * d.radius - d.depth);
        double reach = std::sqrt(dt.reach2) + fr.pitch;
        auto lo = [&](double v, double c, int n) {
            return static_cast<int>(std::clamp(std::floor(v / fr.pitch + c), 0.0, n - 1.0));
        };
        auto hi = [&](double v, double c, int n) {
            return static_cast<int>(std::clamp(std::ceil(v / fr.pitch + c), -1.0, n - 1.0));
        };
        if (d.x + reach < -0.5 * fr.extX || d.x - reach > 0.5 * fr.extX ||
            d.z + reach < -0.5 * fr.extZ || d.z - reach > 0.5 * fr.extZ)
            continue;  // off the map
        dt.i0 = lo(d.x - reach, fr.cx, fr.W);
        dt.i1 = hi(d.x + reach, fr.cx, fr.W);
        dt.j0 = lo(d.z - reach, fr.cz, fr.H);
        dt.j1 = hi(d.z + reach, fr.cz, fr.H);
        dents.push_back(dt);
    }
    return dents;
}

/// The range of the across-path coordinate c over the map: p for milling, the distance to the
/// turning centre for Turned.
std::pair<double, double> acrossRange(const Frame& fr, const ToolMarks& tm) {
    const double hx = 0.5 * fr.extX, hz = 0.5 * fr.extZ;
    if (fr.process == SurfaceSpec::Process::Turned) {
        double nx = std::max(0.0, std::abs(tm.xc) - hx), nz = std::max(0.0, std::abs(tm.zc) - hz);
        return {std::hypot(nx, nz), std::hypot(std::abs(tm.xc) + hx, std::abs(tm.zc) + hz)};
    }
    double h = std::abs(tm.sinA) * hx + std::abs(tm.cosA) * hz;
    return {-h, h};
}

/// Stage 4c: the chatter bands' centres (across-path coordinate), uniform over the map's range.
std::vector<double> placeChatterBands(const SurfaceSpec& spec, const Frame& fr,
                                      const ToolMarks& tm) {
    std::vector<double> bands;
    if (spec.chatterBands <= 0) return bands;
    Pcg32 rng(mix64(spec.seed ^ kBandStream), kBandStream);
    auto [lo, hi] = acrossRange(fr, tm);
    const double w = spec.chatterBandWidth;
    for (int n = 0; n < spec.chatterBands; ++n) {
        const double u = rng.nextDouble();
        // A band wider than the map's range is centred on it.
        bands.push_back(hi - lo > w ? lo + 0.5 * w + u * (hi - lo - w) : 0.5 * (lo + hi));
    }
    return bands;
}

/// The pocket-edge burr: its profile across the edge per column and its height along it per
/// row (both 0 without a burr).
struct Burr {
    std::vector<double> across, along;
};

/// Stage 4d: the burr on the pocket's top edge (see the header).
Burr placeBurr(const SurfaceSpec& spec, const Frame& fr, const GeneratedSurface& out) {
    Burr b;
    if (!(spec.pocketBurrHeight > 0) || !std::isfinite(out.pocketEdgeX)) return b;
    b.across.assign(static_cast<size_t>(fr.W), 0.0);
    b.along.assign(static_cast<size_t>(fr.H), 0.0);
    const double xTop = out.pocketEdgeX - out.pocketEdgeHalfWidth;
    const double half = 0.5 * spec.pocketBurrWidth;
    for (int i = 0; i < fr.W; ++i) {
        double u = ((i - fr.cx) * fr.pitch - xTop) / half;
        double v = 1.0 - u * u;
        b.across[static_cast<size_t>(i)] = std::abs(u) < 1.0 ? v * v : 0.0;
    }
    constexpr double kSpacing = 0.25;  // mm between the random values along the edge
    for (int j = 0; j < fr.H; ++j) {
        double a = (j * fr.pitch) / kSpacing;  // from the map's −z edge
        double fl = std::floor(a);
        auto k = static_cast<int64_t>(fl);
        double v0 = hashUniform(spec.seed, kBurrStream, k);
        double v1 = hashUniform(spec.seed, kBurrStream, k + 1);
        double g = 0.5 + 0.5 * (v0 + (v1 - v0) * smoothstep01(a - fl));
        b.along[static_cast<size_t>(j)] = spec.pocketBurrHeight * g;
    }
    return b;
}

/// The stages' results that compose puts together.
struct Features {
    std::vector<double> pocket;
    std::vector<Scratch> scratches;
    std::vector<Gouge> gouges;
    std::vector<Dent> dents;
    std::vector<double> bands;
    Burr burr;
};

/// Stage 5: every sample's height and truth label, row-parallel (each a pure function of the
/// spec). Labels combine by max: the higher value wins (see the header).
void compose(const SurfaceSpec& spec, const Frame& fr, const ToolMarks& tm, const Features& ft,
             const Roughness& rough, GeneratedSurface& out) {
    const int W = fr.W, H = fr.H;
    const double pitch = fr.pitch, cx = fr.cx, cz = fr.cz;
    const size_t N = static_cast<size_t>(W) * H;
    const int chatterStart = static_cast<int>(std::ceil(spec.chatterStartFraction * W));
    const bool labelChatter = spec.chatterStartFraction > 0 && spec.chatterAmplitude > 0;
    const bool turned = fr.process == SurfaceSpec::Process::Turned;
    const double bandHalf = 0.5 * spec.chatterBandWidth;
    const bool stepOn = spec.toolChangeStep != 0;
    const double stepW = std::max(spec.toolChangeWidth, 2 * pitch);
    const bool burrOn = !ft.burr.across.empty();
    const uint64_t noiseKey = mix64(spec.seed ^ kNoiseStream);
    out.heights.assign(N, 0.0f);
    out.truth.assign(N, 0);
    tbb::parallel_for(tbb::blocked_range<int>(0, H), [&](const tbb::blocked_range<int>& r) {
        throwIfInterrupted();
        std::vector<double> row(static_cast<size_t>(W)), across(static_cast<size_t>(W));
        std::vector<uint8_t> lab(static_cast<size_t>(W));
        auto mark = [&](int i, uint8_t v) {
            uint8_t& l = lab[static_cast<size_t>(i)];
            l = std::max(l, v);
        };
        for (int j = r.begin(); j < r.end(); ++j) {
            const double z = (j - cz) * pitch;
            std::fill(lab.begin(), lab.end(), uint8_t{0});
            for (int i = 0; i < W; ++i) {
                double x = (i - cx) * pitch;
                double t = x * tm.cosA + z * tm.sinA;
                double p = -x * tm.sinA + z * tm.cosA;
                double c = p, rad = 0, theta = 0;
                if (turned) {
                    double dx = x - tm.xc, dz = z - tm.zc;
                    rad = std::hypot(dx, dz);
                    theta = std::atan2(dz, dx);
                    c = rad;
                }
                across[static_cast<size_t>(i)] = c;
                double amp = tm.A;
                bool active = i >= chatterStart;
                for (double b : ft.bands)
                    if (std::abs(c - b) < bandHalf) {
                        amp = spec.chatterBandAmplitude;
                        active = true;
                        mark(i, kTruthChatterBand);
                        break;
                    }
                double sw = 0, cw = 0;
                if (amp > 0 && active && !turned) {
                    sw = std::sin(tm.omega * t);
                    cw = std::cos(tm.omega * t);
                }
                double h = 0;
                switch (fr.process) {
                    case SurfaceSpec::Process::BallEndRaster:
                        h = tm.ballEnd(t, p, sw, cw, amp);
                        break;
                    case SurfaceSpec::Process::FaceMillFeed:
                        h = tm.faceMill(t, p, sw, cw, amp);
                        break;
                    case SurfaceSpec::Process::FlatEndPocket:
                        h = tm.flatEnd(t, p, sw, cw, amp);
                        break;
                    case SurfaceSpec::Process::Turned:
                        h = tm.turned(rad, theta, amp, active);
                        break;
                }
                row[static_cast<size_t>(i)] = h;
            }
            for (const Gouge& g : ft.gouges) {
                if (j < g.seg.j0 || j > g.seg.j1) continue;
                for (int i = g.seg.i0; i <= g.seg.i1; ++i) {
                    double hg = gougeSurface(g, (i - cx) * pitch, z);
                    double& h = row[static_cast<size_t>(i)];
                    if (hg < h) {
                        if (h - hg >= 0.1 * g.spec.depth && g.spec.depth > 0) mark(i, kTruthDefect);
                        h = hg;
                    }
                }
            }
            if (rough.rms > 0)
                for (int i = 0; i < W; ++i) row[static_cast<size_t>(i)] += rough.at(i, j);
            for (const Scratch& c : ft.scratches) {
                if (j < c.seg.j0 || j > c.seg.j1) continue;
                for (int i = c.seg.i0; i <= c.seg.i1; ++i) {
                    bool inGroove = false, lip = false;
                    row[static_cast<size_t>(i)] +=
                        scratchOffset(c, (i - cx) * pitch, z, inGroove, lip);
                    if (inGroove && c.spec.depth > 0) mark(i, kTruthDefect);
                    if (lip && spec.labelScratchLips && c.spec.depth > 0 && c.spec.burr > 0)
                        mark(i, kTruthBurr);
                }
            }
            for (const Dent& d : ft.dents) {
                if (j < d.j0 || j > d.j1) continue;
                for (int i = d.i0; i <= d.i1; ++i) {
                    bool hit = false;
                    row[static_cast<size_t>(i)] += dentOffset(d, (i - cx) * pitch, z, hit);
                    if (hit) mark(i, kTruthDent);
                }
            }
            if (burrOn) {
                const double hb = ft.burr.along[static_cast<size_t>(j)];
                for (int i = 0; i < W; ++i) {
                    const double b = ft.burr.across[static_cast<size_t>(i)];
                    if (b <= 0) continue;
                    row[static_cast<size_t>(i)] += hb * b;
                    if (b >= 0.1) mark(i, kTruthBurr);
                }
            }
            if (stepOn) {
                for (int i = 0; i < W; ++i) {
                    double d = across[static_cast<size_t>(i)] - spec.toolChangeAt;
                    double ramp = smoothstep01(d / stepW + 0.5);
                    if (ramp <= 0) continue;
                    row[static_cast<size_t>(i)] -= spec.toolChangeStep * ramp;
                    if (std::abs(d) < 0.5 * stepW && ramp >= 0.1) mark(i, kTruthToolChange);
                }
            }
            float* dst = out.heights.data() + static_cast<size_t>(j) * W;
            uint8_t* tr = out.truth.data() + static_cast<size_t>(j) * W;
            if (spec.noiseRms > 0) {
                Pcg32 rng(noiseKey, static_cast<uint64_t>(j));
                for (int i = 0; i < W; ++i) {
                    auto k = static_cast<size_t>(i);
                    dst[i] =
                        static_cast<float>(row[k] + ft.pocket[k] + spec.noiseRms * gaussian(rng));
                }
            } else {
                for (int i = 0; i < W; ++i) {
                    auto k = static_cast<size_t>(i);
                    dst[i] = static_cast<float>(row[k] + ft.pocket[k]);
                }
            }
            for (int i = 0; i < W; ++i) {
                auto k = static_cast<size_t>(i);
                const uint8_t region =
                    labelChatter && i >= chatterStart ? kTruthChatter : uint8_t{0};
                tr[i] = std::max(lab[k], region);
            }
        }
    });
}

/// Stage 6b: measurement spikes at random samples (after everything).
void addSpikes(const SurfaceSpec& spec, GeneratedSurface& out) {
    if (spec.spikeCount <= 0) return;
    Pcg32 rng(mix64(spec.seed ^ kSpikeStream), kSpikeStream);
    for (int n = 0; n < spec.spikeCount; ++n) {
        Spike sp;
        sp.i = std::min(out.width - 1, static_cast<int>(rng.nextDouble() * out.width));
        sp.j = std::min(out.height - 1, static_cast<int>(rng.nextDouble() * out.height));
        double sign = rng.nextDouble() < 0.5 ? -1.0 : 1.0;
        sp.height = sign * spec.spikeHeight * (0.5 + 0.5 * rng.nextDouble());
        float& h = out.heights[static_cast<size_t>(sp.j) * out.width + sp.i];
        h = static_cast<float>(h + sp.height);
        out.spikes.push_back(sp);
    }
}

/// Stage 6: the one-line description of what was generated.
std::string describe(const SurfaceSpec& spec, const Frame& fr, const ToolMarks& tm,
                     const GeneratedSurface& out) {
    const int W = fr.W, H = fr.H;
    const double pitch = fr.pitch, extX = fr.extX, extZ = fr.extZ;
    const bool ball = fr.ball;
    const bool labelChatter = spec.chatterStartFraction > 0 && spec.chatterAmplitude > 0;
    char buf[1024];
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
    } else if (fr.process == SurfaceSpec::Process::FaceMillFeed) {
        std::snprintf(buf, sizeof buf,
                      "face mill R=%.4g mm, pass spacing %.4g mm at %.4g deg, feed %.4g mm/tooth, "
                      "nose r=%.4g mm: feed-mark height %.4g um on the pass centre line",
                      R, s, spec.rasterAngleDeg, spec.feedPerTooth, spec.insertNoseRadius,
                      1e3 * out.scallop);
        marks = buf;
    } else if (fr.process == SurfaceSpec::Process::FlatEndPocket) {
        std::snprintf(buf, sizeof buf,
                      "flat end mill R=%.4g mm, corner r=%.4g mm, stepover %.4g mm at %.4g deg: "
                      "step-over ridge %.4g um",
                      R, spec.toolCornerRadius, s, spec.rasterAngleDeg, 1e3 * out.scallop);
        marks = buf;
        if (tm.feedMarks) {
            std::snprintf(buf, sizeof buf, ", feed %.4g mm/tooth (floor marks %.4g um)",
                          spec.feedPerTooth, 1e3 * out.feedMark);
            marks += buf;
        } else {
            marks += ", no feed marks";
        }
    } else {
        std::snprintf(buf, sizeof buf,
                      "face turning about (%.4g, %.4g) mm, nose r=%.4g mm, feed %.4g mm/rev: "
                      "groove cusp %.4g um",
                      spec.turnCentreX, spec.turnCentreZ, spec.insertNoseRadius, spec.feedPerTooth,
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
    // The opt-in kinds, named only when present (so earlier settings read as they always did).
    std::string extras;
    if (!out.chatterBands.empty()) {
        std::snprintf(buf, sizeof buf, "; %zu chatter band(s) %.3g um, %.4g mm wide",
                      out.chatterBands.size(), 1e3 * spec.chatterBandAmplitude,
                      spec.chatterBandWidth);
        extras += buf;
    }
    if (!out.dents.empty()) {
        std::snprintf(buf, sizeof buf, "; %zu dent(s)", out.dents.size());
        extras += buf;
    }
    if (spec.pocketBurrHeight > 0) {
        std::snprintf(buf, sizeof buf, "; burr %.3g um on the pocket edge",
                      1e3 * spec.pocketBurrHeight);
        extras += buf;
    }
    if (spec.labelScratchLips) extras += "; scratch lips labelled burr";
    if (spec.toolChangeStep != 0) {
        std::snprintf(buf, sizeof buf, "; tool-change step %.3g um at %s %.4g mm",
                      1e3 * spec.toolChangeStep,
                      fr.process == SurfaceSpec::Process::Turned ? "radius" : "across-path p",
                      spec.toolChangeAt);
        extras += buf;
    }
    if (spec.noiseRms > 0 || spec.spikeCount > 0) {
        std::snprintf(buf, sizeof buf, "; measurement noise %.3g um rms, %d spike(s) of %.3g um",
                      1e3 * spec.noiseRms, spec.spikeCount, 1e3 * spec.spikeHeight);
        extras += buf;
    }
    std::snprintf(buf, sizeof buf,
                  "synthetic %dx%d @ %.4g mm (%.4g x %.4g mm): %s; chatter %.3g um / %.4g mm%s; "
                  "roughness %.3g um rms; %zu scratch(es), %zu gouge(s); %s%s; seed %llu",
                  W, H, pitch, extX, extZ, marks.c_str(), 1e3 * spec.chatterAmplitude,
                  spec.chatterWavelength, chatterWhere.c_str(), 1e3 * spec.roughnessRms,
                  out.scratches.size(), out.gouges.size(), pocketText.c_str(), extras.c_str(),
                  static_cast<unsigned long long>(spec.seed));
    return buf;
}

}  // namespace

GeneratedSurface generateSurface(const SurfaceSpec& spec) {
    validate(spec);
    const ProgressTask task("generating " + std::to_string(spec.width) + "x" +
                            std::to_string(spec.height) + " surface");
    const Frame fr(spec);
    GeneratedSurface out;
    out.width = spec.width;
    out.height = spec.height;
    out.pitch = spec.pitch;
    const ToolMarks tm = toolMarks(spec, fr);
    switch (spec.process) {
        case SurfaceSpec::Process::BallEndRaster:
            out.scallop = scallopHeight(spec.stepover, spec.toolRadius);
            out.feedMark = tm.feedMarks ? scallopHeight(spec.feedPerTooth, spec.toolRadius) : 0.0;
            break;
        case SurfaceSpec::Process::FaceMillFeed:
            out.scallop = scallopHeight(spec.feedPerTooth, spec.insertNoseRadius);
            out.feedMark = out.scallop;
            break;
        case SurfaceSpec::Process::FlatEndPocket:
            out.scallop = flatEndRidgeHeight(spec.stepover, spec.toolRadius, spec.toolCornerRadius);
            out.feedMark = scallopHeight(spec.feedPerTooth, spec.toolCornerRadius);
            break;
        case SurfaceSpec::Process::Turned:
            out.scallop = scallopHeight(spec.feedPerTooth, spec.insertNoseRadius);
            out.feedMark = out.scallop;
            break;
    }
    // Ctrl-C (core/Interrupt.h): stop between the stages and between the rows' blocks; nothing
    // is written (the caller writes only a finished surface).
    throwIfInterrupted();
    Features ft;
    ft.pocket = pocketColumns(spec, fr, out);
    ft.scratches = placeScratches(spec, fr, out);
    ft.gouges = placeGouges(spec, fr, tm, out);
    ft.dents = placeDents(spec, fr, out);
    ft.bands = placeChatterBands(spec, fr, tm);
    out.chatterBands = ft.bands;
    ft.burr = placeBurr(spec, fr, out);
    throwIfInterrupted();
    Roughness rough;
    rough.build(spec);
    throwIfInterrupted();
    compose(spec, fr, tm, ft, rough, out);
    throwIfInterrupted();
    addSpikes(spec, out);
    out.description = describe(spec, fr, tm, out);
    return out;
}

namespace {

constexpr TruthKind kTruthKinds[] = {
    {kTruthDefect, "defect", "scratch grooves and gouges"},
    {kTruthScratch, "scratch", "inserted scratches (insert-defects, model A)"},
    {kTruthGouge, "gouge", "inserted gouges (insert-defects, model B)"},
    {kTruthPit, "pit", "inserted pits (insert-defects, model A)"},
    {kTruthPitChain, "pit-chain", "inserted chains of pits (insert-defects, model B)"},
    {kTruthDent, "dent", "spherical dents"},
    {kTruthToolChange, "tool-change-step", "the ramp of a tool-change step"},
    {kTruthBurr, "burr", "the pocket-edge burr and labelled scratch lips"},
    {kTruthChatterBand, "chatter-band", "chatter bands"},
    {kTruthChatter, "chatter", "the confined chatter region"},
};

constexpr ProcessRow kProcesses[] = {
    {SurfaceSpec::Process::BallEndRaster, "ballend",
     "ball-end raster paths: scallops between paths, feed marks along them"},
    {SurfaceSpec::Process::FaceMillFeed, "facemill",
     "face mill passes: crescent feed marks of the inserts' nose radius"},
    {SurfaceSpec::Process::FlatEndPocket, "flatend",
     "flat end mill pocket floor: step-over ridges of the corner radius, floor feed marks"},
    {SurfaceSpec::Process::Turned, "turned",
     "face turning: a spiral groove of the nose radius about a centre"},
};

constexpr TestPartRow kTestParts[] = {
    {TestPart::BallEnd, "ballend", "ball-end raster with every defect kind"},
    {TestPart::FaceMill, "facemill",
     "face mill (R 4 mm, passes 3 mm apart) with every defect kind"},
    {TestPart::FlatEnd, "flatend", "flat end mill pocket floor with every defect kind"},
    {TestPart::Turned, "turned", "face-turned section with every defect kind"},
};

}  // namespace

std::span<const TruthKind> truthKinds() {
    return kTruthKinds;
}

std::vector<RegionLabel> truthLegend(const std::vector<uint8_t>& truth) {
    bool present[256] = {};
    for (uint8_t v : truth) present[v] = true;
    std::vector<RegionLabel> legend;
    for (const TruthKind& k : kTruthKinds)
        if (k.value == kTruthDefect || present[k.value]) legend.push_back({k.value, k.name});
    for (int v = 255; v >= 1; --v) {
        if (!present[v]) continue;
        bool known = false;
        for (const TruthKind& k : kTruthKinds) known = known || k.value == v;
        if (!known) legend.push_back({static_cast<uint8_t>(v), "label-" + std::to_string(v)});
    }
    return legend;
}

std::span<const ProcessRow> processTable() {
    return kProcesses;
}

SurfaceSpec processDefaults(SurfaceSpec::Process process) {
    SurfaceSpec s;
    s.process = process;
    switch (process) {
        case SurfaceSpec::Process::BallEndRaster:
        case SurfaceSpec::Process::FaceMillFeed:
            break;
        case SurfaceSpec::Process::FlatEndPocket:
            s.toolRadius = 1.0;
            s.toolCornerRadius = 0.2;
            s.stepover = 1.7;
            s.feedPerTooth = 0.05;
            break;
        case SurfaceSpec::Process::Turned:
            s.insertNoseRadius = 0.8;
            s.feedPerTooth = 0.1;
            break;
    }
    return s;
}

std::span<const TestPartRow> testPartTable() {
    return kTestParts;
}

SurfaceSpec testPartSpec(TestPart part) {
    SurfaceSpec::Process process = SurfaceSpec::Process::BallEndRaster;
    switch (part) {
        case TestPart::BallEnd:
            process = SurfaceSpec::Process::BallEndRaster;
            break;
        case TestPart::FaceMill:
            process = SurfaceSpec::Process::FaceMillFeed;
            break;
        case TestPart::FlatEnd:
            process = SurfaceSpec::Process::FlatEndPocket;
            break;
        case TestPart::Turned:
            process = SurfaceSpec::Process::Turned;
            break;
    }
    SurfaceSpec s = processDefaults(process);
    if (part == TestPart::FaceMill) {
        s.toolRadius = 4.0;
        s.stepover = 3.0;
    }
    s.width = s.height = 1024;
    s.pitch = 0.01;
    s.seed = 1;
    s.scratchCount = 5;
    s.scratchDepthMin = 0.3;
    s.scratchWidthMin = 0.5;
    s.labelScratchLips = true;
    s.gougeCount = 1;
    s.dentCount = 3;
    s.pocketBurrHeight = 0.004;
    s.toolChangeStep = 0.003;
    s.toolChangeAt = part == TestPart::Turned ? 3.0 : -2.0;
    s.chatterStartFraction = 0.6;
    s.chatterBands = 2;
    s.chatterBandAmplitude = 0.0015;
    return s;
}

}  // namespace sl
