#include "app/jobs/OptimizeStages.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <utility>

#include "app/host/Version.h"
#include "app/pipeline/Cache.h"
#include "app/pipeline/InitialState.h"
#include "app/pipeline/JudgeEstimate.h"
#include "app/pipeline/PartOfTransport.h"
#include "app/pipeline/Search.h"
#include "app/pipeline/Truth.h"
#include "app/report/OptimizeFigures.h"
#include "app/report/PartSummary.h"
#include "app/report/Preview.h"
#include "app/report/Report.h"
#include "core/Color.h"
#include "core/Error.h"
#include "core/Hash.h"
#include "core/Interrupt.h"
#include "core/Progress.h"
#include "core/Registry.h"
#include "core/Stopwatch.h"
#include "core/Text.h"
#include "io/AtomicFile.h"
#include "io/EnvMapIO.h"
#include "io/ImageIO.h"
#include "io/MaskIO.h"
#include "io/OptimizeOutDir.h"
#include "io/SceneFile.h"
#include "io/StagedDirectory.h"
#include "io/TransportFile.h"
#include "objective/ImageSpace.h"
#include "objective/Metrics.h"
#include "objective/TransportLoss.h"
#include "objective/UnbiasedObjective.h"
#include "optimize/SpecularInit.h"
#include "render/Footprint.h"
#include "render/Render.h"
#include "scene/EnvMapBasis.h"
#include "scene/EnvMapPresets.h"
#include "scene/EnvMapToE.h"
#include "scene/Scene.h"

