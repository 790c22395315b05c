#include "app/jobs/OptimizeJob.h"

#include <spdlog/spdlog.h>

#include <algorithm>
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

namespace sl {

namespace {

using json = nlohmann::ordered_json;

std::string lambdaName(double lambda) {
    std::ostringstream s;
    s << "lambda-" << lambda;
    return s.str();
}

EnvMap toEnvMap(const std::vector<double>& e, const TransportMatrix& t, bool rgb) {
    EnvMap m = EnvMap::constant(t.envWidth, t.envHeight, 0.0f, rgb ? 3 : 1);
    for (size_t i = 0; i < e.size(); ++i) m.texels[i] = static_cast<float>(e[i]);
    return m;
}

json partsJson(const LossParts& p) {
    return {{"loss", p.total},
            {"L_grad", p.lGrad},
            {"L_reg", p.lReg},
            {"G", p.G},
            {"clamped", p.clamped}};
}

json heldJson(const HeldOutScore& h) {
    return {{"own", partsJson(h.own)},
            {"unbiased", partsJson(h.unbiased)},
            {"paper_eq2", partsJson(h.paper)}};
}

/// The trace's per-pixel sample multipliers as its provenance records them (null: none).
json sppScaleOf(const TransportProvenance& prov) {
    const json in = json::parse(prov.inputs, nullptr, false);
    if (in.is_discarded() || !in.contains("render") || !in["render"].contains("spp_scale"))
        return nullptr;
    return in["render"]["spp_scale"];
}

json transportJson(const TransportSource& src) {
    const TransportMatrix& t = src.file.matrix;
    const auto& prov = src.file.provenance;
    return {{"file", src.path.string()},
            {"fingerprint", prov.fingerprint},
            {"spp", prov.spp},
            {"seed", prov.seed},
            {"max_depth", prov.maxDepth},
            {"channels", t.channels},
            {"planes", t.planes},
            {"storage", t.storage == TransportStorage::Sparse ? "csr" : "dense"},
            {"nnz", t.nnz()},
            {"density", t.density()},
            {"bytes", t.bytes()},
            {"image", {t.width, t.height}},
            {"envmap", {t.envWidth, t.envHeight}},
            {"cache_hit", src.cacheHit},
            {"max_depth_auto", src.autoDepth ? json(src.autoDepth->reason) : json(nullptr)},
            {"spp_auto", src.autoSpp ? json(src.autoSpp->reason) : json(nullptr)},
            {"spp_scale", sppScaleOf(prov)},
            {"seconds", src.secondsTotal}};
}

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

/// Luminance of a render (RGB or already luminance).
std::vector<double> luminanceOf(const std::vector<double>& image, size_t pixels) {
    if (image.size() == pixels) return image;
    std::vector<double> y(pixels);
    for (size_t q = 0; q < pixels; ++q)
        y[q] = luminance(image[3 * q], image[3 * q + 1], image[3 * q + 2]);
    return y;
}

/// A render exposed on its own as a camera would (app/report/Preview.h exposureScale on the part),
/// written as a PNG; returned for the figures.
Image writeExposedPng(const std::filesystem::path& png, const std::vector<double>& image,
                      const TransportMatrix& t) {
    const int ch = image.size() == t.rows() ? 1 : 3;
    const double scale = exposureScale(luminanceOf(image, t.rows()), t.objectMask);
    Image img(t.width, t.height, ch);
    for (size_t i = 0; i < image.size(); ++i) img.data[i] = static_cast<float>(image[i] * scale);
    writePng(png, img);
    return img;
}

/// A direction as the env-map plot shows it: azimuth in [0°, 360°) = u·360° and elevation
/// 90° − v·180° (u, v of EnvMapBasis::directionToUv: azimuth 0° toward −z, 90° toward +x;
/// elevation 90° = +Y).
json directionJson(const Vec3d& d) {
    const auto uv = EnvMapBasis::directionToUv(d);
    const double u = uv[0] < 0 ? uv[0] + 1.0 : uv[0] + 0.0;  // + 0.0: no "-0" in the JSON
    return {{"azimuth_deg", u * 360.0}, {"elevation_deg", 90.0 - uv[1] * 180.0}};
}

}  // namespace

void writeRender(const std::filesystem::path& exr, const std::vector<double>& image, int width,
                 int height, int channels) {
    Image img(width, height, channels);
    for (size_t i = 0; i < image.size(); ++i) img.data[i] = static_cast<float>(image[i]);
    writeExr(exr, img);
    auto png = exr;
    png.replace_extension(".png");
    writePng(png, img);
}

namespace {

constexpr OptimizePresetRow kPresets[] = {
    {OptimizePreset::Paper, "paper",
     "the paper's experiment exactly (eq. 2, lambda 30, E0 = 0.5, Adam lr 0.02 x 100, a fresh "
     "sample set of the scene's spp every iteration: 100 estimates of T)"},
};

}  // namespace

std::span<const OptimizePresetRow> optimizePresetTable() {
    return kPresets;
}

void applyOptimizePreset(OptimizePreset preset, OptimizeJobOptions& o) {
    switch (preset) {
        case OptimizePreset::Paper:
            o.optimizer.method = OptimizerMethod::PaperLoop;
            o.optimizer.iterations = 100;
            o.optimizer.learningRate = 0.02;
            o.lambdas = {30.0};
            o.objective.reg = RegTarget::EnvMap;
            o.starts = {parseInitialState("const:0.5")};
            o.objectiveKind = ObjectiveKind::Paper;
            o.continuation.clear();
            o.planes = 100;
            break;
    }
}

namespace {

// ---- The stages of the job, in the order runOptimizeJob calls them. ----

/// Stage 0: the options with every default filled in (budget, starts, planes) and checked; a
/// method that stands for a set-up (paper-loop) expanded into it.
struct Plan {
    OptimizeJobOptions o;
    OptimizerMethod requested = OptimizerMethod::Lbfgs;  // the name the results carry
    bool blackBox = false;                               // gradients through the renderer
    bool tmInput = false;
    /// Noise-aware training (app/pipeline/TrainingNoise.h): `validate` traces the validation
    /// estimate (the gap and the self-check need it); `noise.adapt` raises the training spp.
    bool validate = false;
    TrainingNoiseOptions noise;
    /// V's spp when its own noise hides the gap (app/pipeline/TrainingNoise.h step 4; 0: T's).
    int validationSpp = 0;
    /// The defect pixels of the defects objective take more samples (app/pipeline/TrainingNoise.h
    /// defectSppScale); not for black boxes (their renders take one spp) nor shards.
    bool superSampleDefects = false;
    /// The optimizer as asked for, before its default budget was filled in: a search resolves
    /// it for its objective (app/pipeline/Defaults.h resolveOptimizer: the default budget's
    /// stall stop; a given budget runs to its end).
    OptimizerOptions requestedOptimizer;
    const Communicator* ranks = nullptr;  // MPI ranks holding shards of T (null: one process)
    bool writes() const { return !ranks || ranks->root(); }  // this process writes OUTDIR
    std::filesystem::path cacheDir;
    std::filesystem::path writeDir;  // where OUTDIR is staged (io/StagedDirectory.h)
    /// Where a path under OUTDIR is written while staged.
    std::filesystem::path staged(const std::filesystem::path& underOutDir) const {
        return (writeDir / underOutDir.lexically_relative(o.outDir)).lexically_normal();
    }
};

Plan plan(const OptimizeJobOptions& options) {
    if (options.lambdas.empty()) throw inputError(option("lambda"), "no value given");
    for (double l : options.lambdas)
        if (!(l >= 0) || !std::isfinite(l))
            throw inputError(option("lambda"), "must be >= 0",
                             "give e.g. 30, or 10,30,100 for a sweep");
    if (options.planes < 0) throw inputError(option("planes"), "must be >= 1");
    if (options.heldOutEvery < 1) throw inputError(option("heldout-every"), "must be >= 1");
    Plan p;
    p.o = options;
    OptimizeJobOptions& o = p.o;
    p.requested = o.optimizer.method;
    const OptimizerMethodRow& row = methodRow(p.requested);
    if (p.requested == OptimizerMethod::PaperLoop) {
        // The paper's loop on T: eq. 2, Adam, a fresh sample set (estimate of T) every step,
        // from the paper's E0.
        o.objectiveKind = ObjectiveKind::Paper;
        if (o.starts.empty()) o.starts = {parseInitialState("const:0.5")};
    }
    if (p.requested != OptimizerMethod::PaperLoop && row.gradient == GradientSource::Renderer) {
        // A black box minimizes eq. 2 through the renderer (optimize/BlackBox.h RenderLoss): the
        // run's loss is that objective, and nothing else is reported as its loss.
        if (o.objectiveKind && *o.objectiveKind != ObjectiveKind::Paper)
            throw inputError(
                option("objective") + " " + objectiveKindName(*o.objectiveKind),
                std::string("the black-box optimizer ") + row.name +
                    " minimizes the paper's eq. 2 through the renderer",
                "drop " + option("objective") + ", or optimize on T (e.g. the default optimizer)");
        o.objectiveKind = ObjectiveKind::Paper;
    }
    if (o.starts.empty())
        for (const std::string& spec : optimizeDefaults().starts)
            o.starts.push_back(parseInitialState(spec));
    p.requestedOptimizer = o.optimizer;
    o.optimizer = resolveOptimizer(o.optimizer);  // the method that runs; iterations 0: its budget
    if (o.planes == 0) o.planes = row.defaultPlanes;
    p.blackBox = row.gradient == GradientSource::Renderer;
    p.tmInput = isTransportFile(o.input);
    if (p.tmInput && !o.sceneOverrides.empty())
        throw inputError(o.input.string(),
                         "is a traced transport matrix: scene overrides (" + option("D") + ", " +
                             option("width") + ", " + option("height") + ", " + option("size") +
                             ") cannot change it",
                         "pass the scene file with the overrides instead of the .tm");
    if (o.renderer != RendererKind::Builtin && !p.blackBox)
        throw inputError(
            option("renderer") + " " + registryRow(rendererKindTable(), o.renderer).name,
            "only the black-box optimizers (fd-adam, spsa) render through it",
            "use " + option("optimizer") +
                " spsa or fd-adam, or build its T with "
                "precompute " +
                option("renderer") + " and optimize the .tm");
    if (o.renderer != RendererKind::Builtin) (void)externalRendererOptions(o.renderer, o.external);
    if (p.blackBox && p.tmInput)
        throw inputError(option("optimizer") + " " + row.name,
                         "renders the scene for every gradient, so it needs the scene file",
                         "pass SCENE.json instead of the .tm");
    if (p.tmInput && o.planes > 1)
        throw inputError(option("planes") + " " + std::to_string(o.planes),
                         "needs independent estimates of T traced from the scene",
                         "pass SCENE.json instead of the .tm, or " + option("planes") + " 1");
    p.cacheDir = cacheDirectory(o.cache);
    // Noise-aware training: spp auto (the default) adapts; a given spp is measured and kept.
    p.noise.maxGap = o.precompute.sppTolerance;
    p.noise.maxSpp = o.noiseMaxSpp;
    if (!(p.noise.maxGap > 0 && p.noise.maxGap < 1))
        throw inputError(option("tolerance"), "is " + formatNumber(p.noise.maxGap, 3),
                         "use a relative train/validation gap in (0, 1), e.g. 0.05");
    if (p.noise.maxSpp < 1) throw inputError(option("max-spp"), "must be >= 1");
    p.noise.adapt = !p.tmInput && (o.precompute.autoSpp || !o.precompute.spp);
    o.precompute.autoSpp = false;  // the rule replaces the gradient-noise pilot here
    const bool distributed = o.ranks && o.ranks->distributed();
    p.validate =
        !distributed && p.requested != OptimizerMethod::PaperLoop && (o.selfCheck || !p.blackBox);
    if (p.blackBox || o.planes > 1 || !p.validate) p.noise.adapt = false;
    // A given T (.tm, .shards) keeps its per-texel light as the spp it was traced at, so one
    // process and MPI ranks (which cannot validate) return the same light from it.
    p.noise.adaptGrid = !o.lightGrid && !p.blackBox && o.planes == 1 && p.validate && !p.tmInput;
    p.superSampleDefects = !p.blackBox && !distributed;
    if (o.ranks && o.ranks->distributed()) {
        p.ranks = o.ranks;
        const std::string over = "over " + std::to_string(p.ranks->size()) + " MPI ranks";
        if (o.input.extension() != ".shards")
            throw inputError(
                o.input.string(),
                over + " optimize needs a .shards list of T's row shards, one per rank",
                "trace the shards with `precompute " + option("rows") +
                    " A:B` and list them (docs/CLUSTER.md)");
        if (o.heldOut.mode != HeldOutMode::None)
            throw inputError(option("heldout"),
                             over +
                                 " the held-out estimate is not supported (it is a whole T, "
                                 "traced or read in one process)",
                             "pass " + option("heldout") +
                                 " none, and judge E* afterwards with "
                                 "`scratchlight judge`");
    }
    return p;
}

/// What every λ run of the job shares.
struct Inputs {
    const Communicator* ranks = nullptr;  // Plan::ranks
    RowShard shard;                       // the rows of T this rank holds (over MPI ranks)
    std::unique_ptr<Scene> scene;         // loaded once; from T's provenance for a .tm when needed
    ObjectiveKind kind = ObjectiveKind::Unbiased;
    bool onHalves() const { return registryRow(objectiveKindTable(), kind).planes == 2; }
    std::vector<uint8_t> defects, reference;  // the defects objective's regions (image)
    /// The training trace's per-pixel sample multipliers (app/pipeline/TrainingNoise.h
    /// defectSppScale; empty: none), chosen on the first load from the scene and the regions, kept
    /// after.
    std::optional<std::vector<uint8_t>> sppScale;
    std::vector<const TransportMatrix*> set;  // the training estimates of T
    LossMask mask;
    std::vector<uint8_t> truth;                    // the truth mask in the image (metrics), 255/0
    std::vector<std::vector<double>> startValues;  // E0 of every start
    std::vector<double> image0;                    // T·E0 of the first start
    VisibilityMetrics metricsInitial;
    // The comparisons (prepareComparisons): the user's lamp and the paper's light on T, and the
    // regions the judge scores and the report outlines (truth, else defects, else a drawn mask).
    std::string lampName;
    std::vector<double> lampE, paperE;
    std::vector<uint8_t> regionLabels;  // image space, 0 = none
    std::vector<RegionLabel> regionLegend;
    std::vector<uint8_t> regionReference;  // the defect region's reference (empty: the default)
    std::string regionSource;              // where the regions come from ("" = none)
    /// defects, reference, truth, truthLabels, lampName and lampE depend on the scene and the
    /// options, not on T: once set (the first load), a training-noise round that traces T again
    /// keeps them instead of projecting the regions (or computing the defect map) again.
    bool sceneParts = false;
    LabelMask truthLabels;  // the truth projected into the image, its legend (truth given)
    /// The training trace's resolved options and seed (what the validation estimate repeats
    /// with its own seed); unset for a .tm.
    std::optional<PrecomputeOptions> trained;
    uint64_t trainingSeed = 0;
};

/// The defects objective's regions in the image (defect map or truth projected), unless this
/// job already has them (they depend on the scene and the options only).
void defectRegionsOnce(const OptimizeJobOptions& o, Inputs& in) {
    if (in.sceneParts || !in.defects.empty()) return;
    DefectRegions regions = defectRegionsInImage(*in.scene, o.defects, o.truth, o.reference);
    in.defects = std::move(regions.defects);
    in.reference = std::move(regions.reference);
}

/// The defect pixels' sample multipliers of the training trace: `given` (> 0), else the rule's
/// factor for the defect pixels on the part's footprint; printed when above 1.
std::vector<uint8_t> chooseDefectSppScale(const Scene& scene, const std::vector<uint8_t>& defects,
                                          int given) {
    size_t part = 0, marked = 0;
    const std::vector<PixelSpan> spans = partFootprint(scene);
    const auto W = static_cast<size_t>(scene.camera.width());
    for (size_t y = 0; y < spans.size(); ++y)
        for (int x = spans[y].begin; x < spans[y].end; ++x) {
            ++part;
            marked += defects[y * W + static_cast<size_t>(x)] != 0;
        }
    const int factor = given > 0 ? given : defectSppFactor(marked, part);
    if (factor > 1)
        spdlog::info(
            "defect pixels: {} of the part's {} take {}x the training spp (their few pairs are "
            "the objective's noisiest sum; +{} % samples)",
            marked, part, factor,
            formatNumber(100.0 * static_cast<double>(marked) * (factor - 1) /
                             static_cast<double>(std::max<size_t>(part, 1)),
                         2));
    return defectSppScale(defects, factor);
}

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
            transportSetForScene(*in.scene, pre, o.planes, p.cacheDir);
        job.transport = std::move(set.front());
        job.transport.autoDepth = depth;
        if (!pre.spp) pre.spp = job.transport.file.provenance.spp;
        in.trained = pre;
        in.trainingSeed = job.transport.file.provenance.seed;
        for (size_t k = 1; k < set.size(); ++k) job.extraPlanes.push_back(std::move(set[k]));
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
    // What needs the scene itself: for a .tm, read from T's provenance.
    bool specularStart = false;
    for (const InitialState& s : o.starts) specularStart |= s.kind == InitialKind::Specular;
    const bool needScene = p.blackBox || o.mask.kind == LossMaskKind::Scratch || specularStart ||
                           in.kind == ObjectiveKind::Defects || !o.truth.empty() ||
                           o.heldOut.mode == HeldOutMode::Judge;
    if (!in.scene && needScene) {
        const std::string purpose =
            o.heldOut.mode == HeldOutMode::Judge
                ? "the held-out estimate (or " + option("heldout") + " none)"
                : option("mask") + " scratch / " + option("init") + " specular / " +
                      option("truth");
        in.scene = sceneOfTransport(job.transport.file, purpose);
    }
    in.set = {&t};
    for (const TransportSource& x : job.extraPlanes) in.set.push_back(&x.file.matrix);
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
    if (hs >= ts && hs < ts + static_cast<uint64_t>(o.planes))
        throw inputError(option("seed"), "the training seed range overlaps the judge's seed",
                         "use another " + option("seed"));
}

/// Stage 2b: the validation estimate (app/pipeline/TrainingNoise.h): the training trace again with
/// its own seed, two sample sets; for a .tm, T's recorded spp and path length on its scene.
void loadValidation(const Plan& p, const Inputs& in, OptimizeJobSummary& job) {
    job.validation.reset();
    if (!p.validate) return;
    if (!in.scene) {
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
    job.validation =
        validationEstimate(*in.scene, v, seed, p.cacheDir, std::max(first, p.validationSpp));
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
                                               maxDepth, in.shard.distributed() ? "" : p.cacheDir,
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
        key = toHex(hash64(w.data(), w.size(), 1)) + toHex(hash64(w.data(), w.size(), 2));
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
    so.planes = 1;
    so.starts = paper.starts;
    std::vector<double> e = search(si, so).e;
    if (!key.empty()) writeCachedLight(p.cacheDir, key, "paper's light on T " + fingerprint, e);
    return e;
}

/// Stage 3b: what E* is compared with (the user's lamp, the paper's light) and the regions the
/// judge scores and the report outlines.
void prepareComparisons(const Plan& p, Inputs& in, const OptimizeJobSummary& job) {
    const OptimizeJobOptions& o = p.o;
    const TransportMatrix& t = job.transport.file.matrix;
    if (!in.sceneParts) {
        // The user's lamp: it does not depend on T (only on the env map's size).
        const EnvMap lamp = o.compare.empty() ? studioEnvMap(t.envWidth, t.envHeight)
                                              : lightFromSpec(o.compare, t.envWidth, t.envHeight,
                                                              o.rgb ? 3 : 0, option("compare"));
        in.lampName = o.compare.empty() ? std::string("studio preset")
                                        : std::filesystem::path(o.compare).filename().string();
        in.lampE = envMapToE(lamp, o.rgb ? 3 : 1);  // as the judge reads a light
        if (!o.truth.empty()) in.truthLabels = projectTruth(*in.scene, o.truth);
        in.sceneParts = true;
    }
    in.paperE = paperLight(p, in, t, job.transport.file.provenance.fingerprint);
    if (!o.truth.empty()) {
        in.regionLabels = in.truthLabels.labels;
        in.regionLegend = in.truthLabels.legend;
        in.regionSource = "truth " + o.truth.filename().string();
    } else if (!in.defects.empty()) {
        in.regionLabels.assign(in.defects.size(), 0);
        for (size_t q = 0; q < in.defects.size(); ++q) in.regionLabels[q] = in.defects[q] ? 255 : 0;
        in.regionLegend = {RegionLabel{255, "defects"}};
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

constexpr const char* kLossCsvHeader =
    "iteration,evaluations,loss,L_grad,L_reg,seconds,heldout_loss,heldout_paper_loss,heldout_U";

/// One λ's optimization: E* and loss.csv's rows.
struct LambdaResult {
    OptimizeRun run;
    std::vector<double> e;  // the answer (app/pipeline/Answer.h): E*, or the reference that beat it
    std::vector<double> optimizedE;  // E* when the answer is a reference (else empty)
    std::vector<std::vector<double>> startResults;  // every start's E (multistart)
    /// The lights the noise rule searched on finer grids at this run's spp before E*'s
    /// (app/pipeline/TrainingNoise.h step 5), named with their grid and gap: the self-check's
    /// fallback.
    std::vector<std::pair<std::string, std::vector<double>>> finer;
    std::vector<std::string> rows;
    LossCurve curve;                        // loss.csv's loss and held-out loss, for the loss plot
    LossParts lampTraining, paperTraining;  // the lamp's and the paper's light on T at λ
};

/// How a person sees the images (the judge's JND): the scene's viewing model, the default one
/// when only T is at hand.
ViewingModel viewingOf(const Inputs& in) {
    return in.scene ? viewingFor(*in.scene) : defaultViewing();
}

/// The objective's options at λ; the jnd measure sees the image as the judge does (viewingOf).
ObjectiveOptions objectiveAt(const Plan& p, const Inputs& in, double lambda) {
    ObjectiveOptions oo = p.o.objective;
    oo.lambda = lambda;
    if (!(oo.viewing.pixelsPerDegree > 0)) oo.viewing = viewingOf(in);
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
        // Every row: the optimizer's own loss (with planes, on the estimate of that step; with
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
        so.planes = o.planes;
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
    AnswerChoice choice = chooseAnswer(validation, std::move(candidates));
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
        run.judgeRounds = judgeInRounds(judgeAt, lights, first,
                                        rounds ? std::max(first, kJudgeDefaultSpp) : first);
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
    for (const std::string& w : run.warnings) spdlog::warn("lambda {}: {}", run.lambda, w);
}

/// Luminance of E per texel (gray E as it is).
std::vector<double> envLuminance(const std::vector<double>& e, bool rgb) {
    if (!rgb) return e;
    std::vector<double> y(e.size() / 3);
    for (size_t i = 0; i < y.size(); ++i) y[i] = luminance(e[3 * i], e[3 * i + 1], e[3 * i + 2]);
    return y;
}

/// Where the light of E* comes from, for the report: the direction toward the camera, the
/// mirror direction a flat part reflects into the camera, and the brightest local maxima of E*
/// (up to 3, on the EnvMapBasis grid, wrapping in azimuth).
json envDirectionsJson(const Inputs& in, const TransportMatrix& t, const std::vector<double>& e,
                       bool rgb) {
    json j;
    if (in.scene) {
        const CameraDesc& c = in.scene->camera.desc();
        const Vec3d toCamera = normalize(c.origin - c.target);
        j["camera"] = directionJson(toCamera);
        j["mirror"] = directionJson(Vec3d{-toCamera.x, toCamera.y, -toCamera.z});
    }
    const std::vector<double> y = envLuminance(e, rgb);
    const int w = t.envWidth, h = t.envHeight;
    auto at = [&](int row, int col) {
        return y[static_cast<size_t>(row) * w + static_cast<size_t>((col % w + w) % w)];
    };
    std::vector<std::pair<double, std::pair<int, int>>> peaks;
    for (int row = 0; row < h; ++row)
        for (int col = 0; col < w; ++col) {
            const double v = at(row, col);
            bool peak = v > kDarkTexel;
            for (int dr = -1; dr <= 1 && peak; ++dr)
                for (int dc = -1; dc <= 1 && peak; ++dc)
                    if ((dr || dc) && row + dr >= 0 && row + dr < h) {
                        const double u = at(row + dr, col + dc);
                        // Plateaus: the first texel in scan order stands for them.
                        peak = u < v || (u == v && (dr > 0 || (dr == 0 && dc > 0)));
                    }
            if (peak) peaks.push_back({v, {row, col}});
        }
    std::stable_sort(peaks.begin(), peaks.end(),
                     [](const auto& a, const auto& b) { return a.first > b.first; });
    const EnvMapBasis basis(w, h);
    json brightest = json::array();
    for (size_t k = 0; k < peaks.size() && k < 3; ++k) {
        json d = directionJson(basis.texelDirection(peaks[k].second.first, peaks[k].second.second));
        d["value"] = peaks[k].first;
        brightest.push_back(d);
    }
    j["brightest"] = brightest;
    return j;
}

/// plot-data.json: the lights' texel luminances and the grid's directions, what the env-map
/// plots are drawn from (app/report/OptimizeFigures.h here, scripts/plot_optimize.py by hand;
/// neither restates the convention).
json plotDataJson(const Inputs& in, const TransportMatrix& t, const std::vector<double>& e,
                  bool rgb) {
    const EnvMapBasis basis(t.envWidth, t.envHeight);
    json az = json::array(), el = json::array();
    for (int col = 0; col < t.envWidth; ++col)
        az.push_back(directionJson(basis.texelDirection(t.envHeight / 2, col))["azimuth_deg"]);
    for (int row = 0; row < t.envHeight; ++row)
        el.push_back(directionJson(basis.texelDirection(row, 0))["elevation_deg"]);
    json j;
    j["convention"] =
        "scene/EnvMapBasis.h: u = atan2(d.x, -d.z)/2pi, v = acos(d.y)/pi; azimuth = u*360 deg "
        "(0 toward -z, 90 toward +x), elevation = 90 - v*180 deg (+90 = +Y, 0 = horizon); rows "
        "at theta = j*pi/(H-1), columns at u = (i+1/2)/W, bilinear, wrapping in u";
    j["width"] = t.envWidth;
    j["height"] = t.envHeight;
    j["azimuth_deg"] = az;
    j["elevation_deg"] = el;
    j["lights"] = {{"optimized", envLuminance(e, rgb)},
                   {"lamp", envLuminance(in.lampE, rgb)},
                   {"paper", envLuminance(in.paperE, rgb)},
                   {"initial", envLuminance(in.startValues.front(), rgb)}};
    j["lamp_name"] = in.lampName;
    return j;
}

/// summary.json of one run.
json runSummaryJson(const Plan& p, const Inputs& in, const OptimizeJobSummary& job,
                    const LambdaResult& r, const VisibilityMetrics& metricsFinal) {
    const OptimizeJobOptions& o = p.o;
    const OptimizeRun& run = r.run;
    std::vector<std::string> starts;
    for (const InitialState& s : o.starts) starts.push_back(s.spec);
    json s;
    s["scratchlight"] = runProvenance(o.commandLine);
    if (in.scene) s["part"] = partSummaryJson(*in.scene);
    s["optimizer"] = run.optimizer.method;
    s["planes"] = o.planes;
    if (p.ranks)  // each rank held one shard; "transport" describes rank 0's
        s["mpi"] = {{"ranks", p.ranks->size()},
                    {"seconds_collectives_optimize", run.secondsCollectives}};
    s["starts"] = starts;
    s["start"] = run.start;
    s["continuation"] = o.continuation;
    s["light_grid"] = o.lightGrid.value_or(LightGrid{}).name();
    s["objective"] = objectiveKindName(in.kind);
    s["lambda"] = run.lambda;
    s["reg"] = o.objective.reg == RegTarget::EnvMap ? "envmap" : "image";
    s["smooth_abs"] = o.objective.smoothAbs;
    s["init"] = starts.front();  // E0 of the report (the first start)
    s["rgb"] = o.rgb;
    s["mask"] = o.mask.name();
    s["mask_pixels"] = job.maskPixels;
    if (in.kind == ObjectiveKind::Defects) {
        s["defects_measure"] = defectMeasureName(o.objective.defectMeasure);
        s["defects"] = defectRegion(o).text();
        s["reference"] =
            o.reference.empty() ? "the part away from the defects" : o.reference.text();
    }
    s["iterations"] = run.optimizer.iterations;
    s["evaluations"] = run.optimizer.evaluations;
    s["termination"] = run.optimizer.termination;
    s["returned_iteration"] = run.optimizer.returnedIteration;
    s["improved"] = run.final.total < run.initial.total;
    s["warnings"] = run.warnings;
    s["interrupted"] = run.interrupted;
    // initial/final: the objective the optimizer minimized, through what it minimized it.
    s["loss_through"] = run.lossThrough;
    s["initial_loss"] = run.initial.total;
    s["final_loss"] = run.final.total;
    s["initial"] = partsJson(run.initial);
    s["final"] = partsJson(run.final);
    s["seconds_precompute"] =
        job.transport.cacheHit || p.tmInput ? 0.0 : job.transport.secondsTotal;
    s["seconds_load_transport"] = job.transport.secondsTotal;
    s["transport_cache_hit"] = job.transport.cacheHit;
    s["seconds_optimize"] = run.optimizer.seconds;
    s["seconds_heldout_scoring"] = run.secondsHeldOutScoring;
    // Where the run's seconds went, every round of the noise rule included (issue 29's speed:
    // scripts/bench-first-answer reads it): tracing T and V, the searches, the self-check, the
    // judge (its first estimate and its rounds).
    s["seconds_phases"] = {{"trace", run.secondsTrace},
                           {"search", run.secondsSearch},
                           {"self_check", run.answer ? run.answer->seconds : 0.0},
                           {"judge", run.secondsJudge}};
    if (run.heldFinal) {
        s["heldout_loss"] = run.heldFinal->own.total;
        s["heldout_L_grad"] = run.heldFinal->own.lGrad;
        s["heldout_L_reg"] = run.heldFinal->own.lReg;
        s["heldout_paper_loss"] = run.heldFinal->paper.total;
        s["heldout_U"] = run.heldFinal->unbiased.total;
        s["heldout_objective"] = objectiveKindName(in.kind);
        s["heldout"] = {{"initial", heldJson(*run.heldInitial)},
                        {"final", heldJson(*run.heldFinal)},
                        {"transport", transportJson(*job.heldOut)},
                        {"curve_spp", run.heldCurveSpp}};
    } else {
        s["heldout_loss"] = nullptr;
    }
    if (in.scene) s["heightmap"] = heightmapLoadJson(*in.scene);  // reader and levelling
    s["transport"] = transportJson(job.transport);
    if (job.validation) {
        json v = {{"transport", transportJson(*job.validation)}};
        if (run.validationFinal) v["final"] = partsJson(*run.validationFinal);
        s["validation"] = v;
    }
    if (!run.noise.rounds.empty()) {
        json rounds = json::array();
        for (const TrainingNoiseRound& nr : run.noise.rounds)
            rounds.push_back({{"spp", nr.spp},
                              {"light_grid", nr.grid.name()},
                              {"training", nr.training},
                              {"validation", nr.validation},
                              {"gap", nr.gap},
                              {"gap_se", nr.gapError},
                              {"validation_spp", nr.validationSpp},
                              {"verdict", gapVerdictName(nr.verdict)},
                              {"decision", nr.decision},
                              {"seconds", nr.seconds}});
        s["training_noise"] = {
            {"figure", figureHigherIsBetter(in.kind) ? "defect visibility (higher is better)"
                                                     : "loss (lower is better)"},
            {"max_gap", run.noise.maxGap},
            {"adapted", run.noise.adapted},
            {"grid_adapted", run.noise.gridAdapted},
            {"met", run.noise.met},
            {"spp", run.noise.spp()},
            {"light_grid", run.noise.grid().name()},
            {"gap", run.noise.gap()},
            {"gap_se", run.noise.gapError()},
            {"gap_sigmas", kGapSigmas},
            {"unresolved", run.noise.unresolved},
            {"seconds_added", run.noise.secondsAdded},
            {"rounds", rounds},
            {"reason", run.noise.reason}};
    }
    if (run.answer) {
        const AnswerChoice& a = *run.answer;
        s["answer"] = answerJson(a);
        if (a.referenceWon()) s["answer"]["optimized_envmap"] = outdir::kEnvMapOptimized;
    }
    if (run.judged) s["judge"] = toJson(*run.judged);
    {
        // The report's headline (app/report/Report.h optimizeHeadline): E* against the user's lamp
        // and the paper's light, on T and (with the held-out estimate) by the judge.
        json cmp;
        cmp["objective"] = objectiveKindName(in.kind);
        cmp["regions"] = in.regionSource;
        json lamp = {{"name", in.lampName},
                     {"spec", o.compare.empty() ? std::string("studio") : o.compare},
                     {"render", outdir::kCompareLampPng},
                     {"training", partsJson(r.lampTraining)}};
        json paper = {{"name", "paper's light"},
                      {"method",
                       "the paper's method run on this T: eq. 2, lambda 30 on mean(E^2), Adam lr "
                       "0.02 x 100 from E0 = 0.5"},
                      {"render", outdir::kComparePaperPng},
                      {"envmap", outdir::kPaperEnvMap},
                      {"training", partsJson(r.paperTraining)}};
        json optimized = {
            {"render", r.optimizedE.empty() ? outdir::kRenderPng : outdir::kRenderOptimizedPng},
            {"training", partsJson(run.final)}};
        if (run.judged) {
            lamp["judge"] = toJson(*run.judgedLamp);
            paper["judge"] = toJson(*run.judgedPaper);
            optimized["judge"] = toJson(run.judgedOptimized ? *run.judgedOptimized : *run.judged);
            cmp["judge_spp"] = job.heldOut->file.provenance.spp;
            cmp["viewing"] = viewingJson(viewingOf(in));
            cmp["judge_rounds"] = roundsJson(run.judgeRounds);
            cmp["judge_reason"] = run.judgeRounds.describe();
            cmp["judge_max_relative_se"] = kJudgeMaxError;
        }
        cmp["lamp"] = lamp;
        cmp["paper"] = paper;
        cmp["optimized"] = optimized;
        if (run.answer && (run.answer->referenceWon() ||
                           run.answer->answer().candidate.kind == CandidateKind::Finer)) {
            // The light returned (envmap.exr) is a reference (or a finer light) that beat E* on
            // validation.
            const AnswerChoice& a = *run.answer;
            json answer = {{"name", a.answer().candidate.name},
                           {"render", outdir::kRenderPng},
                           {"reason", a.reason},
                           {"merit", a.answer().merit.what},
                           {"merit_answer", a.answer().merit.value},
                           {"merit_optimized", a.scored[a.optimized].merit.value},
                           {"visibility_answer", a.answer().merit.visibility},
                           {"visibility_optimized", a.scored[a.optimized].merit.visibility},
                           {"optimized_why", a.scored[a.optimized].why},
                           {"on", "the validation estimate"}};
            if (run.judged) answer["judge"] = toJson(*run.judged);
            cmp["answer"] = answer;
        }
        s["compare"] = cmp;
    }
    s["envmap_directions"] = envDirectionsJson(in, job.transport.file.matrix, r.e, o.rgb);
    s["metrics"] = toJson(metricsFinal);
    s["metrics_initial"] = toJson(in.metricsInitial);
    if (!o.truth.empty()) s["truth"] = o.truth.string();
    if (o.mask.kind == LossMaskKind::Scratch)
        s["scratch_map"] = {{"kernel", o.scratch.kernel},
                            {"patch", o.scratch.patch},
                            {"threshold", o.scratch.threshold}};
    return s;
}

/// What the figures show, from plot-data.json's and summary.json's content (as
/// scripts/plot_optimize.py reads them from the files) and the loss curve.
OptimizeFiguresInput figuresInput(const json& plotData, const json& summary,
                                  const LossCurve& curve) {
    OptimizeFiguresInput f;
    f.envmap.width = plotData.at("width").get<int>();
    f.envmap.height = plotData.at("height").get<int>();
    f.envmap.azimuthDeg = plotData.at("azimuth_deg").get<std::vector<double>>();
    f.envmap.elevationDeg = plotData.at("elevation_deg").get<std::vector<double>>();
    f.envmap.luminance = plotData.at("lights").at("optimized").get<std::vector<double>>();
    const json& dirs = summary.at("envmap_directions");
    auto direction = [](const json& d) {
        return PlotDirection{d.at("azimuth_deg").get<double>(),
                             d.at("elevation_deg").get<double>()};
    };
    if (dirs.contains("camera")) f.directions.camera = direction(dirs["camera"]);
    if (dirs.contains("mirror")) f.directions.mirror = direction(dirs["mirror"]);
    for (const json& d : dirs.at("brightest")) f.directions.brightest.push_back(direction(d));
    f.loss = curve;
    std::ostringstream lambda;
    lambda << summary.at("lambda").get<double>();
    f.lossTitle = summary.at("optimizer").get<std::string>() + " on " +
                  summary.at("objective").get<std::string>() + ", λ = " + lambda.str();
    f.title = "scratchlight optimize: loss " +
              formatNumber(summary.at("initial_loss").get<double>(), 4) + " → " +
              formatNumber(summary.at("final_loss").get<double>(), 4);
    f.lampTitle =
        "your lamp (" + summary.at("compare").at("lamp").at("name").get<std::string>() + ")";
    return f;
}

/// Stage 5: one run's files (the header of OptimizeJob.h lists them); returns its report entry.
ReportRun writeRunOutputs(const Plan& p, const Inputs& in, const OptimizeJobSummary& job,
                          const LambdaResult& r) {
    const OptimizeJobOptions& o = p.o;
    const OptimizeRun& run = r.run;
    const TransportMatrix& t = job.transport.file.matrix;
    const std::vector<uint8_t>& mask = in.mask.pixels;
    // The renders first: over MPI ranks every rank takes part in putting them together, then
    // rank 0 alone writes.
    const std::vector<double> imageFinal = renderImage(t, r.e, in.shard);
    const std::vector<double> imageLamp = renderImage(t, in.lampE, in.shard);
    const std::vector<double> imagePaper = renderImage(t, in.paperE, in.shard);
    const std::vector<double> imageOptimized =
        r.optimizedE.empty() ? imageFinal : renderImage(t, r.optimizedE, in.shard);
    if (!p.writes()) return {};
    const std::filesystem::path dir = p.staged(run.dir);
    std::filesystem::create_directories(dir);
    writeEnvMap(dir / outdir::kEnvMap, toEnvMap(r.e, t, o.rgb));
    writePng(dir / outdir::kEnvMapPng, envMapPreview(toEnvMap(r.e, t, o.rgb), 16));
    const int ch = t.channels == 3 ? 3 : 1;
    writeRender(dir / outdir::kRender, imageFinal, t.width, t.height, ch);
    if (!r.optimizedE.empty()) {  // a reference is the answer: E* beside it
        writeEnvMap(dir / outdir::kEnvMapOptimized, toEnvMap(r.optimizedE, t, o.rgb));
        writePng(dir / outdir::kEnvMapOptimizedPng,
                 envMapPreview(toEnvMap(r.optimizedE, t, o.rgb), 16));
        writeRender(dir / outdir::kRenderOptimized, imageOptimized, t.width, t.height, ch);
    }
    {
        Image i0(t.width, t.height, ch);
        for (size_t i = 0; i < in.image0.size(); ++i) i0.data[i] = static_cast<float>(in.image0[i]);
        writePng(dir / outdir::kInitialPng, i0);
    }
    std::ostringstream csv;
    csv << kLossCsvHeader << '\n';
    for (const auto& row : r.rows) csv << row << '\n';
    writeTextAtomically(dir / outdir::kLossCsv, csv.str());
    writePng(dir / outdir::kInitialEnvMapPng,
             envMapPreview(toEnvMap(in.startValues.front(), t, o.rgb), 16));
    {
        std::vector<uint8_t> visible(mask.size());  // masks hold 0/1; the PNG 0/255
        for (size_t i = 0; i < mask.size(); ++i) visible[i] = mask[i] ? 255 : 0;
        writeMaskPng(dir / outdir::kMaskPng, visible, t.width, t.height);
    }
    if (in.kind == ObjectiveKind::Defects) {
        // regions.png: the render with the defect region outlined red and, when one was given,
        // the reference region blue (app/report/Preview.h).
        std::vector<double> y(t.rows());
        for (size_t q = 0; q < y.size(); ++q)
            y[q] = ch == 3
                       ? luminance(imageFinal[3 * q], imageFinal[3 * q + 1], imageFinal[3 * q + 2])
                       : imageFinal[q];
        std::vector<uint8_t> labels(t.rows(), 0);
        for (size_t q = 0; q < labels.size(); ++q)
            labels[q] = in.defects[q] ? 255 : (!in.reference.empty() && in.reference[q] ? 128 : 0);
        writePng(dir / outdir::kRegionsPng, outlinedRender(y, t.width, t.height, mask, labels));
        writeDefectRegions(dir, {in.defects, in.reference}, t.width, t.height);
    }
    if (!in.mask.scratchCells.empty())
        writeMaskPng(dir / outdir::kScratchMapPng, in.mask.scratchCells, in.scene->mapWidth,
                     in.scene->mapHeight);
    // The comparisons: the user's lamp and the paper's light under T, and what the report shows
    // (each render exposed on its own, the regions' outlines as a transparent layer).
    writeRender(dir / outdir::kCompareLamp, imageLamp, t.width, t.height, ch);
    writeRender(dir / outdir::kComparePaper, imagePaper, t.width, t.height, ch);
    writeEnvMap(dir / outdir::kPaperEnvMap, toEnvMap(in.paperE, t, o.rgb));
    Image lampView = writeExposedPng(dir / outdir::kViewLamp, imageLamp, t);
    Image optimizedView = writeExposedPng(dir / outdir::kViewOptimized, imageOptimized, t);
    writeExposedPng(dir / outdir::kViewPaper, imagePaper, t);
    if (!in.regionLabels.empty()) {
        const Image outlined = outlinedRender(std::vector<double>(t.rows(), 0.0), t.width, t.height,
                                              {}, in.regionLabels);
        Image layer(t.width, t.height, 4);
        for (size_t q = 0; q < t.rows(); ++q) {
            const bool edge = outlined.data[3 * q] > 0 || outlined.data[3 * q + 1] > 0 ||
                              outlined.data[3 * q + 2] > 0;
            for (int c = 0; c < 3; ++c) layer.data[4 * q + c] = outlined.data[3 * q + c];
            layer.data[4 * q + 3] = edge ? 1.0f : 0.0f;
        }
        writePng(dir / outdir::kViewRegions, layer);
    }
    const json plotData = plotDataJson(in, t, r.e, o.rgb);
    writeTextAtomically(dir / outdir::kPlotData, plotData.dump() + "\n");
    const VisibilityMetrics metricsFinal = metricsFor(t, imageFinal, mask, r.e, o.rgb, in.truth);
    const json summary = runSummaryJson(p, in, job, r, metricsFinal);
    writeTextAtomically(dir / outdir::kSummary, summary.dump(2) + "\n");
    // The figures, drawn in-process (app/report/OptimizeFigures.h); when they fail the report says
    // why.
    std::string figureProblem;
    if (!o.figures) {
        figureProblem = "figures not asked for";
    } else {
        const ProgressTask task("figures");
        try {
            OptimizeFiguresInput fig = figuresInput(plotData, summary, r.curve);
            fig.lampView = std::move(lampView);
            fig.optimizedView = std::move(optimizedView);
            writeOptimizeFigures(dir, fig);
        } catch (const std::exception& e) {
            figureProblem = e.what();
            spdlog::warn("figures not made: {}", figureProblem);
        }
    }
    writeTextAtomically(dir / outdir::kReport, renderOptimizeReportHtml(dir, figureProblem));
    std::ostringstream title;
    title << "λ = " << run.lambda << ", " << run.optimizer.method << ", "
          << objectiveKindName(in.kind);
    return reportRunFromOutDir(dir, title.str());
}

/// Stage 6: a sweep's sweep.csv and its report of every λ.
void writeSweep(const Plan& p, const Inputs& in, const OptimizeJobSummary& job,
                const std::vector<ReportRun>& reportRuns) {
    std::ostringstream csv;
    csv << "lambda,optimizer,objective,iterations,evaluations,initial_loss,final_loss,"
           "final_L_grad,final_L_reg,heldout_loss,heldout_paper_loss,seconds\n";
    for (const OptimizeRun& run : job.runs) {
        csv << std::setprecision(10) << run.lambda << ',' << run.optimizer.method << ','
            << objectiveKindName(in.kind) << ',' << run.optimizer.iterations << ','
            << run.optimizer.evaluations << ',' << run.initial.total << ',' << run.final.total
            << ',' << run.final.lGrad << ',' << run.final.lReg << ',';
        if (run.heldFinal)
            csv << run.heldFinal->own.total << ',' << run.heldFinal->paper.total;
        else
            csv << ',';
        csv << ',' << run.optimizer.seconds << '\n';
    }
    writeTextAtomically(p.writeDir / "sweep.csv", csv.str());
    ReportContent rc;
    rc.title = "scratchlight optimize: lambda sweep";
    ReportFigure fig;
    fig.title = "one run per lambda";
    fig.runs = reportRuns;
    fig.combinedLossPlot = true;
    rc.figures.push_back(std::move(fig));
    writeReport(p.writeDir / "report.html", rc);
}

}  // namespace

OptimizeJobSummary runOptimizeJob(const OptimizeJobOptions& options) {
    Plan p = plan(options);
    // OUTDIR is checked before any work and written as a unit: a failure or Ctrl-C leaves the
    // previous results as they were. Over MPI ranks, rank 0 alone writes it.
    std::optional<StagedDirectory> out;
    if (p.writes()) {
        out.emplace(p.o.outDir);
        p.o.outDir = out->target();
        p.writeDir = out->path();
    }
    OptimizeJobSummary job;
    try {
        Inputs in;
        in.ranks = p.ranks;
        // Context first, as each piece is known (the results follow the work).
        // T at `spp` (unset: the scene's or the given one), its validation estimate, and what
        // depends on T; the scene is loaded once.
        double secondsTrace = 0, secondsSearch = 0;  // every round's (OptimizeRun)
        auto load = [&](int spp) {
            Inputs kept = std::move(in);
            in = Inputs{};
            in.ranks = p.ranks;
            in.scene = std::move(kept.scene);  // loaded once
            if (kept.sceneParts) {             // what does not depend on T: computed once
                in.defects = std::move(kept.defects);
                in.reference = std::move(kept.reference);
                in.truth = std::move(kept.truth);
                in.truthLabels = std::move(kept.truthLabels);
                in.lampName = std::move(kept.lampName);
                in.lampE = std::move(kept.lampE);
                in.sceneParts = true;
            }
            in.sppScale = std::move(kept.sppScale);  // chosen with the regions, on the first load
            job.extraPlanes.clear();
            const Stopwatch traceClock;
            loadTraining(p, in, job, spp);
            secondsTrace += traceClock.seconds();
            if (job.transport.autoDepth && spp == 0)
                spdlog::info("max_depth {}: {}", job.transport.autoDepth->maxDepth,
                             job.transport.autoDepth->reason);
            spdlog::info("{}", describeTransport(job.transport));
            const Stopwatch validationClock;
            loadValidation(p, in, job);
            secondsTrace += validationClock.seconds();
            prepareRuns(p, in, job);
            prepareComparisons(p, in, job);
        };
        Stopwatch round;
        double notInRound = 0;  // the judge's estimate is not part of a training round
        load(0);
        {
            const Stopwatch judgeClock;
            loadHeldOut(p, in, job);
            if (job.heldOut)
                spdlog::info("judge estimate (held out): {} ({} spp, seed {})",
                             job.heldOut->path.empty() ? std::string("not stored")
                                                       : job.heldOut->path.string(),
                             job.heldOut->file.provenance.spp, job.heldOut->file.provenance.seed);
            if (job.validation && job.heldOut &&
                job.validation->file.provenance.seed == job.heldOut->file.provenance.seed)
                throw inputError(option("seed"), "the validation estimate's seed is the judge's",
                                 "use another " + option("seed"));
            notInRound = judgeClock.seconds();
        }
        const double secondsHeldOut = notInRound;  // the judge's first estimate
        if (!p.cacheDir.empty() && (!p.tmInput || p.o.heldOut.mode == HeldOutMode::Judge))
            spdlog::info("cache {}", describeCache(cacheContents(p.cacheDir)));
        spdlog::info("mask: {} pixels; writing {}", job.maskPixels, p.o.outDir.string());
        std::vector<ReportRun> reportRuns;
        TrainingNoiseSummary noise;
        noise.maxGap = p.noise.maxGap;
        noise.adapted = p.noise.adapt;
        noise.gridAdapted = p.noise.adaptGrid;
        for (double lambda : p.o.lambdas) {
            Stopwatch searchClock;
            LambdaResult r = optimizeLambda(p, in, job, lambda);
            secondsSearch += searchClock.seconds();
            // Noise-aware training (app/pipeline/TrainingNoise.h), on the first λ: E* on T and on
            // V; the spp is raised (T, V and the comparisons traced again) while the gap is large.
            while (noise.rounds.size() < 16 && job.runs.empty() && r.run.validationFinal &&
                   !p.blackBox && !r.run.interrupted) {
                TrainingNoiseRound nr;
                nr.spp = job.transport.file.provenance.spp;
                nr.grid = p.o.lightGrid.value_or(LightGrid{});
                nr.validationSpp = job.validation->file.provenance.spp;
                nr.training = trainingFigure(in.kind, r.run.final);
                nr.validation = trainingFigure(in.kind, *r.run.validationFinal);
                nr.gap = trainingGap(in.kind, nr.training, nr.validation);
                // The gap's standard error, V's own noise (step 3).
                const ObjectiveOnT onV =
                    validationObjective(in, job, objectiveAt(p, in, lambda), p.o.rgb);
                const Stopwatch gapClock;
                nr.gapError = trainingGapError(
                    in.kind, *onV.loss, r.e, job.validation->file.provenance.seed, kJudgeReplicates,
                    dynamic_cast<const UnbiasedObjective*>(onV.halves.get()));
                nr.secondsGapError = gapClock.seconds();
                // Step 4: V's noise: more V (T's spp for eq. 2, whose V must keep T's spp);
                // over-fit: more T, then a coarser light (step 5).
                const bool freeV = validationSppFree(in.kind);
                const bool vAtMost =
                    freeV ? !p.noise.adapt || nr.validationSpp >= p.noise.maxValidationSpp
                          : !p.noise.adapt || nr.spp >= p.noise.maxSpp;
                nr.verdict = gapVerdict(nr.gap, nr.gapError, p.noise.maxGap, vAtMost);
                nr.seconds = round.seconds() - notInRound;
                noise.met = nr.verdict == GapVerdict::Within;
                const bool vNoise = nr.verdict == GapVerdict::ValidationNoise;
                const int nextV =
                    vNoise && freeV && p.noise.adapt
                        ? nextValidationSpp(nr.validationSpp, nr.gapError, p.noise).value_or(0)
                        : 0;
                const int next = !p.noise.adapt || noise.met || (vNoise && freeV) ? 0
                                 : vNoise
                                     ? nextJudgeSpp(nr.spp,
                                                    std::isnan(nr.gapError)
                                                        ? std::numeric_limits<double>::infinity()
                                                        : nr.gapError,
                                                    p.noise.maxSpp, p.noise.maxGap)
                                     : nextTrainingSpp(nr.spp, nr.gap, p.noise).value_or(0);
                const std::optional<LightGrid> coarser =
                    nr.verdict == GapVerdict::OverFit && next == 0 && p.noise.adaptGrid
                        ? nextLightGrid(nr.grid, job.transport.file.matrix.envWidth,
                                        job.transport.file.matrix.envHeight)
                        : std::nullopt;
                noise.unresolved = vNoise && nextV == 0 && next == 0;
                nr.decision = nextV > 0   ? "V at " + std::to_string(nextV) + " spp"
                              : next > 0  ? "T at " + std::to_string(next) + " spp"
                              : coarser   ? "a coarser light, " + coarser->name()
                              : noise.met ? std::string("kept")
                              : vNoise    ? std::string("kept: not resolved at this cost")
                                          : std::string("kept: over-fit at the limits");
                noise.rounds.push_back(nr);
                spdlog::info(
                    "training noise: {} spp, {}, V {} spp, E*'s {} {} on T and {} on the "
                    "validation estimate: gap {} % ± {} % ({}): {}",
                    nr.spp, nr.grid.name(), nr.validationSpp,
                    figureHigherIsBetter(in.kind) ? "visibility" : "loss",
                    formatNumber(nr.training, 4), formatNumber(nr.validation, 4),
                    formatNumber(100.0 * nr.gap, 3), formatNumber(100.0 * nr.gapError, 3),
                    gapVerdictName(nr.verdict), nr.decision);
                if (nextV > 0) {
                    // The same T and E*, scored again on V at more spp: this round goes on.
                    p.validationSpp = nextV;
                    noise.rounds.back().seconds = 0;  // counted in the round that goes on
                    const Stopwatch validationClock;
                    loadValidation(p, in, job);
                    secondsTrace += validationClock.seconds();
                    r.run.validationFinal =
                        validationObjective(in, job, objectiveAt(p, in, lambda), p.o.rgb)
                            .loss->evaluate(r.e, {});
                    continue;
                }
                if (next == 0 && !coarser) break;
                noise.secondsAdded += nr.seconds;
                round.restart();
                notInRound = 0;
                std::vector<std::pair<std::string, std::vector<double>>> finer;
                if (next > 0) {
                    load(next);
                } else {
                    finer = std::move(r.finer);
                    finer.emplace_back("optimized on " + nr.grid.name() + " (gap " +
                                           formatNumber(100.0 * nr.gap, 3) + " %)",
                                       r.optimizedE.empty() ? r.e : r.optimizedE);
                    p.o.lightGrid = *coarser;
                }
                searchClock.restart();
                r = optimizeLambda(p, in, job, lambda);
                secondsSearch += searchClock.seconds();
                r.finer = std::move(finer);
            }
            // Ctrl-C keeps nothing (the previous OUTDIR stays) unless the user asked to keep
            // the best so far (core/Interrupt.h).
            if (!p.o.keepInterrupted) throwIfInterrupted();
            noise.reason = describeTrainingNoise(noise);
            // The seconds are printed here and recorded as seconds_added, not in the reason
            // (summary.json's text stays the same for any run of the same inputs).
            if (!noise.rounds.empty())
                spdlog::info("training spp: {}{}", noise.reason,
                             noise.rounds.size() > 1
                                 ? "; the rule added " + formatNumber(noise.secondsAdded, 3) + " s"
                                 : std::string());
            r.run.noise = noise;
            checkAnswer(p, in, job, r);
            // V's first round may be below T's spp (app/pipeline/TrainingNoise.h step 1): a
            // choice within V's noise there is made again on V at T's spp.
            if (r.run.answer && job.validation && !noise.rounds.empty() &&
                job.validation->file.provenance.spp < job.transport.file.provenance.spp &&
                !answerDecided(*r.run.answer, noise.rounds.back().gapError)) {
                p.validationSpp = job.transport.file.provenance.spp;
                spdlog::info(
                    "lambda {}: the answer is within {} standard errors on V at {} spp: V at {} "
                    "spp",
                    lambda, formatNumber(kAnswerMarginSigmas, 2),
                    job.validation->file.provenance.spp, p.validationSpp);
                const Stopwatch validationClock;
                loadValidation(p, in, job);
                secondsTrace += validationClock.seconds();
                if (!r.optimizedE.empty()) r.e = std::exchange(r.optimizedE, {});
                checkAnswer(p, in, job, r);
            }
            const Stopwatch judgeClock;
            judgeRun(p, in, job, r);
            r.run.secondsJudge = secondsHeldOut + judgeClock.seconds();
            r.run.secondsTrace = secondsTrace;
            r.run.secondsSearch = secondsSearch;
            const Stopwatch outputsClock;
            reportRuns.push_back(writeRunOutputs(p, in, job, r));
            spdlog::info(
                "lambda {}: seconds: tracing T and V {}, searching {}, self-check {}, judge {}, "
                "figures and report {}",
                r.run.lambda, formatNumber(r.run.secondsTrace, 3),
                formatNumber(r.run.secondsSearch, 3),
                formatNumber(r.run.answer ? r.run.answer->seconds : 0.0, 3),
                formatNumber(r.run.secondsJudge, 3), formatNumber(outputsClock.seconds(), 3));
            job.runs.push_back(std::move(r.run));
            if (job.runs.back().interrupted) {  // the λs after it are not run
                job.interrupted = true;
                break;
            }
        }
        if (p.o.lambdas.size() > 1 && p.writes()) writeSweep(p, in, job, reportRuns);
    } catch (const InputError& e) {
        if (out) throw InputError(out->explain(e.what()));
        throw;
    }
    if (out) out->commit(/*evenIfInterrupted=*/p.o.keepInterrupted);
    return job;
}

}  // namespace sl
