#include "app/bench/Race.h"

#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <tuple>

#include "app/jobs/InsertDefectsJob.h"
#include "app/jobs/OptimizeJob.h"
#include "app/jobs/PartFiles.h"
#include "app/pipeline/Judge.h"
#include "app/pipeline/Transport.h"
#include "app/pipeline/Truth.h"
#include "core/Error.h"
#include "core/Interrupt.h"
#include "core/Progress.h"
#include "core/Registry.h"
#include "core/Stats.h"
#include "core/Stopwatch.h"
#include "core/Text.h"
#include "io/AtomicFile.h"
#include "io/SceneFile.h"
#include "objective/DefectVisibility.h"
#include "optimize/PaperSetup.h"
#include "scene/EnvMapPresets.h"
#include "scene/Scene.h"
#include "synth/DefectInsert.h"

namespace sl {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr int kRaceImageSize = 256;  // the parts' scene files' image (the default world)
constexpr int kRaceMaxDepth = 3;     // the path length every part is traced at

RaceConfig config(const std::string& name, ObjectiveKind objective, OptimizerMethod method,
                  int iterations, int spp, int estimates = 1,
                  const std::vector<std::string>& starts = {"const:0.5"},
                  std::vector<double> continuation = {}) {
    RaceConfig c;
    c.name = name;
    c.spp = spp;
    c.search.objective = objective;
    c.search.optimizer.method = method;
    c.search.optimizer.iterations = iterations;
    c.search.estimates = estimates;
    c.search.starts.clear();
    for (const std::string& spec : starts) c.search.starts.push_back(parseInitialState(spec));
    c.search.continuation = std::move(continuation);
    return c;
}

std::string partList() {
    std::string list;
    for (const std::string& n : knownRaceParts()) list += (list.empty() ? "" : ", ") + n;
    return "use " + list;
}

/// The spec of a race part or a labelled test part (no variant); nullopt for another name.
std::optional<SurfaceSpec> baseSpec(const std::string& name) {
    SurfaceSpec s;
    s.width = s.height = 512;
    s.pitch = 0.01;
    s.seed = 1;
    if (name == "ballend-chatter") {
        s.chatterStartFraction = 0.5;
        s.pocketEdge = false;
    } else if (name == "facemill-scratches") {
        s.process = SurfaceSpec::Process::FaceMillFeed;
        s.toolRadius = 4.0;
        s.stepover = 3.0;
        s.chatterAmplitude = 0.0;
        s.scratchCount = 6;
        s.gougeCount = 0;
        s.pocketEdge = false;
    } else if (name == "pocket") {
        s.chatterAmplitude = 0.0;
        s.stepover = 0.3;
        s.rasterAngleDeg = 30.0;
    } else {
        for (const TestPartRow& row : testPartTable())
            if (name == row.name) return testPartSpec(row.value);
        return std::nullopt;
    }
    return s;
}

/// The spec of any knownRaceParts() name: NAME-shallow / NAME-deep cut their scratches,
/// gouges and dents to kShallowDefectsSq / kDeepDefectsSq × the texture's Sq.
SurfaceSpec partSpec(const std::string& name) {
    std::string base = name;
    double depthSq = 0;
    for (const auto& [suffix, f] : {std::pair{std::string("-shallow"), kShallowDefectsSq},
                                    std::pair{std::string("-deep"), kDeepDefectsSq}})
        if (name.size() > suffix.size() && name.ends_with(suffix)) {
            base = name.substr(0, name.size() - suffix.size());
            depthSq = f;
        }
    std::optional<SurfaceSpec> s = baseSpec(base);
    if (!s) throw inputError(option("parts"), "no race part named '" + name + "'", partList());
    if (depthSq > 0) {
        SurfaceSpec texture = *s;  // the part without its defects and macro shape
        texture.scratchCount = texture.gougeCount = texture.dentCount = 0;
        texture.scratches.clear();
        texture.gouges.clear();
        texture.dents.clear();
        texture.pocketEdge = false;
        texture.pocketBurrHeight = texture.toolChangeStep = 0;
        const GeneratedSurface t = generateSurface(texture);
        const double sq = textureSq(t.heights, t.width, t.height);
        s->scratchDepth = s->gougeDepth = s->dentDepth = depthSq * sq;
    }
    return *s;
}

double regionVisibility(const JudgeScore& s, const std::string& name) {
    for (const auto& r : s.visibility)
        if (r.label.name == name) return r.visibility;
    return kNaN;
}

RaceRow medianRow(const std::vector<const RaceRow*>& rows) {
    RaceRow m = *rows.front();
    m.seed = -1;
    auto med = [&](double RaceRow::*f) {
        std::vector<double> v;
        for (const RaceRow* r : rows)
            if (!std::isnan(r->*f)) v.push_back(r->*f);
        return v.empty() ? kNaN : median(v);
    };
    for (double RaceRow::*f :
         {&RaceRow::secondsPrecompute, &RaceRow::secondsSearch, &RaceRow::seconds, &RaceRow::eq2,
          &RaceRow::unbiased, &RaceRow::meanE, &RaceRow::sparsity, &RaceRow::visDefect,
          &RaceRow::visChatter, &RaceRow::trainLoss, &RaceRow::heldOwn, &RaceRow::ratioU,
          &RaceRow::ratioEq2, &RaceRow::ratioSeconds, &RaceRow::figure, &RaceRow::vsLamp,
          &RaceRow::vsPaper, &RaceRow::jnd, &RaceRow::jndVsLamp})
        m.*f = med(f);
    std::vector<double> ev;
    for (const RaceRow* r : rows) ev.push_back(r->evaluations);
    m.evaluations = static_cast<int>(median(ev));
    return m;
}

}  // namespace

