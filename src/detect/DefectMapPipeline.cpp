// The defect map's pipeline (detect/DefectMap.h): the methods' dispatch and the auto
// method's steps in order, each in its own file (TextureNotch, RingModel, StepLines, LineValleys,
// Hysteresis, TextureChange; the filters in ImageFilters).
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "core/Error.h"
#include "core/Interrupt.h"
#include "core/Stopwatch.h"
#include "detect/DefectMap.h"
#include "detect/Hysteresis.h"
#include "detect/ImageFilters.h"
#include "detect/LineValleys.h"
#include "detect/RingModel.h"
#include "detect/StepLines.h"
#include "detect/TextureChange.h"
#include "detect/TextureNotch.h"

namespace sl {

using namespace defectmap;

namespace {

void checkOptions(const DefectMapOptions& o) {
    auto oddAtLeast3 = [](int v, const char* name, const char* fix) {
        if (v < 3 || v % 2 == 0)
            throw inputError(option(name), "must be odd and >= 3 (got " + std::to_string(v) + ")",
                             fix);
    };
    if (o.pad < 0)
        throw inputError(option("pad"), "must be >= 0 (got " + std::to_string(o.pad) + ")");
    oddAtLeast3(o.spectrumWindow, "spectrum-window", "The default is 9 bins");
    oddAtLeast3(o.levelWindow, "level-window", "The default is 31 samples");
    oddAtLeast3(o.macroWindow, "macro-window", "The default is 61 samples");
    if (o.edgeWindow < 5 || o.edgeWindow % 2 == 0)
        throw inputError(option("edge-window"),
                         "must be odd and >= 5 (got " + std::to_string(o.edgeWindow) + ")",
                         "A quadratic fits 3 samples exactly; the default is 7");
    if (o.energyWindow != 0) oddAtLeast3(o.energyWindow, "energy-window", "0 switches it off");
    if (!(o.notchRatio > 1.0))
        throw inputError(option("notch-ratio"),
                         "must be > 1 (got " + std::to_string(o.notchRatio) + ")");
    if (o.passes < 1)
        throw inputError(option("passes"), "must be >= 1 (got " + std::to_string(o.passes) + ")");
    if (o.notchSpread < 0) throw inputError(option("notch-spread"), "must be >= 0");
    if (!(o.notchGrow > 0.0 && o.notchGrow <= o.notchRatio))
        throw inputError(option("notch-grow"),
                         "must be in (0, notch-ratio] (got " + std::to_string(o.notchGrow) + ")");
    if (o.keepLowBins < 0) throw inputError(option("keep-low-bins"), "must be >= 0");
    if (!(o.seedSigma > 0.0))
        throw inputError(option("seed-sigma"),
                         "must be > 0 (got " + std::to_string(o.seedSigma) + ")");
    if (!(o.growSigma > 0.0 && o.growSigma <= o.seedSigma))
        throw inputError(option("grow-sigma"),
                         "must be in (0, seed-sigma] (got " + std::to_string(o.growSigma) + ")");
    if (!(o.edgeWeight >= 0.0))
        throw inputError(option("edge-weight"),
                         "must be >= 0 (got " + std::to_string(o.edgeWeight) + ")");
    if (o.border < 0)
        throw inputError(option("border"), "must be >= 0 (got " + std::to_string(o.border) + ")");
    if (o.minRegion < 1)
        throw inputError(option("min-region"),
                         "must be >= 1 (got " + std::to_string(o.minRegion) + ")");
    if (o.lineLength != 0 && (o.lineLength < 3 || o.lineLength % 2 == 0))
        throw inputError(option("line-length"),
                         "must be 0 or odd and >= 3 (got " + std::to_string(o.lineLength) + ")",
                         "0 switches the line-valley score off; the default is 15");
    if (o.lineOrientations < 1 || o.lineOrientations > 64)
        throw inputError(option("line-orientations"),
                         "must be in [1, 64] (got " + std::to_string(o.lineOrientations) + ")");
    if (!(o.lineOffset >= 1.0 && o.lineOffset <= 16.0))
        throw inputError(option("line-offset"),
                         "must be in [1, 16] samples (got " + std::to_string(o.lineOffset) + ")");
    if (!(o.seedTail >= 0.0) || !std::isfinite(o.seedTail))
        throw inputError(option("seed-tail"),
                         "must be >= 0 (got " + std::to_string(o.seedTail) + ")",
                         "0 switches the texture's-tail thresholds off");
    if (!(o.growTail >= 0.0) || !std::isfinite(o.growTail))
        throw inputError(option("grow-tail"),
                         "must be >= 0 (got " + std::to_string(o.growTail) + ")",
                         "0 scales the grow thresholds with the seed's");
    if (o.seedTailTiles < 1 || o.seedTailTiles > 64)
        throw inputError(option("seed-tail-tiles"),
                         "must be in [1, 64] (got " + std::to_string(o.seedTailTiles) + ")",
                         "1 takes the quantile over the whole map");
    if (!(o.seedTailWide >= 0.0) || !std::isfinite(o.seedTailWide))
        throw inputError(option("seed-tail-wide"),
                         "must be >= 0 (got " + std::to_string(o.seedTailWide) + ")",
                         "0 takes the tails over wide texture changes too");
    if (!(o.seedTailQuantile > 0.0 && o.seedTailQuantile < 1.0))
        throw inputError(option("seed-tail-quantile"),
                         "must be in (0, 1) (got " + std::to_string(o.seedTailQuantile) + ")");
    if (!(o.lineSeedSigma > 0.0))
        throw inputError(option("line-seed-sigma"),
                         "must be > 0 (got " + std::to_string(o.lineSeedSigma) + ")");
    if (!(o.lineGrowSigma > 0.0 && o.lineGrowSigma <= o.lineSeedSigma))
        throw inputError(option("line-grow-sigma"), "must be in (0, line-seed-sigma] (got " +
                                                        std::to_string(o.lineGrowSigma) + ")");
    if (!(o.textureEnergyRatio > 1.0))
        throw inputError(option("texture-energy-ratio"),
                         "must be > 1 (got " + std::to_string(o.textureEnergyRatio) + ")");
    if (o.textureSectors < 1 || o.textureSectors > 16)
        throw inputError(option("texture-sectors"),
                         "must be in [1, 16] (got " + std::to_string(o.textureSectors) + ")",
                         "1 takes the texture whole; the default is 2");
    if (o.stepWindow < 3 || o.stepWindow % 2 == 0)
        throw inputError(option("step-window"),
                         "must be odd and >= 3 (got " + std::to_string(o.stepWindow) + ")",
                         "The default is 11 samples");
    if (!(o.stepSigma > 0.0))
        throw inputError(option("step-sigma"),
                         "must be > 0 (got " + std::to_string(o.stepSigma) + ")");
    if (!(o.stepSharpness > 0.0 && o.stepSharpness <= 1.0))
        throw inputError(option("step-sharpness"),
                         "must be in (0, 1] (got " + std::to_string(o.stepSharpness) + ")");
    if (o.stepMinLength < 1)
        throw inputError(option("step-min-length"),
                         "must be >= 1 (got " + std::to_string(o.stepMinLength) + ")");
    if (!(o.stepRampHalf > 0.0))
        throw inputError(option("step-ramp-half"),
                         "must be > 0 (got " + std::to_string(o.stepRampHalf) + ")");
    if (!(o.stepBand >= o.stepRampHalf))
        throw inputError(option("step-band"),
                         "must be >= step-ramp-half (got " + std::to_string(o.stepBand) + ")");
    if (!(o.stepGap >= 0.0))
        throw inputError(option("step-gap"), "must be >= 0 (got " + std::to_string(o.stepGap) + ")",
                         "0 fills no gap; the default is 200 samples");
    if (!(o.stepRampMoved >= 0.0 && o.stepRampMoved < 0.5))
        throw inputError(option("step-ramp-moved"),
                         "must be in [0, 0.5) (got " + std::to_string(o.stepRampMoved) + ")",
                         "0 marks the whole ramp; the default is 0.02");
    if (o.ringWindow != 0) oddAtLeast3(o.ringWindow, "ring-window", "0 switches it off");
    if (!(o.ringIsotropy >= 0.0 && o.ringIsotropy <= 1.0))
        throw inputError(option("ring-isotropy"),
                         "must be in [0, 1] (got " + std::to_string(o.ringIsotropy) + ")");
    if (!(o.ringRatio > 0.0 && o.ringRatio <= 1.0))
        throw inputError(option("ring-ratio"),
                         "must be in (0, 1] (got " + std::to_string(o.ringRatio) + ")");
    if (!(o.ringResidual > 0.0))
        throw inputError(option("ring-residual"),
                         "must be > 0 (got " + std::to_string(o.ringResidual) + ")");
    if (!(o.energyRatio > 1.0))
        throw inputError(option("energy-ratio"),
                         "must be > 1 (got " + std::to_string(o.energyRatio) + ")");
}

void checkInput(std::span<const float> heights, int width, int height) {
    if (width < 2 || height < 2)
        throw inputError(
            "defect map",
            "height map is " + std::to_string(width) + "x" + std::to_string(height) + " samples",
            "It needs at least 2x2 samples");
    if (heights.size() != static_cast<size_t>(width) * static_cast<size_t>(height))
        throw inputError("defect map", "height map has " + std::to_string(heights.size()) +
                                           " values, expected " + std::to_string(width) + "x" +
                                           std::to_string(height));
    for (size_t k = 0; k < heights.size(); ++k)
        if (!std::isfinite(heights[k]))
            throw inputError("defect map",
                             "height at row " + std::to_string(k / static_cast<size_t>(width)) +
                                 ", column " + std::to_string(k % static_cast<size_t>(width)) +
                                 " is not finite",
                             "Fill the holes first");
}

}  // namespace

std::vector<float> removeTexture(std::span<const float> heights, int width, int height,
                                 const DefectMapOptions& options) {
    checkOptions(options);
    checkInput(heights, width, height);
    TextureRequest want;
    want.levelDelta = true;
    TextureResidual tr = textureResidual(heights, width, height, options, want);
    for (size_t k = 0; k < tr.levelDelta.size(); ++k) tr.residual[k] += tr.levelDelta[k];
    return std::move(tr.residual);
}

namespace {

// The notch's statistics of steps 1–3 into r (auto's summary).
void recordNotch(const NotchStats& notch, DefectMap& r) {
    r.notchedBins = notch.notchedBins;
    r.spectrumBins = notch.spectrumBins;
    r.fftWidth = notch.fftWidth;
    r.fftHeight = notch.fftHeight;
}

// The selfsim method's map and statistics into r (the selfsim method, and auto on a measured
// texture).
void selfSimInto(DefectMap& r, std::span<const float> heights, int width, int height,
                 const SelfSimMapOptions& o) {
    SelfSimMap m = detectSelfSimDefects(heights, width, height, o);
    r.method = DefectMethod::SelfSim;
    r.map = std::move(m.map);
    static_assert(kUnjudgedRegion == 255,
                  "SelfSimMap::unjudged holds 255 where it could not judge");
    r.unjudged = std::move(m.unjudged);
    r.unjudgedRegions = m.unjudgedRegions;
    if (!r.unjudged.empty()) {
        const int b = m.border;
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x)
                if (x < b || y < b || x >= width - b || y >= height - b)
                    r.unjudged[static_cast<size_t>(y) * width + x] = kUnjudgedBorder;
    }
    r.sigmaLevel = m.sigma;
    r.selfsimOffsets = m.offsetX.size();
    r.selfsimDetections = m.detections;
    r.selfsimRegions = m.regions;
    r.selfsimDropped = m.droppedBorder;
    r.selfsimThreshold = m.threshold;
    r.selfsimTextureThreshold = m.textureThreshold;
    r.selfsimCandidates = m.candidates;
    r.selfsimDroppedTexture = m.droppedTexture;
    r.selfsimLineThreshold = m.lineThreshold;
    r.selfsimTextureLines = m.textureLines;
    r.selfsimDroppedShallow = m.droppedShallow;
    r.selfsimTextureRms = m.shallowRms;
    r.selfsimBorderPieces = m.borderPieces;
    r.selfsimBorderLines = m.borderLines;
    r.selfsimLayLines = m.layLines;
    r.selfsimLayLineSamples = m.layLineSamples;
    r.selfsimLineCopyLines = m.lineCopyLines;
    r.selfsimLineCopySamples = m.lineCopySamples;
    r.selfsimValleyLines = m.valleyLines;
    r.selfsimValleyLineSamples = m.valleyLineSamples;
    r.selfsimRimBands = m.rimBands;
    r.selfsimRimBandSamples = m.rimBandSamples;
    r.selfsimEdgeRingCells = m.edgeRingCells;
    r.selfsimEdgeRingSamples = m.edgeRingSamples;
    r.selfsimValleyRims = m.valleyRims;
    r.selfsimValleyRimSamples = m.valleyRimSamples;
    r.selfsimReliefLevels = m.reliefLevels;
    r.selfsimRaisedLines = m.raisedLines;
    r.selfsimBurrBasin = m.burrBasin;
    r.selfsimHollowRows = m.hollowRows;
    r.selfsimRowHollows = m.rowHollows;
    r.selfsimHollowChains = m.hollowChains;
    r.selfsimChainHollows = m.chainHollows;
    r.selfsimFarBanks = m.farBanks;
    r.selfsimFarBankSamples = m.farBankSamples;
    r.markedScore = r.markedCount();
}

}  // namespace

