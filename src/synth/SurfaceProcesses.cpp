// Synthetic NC-machined surfaces, the machining processes: the tool marks of each process
// (stage 1), the pocket step (stage 2), scallop and ridge heights, the process and test-part
// tables. See SurfaceGenerator.h for the model and conventions.
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/Error.h"
#include "core/Rng.h"
#include "core/Text.h"
#include "synth/SurfaceGenerator.h"
#include "synth/SurfaceGeneratorDetail.h"

namespace sl::surfacegen {
namespace {

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

/// Ground: draws the grit tracks that can reach the map (see SurfaceGenerator.h) and sorts them
/// into bins across the lay, each at least as wide as a track's reach.
void groundTracks(const SurfaceSpec& spec, const Frame& fr, ToolMarks& tm) {
    const double hx = 0.5 * fr.extX, hz = 0.5 * fr.extZ;
    const double deepest = std::min(kGritDepthCut * spec.gritDepth, tm.R);
    // A grit δ deep cuts where its tip has risen less than δ: |q| < √(δ·(2R − δ)).
    const double reach = std::sqrt(deepest * (2 * tm.R - deepest));
    const double halfP = std::abs(tm.sinA) * hx + std::abs(tm.cosA) * hz + reach;
    const double halfT = std::abs(tm.cosA) * hx + std::abs(tm.sinA) * hz + 0.75 * spec.gritLength;
    const double count = (2 * halfP) * (2 * halfT) / (spec.stepover * spec.gritLength);
    require(count < 5.0e7, "stepover",
            "gives " + formatNumber(count) + " grit tracks over the map, too many",
            "Use a larger stepover or gritLength for a ground surface this large");
    Pcg32 rng(mix64(spec.seed ^ kGritStream), kGritStream);
    const auto n = static_cast<size_t>(std::llround(count));
    std::vector<GritTrack> drawn(n);
    for (GritTrack& g : drawn) {
        g.p = -halfP + 2 * halfP * rng.nextDouble();
        const double mid = -halfT + 2 * halfT * rng.nextDouble();
        const double half = 0.5 * spec.gritLength * (0.5 + rng.nextDouble());
        g.t0 = mid - half;
        g.t1 = mid + half;
        g.depth = spec.gritDepth * std::min(-std::log(1.0 - rng.nextDouble()), kGritDepthCut);
    }
    tm.gritLo = -halfP;
    tm.gritBin = std::max(reach, 1e-9);
    const auto bins = static_cast<size_t>(std::ceil(2 * halfP / tm.gritBin)) + 1;
    auto binOf = [&](const GritTrack& g) {
        return std::min(static_cast<size_t>((g.p - tm.gritLo) / tm.gritBin), bins - 1);
    };
    tm.gritStart.assign(bins + 1, 0);
    for (const GritTrack& g : drawn) ++tm.gritStart[binOf(g) + 1];
    for (size_t b = 0; b < bins; ++b) tm.gritStart[b + 1] += tm.gritStart[b];
    tm.grits.resize(n);
    std::vector<uint32_t> next(tm.gritStart.begin(), tm.gritStart.end() - 1);
    for (const GritTrack& g : drawn) tm.grits[next[binOf(g)]++] = g;
}

}  // namespace

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
    if (spec.process == SurfaceSpec::Process::Ground) {
        groundTracks(spec, fr, tm);
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

}  // namespace sl::surfacegen

namespace sl {

using namespace surfacegen;

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

constexpr ProcessRow kProcesses[] = {
    {SurfaceSpec::Process::BallEndRaster, "ballend",
     "ball-end raster paths: scallops between paths, feed marks along them"},
    {SurfaceSpec::Process::FaceMillFeed, "facemill",
     "face mill passes: crescent feed marks of the inserts' nose radius"},
    {SurfaceSpec::Process::FlatEndPocket, "flatend",
     "flat end mill pocket floor: step-over ridges of the corner radius, floor feed marks"},
    {SurfaceSpec::Process::Turned, "turned",
     "face turning: a spiral groove of the nose radius about a centre"},
    {SurfaceSpec::Process::Ground, "ground",
     "surface grinding: the grits' fine tracks along the lay, plateaus between them"},
};

constexpr TestPartRow kTestParts[] = {
    {TestPart::BallEnd, "ballend", "ball-end raster with every defect kind"},
    {TestPart::FaceMill, "facemill",
     "face mill (R 4 mm, passes 3 mm apart) with every defect kind"},
    {TestPart::FlatEnd, "flatend", "flat end mill pocket floor with every defect kind"},
    {TestPart::Turned, "turned", "face-turned section with every defect kind"},
    {TestPart::Ground, "ground", "ground surface with every defect kind"},
};

}  // namespace

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
        case SurfaceSpec::Process::Ground:
            // A coarse finish: grit tips of 40 µm radius, tracks 15 µm apart, 0.8 µm deep on
            // average; the wheel's chatter 0.3 µm (Sq 0.78 µm with the default roughness).
            s.toolRadius = 0.04;
            s.stepover = 0.015;
            s.gritDepth = 0.0008;
            s.gritLength = 1.0;
            s.chatterAmplitude = 0.0003;
            s.chatterWavelength = 0.8;
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
        case TestPart::Ground:
            process = SurfaceSpec::Process::Ground;
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
