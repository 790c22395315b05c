#include "app/jobs/JudgeJob.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <sstream>

#include "app/host/Version.h"
#include "app/report/OptimizeReport.h"
#include "app/report/PartSummary.h"
#include "app/report/Preview.h"
#include "app/report/Report.h"
#include "core/Error.h"
#include "core/Image.h"
#include "io/AtomicFile.h"
#include "io/EnvMapIO.h"
#include "io/ImageIO.h"
#include "io/OptimizeOutDir.h"
#include "io/SceneFile.h"
#include "io/StagedDirectory.h"
#include "scene/EnvMapPresets.h"
#include "scene/Scene.h"

namespace sl {

namespace {

std::filesystem::path envFileOf(const std::filesystem::path& light) {
    if (std::filesystem::is_directory(light)) {
        auto f = light / outdir::kEnvMap;
        if (!std::filesystem::exists(f))
            throw inputError(light.string(),
                             std::string("is a directory without ") + outdir::kEnvMap,
                             "give an env-map file or an optimize output directory");
        return f;
    }
    return light;
}

std::string nameOf(const std::filesystem::path& light) {
    auto p = light;
    if (p.filename().empty()) p = p.parent_path();
    return std::filesystem::is_directory(p) ? p.filename().string() : p.stem().string();
}

/// report.html: every light side by side (its render with the truth regions outlined, its env
/// map) with its scores, and the per-region visibility and contrast as rows.
void writeJudgeReport(const std::filesystem::path& dir, const JudgeJobOptions& o,
                      const Judge& judge, const std::vector<std::pair<std::string, EnvMap>>& lights,
                      const std::vector<std::vector<double>>& images,
                      const std::vector<JudgeScore>& scores, const std::string& part) {
    const TransportMatrix& t = judge.estimate().file.matrix;
    ReportContent rc;
    rc.title = "scratchlight judge: " + o.scene.filename().string();
    rc.notes.push_back(
        "Every light scored on the judge's own estimate (" +
        std::to_string(judge.estimate().file.provenance.spp) +
        " spp in two independent halves, seed " + std::to_string(o.judge.seed) +
        "), not on the samples any optimizer saw. Visibility: the region's RMS image gradient "
        "(noise-unbiased, from the two halves) over the defect-free surface's; 1 means the "
        "region is no more salient than the machining texture. Contrast: the region's RMS "
        "gradient over the part's mean brightness (about 0.01 is the least the eye sees). "
        "Brightness: the part's mean over the white furnace's (E = 1).");
    rc.notes.push_back(part);
    if (!judge.legend().empty()) {
        std::string legend =
            "Regions outlined (" +
            (o.defects.empty()
                 ? "truth " + o.judge.truth.filename().string()
                 : "defect region " + defectRegionSpec(o.defects, o.judge.truth).text()) +
            "):";
        for (const RegionLabel& r : judge.legend()) {
            legend += " ";
            legend += r.name;
            legend += " ";
            legend += outlineOf(r.value).name;
            legend += ";";
        }
        legend.back() = '.';
        rc.notes.push_back(legend);
    }
    ReportFigure fig;
    fig.title = "Lights side by side";
    fig.caption = "Each render is exposed on its own (99th percentile of the part at 0.8).";
    for (size_t k = 0; k < lights.size(); ++k) {
        const std::string stem = "light-" + std::to_string(k);
        writePng(dir / (stem + ".png"),
                 outlinedRender(images[k], t.width, t.height, judge.partMask(), judge.labels()));
        writePng(dir / (stem + "-render.png"),
                 outlinedRender(images[k], t.width, t.height, judge.partMask(), {}));
        writePng(dir / (stem + "-envmap.png"), envMapPreview(lights[k].second, 4));
        const JudgeScore& s = scores[k];
        ReportRun run;
        run.title = s.name;
        run.images = {{"render", dir / (stem + "-render.png")},
                      {"regions outlined", dir / (stem + ".png")},
                      {"env map", dir / (stem + "-envmap.png")}};
        nlohmann::json m = {{"brightness", s.brightness},
                            {"eq2", s.eq2.total},
                            {"U", s.unbiased.total},
                            {"mean_E", s.meanE}};
        for (const RegionVisibility& r : s.visibility) {
            m["visibility"][r.label.name] =
                std::isnan(r.visibility) ? nlohmann::json() : nlohmann::json(r.visibility);
            m["contrast"][r.label.name] =
                std::isnan(r.contrast) ? nlohmann::json() : nlohmann::json(r.contrast);
        }
        run.metrics = m;
        fig.runs.push_back(std::move(run));
    }
    rc.figures.push_back(std::move(fig));
    writeReport(dir / "report.html", rc);
}

}  // namespace

void writeSideBySide(const std::filesystem::path& stem,
                     const std::vector<std::vector<double>>& images, int w, int h,
                     const std::vector<uint8_t>& partMask) {
    const int n = static_cast<int>(images.size());
    if (n == 0) return;
    const int gap = 4, W = n * w + (n - 1) * gap;
    Image lin(W, h, 1), shown(W, h, 1);
    for (int k = 0; k < n; ++k) {
        const double scale = exposureScale(images[k], partMask);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const size_t src = static_cast<size_t>(y) * w + x;
                const size_t dst = static_cast<size_t>(y) * W + k * (w + gap) + x;
                lin.data[dst] = static_cast<float>(images[k][src]);
                shown.data[dst] = static_cast<float>(images[k][src] * scale);
            }
    }
    auto exr = stem, png = stem;
    exr += ".exr";
    png += ".png";
    writeExr(exr, lin);
    writePng(png, shown);
}