DefectMap detectDefects(std::span<const float> heights, int width, int height,
                        const DefectMapOptions& o) {
    const Stopwatch clock;
    DefectMap r;
    r.method = o.method;
    r.width = width;
    r.height = height;
    switch (o.method) {
        case DefectMethod::Paper: {
            checkInput(heights, width, height);
            ScratchMap m = computeScratchMap(heights, width, height, o.paper);
            r.map = std::move(m.map);
            r.seconds = clock.seconds();
            return r;
        }
        case DefectMethod::Lay: {
            checkInput(heights, width, height);
            LayMap m = detectLayDefects(heights, width, height, o.lay);
            r.map = std::move(m.map);
            r.sigmaLevel = m.sigma;
            r.layX = m.layX;
            r.layZ = m.layZ;
            r.layCoherence = m.coherence;
            r.layTextureRms = m.textureRms;
            r.layRegions = m.regions;
            r.layDroppedShallow = m.droppedShallow;
            r.layDroppedBorder = m.droppedBorder;
            r.markedScore = r.markedCount();
            r.seconds = clock.seconds();
            return r;
        }
        case DefectMethod::SelfSim:
            checkInput(heights, width, height);
            selfSimInto(r, heights, width, height, o.selfsim);
            r.seconds = clock.seconds();
            return r;
        case DefectMethod::Auto:
            if (!o.measured) break;
            // a measured texture: the map is the selfsim method's (header, "auto")
            checkInput(heights, width, height);
            selfSimInto(r, heights, width, height, o.selfsim);
            r.measuredTexture = true;
            r.seconds = clock.seconds();
            return r;
    }
    checkOptions(o);
    checkInput(heights, width, height);
    const int W = width, H = height;
    const size_t n = heights.size();
    r.map.assign(n, 0);

    // scale floor: 1e-3 of the heights' own robust spread (a noise-free texture leaves only
    // rounding in A and N; this keeps rounding from being an anomaly)
    double hmean = 0.0;
    for (float v : heights) hmean += v;
    hmean /= static_cast<double>(n);
    std::vector<float> centred(n);
    for (size_t k = 0; k < n; ++k) centred[k] = static_cast<float>(heights[k] - hmean);
    const double floorSigma = 1e-3 * 1.4826 * medianAbs(centred);
    centred = {};
    const bool wantTexture = o.energyWindow > 0 && o.textureEnergy;
    // steps 1–3; period: of h − macro, the ring model's pitch; levelDelta: step 4's Wiener
    // estimate's level minus A (levelWiener)
    TextureRequest want;
    want.texture = wantTexture && o.textureSectors == 1;
    want.sectors = wantTexture && o.textureSectors > 1;
    want.period = o.ringWindow > 0;
    want.levelDelta = o.levelWiener;
    TextureResidual tr = textureResidual(heights, W, H, o, want);
    recordNotch(tr.notch, r);
    std::vector<float> R = std::move(tr.residual), macro = std::move(tr.macro);
    std::vector<float> texture = std::move(tr.texture), levelDelta = std::move(tr.levelDelta);
    std::vector<std::vector<float>> sectors = std::move(tr.sectors);
    const double period = tr.period;
    throwIfInterrupted();  // Ctrl-C between the steps (core/Interrupt.h)
    RingFit rings;
    if (o.ringWindow > 0) {
        rings = ringFit(heights, macro, W, H, o, period, r);
        if (r.ringUsed && o.ringRepass) {
            // steps 1–3 once more, the macro shape the running median of h − T: the texture
            // left the first macro shape biased where its window straddles a corner of the
            // macro shape (the pocket wall's foot and top)
            std::vector<float> T(n);
            for (size_t k = 0; k < n; ++k) T[k] = heights[k] - macro[k] - R[k];
            want.period = false;
            want.prior = std::move(T);
            want.passes = 1;
            tr = textureResidual(heights, W, H, o, std::move(want));
            recordNotch(tr.notch, r);
            R = std::move(tr.residual);
            macro = std::move(tr.macro);
            texture = std::move(tr.texture);
            levelDelta = std::move(tr.levelDelta);
            sectors = std::move(tr.sectors);
        }
    }
    throwIfInterrupted();  // Ctrl-C between the steps (core/Interrupt.h)
    StepModel steps;
    if (o.stepModel) {  // step 4a: the steps of h − T
        std::vector<float> G(n);
        for (size_t k = 0; k < n; ++k) G[k] = macro[k] + R[k];
        steps = detectSteps(G, W, H, o, floorSigma);
        r.stepPoints = steps.points.size();
    }
    std::vector<float> A = separableMedian(R, W, H, o.levelWindow);
    throwIfInterrupted();  // Ctrl-C between the steps (core/Interrupt.h)
    for (size_t k = 0; k < n; ++k) A[k] = R[k] - A[k];
    if (o.ringWindow > 0) ringLevel(heights, macro, A, W, H, o, floorSigma, rings, r);  // 4b
    for (size_t k = 0; k < n; ++k) R[k] += macro[k];
    // the edge residual: both axes at once, or (edgeAxes) one per axis, each with its own σ
    std::vector<float> N = separableQuadratic(R, W, H, o.edgeWindow, true, !o.edgeAxes);
    throwIfInterrupted();  // Ctrl-C between the steps (core/Interrupt.h)
    for (size_t k = 0; k < n; ++k) N[k] = R[k] - N[k];
    std::vector<float> Nz;
    if (o.edgeAxes) {
        Nz = separableQuadratic(R, W, H, o.edgeWindow, false, true);
        for (size_t k = 0; k < n; ++k) Nz[k] = R[k] - Nz[k];
    }
    if (o.edgeRobust && o.edgeAxes) {
        // step 5: the fits again without the samples that alone would seed the map
        const double sx = std::max(1.4826 * medianAbs(N), floorSigma);
        const double sz = std::max(1.4826 * medianAbs(Nz), floorSigma);
        N = robustQuadraticResidual(R, N, W, H, o.edgeWindow, true, o.seedSigma * sx);
        Nz = robustQuadraticResidual(R, Nz, W, H, o.edgeWindow, false, o.seedSigma * sz);
    }
    throwIfInterrupted();  // Ctrl-C between the steps (core/Interrupt.h)
    R = {};
    macro = {};
    r.sigmaLevel = 1.4826 * medianAbs(A);
    // step 8's local energies (of A without the Wiener term, and with textureEnergy of T or its
    // sectors), now: their wide changes are left out of step 7b's tails (header, 7b)
    std::vector<ChangeEnergy> changes;
    if (o.energyWindow > 0) {
        std::vector<float> a = A;
        changes.push_back(changeEnergy(a, W, H, o, floorSigma, o.energyRatio, true));
        if (o.textureEnergy) {
            if (sectors.empty())
                changes.push_back(
                    changeEnergy(texture, W, H, o, floorSigma, o.textureEnergyRatio, false));
            for (std::vector<float>& t : sectors) {
                throwIfInterrupted();  // Ctrl-C between the energies (core/Interrupt.h)
                changes.push_back(
                    changeEnergy(t, W, H, o, floorSigma, o.textureEnergyRatio, false));
            }
        }
        texture = {};
        sectors = {};
    }
    std::vector<uint8_t> widePooled, wide;
    wideChanges(changes, W, H, widePooled, wide);
    const std::vector<uint8_t>* skip = wide.empty() ? nullptr : &wide;
    throwIfInterrupted();  // Ctrl-C between the steps (core/Interrupt.h)
    // the level's Wiener estimate in the notched bins, for the score and the line valleys; σ_A
    // above and step 8 (its energies above) keep the background-magnitude residual
    for (size_t k = 0; k < levelDelta.size(); ++k) A[k] += levelDelta[k];
    levelDelta = {};
    r.sigmaEdge = 1.4826 * medianAbs(N);
    const double sa = std::max(r.sigmaLevel, floorSigma), sn = std::max(r.sigmaEdge, floorSigma);
    const double snz = o.edgeAxes ? std::max(1.4826 * medianAbs(Nz), floorSigma) : 1.0;
    if (sa > 0.0 && sn > 0.0 && snz > 0.0) {
        std::vector<float> S(n);
        tbb::parallel_for(size_t{0}, n, [&](size_t k) {
            double e = std::abs(N[k]) / sn;
            if (o.edgeAxes) e = std::max(e, std::abs(Nz[k]) / snz);
            S[k] = static_cast<float>(std::max(std::abs(A[k]) / sa, o.edgeWeight * e));
        });
        if (o.border > 0)
            tbb::parallel_for(0, H, [&](int y) {
                for (int x = 0; x < W; ++x)
                    if (y < o.border || y >= H - o.border || x < o.border || x >= W - o.border)
                        S[static_cast<size_t>(y) * W + x] = 0.0f;
            });
        // step 7b: the texture's own tail raises the thresholds
        const Thresholds t = tailThresholds(S, W, H, o, o.seedSigma, o.growSigma, skip);
        const double seed = t.seed;
        r.seedUsed = seed;
        r.growUsed = t.grow;
        if (o.lineLength > 0) {
            // step 7a: the line-valley regions seed the hysteresis and are grown through
            const std::vector<uint8_t> lines = lineValleyRegions(A, W, H, o, &r.lineSeedUsed, skip);
            for (size_t k = 0; k < n; ++k)
                if (lines[k]) S[k] = std::max(S[k], static_cast<float>(seed));
        }
        r.markedScore = hysteresis(S, W, H, seed, t.grow, o.minRegion, r.map);
    }
    for (size_t k = 0; k < steps.ramp.size(); ++k) {  // step 4a: a step's band is its ramp
        if (!steps.band[k]) continue;
        if (steps.ramp[k] && !r.map[k]) ++r.markedStep;
        if (!steps.ramp[k] && r.map[k]) --r.markedScore;
        r.map[k] = steps.ramp[k];
    }
    throwIfInterrupted();  // Ctrl-C between the steps (core/Interrupt.h)
    N = {};
    Nz = {};
    wide = {};
    for (const ChangeEnergy& e : changes)  // step 8 on |A| and, with textureEnergy, on |T|
        r.markedEnergy += markTextureChange(e, widePooled, W, H, o, r.map);
    r.seconds = clock.seconds();
    return r;
}

}  // namespace sl