std::vector<std::string> raceParts() {
    return {"ballend-chatter", "facemill-scratches", "pocket"};
}

std::vector<std::string> knownRaceParts() {
    std::vector<std::string> names = raceParts();
    for (const TestPartRow& row : testPartTable()) names.emplace_back(row.name);
    const size_t generated = names.size();
    for (const char* suffix : {"-shallow", "-deep"})
        for (size_t i = 0; i < generated; ++i) names.push_back(names[i] + suffix);
    return names;
}

PartFiles writeRacePart(const std::string& name, const std::filesystem::path& dir) {
    const SurfaceSpec spec = partSpec(name);  // throws for an unknown name, before any file
    std::filesystem::create_directories(dir);
    PartFileOptions pf;
    pf.scene = dir / "scene.json";
    pf.imageSize = kRaceImageSize;
    pf.spp = 16;
    pf.maxDepth = kRaceMaxDepth;
    return writePartFiles(generateSurface(spec), dir / "part.exr", pf);
}

PartFiles writeRealRacePart(const std::filesystem::path& file, const std::filesystem::path& dir) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(file, ec))
        throw inputError(file.string(), "is not a readable file",
                         "give an instrument height map (.x3p, .sdf, .opd, .plu, ...) or a scene "
                         "file, for " +
                             option("real"));
    InsertDefectsJobOptions o;
    o.input = file;
    o.output = dir / "part.exr";
    o.size = kRealPartSamples;
    o.imageSize = kRaceImageSize;
    std::filesystem::create_directories(dir);
    try {
        const InsertDefectsJobSummary s = runInsertDefectsJob(o);
        PartFiles f;
        f.heightmap = s.written.at(0);
        f.truth = s.written.at(1);
        f.legend = s.written.at(2);
        f.scene = s.written.at(3);
        return f;
    } catch (const std::exception& e) {  // every message names the file
        const std::string what = e.what();
        if (what.find(file.string()) != std::string::npos) throw;
        throw inputError(file.string(), what);
    }
}