JudgeJobSummary runJudgeJob(const JudgeJobOptions& o) {
    if (o.lights.empty() && !o.references)
        throw inputError("judge", "no light to score", "give env-map files or keep the references");
    // OUTDIR is checked before any work and replaced as a unit (io/StagedDirectory.h).
    StagedDirectory out(o.outDir);
    const std::filesystem::path dir = out.path();
    JudgeJobSummary sum;
    try {
        auto scene = loadScene(o.scene, o.sceneOverrides);
        const int ew = scene->desc.envmap.width, eh = scene->desc.envmap.height;
        // Load every light before tracing, so a bad file fails fast.
        std::vector<std::pair<std::string, EnvMap>> lights;
        for (const auto& l : o.lights)
            lights.emplace_back(nameOf(l), loadEnvMap(envFileOf(l), ew, eh, 0));
        if (o.references) {
            lights.emplace_back("uniform-0.5", EnvMap::constant(ew, eh, 0.5f));
            lights.emplace_back("studio", studioEnvMap(ew, eh));
        }
        JudgeOptions jo = o.judge;
        jo.cacheDir = cacheDirectory(o.cache);
        if (!jo.viewing) jo.viewing = viewingFor(*scene);
        if (o.defects.empty() && !o.reference.empty())
            throw inputError(option("reference"), "is the reference of a defect region",
                             "give " + option("defects") + " too (e.g. auto)");
        // With a defect region: its regions in the image first (a bad mask fails before the
        // trace), then its labels as optimize's held-out judge scores them (app/pipeline/Truth.h
        // judgedDefectLabels: auto's kinds of mark, else one region "defects").
        std::optional<DefectRegions> regions;
        if (!o.defects.empty())
            regions = defectRegionsInImage(*scene, o.defects, jo.truth, o.reference);
        // The regions in the image once (truth labels, or the defect region), then the judge
        // in rounds (app/pipeline/Judge.h judgeInRounds): the estimate's spp grows until every
        // score's standard error is small, unless --spp is given.
        std::vector<uint8_t> labels, reference;
        std::vector<RegionLabel> legend;
        if (regions) {
            JudgedDefectLabels judged = judgedDefectLabels(
                regions->defects, defectRegionSpec(o.defects, jo.truth).automatic);
            labels = std::move(judged.labels);
            legend = std::move(judged.legend);
            reference = regions->reference;
        } else if (!jo.truth.empty()) {
            LabelMask m = projectTruth(*scene, jo.truth, jo.threads);
            labels = std::move(m.labels);
            legend = std::move(m.legend);
        }
        std::optional<TransportSource> estimate;
        std::unique_ptr<Judge> judged;
        auto judgeAt = [&](int spp) -> const Judge& {
            if (judged && estimate->file.provenance.spp == spp) return *judged;
            judged.reset();
            JudgeOptions at = jo;
            at.spp = spp;
            estimate = judgeEstimate(*scene, at);
            judged = std::make_unique<Judge>(*estimate, at, labels, legend, reference);
            return *judged;
        };
        std::vector<std::pair<std::string, std::vector<double>>> lightE;
        {
            // E on the judge's grid (Judge::envVector needs a judge: the scene's grid is its).
            const int cap = jo.spp == 0 ? kJudgeDefaultSpp : jo.spp;
            const int first = jo.spp == 0 ? std::min(kJudgePilotSpp, cap) : jo.spp;
            const Judge& pilot = judgeAt(first);
            for (const auto& [name, env] : lights) lightE.emplace_back(name, pilot.envVector(env));
            sum.rounds = judgeInRounds(judgeAt, lightE, first, cap);
        }
        jo.spp = sum.rounds.spp();
        const Judge& judge = *judged;
        const TransportMatrix& t = judge.estimate().file.matrix;

        sum.estimate = judge.estimate();
        sum.scores = sum.rounds.scores;
        std::vector<std::vector<double>> images;
        for (const auto& [name, e] : lightE) images.push_back(judge.meanImage(e));

        nlohmann::ordered_json j;
        j["scratchlight"] = runProvenance(o.commandLine);
        j["scene"] = o.scene.string();
        j["heightmap"] = heightmapLoadJson(*scene);
        j["part"] = partSummaryJson(*scene);
        j["estimate"] = {{"spp", jo.spp},
                         {"seed", jo.seed},
                         {"max_depth", sum.estimate.file.provenance.maxDepth},
                         {"fingerprint", sum.estimate.file.provenance.fingerprint},
                         {"cache_hit", sum.estimate.cacheHit},
                         {"image", {t.width, t.height}},
                         {"spp_rule", o.judge.spp == 0 ? "rounds" : "given"},
                         {"max_relative_se", kJudgeMaxError},
                         {"rounds", roundsJson(sum.rounds)},
                         {"reason", sum.rounds.describe()}};
        j["lambda"] = jo.objective.lambda;
        j["viewing"] = viewingJson(*jo.viewing);
        if (!jo.truth.empty()) j["truth"] = jo.truth.string();
        if (regions) {
            j["defects"] = defectRegionSpec(o.defects, jo.truth).text();
            j["reference"] =
                o.reference.empty() ? "the part away from the defects" : o.reference.text();
        }
        j["lights"] = nlohmann::ordered_json::array();
        for (const JudgeScore& s : sum.scores) j["lights"].push_back(toJson(s));
        sum.json = j.dump(2) + "\n";
        writeTextAtomically(dir / "judge.json", sum.json);

        std::ostringstream csv;
        csv.precision(10);
        csv << "light,eq2,unbiased,mean_E,sparsity,brightness";
        const auto& first = sum.scores.front().visibility;
        for (const auto& r : first)
            csv << ",visibility_" << r.label.name << ",contrast_" << r.label.name << ",weber_"
                << r.label.name;
        csv << '\n';
        for (const JudgeScore& s : sum.scores) {
            csv << s.name << ',' << s.eq2.total << ',' << s.unbiased.total << ',' << s.meanE << ','
                << s.sparsity << ',' << s.brightness;
            for (const auto& r : s.visibility)
                csv << ',' << r.visibility << ',' << r.contrast << ',' << r.weber;
            csv << '\n';
        }
        writeTextAtomically(dir / "judge.csv", csv.str());
        writeSideBySide(dir / "renders", images, t.width, t.height, judge.partMask());
        writeJudgeReport(dir, o, judge, lights, images, sum.scores,
                         heightmapSentence(nlohmann::json::parse(j["heightmap"].dump())));
    } catch (const InputError& e) {
        throw InputError(out.explain(e.what()));
    }
    out.commit();
    return sum;
}

}  // namespace sl
