#include "app/jobs/LampsJob.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>

#include "app/host/Version.h"
#include "app/pipeline/Defaults.h"
#include "app/pipeline/InitialState.h"
#include "app/pipeline/JudgeEstimate.h"
#include "app/pipeline/LossMask.h"
#include "app/pipeline/Search.h"
#include "app/pipeline/TrainingNoise.h"
#include "app/report/LampsFigure.h"
#include "app/report/PartSummary.h"
#include "app/report/Preview.h"
#include "app/report/Report.h"
#include "core/Error.h"
#include "core/Stopwatch.h"
#include "core/Text.h"
#include "io/AtomicFile.h"
#include "io/EnvMapIO.h"
#include "io/ImageIO.h"
#include "io/LampsFile.h"
#include "io/SceneFile.h"
#include "io/StagedDirectory.h"
#include "io/TransportFile.h"
#include "scene/EnvMapToE.h"
#include "scene/Scene.h"

namespace sl {

namespace {

using json = nlohmann::ordered_json;
constexpr double kPi = std::numbers::pi;
constexpr double kDeg = 180 / kPi;

EnvMap toEnvMap(std::span<const double> e, int w, int h) {
    EnvMap m = EnvMap::constant(w, h, 0.0f, 1);
    for (size_t i = 0; i < e.size(); ++i) m.texels[i] = static_cast<float>(e[i]);
    return m;
}

void writeEnvMapWithPreview(const std::filesystem::path& exr, const EnvMap& m) {
    writeEnvMap(exr, m);
    auto png = exr;
    png.replace_extension(".png");
    writePng(png, envMapPreview(m, 8));
}

/// The two renders side by side (left, right) with a 4-pixel gap, one exposure.
Image sideBySide(const std::vector<double>& left, const std::vector<double>& right, int w, int h,
                 double exposure) {
    const int gap = 4;
    Image img(2 * w + gap, h, 1);
    std::fill(img.data.begin(), img.data.end(), 0.0f);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const size_t s = static_cast<size_t>(y) * w + x;
            img.data[static_cast<size_t>(y) * (2 * w + gap) + x] =
                static_cast<float>(left[s] * exposure);
            img.data[static_cast<size_t>(y) * (2 * w + gap) + w + gap + x] =
                static_cast<float>(right[s] * exposure);
        }
    return img;
}

}  // namespace

