// scratchlight lamps (SCENE.json | part.tm) [--count K] [--kinds disk,bar,ring] [--from E.exr]
//                    [--objective paper|unbiased|defects] [--truth T.png] [--distance MM]
//                    [--min-elevation DEG]
//                    [--max-elevation DEG] [--forbid-azimuth A:B ...] [-o OUTDIR]
// Fits K physical lamps to the objective through T (app/jobs/LampsJob.h) and prints what each extra
// lamp buys.
#include <spdlog/spdlog.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>

#include "app/jobs/LampsJob.h"
#include "cli/Commands.h"
#include "cli/Common.h"
#include "core/Text.h"
#include "io/EnvMapIO.h"
#include "scene/Lamp.h"

namespace sl::cli {

namespace {

constexpr double kRad = std::numbers::pi / 180;

struct LampsArgs {
    LampsJobOptions job;
    std::string input, out = "out/lamps";
    std::vector<std::string> kinds, forbid;
    double minElevation = 0, maxElevation = 90, cameraMargin = 10;
    bool noJudge = false, noFigures = false;
};

std::pair<double, double> parseAzimuthRange(const std::string& text) {
    const auto range = parseColonPair<double>(text);
    if (!range)
        throw UsageError("--forbid-azimuth " + text +
                         ": expected FROM:TO in degrees (e.g. 150:210; FROM > TO wraps through 0)");
    return {range->first * kRad, range->second * kRad};
}

int runLamps(LampsArgs a) {
    LampsJobOptions& j = a.job;
    j.input = a.input;
    j.outDir = a.out;
    // OUTDIR is replaced as a whole: it must not hold what this run reads (as optimize -o).
    refuseOutputDirOverInputs(
        j.outDir, j.input, j.sceneOverrides,
        {std::filesystem::path(j.from), j.truth, j.defects.file, j.reference.file});
    j.commandLine = invokedCommandLine();
    j.judge = !a.noJudge;
    j.figures = !a.noFigures;
    j.fit.minElevation = a.minElevation * kRad;
    j.fit.maxElevation = a.maxElevation * kRad;
    j.fit.cameraMargin = a.cameraMargin * kRad;
    if (!a.kinds.empty()) {
        j.fit.kinds.clear();
        for (const std::string& k : a.kinds) j.fit.kinds.push_back(parseLampKind(k, "--kinds"));
    }
    for (const std::string& f : a.forbid) j.fit.forbiddenAzimuth.push_back(parseAzimuthRange(f));
    const LampsJobSummary s = runLampsJob(j);
    if (!s.answerLine.empty()) std::printf("%s\n", s.answerLine.c_str());
    std::printf("%3s %14s %10s %9s %6s\n", "K", "loss", "of E*'s", "seconds", "evals");
    for (const LampFitStep& st : s.fit.steps)
        std::printf("%3d %14.6g %10.4f %9.3f %6d\n", st.count, st.loss, st.loss / s.targetLoss,
                    st.seconds, st.evaluations);
    std::printf("E*'s loss %.6g (lower is better)\n", s.targetLoss);
    for (const Lamp& l : s.fit.steps.back().lamps) {
        if (l.radiance <= 0) continue;
        switch (l.kind) {
            case LampKind::Disk:
                std::printf("  disk azimuth %6.1f deg, elevation %5.1f deg, radius %5.1f deg",
                            std::fmod(l.azimuth / kRad + 720.0, 360.0), l.elevation / kRad,
                            l.size / kRad);
                break;
            case LampKind::Bar:
                std::printf(
                    "  bar  azimuth %6.1f deg, elevation %5.1f deg, %5.1f x %4.1f deg, roll "
                    "%6.1f deg",
                    std::fmod(l.azimuth / kRad + 720.0, 360.0), l.elevation / kRad,
                    2 * l.size / kRad, 2 * l.width / kRad, l.roll / kRad);
                break;
            case LampKind::Ring:
                std::printf("  ring elevations %5.1f to %5.1f deg", (l.elevation - l.size) / kRad,
                            (l.elevation + l.size) / kRad);
                break;
        }
        std::printf(", radiance %.3f\n", l.radiance);
    }
    if (s.judgement) {
        std::printf(
            "judge (%s on the held-out estimate, %s is better): E* %.5g, lamps %.5g, "
            "studio %.5g\n",
            s.judgement->measure.c_str(), s.judgement->higherIsBetter ? "higher" : "lower",
            s.judgement->target, s.judgement->lamps, s.judgement->studio);
        for (size_t r = 0; r < s.judgedTarget->visibility.size(); ++r) {
            const RegionVisibility &t = s.judgedTarget->visibility[r],
                                   &l = s.judgedLamps->visibility[r],
                                   &st = s.judgedStudio->visibility[r];
            // JND first (README "Visibility in JND"), the ratio beside it.
            if (std::isfinite(l.jnd))
                std::printf(
                    "  %s: %.3g JND under the lamps, %.3g under E*, %.3g under the studio "
                    "lamp (visibility ratio %.3g, %.3g, %.3g)\n",
                    t.label.name.c_str(), l.jnd, t.jnd, st.jnd, l.visibility, t.visibility,
                    st.visibility);
            else
                std::printf("  visibility of %s: E* %.3g, lamps %.3g, studio %.3g\n",
                            t.label.name.c_str(), t.visibility, l.visibility, st.visibility);
        }
        std::printf("the lamps are %s E* by the judge (%+.1f %%)\n", s.judgement->verdict(),
                    100 * s.judgement->gap);
    }
    if (!s.plotMessage.empty()) std::printf("no plot: %s\n", s.plotMessage.c_str());
    spdlog::info("wrote {}/ (open {}/report.html)", a.out, a.out);
    return kOk;
}

}  // namespace

void registerLamps(CLI::App& app, std::function<int()>& run) {
    auto a = std::make_shared<LampsArgs>();
    LampsJobOptions& j = a->job;
    CLI::App* c = app.add_subcommand(
        "lamps", "Fit K physical lamps (disks, bars, rings) to the objective through T");
    c->add_option("input", a->input, "Scene file (.json, T is traced and cached) or .tm")
        ->required();
    c->add_option("--count", j.fit.count, "Lamps at most (greedy: the score for K = 1..count)")
        ->check(inRange(1, 8))
        ->capture_default_str();
    std::string kindsHelp = "Lamp kinds allowed (comma-separated; default all):";
    for (const LampKindRow& r : lampKindTable())
        kindsHelp += std::string("\n    ") + r.name + ": " + r.help;
    std::vector<std::string> kindNames;
    for (const LampKindRow& r : lampKindTable()) kindNames.emplace_back(r.name);
    c->add_option("--kinds", a->kinds, kindsHelp)->delimiter(',')->check(CLI::IsMember(kindNames));
    c->add_option("--from", j.from,
                  "E*, the env map the lamps start from: " + lightSpecForms() +
                      " (default: optimized here on T)");
    addChoice(c, "--objective", j.objectiveKind, objectiveKindTable(),
              "Objective (default: unbiased; defects when --truth or --defects names the "
              "defects; paper for a .tm without halves)");
    c->add_option("--truth", j.truth,
                  "Ground-truth defect labels in height-map space (e.g. part-truth.png): the "
                  "defects objective's defect region and the judge's per-region visibility");
    addDefectRegionOptions(c, j.defects, j.reference);
    c->add_option("--lambda", j.objective.lambda, "Regulariser weight")->capture_default_str();
    c->add_option("--distance", j.distanceMm, "Mounting distance from the part's centre, mm")
        ->check(positiveNumber())
        ->capture_default_str();
    c->add_option("--min-elevation", a->minElevation, "Lowest lamp centre, degrees")
        ->check(inRange(-90.0, 90.0))
        ->capture_default_str();
    c->add_option("--max-elevation", a->maxElevation, "Highest lamp centre, degrees")
        ->check(inRange(-90.0, 90.0))
        ->capture_default_str();
    c->add_option("--forbid-azimuth", a->forbid,
                  "Azimuth range FROM:TO (degrees) no lamp centre may sit in (camera, fixtures); "
                  "repeatable")
        ->take_all();
    c->add_option("--camera-margin", a->cameraMargin,
                  "No disk or bar centre within this many degrees of the camera's direction "
                  "(seen from the part's centre); 0: no such limit")
        ->check(inRange(0.0, 89.0))
        ->capture_default_str();
    c->add_flag("--no-judge", a->noJudge, "Do not score on the judge's estimate");
    c->add_flag_function(
        "--no-self-check", [&j](std::int64_t) { j.selfCheck = false; },
        "Do not score every K's lamps and the studio lamp on a validation estimate (by default "
        "the best of them is named as the answer, first)");
    c->add_flag("--no-figures", a->noFigures, "Do not draw plot-lamps.png");
    addSceneOverrides(c, j.sceneOverrides, true);
    c->add_option("--spp", j.precompute.spp, "Samples per pixel (overrides render.spp)")
        ->check(inRange(1, 1 << 20));
    c->add_option("--max-depth", j.precompute.maxDepth,
                  "Mitsuba max_depth (overrides render.max_depth)")
        ->check(inRange(1, 64));
    c->add_option("--seed", j.precompute.seed, "Random seed (overrides render.seed)");
    addCacheOptions(c, j.cache);
    c->add_option("-o,--output", a->out, "Output directory")->capture_default_str();
    c->callback([a, &run] { run = [a] { return runLamps(*a); }; });
}

}  // namespace sl::cli
