#include "app/OptimizeJob.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <sstream>

#include "app/InitialState.h"
#include "app/Report.h"
#include "app/Search.h"
#include "app/Truth.h"
#include "core/Error.h"
#include "core/Stopwatch.h"
#include "io/AtomicFile.h"
#include "io/EnvMapIO.h"
#include "io/ImageIO.h"
#include "io/MaskIO.h"
#include "io/SceneFile.h"
#include "objective/ImageSpace.h"
#include "objective/Metrics.h"
#include "objective/TransportLoss.h"
#include "objective/UnbiasedObjective.h"
#include "optimize/SpecularInit.h"
#include "render/Render.h"
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
    return {{"own", partsJson(h.own)}, {"paper_eq2", partsJson(h.paper)}};
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

/// The render a person looks at: RGB when T is RGB, else luminance.
std::vector<double> renderImage(const TransportMatrix& t, const std::vector<double>& e) {
    std::vector<double> out(t.rows() * (t.channels == 3 ? 3 : 1));
    if (t.channels == 3)
        t.applyRgb(e, out);
    else
        t.applyLuminance(e, out);
    return out;
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

/// Fills what was left to the defaults (method, budget, starts, planes) and expands the
/// paper-loop method into the settings it stands for.
void resolveDefaults(OptimizeJobOptions& o) {
    const OptimizeDefaults d = optimizeDefaults();
    if (o.optimizer.method.empty()) o.optimizer.method = d.method;
    if (o.optimizer.method == kPaperLoopMethod) {
        // The paper's loop on T: eq. 2, Adam, a fresh sample set (estimate of T) every step.
        o.objectiveKind = "paper";
        o.optimizer.method = "adam";
        if (o.planes == 0) o.planes = kPaperLoopPlanes;
        o.methodLabel = kPaperLoopMethod;
        if (o.starts.empty() && o.init.empty()) o.init = "const:0.5";  // the paper's E0
    }
    if (o.starts.empty() && o.init.empty()) o.starts = d.starts;
    if (o.optimizer.iterations == 0) o.optimizer.iterations = defaultBudget(o.optimizer.method);
    if (o.planes == 0) o.planes = 1;
}

OptimizeJobSummary runResolved(const OptimizeJobOptions& o);

}  // namespace

std::vector<std::string> optimizePresets() {
    return {"paper"};
}

void applyOptimizePreset(const std::string& name, OptimizeJobOptions& o) {
    if (name != "paper")
        throw inputError(option("preset"), "unknown preset '" + name + "'", "use paper");
    o.optimizer.method = kPaperLoopMethod;
    o.optimizer.iterations = 100;
    o.optimizer.learningRate = 0.02;
    o.lambdas = {30.0};
    o.objective.reg = RegTarget::EnvMap;
    o.init = "const:0.5";
    o.objectiveKind = "paper";
    o.starts.clear();
    o.continuation.clear();
    o.planes = 100;
}

OptimizeDefaults optimizeDefaults() {
    return {};
}

int defaultBudget(const std::string& method) {
    return method == "adam" || method == "fd-adam" || method == "spsa" ? 100 : 2000;
}

OptimizeJobSummary runOptimizeJob(const OptimizeJobOptions& o) {
    if (o.lambdas.empty()) throw inputError(option("lambda"), "no value given");
    for (double l : o.lambdas)
        if (!(l >= 0) || !std::isfinite(l))
            throw inputError(option("lambda"), "must be >= 0",
                             "give e.g. 30, or 10,30,100 for a sweep");

    OptimizeJobOptions resolved = o;
    resolveDefaults(resolved);
    return runResolved(resolved);
}