std::vector<RaceConfig> defaultRaceConfigs() {
    using K = ObjectiveKind;
    using M = OptimizerMethod;
    std::vector<RaceConfig> c;
    // The paper's set-up (optimize/PaperSetup.h) at 16 spp an estimate: its loop over
    // kPaperLoopEstimates estimates, and its Adam on one (the paper's light's set-up).
    const OptimizerMethodRow& loop = methodRow(M::PaperLoop);
    c.push_back(config(loop.name, kPaperSetup.objective, loop.runs, loop.defaultBudget, 16,
                       loop.defaultEstimates, {kPaperSetup.startSpec}));
    c.push_back(config("paper-adam", kPaperSetup.objective, M::Adam, kPaperSetup.steps, 16, 1,
                       {kPaperSetup.startSpec}));
    c.push_back(config("paper-lbfgs-16", K::Paper, M::Lbfgs, 2000, 16));
    c.push_back(config("unbiased-adam-planes8", K::Unbiased, M::Adam, 300, 16, 8));
    c.push_back(config("unbiased-lbfgs-16", K::Unbiased, M::Lbfgs, 2000, 16));
    c.push_back(config("unbiased-newton-tr-16", K::Unbiased, M::NewtonTr,
                       methodRow(M::NewtonTr).defaultBudget, 16));  // as unbiased-lbfgs-16
    c.push_back(config("unbiased-lbfgs-32", K::Unbiased, M::Lbfgs, 2000, 32));
    // optimize's defaults (app/pipeline/Defaults.h optimizeDefaults), for each objective.
    const OptimizeDefaults d = optimizeDefaults();
    c.push_back(config("default-unbiased", K::Unbiased, d.method, methodRow(d.method).defaultBudget,
                       16, 1, d.starts));
    // ... and newton-tr in the unbiased default's place (the starts and spp of default-unbiased).
    c.push_back(config("default-unbiased-newton-tr", K::Unbiased, M::NewtonTr,
                       methodRow(M::NewtonTr).defaultBudget, 16, 1, d.starts));
    c.push_back(config("default-paper", K::Paper, d.method, methodRow(d.method).defaultBudget,
                       d.paperMinSpp, 1, d.starts));
    // ... and with the defects named (the part's truth): the defects objective.
    c.push_back(config("default-defects", d.objectiveWithDefects, d.method,
                       methodRow(d.method).defaultBudget, 16, 1, d.starts));
    // ... and with the defects found without labels (the defect map, `--defects auto`).
    c.push_back(config("default-defects-auto", d.objectiveWithDefects, d.method,
                       methodRow(d.method).defaultBudget, 16, 1, d.starts));
    c.back().autoDefects = true;
    // ... and the defects objective on the visibility ratio (the default before it was raced
    // against JND, objective/DefectObjective.h).
    c.push_back(config("defects-ratio", d.objectiveWithDefects, d.method,
                       methodRow(d.method).defaultBudget, 16, 1, d.starts));
    c.back().measure = DefectMeasure::Ratio;
    c.push_back(config("unbiased-lbfgs-16-multistart", K::Unbiased, M::Lbfgs, 2000, 16, 1,
                       {"const:0.5", "specular", "studio"}));
    c.push_back(config("unbiased-lbfgs-16-continuation", K::Unbiased, M::Lbfgs, 2000, 16, 1,
                       {"const:0.5"}, {4.0, 2.0}));
    c.push_back(config("unbiased-mlsl-16", K::Unbiased, M::Mlsl, 1500, 16));
    // The whole optimize job as a user runs it with the defects named (not raced by default:
    // each run traces T and the validation estimate at the rule's spp; `--configs` names them):
    // its default, and the same with one value per texel always (no coarser light).
    // ... and the job with the defects objective on the ratio.
    const DefectMeasure byDefault = ObjectiveOptions{}.defectMeasure;
    for (const auto& [name, grid, automatic, measure] :
         {std::tuple{"optimize", std::optional<LightGrid>{}, false, byDefault},
          std::tuple{"optimize-auto", std::optional<LightGrid>{}, true, byDefault},
          std::tuple{"optimize-texels", std::optional<LightGrid>{LightGrid{}}, false, byDefault},
          std::tuple{"optimize-ratio", std::optional<LightGrid>{}, false, DefectMeasure::Ratio}}) {
        RaceConfig j;
        j.name = name;
        j.search.objective = d.objectiveWithDefects;
        j.wholeJob = true;
        j.jobLightGrid = grid;
        j.autoDefects = automatic;
        j.measure = measure;
        c.push_back(j);
    }
    return c;
}

std::vector<RaceConfig> settingsRaceConfigs(const std::vector<int>& spps,
                                            const std::vector<Sampling>& samplings,
                                            const std::vector<int>& maxDepths) {
    const OptimizeDefaults d = optimizeDefaults();
    auto make = [&](int spp, Sampling sampling, int depth) {
        RaceConfig c =
            config("", d.objective, d.method, methodRow(d.method).defaultBudget, spp, 1, d.starts);
        c.sampling = sampling;
        c.maxDepth = depth;
        c.name = "spp" + std::to_string(spp) + "-" + registryRow(samplingTable(), sampling).name +
                 "-d" + std::to_string(depth);
        return c;
    };
    std::vector<RaceConfig> c{make(16, RenderDesc{}.sampling, 3)};  // the parts' own setting
    for (int spp : spps)
        for (Sampling sampling : samplings)
            for (int depth : maxDepths) {
                RaceConfig k = make(spp, sampling, depth);
                if (k.name != c.front().name) c.push_back(std::move(k));
            }
    return c;
}

