// scratchlight judge SCENE.json [ENV.exr | OUTDIR ...] [--spp N] [--truth TRUTH.png]
//                   [--lambda 30] [--no-references] [-o DIR]
// Scores env maps on the judge's independent estimate (app/pipeline/Judge.h) and prints a table.
#include <spdlog/spdlog.h>

#include <cstdio>
#include <memory>

#include "app/jobs/JudgeJob.h"
#include "cli/Commands.h"
#include "cli/Common.h"

namespace sl::cli {

namespace {

struct JudgeArgs {
    std::string scene;
    std::vector<std::string> lights;
    bool noReferences = false;
    JudgeJobOptions o;
};

int runJudge(const JudgeArgs& a) {
    JudgeJobOptions o = a.o;
    o.scene = a.scene;
    o.references = !a.noReferences;
    for (const auto& l : a.lights) o.lights.emplace_back(l);
    // OUTDIR is replaced as a whole: it must not hold what this run reads (as optimize -o).
    std::vector<std::filesystem::path> inputs = o.lights;
    for (const auto& f : {o.judge.truth, o.defects.file, o.reference.file}) inputs.push_back(f);
    refuseOutputDirOverInputs(o.outDir, o.scene, o.sceneOverrides, inputs);
    o.commandLine = invokedCommandLine();
    JudgeJobSummary s = runJudgeJob(o);
    const auto& est = s.estimate;
    spdlog::info("judge estimate: {} spp in two halves, seed {}, {} ({}); {}",
                 est.file.provenance.spp, o.judge.seed, est.cacheHit ? "from the cache" : "traced",
                 est.path.string(), s.rounds.describe());
    std::printf("%s", formatJudgeTable(s.scores).c_str());
    std::printf(
        "lower eq2 and U are better; bright: mean brightness over the white furnace's; "
        "visibility: RMS gradient in the region over the defect-free surface's; contrast: "
        "the region's RMS gradient over the mean brightness (the eye needs about 0.01)\n");
    spdlog::info("wrote {}/ (report.html, judge.json, judge.csv, renders.exr, renders.png)",
                 o.outDir.string());
    return kOk;
}

}  // namespace

void registerJudge(CLI::App& app, std::function<int()>& run) {
    auto a = std::make_shared<JudgeArgs>();
    CLI::App* c = app.add_subcommand(
        "judge", "Score env maps on an independent high-spp estimate (eq. 2, U, visibility)");
    c->add_option("scene", a->scene, "Scene file (.json)")->required();
    c->add_option("lights", a->lights,
                  "Env-map files, or optimize output directories (their envmap.exr)");
    c->add_option("--spp", a->o.judge.spp,
                  "Samples per pixel of the estimate (two halves); default: from " +
                      std::to_string(kJudgePilotSpp) +
                      " up, until every score's standard error is <= 1 % (at most " +
                      std::to_string(kJudgeDefaultSpp) + ")")
        ->check(inRange(2, 1 << 20));
    c->add_option("--seed", a->o.judge.seed, "The judge's seed (another judge: another seed)")
        ->capture_default_str();
    c->add_option("--max-depth", a->o.judge.maxDepth, "Mitsuba max_depth (default: the scene's)")
        ->check(inRange(1, 64));
    c->add_option("--truth", a->o.judge.truth,
                  "Truth label mask in height-map space (gen-surface's <stem>-truth.png; "
                  "its <stem>-truth.json names the regions)");
    addDefectRegionOptions(c, a->o.defects, a->o.reference);
    c->add_option("--lambda", a->o.judge.objective.lambda, "λ of eq. 2 and U")
        ->check(nonNegativeNumber())
        ->capture_default_str();
    c->add_flag("--rgb", a->o.judge.rgb, "Score RGB env maps in colour (an RGB estimate)");
    c->add_flag("--no-references", a->noReferences,
                "Leave out the built-in references (uniform 0.5, studio)");
    addSceneOverrides(c, a->o.sceneOverrides, true);
    addCacheOptions(c, a->o.cache);
    c->add_option("--threads", a->o.judge.threads, "Worker threads (0: all cores)")
        ->check(inRange(0, 4096));
    c->add_option("-o,--output", a->o.outDir, "Output directory")->capture_default_str();
    c->callback([a, &run] { run = [a] { return runJudge(*a); }; });
}

}  // namespace sl::cli