namespace {

OptimizeJobSummary runResolved(const OptimizeJobOptions& o) {
    // The objective: as given; by default the noise-unbiased one, except for a .tm without
    // halves, which only the paper's eq. 2 can use (decided once T is read).
    bool unbiased =
        o.objectiveKind.empty()
            ? !isTransportFile(o.input)
            : parseObjectiveKind(o.objectiveKind, option("objective")) == ObjectiveKind::Unbiased;
    if (o.planes < 1) throw inputError(option("planes"), "must be >= 1");
    if (o.heldOutEvery < 1) throw inputError(option("heldout-every"), "must be >= 1");
    OptimizeJobSummary job;
    const auto cacheDir = std::filesystem::absolute(o.outDir).parent_path() / ".scratchlight-cache";
    // fd-adam and spsa take their gradients through the renderer (a black box); T still serves
    // the outputs, metrics and held-out scores.
    const auto bb = blackBoxMethods();
    const bool blackBox = std::find(bb.begin(), bb.end(), o.optimizer.method) != bb.end();
    const bool tmInput = isTransportFile(o.input);
    if (blackBox && tmInput)
        throw inputError(option("optimizer") + " " + o.optimizer.method,
                         "renders the scene for every gradient, so it needs the scene file",
                         "pass SCENE.json instead of the .tm");
    // One loaded scene serves T, the held-out T and what needs the scene itself.
    std::unique_ptr<Scene> scene;
    const bool specularStart = o.init == "specular" || std::find(o.starts.begin(), o.starts.end(),
                                                                 "specular") != o.starts.end();
    const bool needScene =
        blackBox || o.mask == "scratch" || specularStart || !o.truth.empty() || o.heldOut.empty();
    if (!tmInput) scene = loadScene(o.input);
    if (tmInput) {
        const Stopwatch clock;
        job.transport.file = readTransportFile(o.input);
        job.transport.path = o.input;
        job.transport.secondsTotal = clock.seconds();
        if (o.objectiveKind.empty()) unbiased = job.transport.file.matrix.planes == 2;
    } else {
        PrecomputeOptions p = o.precompute;
        p.rgb = o.rgb;
        if (unbiased) p.sampleSets = 2;
        // eq. 2 rewards noise: without a given spp it trains at no fewer than paperMinSpp.
        if (!unbiased && !p.spp && o.methodLabel != kPaperLoopMethod)
            p.spp = std::max(scene->desc.render.spp, optimizeDefaults().paperMinSpp);
        std::vector<TransportSource> set = transportSetForScene(*scene, p, o.planes, cacheDir);
        job.transport = std::move(set.front());
        for (size_t k = 1; k < set.size(); ++k) job.extraPlanes.push_back(std::move(set[k]));
    }
    if (tmInput && o.planes > 1)
        throw inputError(option("planes") + " " + std::to_string(o.planes),
                         "needs independent estimates of T traced from the scene",
                         "pass SCENE.json instead of the .tm, or " + option("planes") + " 1");
    if (!scene && needScene) {
        std::string purpose = o.heldOut.empty()
                                  ? "the held-out estimate (or " + option("heldout") + " none)"
                                  : option("mask") + " scratch / " + option("init") +
                                        " specular / " + option("truth");
        scene = sceneOfTransport(job.transport.file, purpose);
    }
    const TransportMatrix& t = job.transport.file.matrix;
    const std::string objectiveName = unbiased ? "unbiased" : "paper";
    if (o.rgb && t.channels != 3)
        throw inputError(o.input.string(),
                         "is a gray transport matrix; " + option("rgb") + " needs an RGB one",
                         "precompute it with " + option("rgb"));
    if (unbiased && t.planes != 2)
        throw inputError(
            o.input.string(),
            "has no half-sample matrices; " + option("objective") + " unbiased needs them",
            "precompute it with " + option("halves") + ", or pass the scene file");

    // The independent estimate every result is scored on.
    if (o.heldOut != "none") {
        if (isTransportFile(o.heldOut)) {
            TransportSource h;
            h.file = readTransportFile(o.heldOut);
            h.path = o.heldOut;
            const TransportMatrix& ht = h.file.matrix;
            if (ht.width != t.width || ht.height != t.height || ht.envWidth != t.envWidth ||
                ht.envHeight != t.envHeight || ht.planes != 2 || ht.channels != t.channels)
                throw inputError(o.heldOut, "does not fit the training transport matrix",
                                 "it needs the same image and env-map size, the same channels, "
                                 "and two halves (precompute " +
                                     option("halves") + ")");
            job.heldOut = std::move(h);
        } else {
            if (!o.heldOut.empty())
                throw inputError(option("heldout"), "'" + o.heldOut + "' is not a .tm file",
                                 "give a .tm file, none, or leave it out");
            job.heldOut = judgeEstimateFor(job.transport.file, *scene, o.heldOutSpp, cacheDir);
        }
        const uint64_t hs = job.heldOut->file.provenance.seed,
                       ts = job.transport.file.provenance.seed;
        if (hs >= ts && hs < ts + static_cast<uint64_t>(o.planes))
            throw inputError(option("seed"), "the training seed range overlaps the judge's seed",
                             "use another " + option("seed"));
    }

    std::vector<uint8_t> mask = t.objectMask, scratchCells;
    if (o.mask == "scratch") {
        mask = intersectMasks(mask, scratchMaskImage(*scene, o.scratch));
        scratchCells =
            computeScratchMap(scene->heights, scene->mapWidth, scene->mapHeight, o.scratch).map;
    } else if (!o.mask.empty()) {
        mask = intersectMasks(mask, loadImageMask(o.mask, t.width, t.height));
    }
    for (uint8_t m : mask) job.maskPixels += m != 0;
    if (job.maskPixels == 0)
        throw inputError(
            option("mask") + " " + o.mask, "the mask is empty on the part",
            o.mask == "scratch" ? "lower " + option("scratch-threshold") : "draw a larger region");
    std::vector<uint8_t> truth;
    if (!o.truth.empty()) truth = projectMaskFile(*scene, o.truth);

    const std::vector<std::string> starts =
        o.starts.empty() ? std::vector<std::string>{o.init} : o.starts;
    const int maxDepth = job.transport.file.provenance.maxDepth;
    // Every start's E0, once for every λ; the first is the report's "before".
    std::vector<std::vector<double>> startValues;
    for (const std::string& spec : starts)
        startValues.push_back(
            initialEnvMap(spec, t.envWidth, t.envHeight, o.rgb, scene.get(), maxDepth));
    const std::vector<double>& e0 = startValues.front();
    LabelMask truthLabels;  // the judge's regions
    if (job.heldOut && !o.truth.empty()) truthLabels = projectTruth(*scene, o.truth);
    // E0's render and metrics do not depend on λ: computed once for every run.
    const std::vector<double> image0 = renderImage(t, e0);
    const VisibilityMetrics metricsInitial = metricsFor(t, image0, mask, e0, o.rgb, truth);
    std::vector<ReportRun> reportRuns;
    const bool sweep = o.lambdas.size() > 1;
    std::ostringstream sweepCsv;
    sweepCsv << "lambda,optimizer,objective,iterations,evaluations,initial_loss,final_loss,"
                "final_L_grad,final_L_reg,heldout_loss,heldout_paper_loss,seconds\n";

    std::vector<const TransportMatrix*> set{&t};
    for (const TransportSource& x : job.extraPlanes) set.push_back(&x.file.matrix);
    for (double lambda : o.lambdas) {
        ObjectiveOptions oo = o.objective;
        oo.lambda = lambda;
        ImageObjective objective(t.width, t.height, mask, oo);
        std::unique_ptr<UnbiasedObjective> unb;
        if (unbiased) unb = std::make_unique<UnbiasedObjective>(t.width, t.height, mask, oo);
        TransportLoss loss =
            unbiased ? TransportLoss(t, *unb, o.rgb) : TransportLoss(t, objective, o.rgb);
        std::unique_ptr<HeldOutScorer> scorer;
        if (job.heldOut)
            scorer = std::make_unique<HeldOutScorer>(job.heldOut->file.matrix, mask, oo, unbiased,
                                                     o.rgb);

        OptimizeRun run;
        run.lambda = lambda;
        run.dir = sweep ? o.outDir / lambdaName(lambda) : o.outDir;
        std::vector<double> e = e0;
        run.initial = loss.evaluate(e, {});
        if (scorer) run.heldInitial = scorer->score(e);

        std::vector<std::string> rows;
        auto callback = [&](const IterationRecord& r, std::span<const double> x) {
            // Every row: the optimizer's own loss (with planes, on the estimate of that step;
            // with continuation, at that stage's λ). Every heldOutEvery rows also the parts on
            // T at λ and the held-out scores.
            const bool full = r.iteration % o.heldOutEvery == 0;
            std::ostringstream row;
            row << std::setprecision(10) << r.iteration << ',' << r.evaluations << ',' << r.loss
                << ',';
            if (full) {
                const LossParts p = loss.evaluate(x, {});
                row << p.lGrad << ',' << p.lReg;
            } else {
                row << ',';
            }
            row << ',' << r.seconds << ',';
            if (scorer && full) {
                const Stopwatch clock;
                HeldOutScore h = scorer->score(x);
                run.secondsHeldOutScoring += clock.seconds();
                row << h.own.total << ',' << h.paper.total;
            } else {
                row << ',';
            }
            rows.push_back(row.str());
            return o.optimizer.callback ? o.optimizer.callback(r, x) : true;
        };
        if (blackBox) {
            OptimizerOptions opt = o.optimizer;
            opt.callback = callback;
            RenderOptions ro = renderOptionsFor(*scene);
            ro.spp = job.transport.file.provenance.spp;
            ro.seed = job.transport.file.provenance.seed;
            ro.maxDepth = job.transport.file.provenance.maxDepth;
            ro.threads = o.precompute.threads;
            RenderLoss renderLoss(*scene, ro, objective, o.rgb);
            run.optimizer = minimizeBlackBox(renderLoss, e, opt, o.blackBox);
        } else {
            SearchInputs in;
            in.set = set;
            in.mask = mask;
            in.objective = oo;
            in.rgb = o.rgb;
            in.scene = scene.get();
            in.maxDepth = maxDepth;
            in.startValues = startValues;
            in.callback = callback;
            SearchOptions so;
            so.objective = unbiased ? ObjectiveKind::Unbiased : ObjectiveKind::Paper;
            so.optimizer = o.optimizer;
            so.optimizer.callback = nullptr;
            so.planes = o.planes;
            so.starts = starts;
            so.continuation = o.continuation;
            SearchResult sr = search(in, so);
            e = sr.e;
            run.optimizer = sr.optimizer;
            run.start = sr.start;
            run.startLosses = sr.startLosses;
        }
        if (!o.methodLabel.empty()) run.optimizer.method = o.methodLabel;
        run.final = loss.evaluate(e, {});
        if (scorer) {
            run.heldFinal = scorer->score(e);
            // The last row always carries the held-out score of the returned E.
            if (!rows.empty() && rows.back().back() == ',') {
                rows.back().pop_back();
                std::ostringstream tail;
                tail << std::setprecision(10) << ',' << run.heldFinal->own.total << ','
                     << run.heldFinal->paper.total;
                rows.back() += tail.str();
            }
        }
        if (job.heldOut) {  // the judge on the held-out estimate, at this run's λ
            JudgeOptions jo;
            jo.objective = oo;
            jo.rgb = o.rgb;
            const Judge judge(*job.heldOut, jo, truthLabels.labels, truthLabels.legend);
            run.judged = judge.score(e, run.dir.filename().string());
        }
        std::ostringstream csv;
        csv << "iteration,evaluations,loss,L_grad,L_reg,seconds,heldout_loss,heldout_paper_loss\n";
        for (const auto& row : rows) csv << row << '\n';
        spdlog::info("lambda {}: {}", lambda, run.optimizer.briefReport());

        std::filesystem::create_directories(run.dir);
        writeEnvMap(run.dir / "envmap.exr", toEnvMap(e, t, o.rgb));
        writePng(run.dir / "envmap.png", envMapPreview(toEnvMap(e, t, o.rgb), 16));
        const int ch = t.channels == 3 ? 3 : 1;
        const std::vector<double> imageFinal = renderImage(t, e);
        writeRender(run.dir / "render.exr", imageFinal, t.width, t.height, ch);
        {
            Image i0(t.width, t.height, ch);
            for (size_t i = 0; i < image0.size(); ++i) i0.data[i] = static_cast<float>(image0[i]);
            writePng(run.dir / "initial.png", i0);
        }
        writeTextAtomically(run.dir / "loss.csv", csv.str());
        writePng(run.dir / "initial-envmap.png", envMapPreview(toEnvMap(e0, t, o.rgb), 16));
        {
            std::vector<uint8_t> visible(mask.size());  // masks hold 0/1; the PNG 0/255
            for (size_t i = 0; i < mask.size(); ++i) visible[i] = mask[i] ? 255 : 0;
            writeMaskPng(run.dir / "mask.png", visible, t.width, t.height);
        }
        if (!scratchCells.empty()) {
            writeMaskPng(run.dir / "scratchmap.png", scratchCells, scene->mapWidth,
                         scene->mapHeight);
        }

        json s;
        s["optimizer"] = run.optimizer.method;
        s["planes"] = o.planes;
        s["starts"] = starts;
        s["start"] = run.start;
        s["continuation"] = o.continuation;
        s["objective"] = objectiveName;
        s["lambda"] = lambda;
        s["reg"] = oo.reg == RegTarget::EnvMap ? "envmap" : "image";
        s["smooth_abs"] = oo.smoothAbs;
        s["init"] = starts.front();  // E0 of the report (the first start)
        s["rgb"] = o.rgb;
        s["mask"] = o.mask.empty() ? "object" : o.mask;
        s["mask_pixels"] = job.maskPixels;
        s["iterations"] = run.optimizer.iterations;
        s["evaluations"] = run.optimizer.evaluations;
        s["termination"] = run.optimizer.termination;
        s["initial_loss"] = run.initial.total;
        s["final_loss"] = run.final.total;
        s["initial"] = partsJson(run.initial);
        s["final"] = partsJson(run.final);
        s["seconds_precompute"] =
            job.transport.cacheHit || isTransportFile(o.input) ? 0.0 : job.transport.secondsTotal;
        s["seconds_load_transport"] = job.transport.secondsTotal;
        s["transport_cache_hit"] = job.transport.cacheHit;
        s["seconds_optimize"] = run.optimizer.seconds;
        s["seconds_heldout_scoring"] = run.secondsHeldOutScoring;
        if (run.heldFinal) {
            s["heldout_loss"] = run.heldFinal->own.total;
            s["heldout_L_grad"] = run.heldFinal->own.lGrad;
            s["heldout_L_reg"] = run.heldFinal->own.lReg;
            s["heldout_paper_loss"] = run.heldFinal->paper.total;
            s["heldout"] = {{"initial", heldJson(*run.heldInitial)},
                            {"final", heldJson(*run.heldFinal)},
                            {"transport", transportJson(*job.heldOut)}};
        } else {
            s["heldout_loss"] = nullptr;
        }
        s["transport"] = transportJson(job.transport);
        if (run.judged) s["judge"] = toJson(*run.judged);
        s["metrics"] = toJson(metricsFor(t, imageFinal, mask, e, o.rgb, truth));
        s["metrics_initial"] = toJson(metricsInitial);
        if (!o.truth.empty()) s["truth"] = o.truth;
        if (o.mask == "scratch")
            s["scratch_map"] = {{"kernel", o.scratch.kernel},
                                {"patch", o.scratch.patch},
                                {"threshold", o.scratch.threshold}};
        writeTextAtomically(run.dir / "summary.json", s.dump(2) + "\n");
        {
            ReportContent rc;
            rc.title = "scratchlight optimize: " + run.dir.filename().string();
            ReportFigure fig;
            fig.title = "before and after";
            std::ostringstream title;
            title << "λ = " << lambda << ", " << run.optimizer.method << ", " << objectiveName;
            fig.runs.push_back(reportRunFromOutDir(run.dir, title.str()));
            reportRuns.push_back(fig.runs.back());
            rc.figures.push_back(std::move(fig));
            writeReport(run.dir / "report.html", rc);
        }
        sweepCsv << std::setprecision(10) << lambda << ',' << run.optimizer.method << ','
                 << objectiveName << ',' << run.optimizer.iterations << ','
                 << run.optimizer.evaluations << ',' << run.initial.total << ',' << run.final.total
                 << ',' << run.final.lGrad << ',' << run.final.lReg << ',';
        if (run.heldFinal)
            sweepCsv << run.heldFinal->own.total << ',' << run.heldFinal->paper.total;
        else
            sweepCsv << ',';
        sweepCsv << ',' << run.optimizer.seconds << '\n';
        job.runs.push_back(std::move(run));
    }
    if (sweep) {
        writeTextAtomically(o.outDir / "sweep.csv", sweepCsv.str());
        ReportContent rc;
        rc.title = "scratchlight optimize: lambda sweep";
        ReportFigure fig;
        fig.title = "one run per lambda";
        fig.runs = reportRuns;
        fig.combinedLossPlot = true;
        rc.figures.push_back(std::move(fig));
        writeReport(o.outDir / "report.html", rc);
    }
    return job;
}

}  // namespace

}  // namespace sl