namespace {

/// One part at one image size × α × height scale: its files and the scene overrides.
struct RaceWorld {
    std::string name;
    PartFiles files;
    std::vector<std::string> overrides;
};

std::string shortNumber(double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%g", v);
    return b;
}

/// Every part's files (written before any trace, so a bad part or file fails first) at every
/// size × α × height scale.
std::vector<RaceWorld> raceWorlds(const RaceOptions& o) {
    if (o.sizes.empty()) throw inputError(option("sizes"), "none given");
    if (o.heightScales.empty()) throw inputError(option("height-scales"), "none given");
    for (int size : o.sizes)
        if (size < 2) throw inputError(option("sizes"), "must be >= 2");
    for (double a : o.alphas)
        if (!(a > 0 && a <= 1)) throw inputError(option("alphas"), "must be in (0, 1]");
    for (double h : o.heightScales)
        if (!(h != 0 && std::isfinite(h))) throw inputError(option("height-scales"), "non-zero");
    std::vector<std::pair<std::string, PartFiles>> parts;
    for (const std::string& name : o.parts) parts.emplace_back(name, PartFiles{});
    for (const auto& file : o.real) parts.emplace_back(file.stem().string(), PartFiles{});
    for (size_t i = 0; i < parts.size(); ++i)
        for (size_t j = 0; j < i; ++j)
            if (parts[i].first == parts[j].first)
                throw inputError(option(i < o.parts.size() ? "parts" : "real"),
                                 "two parts named '" + parts[i].first + "'",
                                 "give each part once (real textures are named by their stem)");
    for (size_t i = 0; i < parts.size(); ++i) {
        const bool real = i >= o.parts.size();
        const auto dir = o.workDir / ((real ? "real-" : "") + parts[i].first);
        parts[i].second = real ? writeRealRacePart(o.real[i - o.parts.size()], dir)
                               : writeRacePart(parts[i].first, dir);
    }
    std::vector<std::optional<double>> alphas(o.alphas.begin(), o.alphas.end());
    if (alphas.empty()) alphas.emplace_back();  // the part's own
    std::vector<RaceWorld> worlds;
    for (const auto& [part, files] : parts)
        for (int size : o.sizes)
            for (const std::optional<double>& alpha : alphas)
                for (double h : o.heightScales) {
                    RaceWorld w{part,
                                files,
                                {"camera.width=" + std::to_string(size),
                                 "camera.height=" + std::to_string(size),
                                 "render.max_depth=" + std::to_string(kRaceMaxDepth)}};
                    if (size != kRaceImageSize) w.name += "@" + std::to_string(size);
                    if (alpha) {
                        w.overrides.push_back("material.alpha=" + shortNumber(*alpha));
                        w.name += "/a" + shortNumber(*alpha);
                    }
                    if (h != 1.0) {
                        w.overrides.push_back("heightmap.height_scale=" + shortNumber(h));
                        w.name += "/h" + shortNumber(h);
                    }
                    worlds.push_back(std::move(w));
                }
    return worlds;
}

/// "Times better" than a reference on the part's figure.
double timesBetter(bool figureIsU, double figure, double reference) {
    return figureIsU ? reference / figure : figure / reference;
}

void scoreRow(RaceRow& r, const JudgeScore& js, bool figureIsU) {
    r.eq2 = js.eq2.total;
    r.unbiased = js.unbiased.total;
    r.meanE = js.meanE;
    r.sparsity = js.sparsity;
    r.visDefect = regionVisibility(js, "defect");
    r.visChatter = regionVisibility(js, "chatter");
    r.figureIsU = figureIsU;
    r.figure = figureIsU ? js.unbiased.total : combinedVisibility(js.visibility);
    r.jnd = leastVisibleJnd(js.visibility);
}

RaceSummary raceOnWorlds(const RaceOptions& o) {
    if (o.seeds < 1) throw inputError(option("seeds"), "must be >= 1");
    if (o.configs.empty()) throw inputError(option("configs"), "none given");
    auto log = [&](const std::string& s) {
        if (o.log) o.log(s);
    };
    const auto cacheDir = std::filesystem::absolute(o.workDir) / ".scratchlight-cache";
    const std::vector<RaceWorld> worlds = raceWorlds(o);
    const bool anyAuto = std::any_of(o.configs.begin(), o.configs.end(),
                                     [](const RaceConfig& c) { return c.autoDefects; });
    RaceSummary sum;
    ProgressTask task("race", static_cast<double>(worlds.size() * o.configs.size()) * o.seeds);
    for (const RaceWorld& world : worlds) {
        const std::string& partName = world.name;
        auto scene = loadScene(world.files.scene, world.overrides);
        JudgeOptions jo;
        jo.spp = o.judgeSpp;
        jo.objective.lambda = o.lambda;
        jo.truth = world.files.truth;
        jo.cacheDir = cacheDir;
        jo.maxDepth = o.judgeMaxDepth;
        jo.threads = o.threads;
        log(partName + ": judge estimate (" + std::to_string(o.judgeSpp) + " spp)");
        const Judge judge(*scene, jo);
        // the truth's labelled pixels (every label), from the judge's projection of it
        std::vector<uint8_t> truthRegion(judge.labels().size());
        std::transform(judge.labels().begin(), judge.labels().end(), truthRegion.begin(),
                       [](uint8_t v) { return v ? uint8_t{255} : uint8_t{0}; });
        const bool truthInView =
            std::any_of(truthRegion.begin(), truthRegion.end(), [](uint8_t v) { return v; });
        // The reference: the studio lamp on the same judge; its visibility decides the figure.
        const TransportMatrix& jt = judge.estimate().file.matrix;
        const JudgeScore lampScore =
            judge.score(judge.envVector(studioEnvMap(jt.envWidth, jt.envHeight)), kLampConfig);
        const bool figureIsU = !std::isfinite(combinedVisibility(lampScore.visibility));
        // The defect map's regions, for the configurations that find the defects without labels.
        std::optional<DefectRegions> autoRegions;
        if (anyAuto) {
            RegionSpec spec;
            spec.automatic = true;
            try {
                autoRegions = defectRegionsInImage(*scene, spec, {}, {});
            } catch (const InputError& e) {
                log(partName + ": the defect map found no defect: " + e.what());
            }
        }

        for (int seed = 0; seed < o.seeds; ++seed) {
            std::vector<RaceRow> rows;
            for (const RaceConfig& c : o.configs) {
                throwIfInterrupted();
                const bool unb = c.search.objective == ObjectiveKind::Unbiased;
                const bool defects = c.search.objective == ObjectiveKind::Defects;
                RaceRow r;
                r.part = partName;
                r.config = c.name;
                r.seed = seed;
                const DefectRegions* regions =
                    c.autoDefects && autoRegions ? &*autoRegions : nullptr;
                // No light (a figure of NaN, counted as a failure): no defects to name, or
                // an objective that refuses the regions (e.g. no two neighbouring pixels).
                auto noLight = [&](const std::string& why) {
                    for (double RaceRow::*f :
                         {&RaceRow::eq2, &RaceRow::unbiased, &RaceRow::meanE, &RaceRow::sparsity,
                          &RaceRow::visDefect, &RaceRow::visChatter, &RaceRow::trainLoss,
                          &RaceRow::heldOwn, &RaceRow::figure})
                        r.*f = kNaN;
                    r.figureIsU = figureIsU;
                    log(partName + " seed " + std::to_string(seed) + " " + c.name + ": no light (" +
                        why + ")");
                    task.advance();
                    rows.push_back(r);
                };
                if (defects && (c.autoDefects ? !regions : !truthInView)) {
                    noLight("no defects to name");
                    continue;
                }
                if (c.wholeJob) {
                    OptimizeJobOptions opt;
                    opt.input = world.files.scene;
                    opt.sceneOverrides = world.overrides;
                    std::string dirName = partName + "-" + c.name + "-seed" + std::to_string(seed);
                    std::replace(dirName.begin(), dirName.end(), '/', '_');
                    opt.outDir = std::filesystem::absolute(o.workDir) / "jobs" / dirName;
                    opt.lambdas = {o.lambda};
                    if (c.autoDefects) {
                        opt.defects.automatic = true;
                        opt.objectiveKind = ObjectiveKind::Defects;
                    } else {
                        opt.truth = world.files.truth;
                    }
                    opt.heldOut.mode = HeldOutMode::None;  // the race's judge scores the answer
                    opt.figures = false;
                    opt.cache.dir = cacheDir;
                    opt.precompute.seed = static_cast<uint64_t>(seed) * 1000;
                    opt.precompute.threads = o.threads;
                    opt.lightGrid = c.jobLightGrid;
                    opt.objective.defectMeasure = c.measure;
                    const Stopwatch job;
                    OptimizeJobSummary js;
                    try {
                        js = runOptimizeJob(opt);
                    } catch (const InputError& e) {
                        noLight(e.what());
                        continue;
                    }
                    if (js.runs.empty() || !js.runs.front().answer) {
                        noLight("the job returned no self-checked answer");
                        continue;
                    }
                    const OptimizeRun& run = js.runs.front();
                    r.secondsSearch = r.seconds = job.seconds();
                    r.evaluations = run.optimizer.evaluations;
                    scoreRow(r, judge.score(run.answer->answer().candidate.e, c.name), figureIsU);
                    r.trainLoss = run.final.total;
                    r.heldOwn = kNaN;
                    log(partName + " seed " + std::to_string(seed) + " " + c.name + ": " +
                        run.answer->answer().candidate.name + ", " +
                        std::to_string(run.noise.spp()) + " spp, " + run.noise.grid().name() +
                        ", gap " + formatNumber(100.0 * run.noise.gap(), 3) + " % ± " +
                        formatNumber(100.0 * run.noise.gapError(), 3) + " % (" +
                        (run.noise.met          ? "within"
                         : run.noise.unresolved ? "not resolved"
                                                : "above") +
                        "), " + formatNumber(r.seconds, 3) + " s, visibility " +
                        formatNumber(r.figure, 4));
                    task.advance();
                    rows.push_back(r);
                    continue;
                }
                PrecomputeOptions p;
                p.spp = c.spp;
                p.seed = static_cast<uint64_t>(seed) * 1000;
                p.sampleSets = c.search.objective != ObjectiveKind::Paper ? 2 : 1;
                p.sampling = c.sampling;
                p.maxDepth = c.maxDepth;
                p.threads = o.threads;
                const Stopwatch precompute;
                const std::vector<TransportSource> set =
                    transportSetForScene(*scene, p, c.search.estimates, {});
                r.secondsPrecompute = precompute.seconds();
                SearchInputs in;
                for (const auto& s : set) in.set.push_back(&s.file.matrix);
                in.mask = set.front().file.matrix.objectMask;  // as optimize: T's part mask
                in.objective.lambda = o.lambda;
                in.objective.defectMeasure = c.measure;
                in.objective.viewing = viewingFor(*scene);
                in.scene = scene.get();
                in.maxDepth = set.front().file.provenance.maxDepth;
                if (defects && regions) {  // the defect map names the defects
                    in.defects = regions->defects;
                    in.reference = regions->reference;
                } else if (defects) {
                    in.defects = truthRegion;  // the truth names the defects
                }
                const Stopwatch searching;
                SearchResult sr;
                try {
                    sr = search(in, c.search);
                } catch (const InputError& e) {
                    noLight(e.what());
                    continue;
                }
                r.secondsSearch = searching.seconds();
                r.seconds = r.secondsPrecompute + r.secondsSearch;
                r.evaluations = sr.optimizer.evaluations;
                scoreRow(r, judge.score(sr.e, c.name), figureIsU);
                r.trainLoss = sr.training.total;
                // Own objective on the judge's estimate: U or eq. 2; the defects objective is
                // read from its visibility columns instead (NaN here).
                r.heldOwn = defects ? kNaN : (unb ? r.unbiased : r.eq2);
                char buf[320];
                std::snprintf(buf, sizeof buf,
                              "%s seed %d %-30s %6.2f s  eq2 %8.4f  U %8.4f  %s %8.4f",
                              partName.c_str(), seed, c.name.c_str(), r.seconds, r.eq2, r.unbiased,
                              figureIsU ? "U" : "visibility", r.figure);
                log(buf);
                task.advance();
                rows.push_back(r);
            }
            RaceRow lamp;
            lamp.part = partName;
            lamp.config = kLampConfig;
            lamp.seed = seed;
            scoreRow(lamp, lampScore, figureIsU);
            lamp.trainLoss = lamp.heldOwn = kNaN;
            rows.push_back(lamp);
            const RaceRow& base = rows.front();  // paper-loop (the first config)
            for (RaceRow& r : rows) {
                r.ratioU = r.unbiased / base.unbiased;
                r.ratioEq2 = r.eq2 / base.eq2;
                r.ratioSeconds = r.seconds / base.seconds;
                r.vsLamp = timesBetter(figureIsU, r.figure, lamp.figure);
                r.vsPaper = timesBetter(figureIsU, r.figure, base.figure);
                r.jndVsLamp = lamp.jnd > 0 ? r.jnd / lamp.jnd : kNaN;
            }
            sum.lamps.push_back(rows.back());
            rows.pop_back();
            sum.rows.insert(sum.rows.end(), rows.begin(), rows.end());
        }
    }
    std::map<std::pair<std::string, std::string>, std::vector<const RaceRow*>> byPart;
    std::map<std::string, std::vector<const RaceRow*>> byConfig;
    for (const RaceRow& r : sum.rows) {
        byPart[{r.part, r.config}].push_back(&r);
        byConfig[r.config].push_back(&r);
    }
    for (const RaceRow& r : sum.lamps) byPart[{r.part, r.config}].push_back(&r);
    for (const RaceWorld& w : worlds) {
        for (const RaceConfig& c : o.configs)
            sum.medians.push_back(medianRow(byPart[{w.name, c.name}]));
        sum.lampMedians.push_back(medianRow(byPart[{w.name, kLampConfig}]));
    }
    std::vector<std::string> names;
    for (const RaceConfig& c : o.configs) {
        RaceRow m = medianRow(byConfig[c.name]);
        m.part = "all";
        sum.overall.push_back(m);
        names.push_back(c.name);
    }
    names.emplace_back(kLampConfig);
    std::vector<RaceRow> perPart = sum.medians;
    perPart.insert(perPart.end(), sum.lampMedians.begin(), sum.lampMedians.end());
    sum.standings = raceStandings(perPart, names);
    sum.winner = raceWinner(sum.standings);
    return sum;
}

}  // namespace