LampsJobSummary runLampsJob(const LampsJobOptions& o) {
    StagedDirectory out(o.outDir);
    const std::filesystem::path dir = out.path();
    LampsJobSummary job;
    Stopwatch phase;
    auto lap = [&phase](double& into) {
        into = phase.seconds();
        phase.restart();
    };
    try {
        const bool tmInput = isTransportFile(o.input);
        std::unique_ptr<Scene> scene;
        std::optional<PrecomputeOptions> trained;  // T's trace options (a scene given)
        // The objective: as given, else the defaults' (app/pipeline/Defaults.h), for a .tm
        // settled once its planes are read.
        const bool defectsNamed = !o.truth.empty() || !o.defects.empty();
        ObjectiveKind kind = o.objectiveKind ? *o.objectiveKind : defaultObjective(defectsNamed);
        const bool halves = kind != ObjectiveKind::Paper;
        checkLampFitOptions(o.fit);  // before any work
        const std::filesystem::path cacheDir = cacheDirectory(o.cache);
        if (!tmInput) {
            trained = o.precompute;
            trained->rgb = false;
            if (halves) trained->sampleSets = 2;
        }
        InputTransport input =
            transportOfInput(o.input, o.sceneOverrides, trained.value_or(o.precompute), cacheDir);
        job.transport = std::move(input.transport);
        scene = std::move(input.scene);
        if (tmInput && !o.objectiveKind)
            kind = defaultObjective(defectsNamed, job.transport.file.matrix.planes);
        const TransportMatrix& t = job.transport.file.matrix;
        spdlog::info("{}", describeTransport(job.transport));
        if (t.channels != 1)
            throw inputError(o.input.string(), "is not a gray transport matrix",
                             "precompute it without " + option("rgb"));
        std::vector<double> target;  // E*, on T's env-map grid
        if (!o.from.empty())
            target =
                envMapToE(lightFromSpec(o.from, t.envWidth, t.envHeight, 1, option("from")), 1);
        if (kind != ObjectiveKind::Paper && t.planes != 2)
            throw inputError(o.input.string(),
                             std::string("has no half-sample matrices; the ") +
                                 objectiveKindName(kind) + " objective needs them",
                             "precompute it with " + option("halves") + ", or pass the scene file");
        if (!scene && kind == ObjectiveKind::Defects)
            scene = sceneOfTransport(job.transport.file, "the defects objective's regions");
        if (!scene && (o.judge || o.from.empty())) {
            try {
                scene = sceneOfTransport(job.transport.file, "the judge and the specular start");
            } catch (const InputError& e) {
                spdlog::warn("{}: no judge scores, E* from const:0.5", e.what());
            }
        }

        lap(job.phases.load);

        // The objective on T.
        SearchInputs in;
        in.set = {&t};
        in.mask = lossMask(LossMaskSpec{}, t, scene.get(), ScratchMapOptions{}).pixels;
        in.objective = o.objective;
        in.scene = scene.get();
        in.maxDepth = job.transport.file.provenance.maxDepth;
        if (kind == ObjectiveKind::Defects) {
            DefectRegions regions = defectRegionsInImage(*scene, o.defects, o.truth, o.reference);
            if (const std::string w =
                    unjudgedRegionsWarning(regions.unjudgedRegions, regions.unjudgedShare);
                !w.empty())
                spdlog::warn("{}", w);
            in.defects = std::move(regions.defects);
            in.reference = std::move(regions.reference);
        }
        in.gramCache = cacheDir;  // E*'s search reads the Gram the fit holds (below)
        in.fingerprint = job.transport.file.provenance.fingerprint;
        job.objective = kind;
        const ObjectiveOnT objective = objectiveOnT(kind, t, in, o.objective);
        // T's Gram matrices, built once for E*'s search and the fit (or read from the cache,
        // app/pipeline/Cache.h cachedGram): a loss on the same T and mask shares them while one
        // holds them (objective/TransportLoss.h gram()).
        if (!cachedGram(cacheDir, job.transport.file.provenance.fingerprint, *objective.loss) &&
            objective.loss->gramPays())
            objective.loss->gram();

        // E*.
        if (o.from.empty()) {
            const Stopwatch clock;
            SearchOptions so;
            so.objective = kind;
            so.optimizer = resolveOptimizer(optimizeJobOptimizerOptions());
            so.starts = {parseInitialState(scene ? "specular" : "const:0.5", option("from"))};
            target = search(in, so).e;
            job.secondsTarget = clock.seconds();
            spdlog::info("E* optimized on T ({}, L-BFGS) in {:.2f} s", objectiveKindName(kind),
                         job.secondsTarget);
        }

        lap(job.phases.target);

        // The lamps, kept out of the camera's cone (seen from the part's centre, the camera's
        // target).
        LampFitOptions fit = o.fit;
        if (scene && fit.cameraMargin > 0) {
            const CameraDesc& c = scene->camera.desc();
            const Vec3d d = normalize(c.origin - c.target);
            fit.camera =
                std::array<double, 2>{std::atan2(d.x, -d.z), std::asin(std::clamp(d.y, -1.0, 1.0))};
            spdlog::info(
                "no lamp centre within {} deg of the camera (azimuth {} deg, elevation "
                "{} deg)",
                formatNumber(fit.cameraMargin * kDeg), formatNumber((*fit.camera)[0] * kDeg),
                formatNumber((*fit.camera)[1] * kDeg));
        }
        job.fit = fitLamps(*objective.loss, target, fit);
        job.targetLoss = job.fit.targetLoss;
        const std::vector<Lamp>& lamps = job.fit.steps.back().lamps;
        lap(job.phases.fit);

        // What the judge and the self-check score: per-region visibility of the defects
        // objective's defect region, else of the truth's labels.
        JudgeOptions jo;
        jo.objective = o.objective;
        jo.viewing = scene ? viewingFor(*scene) : defaultViewing();
        std::vector<uint8_t> labels;
        std::vector<RegionLabel> legend;
        if (kind == ObjectiveKind::Defects) {
            JudgedDefectLabels judged =
                judgedDefectLabels(in.defects, defectRegionSpec(o.defects, o.truth).automatic);
            labels = std::move(judged.labels);
            legend = std::move(judged.legend);
        } else if (!o.truth.empty() && scene) {
            LabelMask truth = projectTruth(*scene, o.truth);
            labels = std::move(truth.labels);
            legend = std::move(truth.legend);
        }

        // The judge.
        std::optional<TransportSource> estimate;
        if (o.judge && scene) {
            estimate = judgeEstimateFor(job.transport.file, *scene, 0, cacheDir);
            Judge judge(*estimate, jo, labels, legend);
            const EnvMap studioMap = lightFromSpec("studio", t.envWidth, t.envHeight, 1, "studio");
            const std::vector<double> studio = judge.envVector(studioMap);
            job.judgedTarget = judge.score(target, "E*");
            job.judgedLamps = judge.score(job.fit.envMap, "lamps");
            job.judgedStudio = judge.score(studio, "studio");
            LampsJudgement jd;
            if (kind == ObjectiveKind::Defects) {
                jd.measure = "defect visibility";
                jd.higherIsBetter = true;
                jd.target = job.judgedTarget->visibility.front().visibility;
                jd.lamps = job.judgedLamps->visibility.front().visibility;
                jd.studio = job.judgedStudio->visibility.front().visibility;
                jd.gap = (jd.target - jd.lamps) / std::max(std::abs(jd.target), 1e-300);
            } else {
                const bool paper = kind == ObjectiveKind::Paper;
                auto own = [&](const JudgeScore& js) {
                    return paper ? js.eq2.total : js.unbiased.total;
                };
                jd.measure = paper ? "eq. 2" : "U";
                jd.target = own(*job.judgedTarget);
                jd.lamps = own(*job.judgedLamps);
                jd.studio = own(*job.judgedStudio);
                jd.gap = (jd.lamps - jd.target) / std::max(std::abs(jd.target), 1e-300);
            }
            job.judgement = jd;
        }

        lap(job.phases.judge);

        // The self-check: every K's lamps and the studio lamp on the validation estimate.
        if (o.selfCheck && scene) {
            PrecomputeOptions v;
            if (trained) {
                v = *trained;
                v.spp = job.transport.file.provenance.spp;
            } else {
                v.spp = job.transport.file.provenance.spp;
                v.maxDepth = job.transport.file.provenance.maxDepth;
            }
            const TransportSource vs =
                validationEstimate(*scene, v, job.transport.file.provenance.seed, cacheDir);
            const Judge validation(vs, jo, labels, legend);
            const LampRasterizer raster(EnvMapBasis(t.envWidth, t.envHeight), o.fit.raster);
            std::vector<AnswerCandidate> cands;
            for (const LampFitStep& st : job.fit.steps)
                cands.push_back({std::to_string(st.count) + (st.count == 1 ? " lamp" : " lamps"),
                                 CandidateKind::Optimized, raster.rasterize(st.lamps)});
            const EnvMap studioMap = lightFromSpec("studio", t.envWidth, t.envHeight, 1, "studio");
            cands.push_back(
                {"studio preset", CandidateKind::Reference, validation.envVector(studioMap)});
            job.answer = chooseAnswer(validation, std::move(cands));
            const AnswerChoice& a = *job.answer;
            const std::string fitted = std::to_string(job.fit.steps.size()) + " lamps";
            job.answerLine =
                a.referenceWon()
                    ? "The answer is the studio lamp, not the fitted lamps: " + a.reason
                : a.answer().candidate.name != fitted
                    ? "The answer is " + a.answer().candidate.name + " (lamps.json keeps all " +
                          fitted + "; greedy.csv has each K): " + a.reason
                    : "The answer is the " + fitted + ": " + a.reason;
        }

        lap(job.phases.selfCheck);

        // Outputs.
        const json lj = lampsToJson(lamps, o.distanceMm);
        writeTextAtomically(dir / "lamps.json", lj.dump(2) + "\n");
        writeEnvMapWithPreview(dir / "lamps-envmap.exr",
                               toEnvMap(job.fit.envMap, t.envWidth, t.envHeight));
        writeEnvMapWithPreview(dir / "target-envmap.exr",
                               toEnvMap(target, t.envWidth, t.envHeight));
        std::vector<double> yLamps(t.rows()), yTarget(t.rows());
        t.applyLuminance(job.fit.envMap, yLamps);
        t.applyLuminance(target, yTarget);
        writeRender(dir / "render-lamps.exr", yLamps, t.width, t.height, 1);
        writeRender(dir / "render-target.exr", yTarget, t.width, t.height, 1);
        writePng(dir / "renders.png", sideBySide(yTarget, yLamps, t.width, t.height,
                                                 exposureScale(yTarget, t.objectMask)));
        std::ostringstream csv;
        csv << "k,loss,loss_over_target,seconds,evaluations\n";
        for (const LampFitStep& s : job.fit.steps)
            csv << s.count << ',' << s.loss << ',' << s.loss / job.targetLoss << ',' << s.seconds
                << ',' << s.evaluations << '\n';
        writeTextAtomically(dir / "greedy.csv", csv.str());

        json pd;  // the plot's data: E*'s texels and the grid's directions, the lamps
        pd["width"] = t.envWidth;
        pd["height"] = t.envHeight;
        pd["target"] = target;
        pd["lamps_envmap"] = job.fit.envMap;
        json az = json::array(), el = json::array();
        for (int i = 0; i < t.envWidth; ++i) az.push_back(360.0 * (i + 0.5) / t.envWidth);
        for (int j = 0; j < t.envHeight; ++j) el.push_back(90.0 - 180.0 * j / (t.envHeight - 1));
        pd["column_azimuth_deg"] = az;
        pd["row_elevation_deg"] = el;
        pd["lamps"] = lj["lamps"];
        writeTextAtomically(dir / "plot-lamps.json", pd.dump() + "\n");
        if (o.figures) {
            // In-process (app/report/LampsFigure.h); scripts/plot_lamps.py draws the same from
            // plot-lamps.json for a person who runs it by hand.
            auto plotOf = [&](std::span<const double> e) {
                EnvMapPlot p;
                p.width = t.envWidth;
                p.height = t.envHeight;
                for (const auto& a : az) p.azimuthDeg.push_back(a.get<double>());
                for (const auto& v : el) p.elevationDeg.push_back(v.get<double>());
                p.luminance.assign(e.begin(), e.end());
                for (double& v : p.luminance) v = std::max(v, 0.0);
                return p;
            };
            const std::vector<uint8_t> png =
                lampsFigure(plotOf(target), plotOf(job.fit.envMap), lamps).png();
            writeBytesAtomically(dir / "plot-lamps.png", png.data(), png.size());
        } else {
            job.plotMessage = "figures off";
        }

        lap(job.phases.outputs);
        json s;
        s["provenance"] = runProvenance(o.commandLine);
        s["input"] = o.input.string();
        if (scene) s["part"] = partSummaryJson(*scene);
        s["objective"] = objectiveKindName(kind);
        s["lambda"] = o.objective.lambda;
        s["from"] = o.from.empty() ? "optimized on T" : o.from;
        s["seconds_target"] = job.secondsTarget;
        s["seconds_fit"] = job.fit.seconds;
        s["seconds_phases"] = {{"load", job.phases.load},
                               {"target", job.phases.target},
                               {"fit", job.phases.fit},
                               {"judge", job.phases.judge},
                               {"self_check", job.phases.selfCheck},
                               {"outputs", job.phases.outputs}};
        s["target_loss"] = job.targetLoss;
        json steps = json::array();
        for (const LampFitStep& st : job.fit.steps)
            steps.push_back({{"k", st.count},
                             {"loss", st.loss},
                             {"loss_over_target", st.loss / job.targetLoss},
                             {"seconds", st.seconds},
                             {"evaluations", st.evaluations}});
        s["greedy"] = steps;
        if (job.answer) {
            s["answer"] = answerJson(*job.answer);
            s["answer"]["line"] = job.answerLine;
        }
        if (job.judgedTarget) {
            s["judge"] = {{"objective",
                           {{"measure", job.judgement->measure},
                            {"higher_is_better", job.judgement->higherIsBetter},
                            {"target", job.judgement->target},
                            {"lamps", job.judgement->lamps},
                            {"studio", job.judgement->studio},
                            {"lamps_gap", job.judgement->gap}}},
                          {"target", toJson(*job.judgedTarget)},
                          {"lamps", toJson(*job.judgedLamps)},
                          {"studio", toJson(*job.judgedStudio)}};
        }
        s["plot"] = job.plotMessage.empty() ? "plot-lamps.png" : job.plotMessage;
        writeTextAtomically(dir / "summary.json", s.dump(2) + "\n");

        // report.html: one page, images inline.
        std::ostringstream h;
        h << "<!doctype html><html><head><meta charset=\"utf-8\"><title>scratchlight lamps"
             "</title><style>body{font-family:sans-serif;max-width:1100px;margin:auto}"
             "img{max-width:100%}td,th{padding:2px 10px;text-align:right}</style></head><body>";
        h << "<h1>" << lamps.size() << " lamps for " << escapeXml(o.input.filename().string())
          << "</h1>";
        if (!job.answerLine.empty()) h << "<p><b>" << escapeXml(job.answerLine) << "</b></p>";
        const double ratio = job.fit.steps.back().loss / job.targetLoss;
        h << "<p>Training loss (" << objectiveKindName(kind) << ", lower is better): E* "
          << formatNumber(job.targetLoss) << ", the lamps "
          << formatNumber(job.fit.steps.back().loss) << " (" << formatNumber(ratio)
          << " of E*'s).</p>";
        if (job.judgedTarget) {
            const LampsJudgement& jd = *job.judgement;
            h << "<p>On the judge's held-out estimate the lamps are ";
            h << jd.verdict();
            h << " E* (" << formatNumber(100 * jd.gap) << " % in " << escapeXml(jd.measure)
              << ", the " << objectiveKindName(kind) << " objective's measure; "
              << (jd.higherIsBetter ? "higher" : "lower") << " is better).</p>";
            h << "<table><tr><th>light</th><th>judge: " << escapeXml(jd.measure)
              << "</th><th>eq. 2</th><th>U</th><th>brightness</th>";
            for (const RegionVisibility& v : job.judgedTarget->visibility)
                h << "<th>visibility: " << escapeXml(v.label.name) << "</th>";
            h << "</tr>";
            const double own[3] = {jd.target, jd.lamps, jd.studio};
            int row = 0;
            for (const JudgeScore* js :
                 {&*job.judgedTarget, &*job.judgedLamps, &*job.judgedStudio}) {
                h << "<tr><td>" << escapeXml(js->name) << "</td><td>" << formatNumber(own[row++])
                  << "</td><td>" << formatNumber(js->eq2.total) << "</td><td>"
                  << formatNumber(js->unbiased.total) << "</td><td>" << formatNumber(js->brightness)
                  << "</td>";
                for (const RegionVisibility& v : js->visibility)
                    h << "<td>" << formatNumber(v.visibility) << "</td>";
                h << "</tr>";
            }
            h << "</table>";
        }
        h << "<h2>Renders: left under E*, right under the lamps (one exposure)</h2><img src=\""
          << dataUri(dir / "renders.png") << "\" style=\"image-rendering:pixelated;width:"
          << "100%\">";
        h << "<h2>The lamps over E* (upper hemisphere)</h2>";
        if (job.plotMessage.empty())
            h << "<img src=\"" << dataUri(dir / "plot-lamps.png") << "\">";
        else
            h << "<p>figure not made: " << escapeXml(job.plotMessage) << "</p>";
        h << "<h2>What each lamp buys</h2><table><tr><th>K</th><th>loss</th><th>of E*'s</th>"
             "<th>seconds</th></tr>";
        for (const LampFitStep& st : job.fit.steps)
            h << "<tr><td>" << st.count << "</td><td>" << formatNumber(st.loss) << "</td><td>"
              << formatNumber(st.loss / job.targetLoss) << "</td><td>" << formatNumber(st.seconds)
              << "</td></tr>";
        h << "</table><h2>lamps.json</h2><pre>" << escapeXml(lj.dump(2))
          << "</pre></body></html>\n";
        writeTextAtomically(dir / "report.html", h.str());
    } catch (const InputError& e) {
        throw InputError(out.explain(e.what()));
    }
    out.commit();
    return job;
}

}  // namespace sl
