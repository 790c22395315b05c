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
#include "synth/SurfaceGeneratorDetail.h"

namespace sl {

using namespace surfacegen;

namespace {

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

}  // namespace

namespace surfacegen {

void require(bool ok, const std::string& field, const std::string& problem,
             const std::string& fix) {
    if (!ok) throw inputError(option(optionName(field)), problem, fix);
}

}  // namespace surfacegen

namespace {

void requireFinite(double v, const std::string& field) {
    require(std::isfinite(v), field, "must be a finite number, got " + formatNumber(v),
            "Set it to a finite value in mm (or degrees for angles)");
}

/// A length in mm: finite, then > 0 ("must be > 0 mm, got ..."), `fix` saying what it is.
void requirePositiveMm(double v, const std::string& field, const std::string& fix) {
    requireFinite(v, field);
    require(v > 0, field, "must be > 0 mm, got " + formatNumber(v), fix);
}

/// A length in mm that may be 0 (how a spec says "none"): finite, then >= 0.
void requireNonNegativeMm(double v, const std::string& field, const std::string& fix) {
    requireFinite(v, field);
    require(v >= 0, field, "must be >= 0 mm, got " + formatNumber(v), fix);
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
    requirePositiveMm(s.pitch, "pitch", "Set the sample spacing in mm, e.g. 0.01");
    requirePositiveMm(s.toolRadius, "toolRadius",
                      "Set the ball (or face-mill cutter) radius in mm");
    requirePositiveMm(s.stepover, "stepover", "Set the spacing of the tool paths in mm");
    require(s.stepover < 2 * s.toolRadius, "stepover",
            "must be < 2*toolRadius = " + formatNumber(2 * s.toolRadius) + " mm, got " +
                formatNumber(s.stepover),
            "Paths further apart than the tool's diameter leave uncut material");
    requireFinite(s.pathOffset, "pathOffset");
    requireFinite(s.rasterAngleDeg, "rasterAngleDeg");
    requireNonNegativeMm(s.feedPerTooth, "feedPerTooth",
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
        requirePositiveMm(s.insertNoseRadius, "insertNoseRadius", "Typical " + inserts);
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
    if (s.process == SurfaceSpec::Process::Ground) {
        requirePositiveMm(s.gritDepth, "gritDepth",
                          "The grits' mean depth of cut in mm, e.g. 0.0008");
        requirePositiveMm(s.gritLength, "gritLength",
                          "The grit tracks' mean length along the lay in mm, e.g. 1");
    }
    if (s.process == SurfaceSpec::Process::Turned) {
        requireInsert("turning inserts: 0.2-1.6 mm", "per revolution for turning",
                      "0.05-0.2 mm per revolution");
        requireFinite(s.turnCentreX, "turnCentreX");
        requireFinite(s.turnCentreZ, "turnCentreZ");
    }
    // A length the chosen process or defect count does not use is still never negative or
    // infinite: a value given for it is a mistake, so it is refused by its name too (0 stays
    // allowed: it is how a scene says "none").
    for (auto [v, field] :
         {std::pair{s.insertNoseRadius, "insertNoseRadius"},
          std::pair{s.toolCornerRadius, "toolCornerRadius"},
          std::pair{s.chatterWavelength, "chatterWavelength"},
          std::pair{s.chatterBandWidth, "chatterBandWidth"},
          std::pair{s.chatterBandAmplitude, "chatterBandAmplitude"},
          std::pair{s.roughnessCorrelation, "roughnessCorrelation"},
          std::pair{s.scratchDepth, "scratchDepth"}, std::pair{s.scratchWidth, "scratchWidth"},
          std::pair{s.gougeDepth, "gougeDepth"}, std::pair{s.gougeLength, "gougeLength"},
          std::pair{s.dentDepth, "dentDepth"}, std::pair{s.dentRadius, "dentRadius"},
          std::pair{s.gritDepth, "gritDepth"}, std::pair{s.gritLength, "gritLength"}}) {
        requireNonNegativeMm(v, field,
                             "A length is never negative (this run may not use it: leave it out)");
    }
    requireNonNegativeMm(s.chatterAmplitude, "chatterAmplitude", "Use 0 to disable chatter");
    requireFinite(s.chatterStartFraction, "chatterStartFraction");
    require(s.chatterStartFraction >= 0 && s.chatterStartFraction < 1, "chatterStartFraction",
            "must be in [0, 1), got " + formatNumber(s.chatterStartFraction),
            "Use 0 for chatter everywhere, 0.5 for the right half");
    require(s.chatterBands >= 0 && s.chatterBands <= 10000, "chatterBands",
            "must be in [0, 10000], got " + std::to_string(s.chatterBands),
            "Use 0 for no chatter bands");
    if (s.chatterBands > 0) {
        requirePositiveMm(s.chatterBandWidth, "chatterBandWidth",
                          "Set the width of a chatter band across the paths in mm, e.g. 0.8");
        requirePositiveMm(s.chatterBandAmplitude, "chatterBandAmplitude",
                          "Set the chatter amplitude inside the bands in mm, or chatterBands = 0");
    }
    if (s.chatterAmplitude > 0 || s.chatterBands > 0) {
        requireFinite(s.chatterWavelength, "chatterWavelength");
        require(
            s.chatterWavelength > 0, "chatterWavelength",
            "must be > 0 mm when chatterAmplitude > 0, got " + formatNumber(s.chatterWavelength),
            "Set the chatter wavelength in mm, or chatterAmplitude = 0");
    }
    requireNonNegativeMm(s.roughnessRms, "roughnessRms", "Use 0 to disable roughness");
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
            requireNonNegativeMm(s.scratchDepth, "scratchDepth", "Scratch depths are in mm");
            requirePositiveMm(s.scratchWidth, "scratchWidth", "Scratch widths are in mm");
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
            requireNonNegativeMm(s.gougeDepth, "gougeDepth", "Gouge depths are in mm");
            requirePositiveMm(s.gougeLength, "gougeLength", "Gouge lengths are in mm");
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
            requirePositiveMm(s.dentRadius, "dentRadius", "The indenter's radius in mm, e.g. 0.5");
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
    require(s.crackCount >= 0 && s.crackCount <= 100000, "crackCount",
            "must be in [0, 100000], got " + std::to_string(s.crackCount), "Use 0 for no cracks");
    if (s.crackCount > 0) {
        requirePositiveMm(s.crackLength, "crackLength",
                          "The crack's length along its path in mm, e.g. 1.5");
        requirePositiveMm(s.crackWidth, "crackWidth",
                          "The crack's widest opening in mm, e.g. 0.025");
        requireNonNegativeMm(s.crackDepth, "crackDepth",
                             "The crack's deepest point in mm, e.g. 0.006");
        require(s.crackBranches >= 0 && s.crackBranches <= 100, "crackBranches",
                "must be in [0, 100], got " + std::to_string(s.crackBranches),
                "Use 0 for a crack without branches");
    }
    requireNonNegativeMm(s.pocketBurrHeight, "pocketBurrHeight", "Use 0 for no burr");
    if (s.pocketBurrHeight > 0) {
        require(s.pocketEdge && s.pocketDepth > 0, "pocketBurrHeight",
                "a burr sits on the pocket edge, and there is none",
                "Keep the pocket edge (pocketEdge = true, pocketDepth > 0) or set it to 0");
        requirePositiveMm(s.pocketBurrWidth, "pocketBurrWidth",
                          "The burr's width across the edge in mm, e.g. 0.04");
    }
    requireFinite(s.toolChangeStep, "toolChangeStep");
    if (s.toolChangeStep != 0) {
        requireFinite(s.toolChangeAt, "toolChangeAt");
        requireNonNegativeMm(s.toolChangeWidth, "toolChangeWidth",
                             "The width of the step's ramp in mm (at least 2 samples are used)");
    }
    requireNonNegativeMm(s.noiseRms, "noiseRms", "Use 0 for no measurement noise");
    require(s.spikeCount >= 0 && s.spikeCount <= 1000000, "spikeCount",
            "must be in [0, 1000000], got " + std::to_string(s.spikeCount), "Use 0 for no spikes");
    if (s.spikeCount > 0) {
        requireNonNegativeMm(s.spikeHeight, "spikeHeight",
                             "It is the largest spike's height; each spike's sign is random");
    }
    if (s.pocketEdge) {
        requireNonNegativeMm(s.pocketDepth, "pocketDepth",
                             "The pocket floor is pocketDepth below the top");
        requireFinite(s.pocketWallFraction, "pocketWallFraction");
        require(s.pocketWallFraction > 0 && s.pocketWallFraction < 1, "pocketWallFraction",
                "must be in (0, 1), got " + formatNumber(s.pocketWallFraction),
                "It is the fraction of the map width (in +x) that is pocket floor");
        requireNonNegativeMm(s.cornerRadius, "cornerRadius", "Use 0 for a sharp step");
    }
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

/// The stages' results that compose puts together.
struct Features {
    std::vector<double> pocket;
    std::vector<Scratch> scratches;
    std::vector<Gouge> gouges;
    std::vector<Dent> dents;
    std::vector<Crack> cracks;
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
                    case SurfaceSpec::Process::Ground:
                        h = tm.ground(t, p, sw, amp);
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
            for (const Crack& k : ft.cracks) {
                if (j < k.j0 || j > k.j1) continue;
                for (int i = k.i0; i <= k.i1; ++i) {
                    const double off = crackOffset(k.paths, (i - cx) * pitch, z);
                    row[static_cast<size_t>(i)] += off;
                    if (k.spec.depth > 0 && off <= -0.1 * k.spec.depth) mark(i, kTruthCrack);
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
    } else if (fr.process == SurfaceSpec::Process::Ground) {
        std::snprintf(buf, sizeof buf,
                      "surface grinding along %.4g deg: grit tips r=%.4g mm, %zu tracks %.4g mm "
                      "apart across the lay, %.4g mm long, %.4g um deep on average",
                      spec.rasterAngleDeg, R, tm.grits.size(), s, spec.gritLength,
                      1e3 * spec.gritDepth);
        marks = buf;
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
    if (!out.cracks.empty()) {
        std::snprintf(
            buf, sizeof buf, "; %zu crack(s) up to %.3g um deep, %.4g mm long, %d branch(es)",
            out.cracks.size(), 1e3 * spec.crackDepth, spec.crackLength, spec.crackBranches);
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
        case SurfaceSpec::Process::Ground:
            out.scallop = spec.gritDepth;  // the grits' mean depth: no scallop between tracks
            out.feedMark = 0.0;
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
    ft.cracks = placeCracks(spec, fr, out);
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

}  // namespace sl