RaceSummary runRace(const RaceOptions& o) {
    if (o.threads < 0) throw inputError(option("threads"), "must be >= 0");
    if (o.threads == 0) return raceOnWorlds(o);
    tbb::task_arena arena(o.threads);  // the search's and the scene's parallel loops too
    return arena.execute([&] { return raceOnWorlds(o); });
}

std::vector<RaceStanding> raceStandings(const std::vector<RaceRow>& medians,
                                        const std::vector<std::string>& configs) {
    std::vector<RaceStanding> out;
    for (const std::string& name : configs) {
        RaceStanding st;
        st.config = name;
        std::vector<double> lamp, paper, jnd, seconds;
        st.worstVsLamp = st.worstVsPaper = st.worstJndVsLamp =
            std::numeric_limits<double>::infinity();
        for (const RaceRow& r : medians) {
            if (r.config != name) continue;
            ++st.parts;
            seconds.push_back(r.seconds);
            // No figure of its own (no light returned, or one that shows nothing): ratio 0. A
            // reference without one leaves the part out of that ratio.
            const bool failed = !std::isfinite(r.figure);
            st.failed += failed;
            auto take = [&](double ratio, std::vector<double>& v, double& worst,
                            std::string& worstPart) {
                if (!failed && !std::isfinite(ratio)) return;
                const double x = failed ? 0.0 : ratio;
                v.push_back(x);
                if (x < worst) {
                    worst = x;
                    worstPart = r.part;
                }
            };
            take(r.vsLamp, lamp, st.worstVsLamp, st.worstLampPart);
            take(r.vsPaper, paper, st.worstVsPaper, st.worstPaperPart);
            take(r.jndVsLamp, jnd, st.worstJndVsLamp, st.worstJndPart);
        }
        auto summarize = [](const std::vector<double>& v, double& med, double& worst) {
            med = v.empty() ? kNaN : median(v);
            if (v.empty()) worst = kNaN;
        };
        summarize(lamp, st.medianVsLamp, st.worstVsLamp);
        summarize(paper, st.medianVsPaper, st.worstVsPaper);
        summarize(jnd, st.medianJndVsLamp, st.worstJndVsLamp);
        st.medianSeconds = seconds.empty() ? kNaN : median(seconds);
        out.push_back(st);
    }
    return out;
}

