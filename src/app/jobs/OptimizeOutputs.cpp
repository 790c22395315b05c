#include "app/jobs/OptimizeOutputs.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <future>
#include <iomanip>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "app/host/Version.h"
#include "app/pipeline/Cache.h"
#include "app/pipeline/InitialState.h"
#include "app/pipeline/JudgeEstimate.h"
#include "app/pipeline/Search.h"
#include "app/pipeline/Truth.h"
#include "app/report/OptimizeFigures.h"
#include "app/report/OptimizeReport.h"
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
#include "io/OptimizeSummary.h"
#include "io/SceneFile.h"
#include "io/StagedDirectory.h"
#include "io/TransportFile.h"
#include "objective/ImageSpace.h"
#include "objective/Metrics.h"
#include "objective/TransportLoss.h"
#include "objective/UnbiasedObjective.h"
#include "optimize/PaperSetup.h"
#include "optimize/SpecularInit.h"
#include "render/Footprint.h"
#include "render/Render.h"
#include "scene/EnvMapBasis.h"
#include "scene/EnvMapPresets.h"
#include "scene/EnvMapToE.h"
#include "scene/Scene.h"

namespace sl::optimizejob {

namespace {

using json = nlohmann::ordered_json;

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

/// Luminance of a render (RGB or already luminance).
std::vector<double> luminanceOf(const std::vector<double>& image, size_t pixels) {
    if (image.size() == pixels) return image;
    std::vector<double> y(pixels);
    for (size_t q = 0; q < pixels; ++q)
        y[q] = luminance(image[3 * q], image[3 * q + 1], image[3 * q + 2]);
    return y;
}

/// A render exposed on its own as a camera would (app/report/Preview.h exposureScale on the part),
/// for its PNG and the figures.
Image exposedImage(const std::vector<double>& image, const TransportMatrix& t) {
    const int ch = image.size() == t.rows() ? 1 : 3;
    const double scale = exposureScale(luminanceOf(image, t.rows()), t.objectMask);
    Image img(t.width, t.height, ch);
    for (size_t i = 0; i < image.size(); ++i) img.data[i] = static_cast<float>(image[i] * scale);
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
    if (in.scene || in.part) {
        const CameraDesc& c = in.scene ? in.scene->camera.desc() : in.part->camera;
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
    if (in.scene)
        s["part"] = partSummaryJson(*in.scene);
    else if (in.part && in.part->recorded())
        s["part"] = in.part->part;
    s["optimizer"] = run.optimizer.method;
    s["estimates"] = o.estimates;
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
    if (in.scene)
        s["heightmap"] = heightmapLoadJson(*in.scene);  // reader and levelling
    else if (in.part && in.part->recorded())
        s["heightmap"] = in.part->heightmap;
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
        // The report's headline (app/report/OptimizeReport.h optimizeHeadline): E* against the
        // user's lamp and the paper's light, on T and (with the held-out estimate) by the judge.
        json cmp;
        cmp["objective"] = objectiveKindName(in.kind);
        cmp["regions"] = in.regionSource;
        json lamp = {{"name", in.lampName},
                     {"spec", o.compare.empty() ? std::string("studio") : o.compare},
                     {"render", outdir::kCompareLampPng},
                     {"envmap", outdir::kLampEnvMap},
                     {"training", partsJson(r.lampTraining)}};
        json paper = {{"name", "paper's light"},
                      {"method", "the paper's method run on this T: " + paperSetupText()},
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
/// scripts/plot_optimize.py reads them from the files; the summary through its typed reader,
/// io/OptimizeSummary.h) and the loss curve.
OptimizeFiguresInput figuresInput(const json& plotData, const json& summaryJson,
                                  const LossCurve& curve) {
    OptimizeFiguresInput f;
    f.envmap.width = plotData.at("width").get<int>();
    f.envmap.height = plotData.at("height").get<int>();
    f.envmap.azimuthDeg = plotData.at("azimuth_deg").get<std::vector<double>>();
    f.envmap.elevationDeg = plotData.at("elevation_deg").get<std::vector<double>>();
    f.envmap.luminance = plotData.at("lights").at("optimized").get<std::vector<double>>();
    const outdir::OptimizeSummary summary = outdir::optimizeSummaryFromJson(
        nlohmann::json::parse(summaryJson.dump()), outdir::kSummary);
    if (!summary.envmapDirections || !summary.comparison)
        throw std::runtime_error("summary.json has no envmap_directions or no compare");
    const outdir::EnvDirections& dirs = *summary.envmapDirections;
    auto direction = [](const outdir::EnvDirection& d) {
        return PlotDirection{d.azimuthDeg, d.elevationDeg};
    };
    if (dirs.camera) f.directions.camera = direction(*dirs.camera);
    if (dirs.mirror) f.directions.mirror = direction(*dirs.mirror);
    for (const outdir::EnvDirection& d : dirs.brightest)
        f.directions.brightest.push_back(direction(d));
    f.loss = curve;
    std::ostringstream lambda;
    lambda << summary.lambda;
    f.lossTitle = summary.optimizer + " on " + summary.objective + ", λ = " + lambda.str();
    f.title = "scratchlight optimize: loss " + formatNumber(summary.initialLoss.get<double>(), 4) +
              " → " + formatNumber(summary.finalLoss.get<double>(), 4);
    f.lampTitle = "your lamp (" + summary.comparison->lamp.name + ")";
    return f;
}

}  // namespace

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
    // What the figures are drawn from, first: they are drawn on another core while the files
    // below are written (app/report/OptimizeFigures.h; a third of the outputs' time at 256²).
    const json plotData = plotDataJson(in, t, r.e, o.rgb);
    const VisibilityMetrics metricsFinal = metricsFor(t, imageFinal, mask, r.e, o.rgb, in.truth);
    const json summary = runSummaryJson(p, in, job, r, metricsFinal);
    const Image lampView = exposedImage(imageLamp, t);
    const Image optimizedView = exposedImage(imageOptimized, t);
    std::optional<ProgressTask> figuresTask;
    std::future<std::string> figures;  // what went wrong ("" when drawn); waited for when it goes
    if (o.figures) {
        figuresTask.emplace("figures");
        figures = std::async(std::launch::async, [&] {
            try {
                OptimizeFiguresInput fig = figuresInput(plotData, summary, r.curve);
                fig.lampView = lampView;
                fig.optimizedView = optimizedView;
                writeOptimizeFigures(dir, fig);
                return std::string();
            } catch (const std::exception& e) {
                return std::string(e.what());
            }
        });
    }
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
    writeEnvMap(dir / outdir::kLampEnvMap, toEnvMap(in.lampE, t, o.rgb));
    writeEnvMap(dir / outdir::kPaperEnvMap, toEnvMap(in.paperE, t, o.rgb));
    writePng(dir / outdir::kViewLamp, lampView);
    writePng(dir / outdir::kViewOptimized, optimizedView);
    writePng(dir / outdir::kViewPaper, exposedImage(imagePaper, t));
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
    writeTextAtomically(dir / outdir::kPlotData, plotData.dump() + "\n");
    writeTextAtomically(dir / outdir::kSummary, summary.dump(2) + "\n");
    // The figures, drawn in-process (app/report/OptimizeFigures.h); when they fail the report says
    // why.
    std::string figureProblem = "figures not asked for";
    if (figures.valid()) {
        figureProblem = figures.get();
        figuresTask.reset();
        if (!figureProblem.empty()) spdlog::warn("figures not made: {}", figureProblem);
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

}  // namespace sl::optimizejob
