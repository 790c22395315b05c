// scratchlight defectmap (HEIGHTMAP | SCENE.json) [--method auto|lay|selfsim|paper] [-o map.png]
//                        [--image-output MASK.png] [--truth TRUTH.png] [--score-output FILE]
//                        [--unjudged-output FILE.png] [--preview-output FILE.png]
//                        [tuning ...]
// Parses the options and prints the result; the work is app/jobs/DefectMapJob.h and
// detect/DefectMap.h.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

#include "app/jobs/DefectMapJob.h"
#include "cli/Commands.h"
#include "cli/Common.h"

namespace sl::cli {

namespace {

// The border the method that ran never marks, and the option that sets it (none for paper).
struct BorderInForce {
    int samples = 0;
    const char* flag = nullptr;
};

BorderInForce borderInForce(const DefectMapOptions& o, const DefectMap& m) {
    if (m.measuredTexture || m.method == DefectMethod::SelfSim)
        return {o.selfsim.border, "--selfsim-border"};
    if (m.method == DefectMethod::Lay) return {o.lay.border, "--lay-border"};
    if (m.method == DefectMethod::Auto) return {o.border, "--border"};
    return {};
}

// a border taking at least this share of the map is warned about
constexpr double kBorderShareWarn = 0.5;

// the border b that leaves half of a width×height map inside it: (w − 2b)(h − 2b) = w·h/2
int halfMapBorder(int width, int height) {
    const double s = static_cast<double>(width) + height, p = static_cast<double>(width) * height;
    return static_cast<int>(std::floor((s - std::sqrt(s * s - 2.0 * p)) / 4.0));
}

// A map so small that its border (never marked) takes most of it: say so, and which option sets
// the border (a smaller one was measured on one small map, the Sensofar land at 2x2 means, 459 x
// 128: 27 and 20 found no more than 40; docs/RESULTS.md, "The map on the five textures turned
// and resampled").
void warnSmallMap(const DefectMapOptions& o, const DefectMap& m, int width, int height) {
    const BorderInForce b = borderInForce(o, m);
    if (!b.flag || b.samples <= 0) return;
    const double inner = std::max(0, width - 2 * b.samples) * std::max(0, height - 2 * b.samples);
    const double share = 1.0 - inner / (static_cast<double>(width) * height);
    if (share < kBorderShareWarn) return;
    spdlog::warn(
        "the border of {} samples at the map's edges, never marked, is {:.0f}% of this {}x{} "
        "map: a defect within {} samples of an edge is not marked. {} sets the border ({} keeps "
        "half of the map), but a smaller border is not known to find more: the maps were tuned "
        "at the default on maps of 256 samples a side or more",
        b.samples, 100.0 * share, width, height, b.samples, b.flag, halfMapBorder(width, height));
}

int runDefectMap(const DefectMapJobOptions& o) {
    const DefectMapJobSummary s = runDefectMapJob(o);
    const DefectMap& m = s.map;
    std::printf("defect map (%s) of %dx%d samples: %zu marked (%.2f%% of the map), %.3f s\n",
                defectMethodName(m.method), s.width, s.height, m.markedCount(),
                100.0 * m.markedFraction(), m.seconds);
    warnSmallMap(o.map, m, s.width, s.height);
    if (m.measuredTexture)
        std::printf(
            "  auto on a measured texture (an instrument's height map, or the scene's "
            "heightmap.measured): the selfsim method, what the texture does not repeat\n");
    if (m.method == DefectMethod::Auto)
        std::printf(
            "  FFT %dx%d, %zu of %zu spectrum bins notched as texture; sigma level %.4g, edge "
            "%.4g (height units); %zu marked by level/edge, %zu more by step ramps (%zu step "
            "centre points), %zu more by texture change\n",
            m.fftWidth, m.fftHeight, m.notchedBins, m.spectrumBins, m.sigmaLevel, m.sigmaEdge,
            m.markedScore, m.markedStep, m.stepPoints, m.markedEnergy);
    if (m.method == DefectMethod::Auto)
        std::printf(
            "  thresholds used: score seed %.3g grow %.3g, line valleys seed %.3g (robust "
            "sigmas)\n",
            m.seedUsed, m.growUsed, m.lineSeedUsed);
    if (m.method == DefectMethod::Auto && m.ringPitch > 0)
        std::printf(
            "  rings: centre (%.2f, %.2f) samples, pitch %.3f, hand %+d, isotropy %.3f, residual "
            "%.3f: %s, %zu levels lowered\n",
            m.ringCentreX, m.ringCentreZ, m.ringPitch, m.ringHand, m.ringIsotropy, m.ringResidual,
            m.ringUsed ? "used" : "not used", m.ringLowered);
    else if (m.method == DefectMethod::Auto && m.ringIsotropy > 0)
        std::printf("  rings: isotropy %.3f: not used (the texture's orientations do not turn)\n",
                    m.ringIsotropy);
    if (m.method == DefectMethod::Lay)
        std::printf(
            "  lay (%.3f, %.3f), coherence %.3f; sigma %.4g, texture RMS %.4g (height units); "
            "%zu regions kept, %zu below the texture's RMS and %zu at the border dropped\n",
            m.layX, m.layZ, m.layCoherence, m.sigmaLevel, m.layTextureRms, m.layRegions,
            m.layDroppedShallow, m.layDroppedBorder);
    if (m.method == DefectMethod::SelfSim)
        std::printf(
            "  %zu texture offsets; residual sigma %.4g (height units), detection at %.3f "
            "robust sigmas (NFA); %zu samples detected, %zu regions kept, %zu at the border "
            "dropped (%zu of their pieces kept); the texture's own tail at %.3f robust sigmas "
            "(of %zu regions grown), %zu regions below it dropped; %zu regions shallower than "
            "the texture's RMS %.4g (height units) dropped\n",
            m.selfsimOffsets, m.sigmaLevel, m.selfsimThreshold, m.selfsimDetections,
            m.selfsimRegions, m.selfsimDropped, m.selfsimBorderPieces, m.selfsimTextureThreshold,
            m.selfsimCandidates, m.selfsimDroppedTexture, m.selfsimDroppedShallow,
            m.selfsimTextureRms);
    if (m.method == DefectMethod::SelfSim && m.selfsimTextureLines > 0)
        std::printf(
            "  %zu pieces of those regions kept as lines above the texture's own tail of "
            "lines (%.3f at the growth's level)\n",
            m.selfsimTextureLines, m.selfsimLineThreshold);
    if (m.method == DefectMethod::SelfSim && m.selfsimBorderLines > 0)
        std::printf("  %zu of those pieces kept as lines across the texture's lay\n",
                    m.selfsimBorderLines);
    if (m.method == DefectMethod::SelfSim && m.selfsimRaisedLines > 0)
        std::printf("  %zu raised pieces at the border kept as burrs across the texture's lay\n",
                    m.selfsimRaisedLines);
    if (m.method == DefectMethod::SelfSim && m.selfsimBurrBasin > 0)
        std::printf("  %zu samples of those burrs' basins taken back\n", m.selfsimBurrBasin);
    if (m.method == DefectMethod::SelfSim && m.selfsimHollowRows > 0)
        std::printf("  %zu rows of hollows: %zu hollows dropped alone kept with their row\n",
                    m.selfsimHollowRows, m.selfsimRowHollows);
    if (m.method == DefectMethod::SelfSim && m.selfsimHollowChains > 0)
        std::printf("  %zu chains of hollows on a rough stretch: %zu hollows kept\n",
                    m.selfsimHollowChains, m.selfsimChainHollows);
    if (m.method == DefectMethod::SelfSim && m.selfsimFarBanks > 0)
        std::printf("  %zu raised lines beside grooves kept as their banks: %zu samples\n",
                    m.selfsimFarBanks, m.selfsimFarBankSamples);
    if (m.method == DefectMethod::SelfSim) {
        // the steps that add samples to marks (8l, 8r, 8t, 8s, 8u, 8v), in the order they run
        struct Added {
            size_t count, samples;
            const char* what;
        };
        const Added added[] = {
            {m.selfsimLayLines, m.selfsimLayLineSamples,
             "marks along the texture's lay judged again without the copies on them"},
            {m.selfsimLineCopyLines, m.selfsimLineCopySamples,
             "lines along the lay judged on copies chosen for them"},
            {m.selfsimValleyLines, m.selfsimValleyLineSamples,
             "valleys of the heights beside marks"},
            {m.selfsimRimBands, m.selfsimRimBandSamples,
             "segments of grooves' rims judged along them"},
            {m.selfsimEdgeRingCells, m.selfsimEdgeRingSamples,
             "cells of the marks' edge taken where it keeps their sign"},
            {m.selfsimValleyRims, m.selfsimValleyRimSamples,
             "segments of rims the heights show beside valley lines"},
        };
        for (const Added& a : added)
            if (a.count > 0)
                std::printf("  %zu %s: %zu samples added\n", a.count, a.what, a.samples);
    }
    if (!m.unjudged.empty() && m.unjudgedRegions == 0) {
        std::printf(
            "  judged everywhere inside the border: no region that stands out of the texture "
            "reaches the border's line; the border itself is never marked\n");
    } else if (!m.unjudged.empty()) {
        const size_t unjudged = m.unjudgedCount();
        std::printf(
            "  not judged: %zu regions that stand out of the texture reach the border's line "
            "(they go on beyond what the map shows), %zu samples (%.2f%% of the map) left "
            "unmarked for a person to look at; the border itself is never marked\n",
            m.unjudgedRegions, unjudged,
            100.0 * static_cast<double>(unjudged) / static_cast<double>(m.unjudged.size()));
    }
    if (const std::string why = m.whyNothingMarked(); !why.empty())
        spdlog::warn(
            "nothing marked: {}. If you see defects, outline them in a mask and give it "
            "to optimize with --defects MASK (or labels with --truth)",
            why);
    if (m.method == DefectMethod::SelfSim && m.selfsimReliefLevels > 0)
        std::printf("  a relief: its %zu plateau levels taken out before the copies\n",
                    m.selfsimReliefLevels);
    if (s.score) {
        const DefectScore& sc = *s.score;
        std::printf("%-18s %5s %10s %10s %10s %9s %7s %7s\n", "kind", "value", "truth", "hits",
                    "marked", "precision", "recall", "F1");
        auto row = [](const DefectScoreRow& r) {
            std::printf("%-18s %5d %10zu %10zu %10zu %9.3f %7.3f %7.3f\n", r.name.c_str(),
                        static_cast<int>(r.value), r.truth, r.hits, r.marked, r.precision, r.recall,
                        r.f1);
        };
        row(sc.overall);
        for (const DefectScoreRow& r : sc.kinds) row(r);
    }
    if (s.imageWidth > 0)
        std::printf("image-space map %dx%d: %zu of %zu part pixels marked\n", s.imageWidth,
                    s.imageHeight, s.imageMarked, s.imagePartPixels);
    for (const auto& f : s.written) std::printf("wrote %s\n", f.string().c_str());
    return kOk;
}

}  // namespace

void registerDefectMap(CLI::App& app, std::function<int()>& run) {
    auto a = std::make_shared<DefectMapJobOptions>();
    CLI::App* c = app.add_subcommand(
        "defectmap",
        "Defect map without labels: model the machining texture, mark what it cannot explain "
        "(height-map space; projected into the image with a scene)");
    addHeightSourceInput(c, a->input, a->sceneOverrides,
                         "Height map (EXR/TIFF/PNG/.npy) or a scene file (JSON: its height map, "
                         "and its camera for --image-output)");
    addChoice(c, "--method", a->map.method, defectMethodTable(), "Method (default auto)");
    c->add_option_function<std::string>(
         "-o,--output", [a](const std::string& v) { a->output = v; },
         "Map in height-map space (8-bit PNG, 255 = defect)")
        ->default_str("defectmap.png");
    c->add_option_function<std::string>(
        "--image-output", [a](const std::string& v) { a->imageOutput = v; },
        "Also write the map projected into the scene camera's image (PNG; needs SCENE.json)");
    c->add_option_function<std::string>(
        "--truth", [a](const std::string& v) { a->truth = v; },
        "Truth label PNG in height-map space (gen-surface's OUT-truth.png): prints precision/"
        "recall/F1 per kind and writes them as CSV");
    c->add_option_function<std::string>(
        "--score-output", [a](const std::string& v) { a->csv = v; },
        "CSV of the score (default: <output stem>-score.csv beside the map)");
    c->add_option_function<std::string>(
        "--unjudged-output", [a](const std::string& v) { a->unjudgedOutput = v; },
        "Where the map could not judge, 8-bit PNG (255: a region that stands out of the texture "
        "but reaches the border, left unmarked; 128: the border; written by selfsim and by auto "
        "on a measured texture; default: <output stem>-unjudged.png beside the map)");
    c->add_option_function<std::string>(
        "--preview-output", [a](const std::string& v) { a->previewOutput = v; },
        "A picture of the map: the hill-shaded heights, the marks outlined red, where it could "
        "not judge blue, the border dimmed (default: <output stem>-preview.png beside the map)");
    std::string negatives;  // the default as numbers (uint8_t would print as a character)
    for (uint8_t v : a->negatives) negatives += (negatives.empty() ? "" : ",") + std::to_string(v);
    c->add_option("--negatives", a->negatives,
                  "Truth values scored as defect-free (a mark there is a false positive)")
        ->delimiter(',')
        ->default_str(negatives);
    DefectMapOptions& m = a->map;
    c->add_option("--notch-ratio", m.notchRatio,
                  "auto: a spectrum bin above this x its "
                  "background is texture")
        ->capture_default_str();
    c->add_option("--spectrum-window", m.spectrumWindow,
                  "auto: bins of the spectral background's running medians (odd)")
        ->capture_default_str();
    c->add_option("--notch-spread", m.notchSpread,
                  "auto: bins around a notched bin that join it when above --notch-grow x B")
        ->capture_default_str();
    c->add_option("--notch-grow", m.notchGrow, "auto: see --notch-spread")->capture_default_str();
    c->add_option("--keep-low-bins", m.keepLowBins, "auto: bins around DC never notched")
        ->capture_default_str();
    c->add_option("--level-wiener", m.levelWiener,
                  "auto: the score's level takes the notched bins' Wiener estimate, not their "
                  "background with the texture's phase (true/false)")
        ->capture_default_str();
    c->add_option("--macro-window", m.macroWindow,
                  "auto: samples of the macro shape's running median (odd)")
        ->capture_default_str();
    c->add_option("--passes", m.passes, "auto: macro-shape + notch passes")->capture_default_str();
    c->add_option("--pad", m.pad, "auto: samples of mirror padding per side")
        ->capture_default_str();
    c->add_option("--level-window", m.levelWindow,
                  "auto: samples of the local level's running median (odd)")
        ->capture_default_str();
    c->add_option("--edge-window", m.edgeWindow,
                  "auto: samples of the edge residual's quadratic fit (odd)")
        ->capture_default_str();
    c->add_option("--edge-weight", m.edgeWeight, "auto: weight of the edge residual in the score")
        ->capture_default_str();
    c->add_option("--edge-axes", m.edgeAxes,
                  "auto: one edge residual per axis, each in its own robust sigma (true/false)")
        ->capture_default_str();
    c->add_option("--edge-robust", m.edgeRobust,
                  "auto: with --edge-axes, the edge fits leave out the samples that alone seed "
                  "the map (true/false)")
        ->capture_default_str();
    c->add_option("--seed-sigma", m.seedSigma, "auto: hysteresis seed threshold (robust sigmas)")
        ->capture_default_str();
    c->add_option("--grow-sigma", m.growSigma, "auto: hysteresis grow threshold (robust sigmas)")
        ->capture_default_str();
    c->add_option("--line-length", m.lineLength,
                  "auto: samples of the line-valley score's segment (odd; 0: off)")
        ->capture_default_str();
    c->add_option("--line-orientations", m.lineOrientations,
                  "auto: directions of the line-valley score over 180 degrees")
        ->capture_default_str();
    c->add_option("--line-offset", m.lineOffset,
                  "auto: samples from a line to the sides the line-valley score compares it with")
        ->capture_default_str();
    c->add_option("--line-seed-sigma", m.lineSeedSigma,
                  "auto: a line region reaches this line-valley score (robust sigmas)")
        ->capture_default_str();
    c->add_option("--line-grow-sigma", m.lineGrowSigma,
                  "auto: a line region holds this line-valley score (robust sigmas)")
        ->capture_default_str();
    c->add_option("--seed-tail", m.seedTail,
                  "auto: seed thresholds raised to this x the texture's own score quantile "
                  "(--seed-tail-quantile) when higher (0: off)")
        ->capture_default_str();
    c->add_option("--seed-tail-quantile", m.seedTailQuantile,
                  "auto: the quantile of the score that --seed-tail scales")
        ->capture_default_str();
    c->add_option("--seed-tail-tiles", m.seedTailTiles,
                  "auto: that quantile taken per tile of an NxN grid, their median used "
                  "(a defect is in few tiles; 1: the whole map's quantile)")
        ->capture_default_str();
    c->add_option("--seed-tail-wide", m.seedTailWide,
                  "auto: with --seed-tail, a texture change of at least this many tiles' "
                  "samples is no texture's tail: left out of the tails and marked (0: off)")
        ->capture_default_str();
    c->add_option("--grow-tail", m.growTail,
                  "auto: with --seed-tail, grow thresholds at least this x the same score "
                  "quantile, not scaled with the seed (0: scaled)")
        ->capture_default_str();
    c->add_option("--border", m.border, "auto: samples at the map's edges never marked")
        ->capture_default_str();
    c->add_option("--min-region", m.minRegion, "auto: smallest region kept (samples)")
        ->capture_default_str();
    c->add_option("--energy-window", m.energyWindow,
                  "auto: samples of the texture-change detector's running median (odd; 0: off)")
        ->capture_default_str();
    c->add_option("--energy-ratio", m.energyRatio,
                  "auto: local amplitude over its median that marks a texture change")
        ->capture_default_str();
    c->add_option("--energy-grow-border", m.energyGrowBorder,
                  "auto: texture-change marks grow outward into the --border samples where the "
                  "local amplitude stays high (true/false)")
        ->capture_default_str();
    c->add_option("--texture-energy", m.textureEnergy,
                  "auto: also mark where the texture's own local amplitude is energy-ratio x its "
                  "median (true/false)")
        ->capture_default_str();
    c->add_option("--texture-energy-ratio", m.textureEnergyRatio,
                  "auto: the ratio of --texture-energy")
        ->capture_default_str();
    c->add_option("--texture-sectors", m.textureSectors,
                  "auto: --texture-energy on the texture split into this many orientation "
                  "sectors of its spectrum, each against its own median (1: whole)")
        ->capture_default_str();
    c->add_option("--step-model", m.stepModel,
                  "auto: detect sharp steps explicitly and mark only their ramps, not the running "
                  "medians' smear of them (true/false)")
        ->capture_default_str();
    c->add_option("--step-window", m.stepWindow,
                  "auto: 2m+1, each side of the step detector taking 2m samples (odd)")
        ->capture_default_str();
    c->add_option("--step-sigma", m.stepSigma,
                  "auto: a step centre's jump in robust sigmas of the detector")
        ->capture_default_str();
    c->add_option("--step-sharpness", m.stepSharpness,
                  "auto: a step centre's 2-sample rise over its jump")
        ->capture_default_str();
    c->add_option("--step-plateau", m.stepPlateau,
                  "auto: a step centre's difference of its sides' medians over its jump")
        ->capture_default_str();
    c->add_option("--step-min-length", m.stepMinLength,
                  "auto: samples of the shortest step centre line kept")
        ->capture_default_str();
    c->add_option("--step-ramp-half", m.stepRampHalf,
                  "auto: samples marked within this distance of a step's centre line")
        ->capture_default_str();
    c->add_option("--step-ramp-moved", m.stepRampMoved,
                  "auto: on a step's high side, mark only where a smoothstep ramp has moved the "
                  "surface by this share of the jump")
        ->capture_default_str();
    c->add_option("--step-gap", m.stepGap,
                  "auto: samples of the longest arc between a circular step's points that is "
                  "filled (0: none)")
        ->capture_default_str();
    c->add_option("--step-band", m.stepBand,
                  "auto: samples around a step's centre line where only its ramp is marked")
        ->capture_default_str();
    c->add_option("--ring-window", m.ringWindow,
                  "auto: samples of arc of the ring model's median (rotational textures; 0: off)")
        ->capture_default_str();
    c->add_option("--ring-isotropy", m.ringIsotropy,
                  "auto: the ring model needs this spread of the texture's orientations")
        ->capture_default_str();
    c->add_option("--ring-residual", m.ringResidual,
                  "auto: ... and leaves at most this share of the texture's median amplitude")
        ->capture_default_str();
    c->add_option("--ring-ratio", m.ringRatio,
                  "auto: the ring model's level replaces the level when at most this share of it")
        ->capture_default_str();
    c->add_option("--ring-repass", m.ringRepass,
                  "auto: where the ring model is used, remove the texture once more with the macro "
                  "shape of the map minus the texture (true/false)")
        ->capture_default_str();
    LayMapOptions& l = m.lay;
    c->add_option("--lay-length", l.layLength, "lay: samples of the median along the lay (odd)")
        ->capture_default_str();
    c->add_option(
         "--lay-clip-quantile", l.clipQuantile,
         "lay: gradients clipped at this quantile of their magnitude for the lay direction")
        ->capture_default_str();
    c->add_option("--lay-field-sigma", l.fieldSigma,
                  "lay: sigma (samples) of the local lay field's tensor (0: one lay for the map)")
        ->capture_default_str();
    c->add_option("--lay-field-coherence", l.fieldCoherence,
                  "lay: below this local coherence, the global lay")
        ->capture_default_str();
    c->add_option("--lay-passes", l.layPasses,
                  "lay: times the lay is taken out (the second on the residual: a crossing lay)")
        ->capture_default_str();
    c->add_option("--lay-field-exclude", l.fieldExclude,
                  "lay: the field leaves out the first pass's marks grown by this many samples")
        ->capture_default_str();
    c->add_option("--lay-level-window", l.levelWindow,
                  "lay: samples of the residual's running median (odd)")
        ->capture_default_str();
    c->add_option("--lay-macro-window", l.macroWindow,
                  "lay: samples of the running median the texture's RMS is taken about (odd)")
        ->capture_default_str();
    c->add_option("--lay-seed-sigma", l.seedSigma,
                  "lay: a region reaches this many robust sigmas of the residual")
        ->capture_default_str();
    c->add_option("--lay-grow-sigma", l.growSigma, "lay: ... and holds this many")
        ->capture_default_str();
    c->add_option("--lay-texture-rms", l.textureRms,
                  "lay: a region's peak is at least this x the texture's RMS (0: off)")
        ->capture_default_str();
    c->add_option("--lay-border", l.border, "lay: samples at the map's edges never marked")
        ->capture_default_str();
    c->add_option("--lay-min-region", l.minRegion, "lay: smallest region kept (samples)")
        ->capture_default_str();
    c->add_option("--lay-drop-border-regions", l.dropBorderRegions,
                  "lay: drop regions that reach the border's inner line (true/false)")
        ->capture_default_str();
    c->add_option("--lay-border-regrow", l.borderRegrow,
                  "lay: a region reaching the border is split again at this x the texture-RMS "
                  "threshold; parts that do not reach it are kept")
        ->capture_default_str();
    SelfSimMapOptions& q = m.selfsim;
    c->add_option("--selfsim-patch", q.patch, "selfsim: side of the patches compared (odd)")
        ->capture_default_str();
    c->add_option("--selfsim-offsets", q.offsets,
                  "selfsim: texture offsets kept (copies of each sample)")
        ->capture_default_str();
    c->add_option("--selfsim-search-radius", q.searchRadius,
                  "selfsim: largest offset searched, samples")
        ->capture_default_str();
    c->add_option("--selfsim-exclusion", q.exclusion,
                  "selfsim: smallest offset (the sample's own neighbourhood), samples")
        ->capture_default_str();
    c->add_option("--selfsim-refine", q.refine,
                  "selfsim: each copy's offset refined within this many samples per axis")
        ->capture_default_str();
    c->add_option("--selfsim-sectors", q.sectors,
                  "selfsim: the offsets' directions (mod 180 deg) in this many sectors")
        ->capture_default_str();
    c->add_option("--selfsim-per-sector", q.perSector,
                  "selfsim: at most this many offsets in each direction sector")
        ->capture_default_str();
    c->add_option("--selfsim-quality", q.quality,
                  "selfsim: an offset's median difference at most this x the tile's best")
        ->capture_default_str();
    c->add_option("--selfsim-tile", q.tile,
                  "selfsim: offsets chosen per tile of this side (0: one set for the map)")
        ->capture_default_str();
    c->add_option("--selfsim-context", q.context,
                  "selfsim: ... on the tile grown by this many samples")
        ->capture_default_str();
    c->add_option("--selfsim-keep", q.keep,
                  "selfsim: share of the copies (most similar patches) in the median")
        ->capture_default_str();
    c->add_option("--selfsim-scales", q.scales, "selfsim: detection scales (sigma 0, 1, 2, 4, ...)")
        ->capture_default_str();
    c->add_option("--selfsim-nfa", q.nfa,
                  "selfsim: expected false detections on a Gaussian residual")
        ->capture_default_str();
    c->add_option("--selfsim-tail-quantile", q.tailQuantile,
                  "selfsim: sigma at least this quantile of the residual over the Gaussian's (0: "
                  "off)")
        ->capture_default_str();
    c->add_option("--selfsim-texture-rms", q.textureRms,
                  "selfsim: a region's peak residual at least this x the texture's RMS (0: off)")
        ->capture_default_str();
    c->add_option("--selfsim-roughness-cutoff", q.roughnessCutoff,
                  "selfsim: ... that RMS the roughness's: the heights less their Gaussian "
                  "low-pass of this cutoff wavelength, samples (0: off)")
        ->capture_default_str();
    c->add_option("--selfsim-grow-sigma", q.growSigma,
                  "selfsim: regions grow into this many robust sigmas")
        ->capture_default_str();
    c->add_option("--selfsim-grow-scale", q.growScale, "selfsim: ... at scales up to this index")
        ->capture_default_str();
    c->add_option("--selfsim-border", q.border, "selfsim: samples at the map's edges never marked")
        ->capture_default_str();
    c->add_option("--selfsim-min-region", q.minRegion, "selfsim: smallest region kept (samples)")
        ->capture_default_str();
    c->add_option("--selfsim-drop-border-regions", q.dropBorderRegions,
                  "selfsim: drop regions that reach the border's inner line (true/false)")
        ->capture_default_str();
    c->add_option("--selfsim-texture-nfa", q.textureNfa,
                  "selfsim: expected texture regions above the texture's own tail of region "
                  "peaks (0: off)")
        ->capture_default_str();
    c->add_option("--selfsim-texture-quantile", q.textureQuantile,
                  "selfsim: ... the tail starting at this quantile of the regions' peaks")
        ->capture_default_str();
    c->add_option("--selfsim-line-nfa", q.lineNfa,
                  "selfsim: expected texture pieces above the texture's own tail of line scores "
                  "(a region under the tail of peaks kept where it holds a line; 0: off)")
        ->capture_default_str();
    c->add_option("--selfsim-trim-share", q.trimShare,
                  "selfsim: a kept region keeps its samples scoring at least this share of its "
                  "largest score (0: off)")
        ->capture_default_str();
    c->add_option("--selfsim-particle-elongation", q.particleElongation,
                  "selfsim: a kept region more compact than this elongation and raised is a "
                  "particle, dropped (0: off)")
        ->capture_default_str();
    c->add_option("--selfsim-particle-raised-share", q.particleRaisedShare,
                  "selfsim: ... raised: at least this share of its residual above the texture")
        ->capture_default_str();
    c->add_option("--selfsim-border-piece-fill", q.borderPieceFill,
                  "selfsim: a region at the border is split by sign; a piece off the border is "
                  "kept when its mean score is at least this share of its largest (0: off)")
        ->capture_default_str();
    c->add_option("--selfsim-border-piece-min", q.borderPieceMin,
                  "selfsim: ... and it keeps at least this many samples")
        ->capture_default_str();
    c->add_option("--selfsim-border-piece-rim", q.borderPieceRim,
                  "selfsim: ... a kept piece takes its region's raised samples within this many "
                  "samples of it, its pile-up (0: off)")
        ->capture_default_str();
    c->add_option("--selfsim-border-piece-sigma", q.borderPieceSigma,
                  "selfsim: ... pieces only on a map whose residual sigma is at least this share "
                  "of its RMS (a texture, not a relief; 0: every map)")
        ->capture_default_str();
    c->add_option("--selfsim-border-level-step", q.borderLevelStep,
                  "selfsim: a region at the border is split again at levels of its score rising "
                  "by this factor; a piece off the border is judged as the pieces above (0: off)")
        ->capture_default_str();
    c->add_option("--selfsim-border-level-fill", q.borderLevelFill,
                  "selfsim: ... and kept when its mean score is at least this share of its largest")
        ->capture_default_str();
    c->add_option("--selfsim-border-level-shape", q.borderLevelShape,
                  "selfsim: ... and its mean excess over the level at least this share of its "
                  "largest excess")
        ->capture_default_str();
    c->add_option("--selfsim-border-basin", q.borderBasin,
                  "selfsim: ... a piece kept at a level takes back its basin, flooded down to the "
                  "growth's level with levels falling by this factor (0: off)")
        ->capture_default_str();
    c->add_option("--selfsim-border-basin-growth", q.borderBasinGrowth,
                  "selfsim: ... the basin given up when it holds more than this many times the "
                  "piece's samples (0: no bound)")
        ->capture_default_str();
    c->add_option("--selfsim-line-elongation", q.lineElongation,
                  "selfsim: a piece of a region at the border at least this elongated ...")
        ->capture_default_str();
    c->add_option("--selfsim-line-angle", q.lineAngle,
                  "selfsim: ... and crossing the texture's lay by at least this many degrees is "
                  "kept as a groove, whatever its depth profile (0 elongation: off)")
        ->capture_default_str();
    c->add_option("--selfsim-line-lay-contrast", q.lineLayContrast,
                  "selfsim: ... where its tile has a lay: its best offset's difference at most "
                  "1 / this of the best one 45 degrees or more from it")
        ->capture_default_str();
    c->add_option("--selfsim-burr-elongation", q.burrElongation,
                  "selfsim: a piece of a region at the border above the texture at least this "
                  "elongated and crossing the texture's lay as the line angle asks is kept, a burr "
                  "across the striae (0: off)")
        ->capture_default_str();
    c->add_option("--selfsim-burr-basin", q.burrBasin,
                  "selfsim: ... a burr kept takes back its basin above the texture, flooded down "
                  "to the growth's level with levels falling by this factor (0: off)")
        ->capture_default_str();
    c->add_option("--selfsim-hollow-row-gap", q.hollowRowGap,
                  "selfsim: compact regions below the texture whose centres are at most this many "
                  "samples apart are linked; a row of them in a line is kept, a pit chain (0: off)")
        ->capture_default_str();
    c->add_option("--selfsim-hollow-row-members", q.hollowRowMembers,
                  "selfsim: ... a row: at least this many of them")
        ->capture_default_str();
    c->add_option("--selfsim-hollow-chain-tolerance", q.chainTolerance,
                  "selfsim: hollows of the regions at the border (and off it) evenly spaced on a "
                  "line, each within this share of the step of where it falls, are a chain, kept "
                  "(0: off)")
        ->capture_default_str();
    c->add_option("--selfsim-hollow-chain-lay-angle", q.chainLayAngle,
                  "selfsim: ... unless the chain runs within this many degrees of its tile's lay "
                  "(0: no test)")
        ->capture_default_str();
    c->add_option("--selfsim-far-bank-reach", q.farBankReach,
                  "selfsim: a raised line beside a groove and parallel to it, its centre within "
                  "this many samples of the groove's axis, is kept as the groove's bank (0: off)")
        ->capture_default_str();
    c->add_option("--selfsim-lay-line-elongation", q.layLineElongation,
                  "selfsim: a mark at least this elongated along its tile's lay ... (0: off)")
        ->capture_default_str();
    c->add_option("--selfsim-lay-line-angle", q.layLineAngle,
                  "selfsim: ... its long axis within this many degrees of the lay ...")
        ->capture_default_str();
    c->add_option("--selfsim-lay-line-stand-out", q.layLineStandOut,
                  "selfsim: ... its median score on the residual below at least this ...")
        ->capture_default_str();
    c->add_option("--selfsim-lay-line-stand-out-max", q.layLineStandOutMax,
                  "selfsim: ... and at most this (0: no cap) ...")
        ->capture_default_str();
    c->add_option("--selfsim-lay-line-kept", q.layLineKept,
                  "selfsim: ... its median |r| at most this times its median on that residual "
                  "(0: no test) ...")
        ->capture_default_str();
    c->add_option("--selfsim-lay-line-reach", q.layLineReach,
                  "selfsim: ... takes the samples within this many samples of it, connected to "
                  "it ...")
        ->capture_default_str();
    c->add_option("--selfsim-lay-line-sigma", q.layLineSigma,
                  "selfsim: ... that score at least this on the residual whose copies come from "
                  "the offsets ...")
        ->capture_default_str();
    c->add_option("--selfsim-lay-line-width", q.layLineWidth,
                  "selfsim: ... crossing the lay by more than this many samples (no copy lands "
                  "on the line)")
        ->capture_default_str();
    c->add_option("--selfsim-line-copies-sigma", q.lineCopiesSigma,
                  "selfsim: a line along the lay takes the samples of its corridor scoring at "
                  "least this on the residual of copies chosen for it across it (0: off)")
        ->capture_default_str();
    c->add_option("--selfsim-valley-line-sigma", q.valleyLineSigma,
                  "selfsim: a valley of the heights beside a mark, its seed this many robust "
                  "sigmas of the texture's valley response (0: off)")
        ->capture_default_str();
    c->add_option("--selfsim-valley-line-grow", q.valleyLineGrow,
                  "selfsim: ... grown down to this many")
        ->capture_default_str();
    c->add_option("--selfsim-valley-line-gate", q.valleyLineGate,
                  "selfsim: ... when at most this share of the texture reaches the seed's score")
        ->capture_default_str();
    c->add_option("--selfsim-rim-band-mean", q.rimBandMean,
                  "selfsim: a groove's rims judged along it: a segment of the band beside it "
                  "whose mean robust-sigma score is at least this takes its samples above the "
                  "texture (0: off)")
        ->capture_default_str();
    c->add_option("--selfsim-rim-band-share", q.rimBandShare,
                  "selfsim: ... and at least this share of whose samples lie above the texture")
        ->capture_default_str();
    c->add_option("--selfsim-rim-band-reach", q.rimBandReach,
                  "selfsim: ... the band reaching this times the groove's core width from it")
        ->capture_default_str();
    c->add_option("--selfsim-rim-band-segment", q.rimBandSegment,
                  "selfsim: ... a segment this times the mark's width long")
        ->capture_default_str();
    c->add_option("--selfsim-edge-ring-sigma", q.edgeRingSigma,
                  "selfsim: the marks' edge a cell at a time: a sample beside a mark scoring at "
                  "least this many robust sigmas with the mark's sign (0: off) ...")
        ->capture_default_str();
    c->add_option("--selfsim-edge-ring-share", q.edgeRingShare,
                  "selfsim: ... is marked when at least this share of its cell's edge samples are")
        ->capture_default_str();
    c->add_option("--selfsim-edge-ring-cell", q.edgeRingCell,
                  "selfsim: ... the cells this many samples square")
        ->capture_default_str();
    c->add_option("--selfsim-valley-rim-mean", q.valleyRimMean,
                  "selfsim: beside a valley line (step 8t's), a segment of the band whose heights "
                  "stand this many robust sigmas of its ground above the ground (0: off) ...")
        ->capture_default_str();
    c->add_option("--selfsim-valley-rim-share", q.valleyRimShare,
                  "selfsim: ... at least this share of them above it, gives them to the map")
        ->capture_default_str();
    c->add_option("--selfsim-valley-rim-reach", q.valleyRimReach,
                  "selfsim: ... the band this times the line's width wide")
        ->capture_default_str();
    c->add_option("--selfsim-relief", q.relief,
                  "selfsim: on a relief (heights on a few flat levels: lettering, a stepped part) "
                  "take each sample's plateau level out first (true/false)")
        ->capture_default_str();
    c->add_option("--selfsim-groove-bank-width", q.grooveBankWidth,
                  "selfsim: a mark below the texture as long as a line takes the samples above it "
                  "scoring at least the growth's sigma within this times its width of it, its "
                  "banks (0: off)")
        ->capture_default_str();
    c->add_option("--selfsim-groove-length", q.grooveLength,
                  "selfsim: ... a line: its samples at least this times its width squared")
        ->capture_default_str();
    c->add_option("--selfsim-groove-rim-sigma", q.grooveRimSigma,
                  "selfsim: a groove's raised rims (a mark below the texture as long as a line) "
                  "taken from this many robust sigmas (0: off)")
        ->capture_default_str();
    c->add_option("--selfsim-groove-rim-length", q.grooveRimLength,
                  "selfsim: ... a line: its samples at least this times its width squared ...")
        ->capture_default_str();
    c->add_option("--selfsim-groove-rim-width", q.grooveRimWidth,
                  "selfsim: ... within this times its width of it ...")
        ->capture_default_str();
    c->add_option("--selfsim-groove-rim-share", q.grooveRimShare,
                  "selfsim: ... when at least this share of the residual there is above the "
                  "texture (0: no test)")
        ->capture_default_str();
    c->add_option("--selfsim-pile-up-reach", q.pileUpReach,
                  "selfsim: a kept region below the texture takes the samples above it within "
                  "this many samples, its pile-up (0: off)")
        ->capture_default_str();
    c->add_option("--selfsim-pile-up-sigma", q.pileUpSigma,
                  "selfsim: ... those scoring at least this many robust sigmas")
        ->capture_default_str();
    c->add_option("--selfsim-pile-up-share", q.pileUpShare,
                  "selfsim: ... when at least this share of its residual is below the texture")
        ->capture_default_str();
    c->add_option("--selfsim-extend-steps", q.extendSteps,
                  "selfsim: a kept region grows this many samples further into its flanks (0: "
                  "off)")
        ->capture_default_str();
    c->add_option("--selfsim-extend-share", q.extendShare,
                  "selfsim: ... into samples of its sign scoring at least this share of its peak")
        ->capture_default_str();
    c->add_option("--selfsim-extend-sigma", q.extendSigma,
                  "selfsim: ... and at least this many robust sigmas")
        ->capture_default_str();
    c->add_option("--kernel", m.paper.kernel, "paper: moving-average window, samples")
        ->capture_default_str();
    c->add_option("--patch", m.paper.patch, "paper: patch side, samples")->capture_default_str();
    c->add_option("--threshold", m.paper.threshold, "paper: patch range threshold in [0, 1]")
        ->capture_default_str();
    c->callback([a, &run] { run = [a] { return runDefectMap(*a); }; });
}

}  // namespace sl::cli