std::string raceWinner(const std::vector<RaceStanding>& standings) {
    auto raced = [](const RaceStanding& s) { return s.config != kLampConfig && s.parts > 0; };
    // JND when every configuration has it (the judge's first figure), else the ratio.
    const bool jnd = std::any_of(standings.begin(), standings.end(), raced) &&
                     std::all_of(standings.begin(), standings.end(), [&](const RaceStanding& s) {
                         return !raced(s) || std::isfinite(s.worstJndVsLamp);
                     });
    const double RaceStanding::*worst =
        jnd ? &RaceStanding::worstJndVsLamp : &RaceStanding::worstVsLamp;
    const double RaceStanding::*med =
        jnd ? &RaceStanding::medianJndVsLamp : &RaceStanding::medianVsLamp;
    const RaceStanding* best = nullptr;
    for (const RaceStanding& s : standings) {
        if (!raced(s) || !std::isfinite(s.*worst)) continue;
        if (!best || s.*worst > best->*worst || (s.*worst == best->*worst && s.*med > best->*med))
            best = &s;
    }
    return best ? best->config : std::string();
}

std::string formatRaceStandings(const std::vector<RaceStanding>& standings) {
    std::ostringstream out;
    char buf[512];
    std::snprintf(buf, sizeof buf, "%-31s %5s %6s %9s %9s %-26s %9s %9s %-26s %8s %9s %9s %-26s\n",
                  "config", "parts", "failed", "xlamp-med", "xlamp-min", "worst part (lamp)",
                  "xpl-med", "xpl-min", "worst part (paper-loop)", "seconds", "JNDx-med",
                  "JNDx-min", "worst part (JND, lamp)");
    out << buf;
    for (const RaceStanding& s : standings) {
        std::snprintf(buf, sizeof buf,
                      "%-31s %5d %6d %9.3f %9.3f %-26s %9.3f %9.3f %-26s %8.3f %9.3f %9.3f %-26s\n",
                      s.config.c_str(), s.parts, s.failed, s.medianVsLamp, s.worstVsLamp,
                      s.worstLampPart.c_str(), s.medianVsPaper, s.worstVsPaper,
                      s.worstPaperPart.c_str(), s.medianSeconds, s.medianJndVsLamp,
                      s.worstJndVsLamp, s.worstJndPart.c_str());
        out << buf;
    }
    return out.str();
}