namespace sl::optimizejob {

namespace {

std::string lambdaName(double lambda) {
    std::ostringstream s;
    s << "lambda-" << lambda;
    return s.str();
}

}  // namespace

VisibilityMetrics metricsFor(const TransportMatrix& t, const std::vector<double>& image,
                             const std::vector<uint8_t>& mask, const std::vector<double>& e,
                             bool rgb, const std::vector<uint8_t>& truth) {
    MetricsInput in;
    in.width = t.width;
    in.height = t.height;
    in.channels = t.channels == 3 ? 3 : 1;
    in.image = image;
    in.objectMask = t.objectMask;
    in.lossMask = mask;
    in.envmap = e;
    in.envChannels = rgb ? 3 : 1;
    in.truthMask = truth;
    return computeVisibilityMetrics(in);
}

/// The render a person looks at: RGB when T is RGB, else luminance. Over MPI ranks t is this
/// rank's shard (the rows of `shard`) and the image is put together over the ranks.
std::vector<double> renderImage(const TransportMatrix& t, const std::vector<double>& e,
                                const RowShard& shard) {
    const size_t ch = t.channels == 3 ? 3 : 1;
    std::vector<double> out(t.rows() * ch);
    if (t.channels == 3)
        t.applyRgb(e, out);
    else
        t.applyLuminance(e, out);
    shard.gatherImage(out, static_cast<size_t>(t.width), ch);
    return out;
}

namespace {

/// The defects objective's regions in the image (defect map or truth projected), unless this
/// job already has them (they depend on the scene and the options only).
void defectRegionsOnce(const OptimizeJobOptions& o, Inputs& in) {
    if (in.sceneParts || !in.defects.empty()) return;
    DefectRegions regions = defectRegionsInImage(*in.scene, o.defects, o.truth, o.reference);
    in.defects = std::move(regions.defects);
    in.reference = std::move(regions.reference);
    in.unjudgedRegions = regions.unjudgedRegions;
    in.unjudgedShare = regions.unjudgedShare;
}

/// The defect pixels' sample multipliers of the training trace: `given` (> 0) on every defect
/// pixel, else the rule's factor per label (app/pipeline/TrainingNoise.h defectSppFactors) for the
/// defect pixels on the part's footprint; printed when above 1.
std::vector<uint8_t> chooseDefectSppScale(const Scene& scene, const std::vector<uint8_t>& defects,
                                          int given) {
    size_t part = 0;
    std::array<size_t, 256> labelPixels{};
    const std::vector<PixelSpan> spans = partFootprint(scene);
    const auto W = static_cast<size_t>(scene.camera.width());
    for (size_t y = 0; y < spans.size(); ++y)
        for (int x = spans[y].begin; x < spans[y].end; ++x) {
            ++part;
            ++labelPixels[defects[y * W + static_cast<size_t>(x)]];
        }
    std::array<int, 256> factors;
    if (given > 0)
        factors.fill(given);
    else
        factors = defectSppFactors(labelPixels, part);
    size_t marked = 0;
    double extra = 0;
    std::string perLabel;
    for (const size_t v : labelsBySize(labelPixels)) {  // as the rule takes them
        marked += labelPixels[v];
        extra += static_cast<double>(labelPixels[v]) * (factors[v] - 1);
        perLabel +=
            fmt::format("{}{} px {}x", perLabel.empty() ? "" : ", ", labelPixels[v], factors[v]);
    }
    const std::string share =
        formatNumber(100.0 * extra / static_cast<double>(std::max<size_t>(part, 1)), 2);
    if (extra > 0 && given > 0)
        spdlog::info(
            "defect pixels: {} of the part's {} take {}x the training spp (given; +{} % "
            "samples)",
            marked, part, given, share);
    else if (extra > 0)
        spdlog::info(
            "defect pixels: {} of the part's {} take more of the training spp, by label from the "
            "smallest ({}; their few pairs are the objective's noisiest sums; +{} % samples)",
            marked, part, perLabel, share);
    return defectSppScale(defects, factors);
}

/// The cache a stage reads and writes what it derives from T in (the specular start, the part's
/// record, V found by T's inputs): none on an MPI rank's shard of T.
std::filesystem::path derivedCacheDir(const Plan& p, const Inputs& in) {
    return in.shard.distributed() ? std::filesystem::path() : p.cacheDir;
}

/// A .tm's scene, loaded now (from T's provenance) for `purpose`; what it says of the part is
/// kept beside T for the next run (app/pipeline/PartOfTransport.h).
void sceneOfTm(const Plan& p, Inputs& in, const OptimizeJobSummary& job,
               const std::string& purpose) {
    in.scene = sceneOfTransport(job.transport.file, purpose);
    if (auto kept = keepPartOfTransport(derivedCacheDir(p, in), job.transport.file, *in.scene,
                                        partSummaryJson(*in.scene)))
        in.part = std::move(kept);
}

}  // namespace

/// Stage 1: the scene and the training estimates of T (traced or cached, or the .tm); `spp`:
/// the noise-aware rule's choice (app/pipeline/TrainingNoise.h), over any other (0: none).
void loadTraining(const Plan& p, Inputs& in, OptimizeJobSummary& job, int spp) {
    const OptimizeJobOptions& o = p.o;
    // The objective: as given, else the defaults' (app/pipeline/Defaults.h defaultObjective);
    // for a .tm settled once its planes are read.
    const bool defectsNamed = !o.truth.empty() || !o.defects.empty();
    in.kind = o.objectiveKind ? *o.objectiveKind
                              : (p.tmInput ? ObjectiveKind::Paper : defaultObjective(defectsNamed));
    if (!o.objectiveKind && in.kind == ObjectiveKind::Defects &&
        o.objective.reg != RegTarget::EnvMap)
        throw inputError(option("reg") + " image",
                         "does not go with the defects objective, the default when " +
                             option("truth") + " or " + option("defects") + " names the defects",
                         "add " + option("objective") +
                             " unbiased (or paper) for the regulariser "
                             "on the image");
    if (p.tmInput) {
        const Stopwatch clock;
        job.transport.file =
            p.ranks ? readShardOfRank(o.input, *p.ranks, &in.shard) : readTransportFile(o.input);
        job.transport.path = o.input;
        job.transport.secondsTotal = clock.seconds();
        if (!o.objectiveKind)
            in.kind = defaultObjective(defectsNamed, job.transport.file.matrix.planes);
    } else {
        if (!in.scene) in.scene = loadScene(o.input, o.sceneOverrides);
        PrecomputeOptions pre = o.precompute;
        pre.rgb = o.rgb;
        if (in.onHalves()) pre.sampleSets = 2;
        const auto depth = resolveMaxDepth(*in.scene, pre);
        if (o.traceMaskOnly && o.mask.kind == LossMaskKind::Object)
            throw inputError(option("trace-mask-only"), "needs a mask to trace",
                             "add " + option("mask") + " FILE or " + option("mask") +
                                 " scratch, or drop it (the whole part is traced)");
        // The loss mask's pixels before T exists, when only they are traced.
        if (o.traceMaskOnly) pre.pixels = lossMaskRegion(o.mask, *in.scene, o.scratch);
        // eq. 2 rewards noise: without a given spp it starts at no fewer than paperMinSpp (the
        // paper's own loop and the black boxes keep the scene's spp); the noise-aware rule
        // then measures what is left.
        const int minSpp = optimizeDefaults().paperMinSpp;
        if (in.kind == ObjectiveKind::Paper && p.requested != OptimizerMethod::PaperLoop &&
            !p.blackBox && !pre.spp)
            pre.spp = std::max(in.scene->desc.render.spp, minSpp);
        if (spp > 0) pre.spp = spp;
        // The defect pixels take more samples (app/pipeline/TrainingNoise.h defectSppScale): the
        // defects objective's regions are needed before T.
        if (in.kind == ObjectiveKind::Defects && p.superSampleDefects && !in.sppScale) {
            defectRegionsOnce(o, in);
            in.sppScale = chooseDefectSppScale(*in.scene, in.defects, o.defectSppScale);
        }
        if (in.sppScale) pre.sppScale = *in.sppScale;
        std::vector<TransportSource> set =
            transportSetForScene(*in.scene, pre, o.estimates, p.cacheDir);
        job.transport = std::move(set.front());
        job.transport.autoDepth = depth;
        if (!pre.spp) pre.spp = job.transport.file.provenance.spp;
        in.trained = pre;
        in.trainingSeed = job.transport.file.provenance.seed;
        for (size_t k = 1; k < set.size(); ++k) job.extraEstimates.push_back(std::move(set[k]));
    }
    const TransportMatrix& t = job.transport.file.matrix;
    if (o.rgb && t.channels != 3)
        throw inputError(o.input.string(),
                         "is a gray transport matrix; " + option("rgb") + " needs an RGB one",
                         "precompute it with " + option("rgb"));
    if (in.onHalves() && t.planes != 2)
        throw inputError(o.input.string(),
                         "has no half-sample matrices; " + option("objective") + " " +
                             objectiveKindName(in.kind) + " needs them",
                         "precompute it with " + option("halves") + ", or pass the scene file");
    // What needs the scene itself: for a .tm, read from T's provenance. A specular start only
    // when it is not cached; V is read from the cache by T's recorded inputs when it is there
    // (loadValidation), and with the part's record in the cache (app/pipeline/PartOfTransport.h)
    // the height map is then not read at all.
    if (!in.scene) {
        bool specularStart = false, specularTraced = false;
        for (const InitialState& s : o.starts) {
            specularStart |= s.kind == InitialKind::Specular;
            specularTraced |= initialEnvMapNeedsScene(
                s, t.envWidth, t.envHeight, o.rgb, job.transport.file.provenance.maxDepth,
                derivedCacheDir(p, in), job.transport.file.provenance.fingerprint);
        }
        const bool needHeights = p.blackBox || o.mask.kind == LossMaskKind::Scratch ||
                                 specularTraced || in.kind == ObjectiveKind::Defects ||
                                 !o.truth.empty() || o.heldOut.mode == HeldOutMode::Judge;
        if (!needHeights && specularStart && !in.part)
            in.part = partOfTransport(job.transport.file, p.cacheDir);
        const std::string purpose =
            o.heldOut.mode == HeldOutMode::Judge
                ? "the held-out estimate (or " + option("heldout") + " none)"
                : option("mask") + " scratch / " + option("init") + " specular / " +
                      option("truth");
        if (needHeights || (specularStart && !(in.part && in.part->recorded())))
            sceneOfTm(p, in, job, purpose);
    }
    in.set = {&t};
    for (const TransportSource& x : job.extraEstimates) in.set.push_back(&x.file.matrix);
}

/// Stage 2: the independent estimate every result is scored on.
void loadHeldOut(const Plan& p, const Inputs& in, OptimizeJobSummary& job) {
    const OptimizeJobOptions& o = p.o;
    const TransportMatrix& t = job.transport.file.matrix;
    switch (o.heldOut.mode) {
        case HeldOutMode::None:
            return;
        case HeldOutMode::File: {
            TransportSource h;
            h.file = readTransportFile(o.heldOut.file);
            h.path = o.heldOut.file;
            const TransportMatrix& ht = h.file.matrix;
            if (ht.width != t.width || ht.height != t.height || ht.envWidth != t.envWidth ||
                ht.envHeight != t.envHeight || ht.planes != 2 || ht.channels != t.channels)
                throw inputError(o.heldOut.file.string(),
                                 "does not fit the training transport matrix",
                                 "it needs the same image and env-map size, the same channels, "
                                 "and two halves (precompute " +
                                     option("halves") + ")");
            job.heldOut = std::move(h);
            break;
        }
        case HeldOutMode::Judge:
            // The judge's first round (judgeRun adds rounds while the scores are too noisy).
            job.heldOut =
                judgeEstimateFor(job.transport.file, *in.scene,
                                 o.heldOutSpp > 0 ? o.heldOutSpp : kJudgePilotSpp, p.cacheDir);
            break;
    }
    const uint64_t hs = job.heldOut->file.provenance.seed, ts = job.transport.file.provenance.seed;
    if (hs >= ts && hs < ts + static_cast<uint64_t>(o.estimates))
        throw inputError(option("seed"), "the training seed range overlaps the judge's seed",
                         "use another " + option("seed"));
}

/// Stage 2b: the validation estimate (app/pipeline/TrainingNoise.h): the training trace again with
/// its own seed, two sample sets; for a .tm, T's recorded spp and path length on its scene.
void loadValidation(const Plan& p, Inputs& in, OptimizeJobSummary& job) {
    job.validation.reset();
    if (!p.validate) return;
    if (!in.scene && !in.part) {
        spdlog::info(
            "no validation estimate: the transport matrix records no scene to trace it from, so "
            "E* is neither checked for over-fitting nor against the references");
        return;
    }
    PrecomputeOptions v;
    uint64_t seed = in.trainingSeed;
    if (in.trained) {
        v = *in.trained;
    } else {
        const TransportProvenance& prov = job.transport.file.provenance;
        v.spp = prov.spp;
        v.maxDepth = prov.maxDepth;
        v.rgb = job.transport.file.matrix.channels == 3;
        seed = prov.seed;
    }
    // V's first round (app/pipeline/TrainingNoise.h step 1): a quarter of T's spp where its
    // figure does not depend on its spp and the rule adapts; more once its rounds asked for it.
    const int tSpp = job.transport.file.provenance.spp;
    const int first = p.noise.adapt && validationSppFree(in.kind) ? validationPilotSpp(tSpp) : tSpp;
    const int spp = std::max(first, p.validationSpp);
    if (!in.scene) {  // a .tm's part: V from the cache by T's recorded inputs, else traced
        job.validation = cachedTransport(in.part->sceneInputs, in.part->sceneRender(),
                                         validationOptions(v, seed, spp), derivedCacheDir(p, in));
        if (job.validation) return;
        sceneOfTm(p, in, job, "the validation estimate");
    }
    job.validation = validationEstimate(*in.scene, v, seed, p.cacheDir, spp);
}

/// The objective in use through the validation estimate (its figure of E* and the gap's SE).
ObjectiveOnT validationObjective(const Inputs& in, const OptimizeJobSummary& job,
                                 const ObjectiveOptions& oo, bool rgb) {
    SearchInputs si;
    si.mask = in.mask.pixels;
    si.rgb = rgb;
    si.defects = in.defects;
    si.reference = in.reference;
    si.shard = in.shard;
    return objectiveOnT(in.kind, job.validation->file.matrix, si, oo);
}

RegionSpec defectRegion(const OptimizeJobOptions& o) {
    return defectRegionSpec(o.defects, o.truth);
}

/// Stage 3: the loss mask, the truth, every start's E0 and what E0 shows (the same for every λ).
void prepareRuns(const Plan& p, Inputs& in, OptimizeJobSummary& job) {
    const OptimizeJobOptions& o = p.o;
    const TransportMatrix& t = job.transport.file.matrix;
    in.mask = lossMask(o.mask, t, in.scene.get(), o.scratch);
    job.maskPixels = in.mask.count;
    if (in.kind == ObjectiveKind::Defects) defectRegionsOnce(o, in);
    if (!o.truth.empty() && !in.sceneParts) in.truth = projectMaskFile(*in.scene, o.truth);
    const int maxDepth = job.transport.file.provenance.maxDepth;
    for (const InitialState& s : o.starts)
        in.startValues.push_back(initialEnvMap(s, t.envWidth, t.envHeight, o.rgb, in.scene.get(),
                                               maxDepth, derivedCacheDir(p, in),
                                               job.transport.file.provenance.fingerprint));
    // A start whose image has no contrast on the part (E = 0: all black) is a plateau of every
    // objective (G = 0, gradient 0): no optimizer can leave it.
    for (size_t k = 0; k < o.starts.size(); ++k) {
        std::vector<double> image = renderImage(t, in.startValues[k], in.shard);
        const size_t ch = image.size() / t.rows();
        double lo = std::numeric_limits<double>::infinity(), hi = -lo;
        for (size_t pix = 0; pix < t.rows(); ++pix)
            if (in.mask.pixels[pix])
                for (size_t c = 0; c < ch; ++c) {
                    lo = std::min(lo, image[pix * ch + c]);
                    hi = std::max(hi, image[pix * ch + c]);
                }
        if (!(hi > lo))
            throw inputError(
                option(o.starts.size() > 1 ? "starts" : "init") + " " + o.starts[k].spec,
                "lights the part without any contrast (every pixel " + formatNumber(hi) +
                    "): the objective's G is 0 and its gradient "
                    "0 there, so no optimizer can leave it",
                "start from a light that shows the part, e.g. const:0.5 or specular");
        if (k == 0) in.image0 = std::move(image);  // T·E0 of the first start, rendered once
    }
    in.metricsInitial =
        metricsFor(t, in.image0, in.mask.pixels, in.startValues.front(), o.rgb, in.truth);
}

namespace {

/// The paper's light on our T: eq. 2 at the paper's λ 30 on mean(E²), Adam lr 0.02 × 100 from
/// E0 = 0.5 (applyOptimizePreset's "paper" settings), on the training estimate T itself rather
/// than 100 fresh estimates. It depends only on T, the loss mask and the channels, so it is
/// kept in the cache beside T (app/pipeline/Cache.h readCachedLight), keyed by T's fingerprint and
/// those: a run on a cached T does not optimize it again (the same values, bit for bit).
std::vector<double> paperLight(const Plan& p, const Inputs& in, const TransportMatrix& t,
                               const std::string& fingerprint) {
    OptimizeJobOptions paper;
    applyOptimizePreset(OptimizePreset::Paper, paper);
    std::string key;
    if (!p.cacheDir.empty() && !fingerprint.empty() && !in.shard.distributed()) {
        std::ostringstream what;
        what << std::setprecision(17) << "paper's light 1; T " << fingerprint << "; rgb " << p.o.rgb
             << "; mask " << toHex(hash64(in.mask.pixels.data(), in.mask.pixels.size()))
             << "; lambda " << paper.lambdas.front() << "; lr " << paper.optimizer.learningRate
             << "; iterations " << paper.optimizer.iterations << "; start "
             << paper.starts.front().spec << "; reg " << static_cast<int>(paper.objective.reg);
        const std::string w = what.str();
        key = hexKey128(w);
        if (auto cached = readCachedLight(p.cacheDir, key);
            cached && cached->size() == t.cols() * (p.o.rgb ? 3 : 1)) {
            spdlog::info("the paper's light on T from cache");
            return *cached;
        }
    }
    SearchInputs si;
    si.set = {&t};
    si.mask = in.mask.pixels;
    si.objective = paper.objective;
    si.objective.lambda = paper.lambdas.front();
    si.rgb = p.o.rgb;
    si.shard = in.shard;
    SearchOptions so;
    so.objective = ObjectiveKind::Paper;
    so.optimizer = paper.optimizer;
    so.optimizer.method = OptimizerMethod::Adam;
    so.optimizer.callback = nullptr;
    so.estimates = 1;
    so.starts = paper.starts;
    std::vector<double> e = search(si, so).e;
    if (!key.empty()) writeCachedLight(p.cacheDir, key, "paper's light on T " + fingerprint, e);
    return e;
}

}  // namespace

/// Stage 3b: what E* is compared with (the user's lamp, the paper's light) and the regions the
/// judge scores and the report outlines.
void prepareComparisons(const Plan& p, Inputs& in, const OptimizeJobSummary& job) {
    const OptimizeJobOptions& o = p.o;
    const TransportMatrix& t = job.transport.file.matrix;
    if (!in.sceneParts) {
        // The user's lamp: it does not depend on T (only on the env map's size).
        in.lampName = o.compare.empty() ? std::string("studio preset")
                                        : std::filesystem::path(o.compare).filename().string();
        in.lampE = o.compare.empty() ? defaultLampE(t.envWidth, t.envHeight, o.rgb)
                                     : envMapToE(lightFromSpec(o.compare, t.envWidth, t.envHeight,
                                                               o.rgb ? 3 : 0, option("compare")),
                                                 o.rgb ? 3 : 1);  // as the judge reads a light
        if (!o.truth.empty()) in.truthLabels = projectTruth(*in.scene, o.truth);
        in.sceneParts = true;
    }
    in.paperE = paperLight(p, in, t, job.transport.file.provenance.fingerprint);
    if (!o.truth.empty()) {
        in.regionLabels = in.truthLabels.labels;
        in.regionLegend = in.truthLabels.legend;
        in.regionSource = "truth " + o.truth.filename().string();
    } else if (!in.defects.empty()) {
        JudgedDefectLabels judged = judgedDefectLabels(in.defects, defectRegion(o).automatic);
        in.regionLabels = std::move(judged.labels);
        in.regionLegend = std::move(judged.legend);
        in.regionReference = in.reference;  // as judge --defects --reference scores it
        in.regionSource = "defect region " + defectRegion(o).text();
    } else if (o.mask.kind != LossMaskKind::Object) {
        in.regionLabels.assign(in.mask.pixels.size(), 0);
        for (size_t q = 0; q < in.mask.pixels.size(); ++q)
            in.regionLabels[q] = in.mask.pixels[q] ? 255 : 0;
        in.regionLegend = {RegionLabel{255, "mask"}};
        in.regionSource = "loss mask " + o.mask.name();
    }
}

namespace {

/// What a person must know about a result before trusting it.
std::vector<std::string> resultWarnings(const OptimizeRun& run, const std::vector<double>& e) {
    std::vector<std::string> w;
    if (run.interrupted)
        w.push_back("interrupted at iteration " + std::to_string(run.optimizer.iterations) +
                    ": the light is the best iterate so far");
    if (run.optimizer.failed) w.push_back("the optimizer failed: " + run.optimizer.termination);
    if (!(run.final.total < run.initial.total))
        w.push_back("no improvement on the start (loss " + formatNumber(run.initial.total) +
                    " -> " + formatNumber(run.final.total) + ")");
    if (std::all_of(e.begin(), e.end(), [](double v) { return v <= 0; }))
        w.push_back("the light is all black (every texel 0): lower lambda");
    if (run.final.clamped)
        w.push_back("the image has no contrast on the mask (the objective's G is at its floor)");
    return w;
}

}  // namespace

/// How a person sees the images (the judge's JND): the scene's viewing model, the default one
/// when only T is at hand.
ViewingModel viewingOf(const Inputs& in) {
    if (in.scene) return viewingFor(*in.scene);
    return in.part && in.part->viewing ? *in.part->viewing : defaultViewing();
}

/// The objective's options at λ; the jnd measure sees the image as the judge does (viewingOf).
ObjectiveOptions objectiveAt(const Plan& p, const Inputs& in, double lambda) {
    ObjectiveOptions oo = p.o.objective;
    oo.lambda = lambda;
    if (!(oo.viewing.pixelsPerDegree > 0)) oo.viewing = viewingOf(in);
    if (oo.defectMeasure == DefectMeasure::Both && oo.anchorLight.empty())
        oo.anchorLight = in.lampE;
    return oo;
}

/// Stage 4: one λ run (the search on T, or the black box through the renderer), its held-out
/// scores and the judge's.
LambdaResult optimizeLambda(const Plan& p, const Inputs& in, const OptimizeJobSummary& job,
                            double lambda) {
    const OptimizeJobOptions& o = p.o;
    const TransportMatrix& t = job.transport.file.matrix;
    const ObjectiveOptions oo = objectiveAt(p, in, lambda);
    const std::vector<uint8_t>& mask = in.mask.pixels;
    ImageObjective objective(t.width, t.height, mask, oo);  // the black box's (eq. 2)
    SearchInputs si;
    si.set = in.set;
    si.mask = mask;
    si.objective = oo;
    si.rgb = o.rgb;
    si.scene = in.scene.get();
    si.maxDepth = job.transport.file.provenance.maxDepth;
    si.startValues = in.startValues;
    si.defects = in.defects;
    si.reference = in.reference;
    si.shard = in.shard;
    si.gramCache = p.cacheDir;  // T's Gram matrices kept beside T
    si.fingerprint = job.transport.file.provenance.fingerprint;
    const ObjectiveOnT own = objectiveOnT(in.kind, t, si, oo);
    const TransportLoss& loss = *own.loss;
    std::unique_ptr<HeldOutScorer> scorer;
    if (job.heldOut)
        scorer = std::make_unique<HeldOutScorer>(job.heldOut->file.matrix, mask, oo, in.kind, o.rgb,
                                                 in.defects, in.reference);

    LambdaResult res;
    OptimizeRun& run = res.run;
    run.lambda = lambda;
    run.objective = objectiveKindName(in.kind);
    run.dir = o.lambdas.size() > 1 ? o.outDir / lambdaName(lambda) : o.outDir;
    res.e = in.startValues.front();
    run.initial = loss.evaluate(res.e, {});
    if (scorer) run.heldInitial = scorer->score(res.e);

    // loss.csv as it goes: the staged copy grows a row per iteration (flushed about once a
    // second); the final file replaces it with the returned E's held-out score on its last row.
    // Over MPI ranks only rank 0 writes.
    std::ofstream live;
    if (p.writes()) {
        const std::filesystem::path liveCsv = p.staged(run.dir) / "loss.csv";
        std::filesystem::create_directories(liveCsv.parent_path());
        live.open(liveCsv);
        live << kLossCsvHeader << '\n' << std::flush;
        spdlog::info("lambda {}: loss.csv as it goes: {}", lambda, liveCsv.string());
    }
    Stopwatch sinceFlush;
    // Progress over the whole budget: every start, every continuation stage.
    const double budget = static_cast<double>(o.optimizer.iterations) *
                          static_cast<double>(p.blackBox ? 1 : o.starts.size()) *
                          static_cast<double>(p.blackBox ? 1 : o.continuation.size() + 1);
    ProgressTask task(o.lambdas.size() > 1 ? "optimize (lambda " + formatNumber(lambda) + ")"
                                           : std::string("optimize"),
                      budget);
    double lastHeld = std::nan("");

    auto callback = [&](const IterationRecord& r, std::span<const double> x) {
        // Every row: the optimizer's own loss (with estimates, on the estimate of that step; with
        // continuation, at that stage's λ). Every heldOutEvery rows also the parts on T at λ
        // and the held-out scores.
        const bool full = r.iteration % o.heldOutEvery == 0;
        std::ostringstream row;
        row << std::setprecision(10) << r.iteration << ',' << r.evaluations << ',' << r.loss << ',';
        if (full) {
            const LossParts parts = loss.evaluate(x, {});
            row << parts.lGrad << ',' << parts.lReg;
        } else {
            row << ',';
        }
        row << ',' << r.seconds << ',';
        if (scorer && full) {
            const Stopwatch clock;
            HeldOutScore h = scorer->score(x);
            run.secondsHeldOutScoring += clock.seconds();
            row << h.own.total << ',' << h.paper.total << ',' << h.unbiased.total;
            lastHeld = h.own.total;
        } else {
            row << ",,";
        }
        res.rows.push_back(row.str());
        res.curve.iteration.push_back(static_cast<double>(r.iteration));
        res.curve.loss.push_back(r.loss);
        if (scorer && full) {
            res.curve.heldIteration.push_back(static_cast<double>(r.iteration));
            res.curve.held.push_back(lastHeld);
        }
        if (live.is_open()) live << res.rows.back() << '\n';
        if (live.is_open() && (res.rows.size() == 1 || sinceFlush.seconds() >= 1.0)) {
            live.flush();
            sinceFlush.restart();
        }
        task.set(r.iteration);
        task.detail("loss " + formatNumber(r.loss, 4) +
                    (std::isnan(lastHeld) ? "" : ", held out " + formatNumber(lastHeld, 4)));
        spdlog::debug("iteration {}: loss {}", r.iteration, r.loss);
        // Ctrl-C: stop at this iteration; the optimizer returns its best iterate. Over MPI
        // ranks all stop at the same iteration when any was asked to.
        double stop = interruptRequested() ? 1.0 : 0.0;
        if (in.ranks) in.ranks->sum(std::span<double>(&stop, 1));
        if (stop > 0) {
            run.interrupted = true;
            return false;
        }
        return o.optimizer.callback ? o.optimizer.callback(r, x) : true;
    };
    if (p.blackBox) {
        OptimizerOptions opt = o.optimizer;
        opt.callback = callback;
        RenderOptions ro = renderOptionsFor(*in.scene);
        ro.spp = job.transport.file.provenance.spp;
        ro.seed = job.transport.file.provenance.seed;
        ro.maxDepth = job.transport.file.provenance.maxDepth;
        ro.threads = o.precompute.threads;
        if (o.renderer == RendererKind::Builtin) {
            RenderLoss renderLoss(*in.scene, ro, objective, o.rgb);
            run.optimizer = minimizeBlackBox(renderLoss, res.e, opt, o.blackBox);
        } else {
            const ExternalRendererOptions eo = externalRendererOptions(o.renderer, o.external);
            const ExternalRenderer external(*in.scene, eo);
            const RenderLoss renderLoss(external, in.scene->basis.width(), in.scene->basis.height(),
                                        ro.seed, objective, o.rgb);
            // POV-Ray's process mostly waits (app/host/ExternalRenderer.h): more renders than
            // cores.
            BlackBoxOptions bb = o.blackBox;
            if (bb.fd.threads == 0) bb.fd.threads = concurrentRenders(eo);
            if (bb.spsa.threads == 0) bb.spsa.threads = concurrentRenders(eo);
            run.optimizer = minimizeBlackBox(renderLoss, res.e, opt, bb);
            run.optimizer.settings += "; renderer " + external.name();
        }
        run.lossThrough =
            o.renderer == RendererKind::Builtin
                ? "our renderer (" + std::to_string(ro.spp) + " spp)"
                : std::string("the renderer ") + registryRow(rendererKindTable(), o.renderer).name;
    } else {
        si.callback = callback;
        SearchOptions so;
        so.objective = in.kind;
        so.optimizer = resolveOptimizer(p.requestedOptimizer, in.kind, oo);
        so.optimizer.callback = nullptr;
        so.estimates = o.estimates;
        so.starts = o.starts;
        so.continuation = o.continuation;
        so.lightGrid = o.lightGrid.value_or(LightGrid{});
        const double collectives0 = in.ranks ? in.ranks->secondsInCollectives() : 0.0;
        SearchResult sr = search(si, so);
        if (in.ranks) run.secondsCollectives = in.ranks->secondsInCollectives() - collectives0;
        res.e = sr.e;
        run.optimizer = sr.optimizer;
        run.start = sr.start;
        run.startLosses = sr.startLosses;
        res.startResults = std::move(sr.startResults);
    }
    run.optimizer.method = methodName(p.requested);
    live.close();
    run.final = loss.evaluate(res.e, {});
    if (p.blackBox) {
        // The loss the black box minimized, through its renderer (not eq. 2 on our T).
        run.initial = LossParts{};
        run.initial.total = run.optimizer.initialLoss;
        run.final = LossParts{};
        run.final.total = run.optimizer.finalLoss;
    }
    if (job.validation)
        run.validationFinal = validationObjective(in, job, oo, o.rgb).loss->evaluate(res.e, {});
    if (scorer) {
        run.heldFinal = scorer->score(res.e);
        // The last row always carries the held-out score of the returned E.
        if (!res.rows.empty() && res.rows.back().ends_with(",,,")) {
            res.rows.back().resize(res.rows.back().size() - 3);
            std::ostringstream tail;
            tail << std::setprecision(10) << ',' << run.heldFinal->own.total << ','
                 << run.heldFinal->paper.total << ',' << run.heldFinal->unbiased.total;
            res.rows.back() += tail.str();
            res.curve.heldIteration.push_back(res.curve.iteration.back());
            res.curve.held.push_back(run.heldFinal->own.total);
        }
    }
    res.lampTraining = loss.evaluate(in.lampE, {});
    res.paperTraining = loss.evaluate(in.paperE, {});
    spdlog::info("lambda {}: {}", lambda, run.optimizer.briefReport());
    return res;
}

/// Stage 4b: the self-checked answer (app/pipeline/Answer.h) on the validation estimate: E*, every
/// other start's result and the references; a reference that wins becomes the answer and E*
/// is kept beside it.
void checkAnswer(const Plan& p, const Inputs& in, const OptimizeJobSummary& job, LambdaResult& r) {
    if (!job.validation || !p.o.selfCheck) return;
    JudgeOptions jo;
    jo.objective = objectiveAt(p, in, r.run.lambda);
    jo.rgb = p.o.rgb;
    jo.viewing = viewingOf(in);  // the answer is chosen on what the judge reports first: JND
    const Judge validation(*job.validation, jo, in.regionLabels, in.regionLegend,
                           in.regionReference);
    std::vector<AnswerCandidate> candidates;
    candidates.push_back({"optimized", CandidateKind::Optimized, r.e});
    for (size_t k = 0; k < r.startResults.size(); ++k)
        if (p.o.starts[k].spec != r.run.start)
            candidates.push_back(
                {"optimized from " + p.o.starts[k].spec, CandidateKind::Start, r.startResults[k]});
    for (const auto& [name, e] : r.finer) candidates.push_back({name, CandidateKind::Finer, e});
    candidates.push_back({in.lampName, CandidateKind::Reference, in.lampE});
    candidates.push_back(
        {"uniform-0.5", CandidateKind::Reference, std::vector<double>(in.lampE.size(), 0.5)});
    candidates.push_back({"paper's light", CandidateKind::Reference, in.paperE});
    AnswerOptions ao;
    // The defects objective on both measures chooses on its own figure; the others on the JND.
    if (in.kind == ObjectiveKind::Defects && jo.objective.defectMeasure == DefectMeasure::Both)
        ao.gainOver = in.lampName;
    AnswerChoice choice = chooseAnswer(validation, std::move(candidates), ao);
    choice.validationSpp = job.validation->file.provenance.spp;
    const ScoredCandidate& a = choice.answer();
    if (choice.chosen != 0) {
        r.optimizedE = r.e;
        r.e = a.candidate.e;
    }
    spdlog::info("lambda {}: answer: {} [{} candidates scored in {:.2f} s]", r.run.lambda,
                 choice.reason, choice.scored.size(), choice.seconds);
    r.run.answer = std::move(choice);
}

/// Stage 4c: the judge's scores (the held-out estimate, at this run's λ) of the answer, the
/// user's lamp, the paper's light and, when a reference is the answer, E*; the warnings.
void judgeRun(const Plan& p, const Inputs& in, OptimizeJobSummary& job, LambdaResult& r) {
    OptimizeRun& run = r.run;
    if (job.heldOut) {
        JudgeOptions jo;
        jo.objective = objectiveAt(p, in, run.lambda);
        jo.rgb = p.o.rgb;
        jo.viewing = viewingOf(in);
        // In rounds (app/pipeline/Judge.h judgeInRounds): the judge's estimate is traced again at
        // more spp while a score's standard error is above 1 % (not for a given --heldout-spp or a
        // given held-out file).
        const int first = job.heldOut->file.provenance.spp;
        const bool rounds = p.o.heldOut.mode == HeldOutMode::Judge && p.o.heldOutSpp == 0;
        std::unique_ptr<Judge> judge;
        auto judgeAt = [&](int spp) -> const Judge& {
            if (!judge || spp != job.heldOut->file.provenance.spp) {
                judge.reset();
                if (spp != job.heldOut->file.provenance.spp)
                    job.heldOut = judgeEstimateFor(job.transport.file, *in.scene, spp, p.cacheDir);
                judge = std::make_unique<Judge>(*job.heldOut, jo, in.regionLabels, in.regionLegend,
                                                in.regionReference);
            }
            return *judge;
        };
        std::vector<std::pair<std::string, std::vector<double>>> lights = {
            {run.dir.filename().string(), r.e}, {"lamp", in.lampE}, {"paper", in.paperE}};
        if (!r.optimizedE.empty()) lights.emplace_back("optimized", r.optimizedE);
        // The answer first; the others are read only against it (JudgeStopRule::againstFirst).
        JudgeStopRule rule;
        rule.againstFirst = true;
        run.judgeRounds = judgeInRounds(judgeAt, lights, first,
                                        rounds ? std::max(first, kJudgeDefaultSpp) : first, rule);
        spdlog::info("lambda {}: judge estimate {}", run.lambda, run.judgeRounds.describe());
        const std::vector<JudgeScore>& s = run.judgeRounds.scores;
        run.judged = s[0];
        run.judgedLamp = s[1];
        run.judgedPaper = s[2];
        if (s.size() > 3) run.judgedOptimized = s[3];
        run.heldCurveSpp = first;
        if (job.heldOut->file.provenance.spp != first && run.heldFinal) {
            // The held-out figures of the start and of E* on the last round's estimate; the
            // curve's earlier points stay on the first round's.
            const HeldOutScorer scorer(job.heldOut->file.matrix, in.mask.pixels, jo.objective,
                                       in.kind, p.o.rgb, in.defects, in.reference);
            run.heldInitial = scorer.score(in.startValues.front());
            run.heldFinal = scorer.score(r.optimizedE.empty() ? r.e : r.optimizedE);
            if (!r.rows.empty()) {
                std::string& last = r.rows.back();
                for (int k = 0; k < 3; ++k) last.resize(last.rfind(','));
                std::ostringstream tail;
                tail << std::setprecision(10) << ',' << run.heldFinal->own.total << ','
                     << run.heldFinal->paper.total << ',' << run.heldFinal->unbiased.total;
                last += tail.str();
            }
            if (!r.curve.held.empty()) r.curve.held.back() = run.heldFinal->own.total;
        }
    }
    run.warnings = resultWarnings(run, r.optimizedE.empty() ? r.e : r.optimizedE);
    if (run.answer && run.answer->referenceWon())
        run.warnings.insert(run.warnings.begin(),
                            "the answer is " + run.answer->answer().candidate.name +
                                ", not the optimized light: " + run.answer->reason);
    if (run.noise.rounds.size() && !run.noise.met)
        run.warnings.push_back("training noise: " + run.noise.reason);
    if (!run.judgeRounds.rounds.empty() && !run.judgeRounds.met)
        run.warnings.push_back("judge: " + run.judgeRounds.describe());
    if (const std::string w = unjudgedRegionsWarning(in.unjudgedRegions, in.unjudgedShare);
        !w.empty())
        run.warnings.push_back(w);
    for (const std::string& w : run.warnings) spdlog::warn("lambda {}: {}", run.lambda, w);
}

}  // namespace sl::optimizejob