void writeRaceStandingsCsv(const std::filesystem::path& file,
                           const std::vector<RaceStanding>& standings) {
    std::ostringstream s;
    s.precision(10);
    s << "config,parts,failed,vs_lamp_median,vs_lamp_worst,vs_lamp_worst_part,vs_paper_median,"
         "vs_paper_worst,vs_paper_worst_part,seconds_median,jnd_vs_lamp_median,jnd_vs_lamp_worst,"
         "jnd_vs_lamp_worst_part\n";
    for (const RaceStanding& r : standings)
        s << r.config << ',' << r.parts << ',' << r.failed << ',' << r.medianVsLamp << ','
          << r.worstVsLamp << ',' << r.worstLampPart << ',' << r.medianVsPaper << ','
          << r.worstVsPaper << ',' << r.worstPaperPart << ',' << r.medianSeconds << ','
          << r.medianJndVsLamp << ',' << r.worstJndVsLamp << ',' << r.worstJndPart << '\n';
    writeTextAtomically(file, s.str());
}

void writeRaceCsv(const std::filesystem::path& file, const std::vector<RaceRow>& rows) {
    std::ostringstream s;
    s.precision(10);
    s << "part,config,seed,seconds_precompute,seconds_search,seconds,evaluations,eq2,unbiased,"
         "mean_E,sparsity,visibility_defect,visibility_chatter,train_loss,heldout_own,"
         "ratio_U,ratio_eq2,ratio_seconds,figure,figure_value,vs_lamp,vs_paper,jnd,jnd_vs_lamp\n";
    for (const RaceRow& r : rows)
        s << r.part << ',' << r.config << ',' << r.seed << ',' << r.secondsPrecompute << ','
          << r.secondsSearch << ',' << r.seconds << ',' << r.evaluations << ',' << r.eq2 << ','
          << r.unbiased << ',' << r.meanE << ',' << r.sparsity << ',' << r.visDefect << ','
          << r.visChatter << ',' << r.trainLoss << ',' << r.heldOwn << ',' << r.ratioU << ','
          << r.ratioEq2 << ',' << r.ratioSeconds << ',' << (r.figureIsU ? "U" : "visibility") << ','
          << r.figure << ',' << r.vsLamp << ',' << r.vsPaper << ',' << r.jnd << ',' << r.jndVsLamp
          << '\n';
    writeTextAtomically(file, s.str());
}

std::string formatRaceTable(const std::vector<RaceRow>& rows) {
    std::ostringstream out;
    char buf[512];
    std::snprintf(buf, sizeof buf, "%-28s %-31s %7s %6s %8s %8s %7s %7s %7s %6s %6s %7s %7s %7s\n",
                  "part", "config", "seconds", "evals", "eq2", "U", "U/pl", "eq2/pl", "t/pl",
                  "vis-d", "vis-c", "gap", "xlamp", "xpl");
    out << buf;
    for (const RaceRow& r : rows) {
        // The defects objective has no held-out own loss here (its visibility columns are).
        char g[32] = "n/a";
        if (std::isfinite(r.heldOwn))
            std::snprintf(g, sizeof g, "%+6.1f%%", 100.0 * (r.heldOwn / r.trainLoss - 1.0));
        const std::string gap = g;
        std::snprintf(buf, sizeof buf,
                      "%-28s %-31s %7.3f %6d %8.4f %8.4f %7.3f %7.3f %7.3f %6.2f %6.2f %7s %7.3f "
                      "%7.3f\n",
                      r.part.c_str(), r.config.c_str(), r.seconds, r.evaluations, r.eq2, r.unbiased,
                      r.ratioU, r.ratioEq2, r.ratioSeconds, r.visDefect, r.visChatter, gap.c_str(),
                      r.vsLamp, r.vsPaper);
        out << buf;
    }
    return out.str();
}

}  // namespace sl
