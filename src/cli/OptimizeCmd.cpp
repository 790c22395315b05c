// scratchlight optimize (SCENE.json | part.tm) [--optimizer NAME] [--lambda L[,L...]] ...
#include <spdlog/spdlog.h>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <memory>

#include "app/host/ExternalRenderer.h"
#include "app/jobs/OptimizeJob.h"
#include "app/pipeline/Cache.h"
#include "app/pipeline/TrainingNoise.h"
#include "app/pipeline/Transport.h"
#include "app/report/OptimizeReport.h"
#include "app/report/Preview.h"
#include "app/report/Report.h"
#include "cli/Commands.h"
#include "cli/Common.h"
#include "cli/TraceOptions.h"
#include "core/Error.h"
#include "core/Interrupt.h"
#include "core/Text.h"
#include "io/EnvMapIO.h"
#include "io/ImageIO.h"
#include "io/InputFile.h"
#include "io/SceneFile.h"
#include "optimize/BlackBox.h"
#include "optimize/Methods.h"
#include "scene/EnvMapToE.h"

namespace sl::cli {

namespace {

struct OptimizeArgs {
    OptimizeJobOptions job;
    std::string input, out = "out/optimize", reg = "envmap";
    std::optional<OptimizePreset> preset;
};

int runOptimize(OptimizeArgs a) {
    // OUTDIR is replaced as a whole: it must not hold what this run reads.
    refuseOutputDirOverInputs(
        a.out, a.input, a.job.sceneOverrides,
        {a.job.truth, a.job.mask.file, a.job.compare, a.job.defects.file, a.job.reference.file});
    a.job.input = a.input;
    a.job.outDir = a.out;
    a.job.objective.reg = a.reg == "image" ? RegTarget::Image : RegTarget::EnvMap;
    if (a.preset) applyOptimizePreset(*a.preset, a.job);
    a.job.commandLine = invokedCommandLine();
    a.job.ranks = worldRanks();
    OptimizeJobSummary s = runOptimizeJob(a.job);
    if (a.job.ranks && !a.job.ranks->root()) return kOk;  // rank 0 prints and writes
    std::printf("%10s %-12s %6s %6s %14s %14s %14s %14s %10s\n", "lambda", "optimizer", "iters",
                "evals", "initial loss", "final loss", "held-out init", "held-out final",
                "seconds");
    for (const OptimizeRun& r : s.runs)
        std::printf("%10g %-12s %6d %6d %14.6g %14.6g %14.6g %14.6g %10.4f\n", r.lambda,
                    r.optimizer.method.c_str(), r.optimizer.iterations, r.optimizer.evaluations,
                    r.initial.total, r.final.total,
                    r.heldInitial ? r.heldInitial->own.total : std::nan(""),
                    r.heldFinal ? r.heldFinal->own.total : std::nan(""), r.optimizer.seconds);
    // The held-out columns are the optimized objective on the independent estimate, U beside.
    for (const OptimizeRun& r : s.runs)
        if (r.heldFinal)
            std::printf(
                "held out (lambda %g, %d spp): the %s loss %.6g -> %.6g (lower is better); U "
                "there %.6g -> %.6g\n",
                r.lambda, s.heldOut ? s.heldOut->file.provenance.spp : 0, r.objective.c_str(),
                r.heldInitial->own.total, r.heldFinal->own.total, r.heldInitial->unbiased.total,
                r.heldFinal->unbiased.total);
    // The judge's scores with their standard errors (app/pipeline/Judge.h), relative to each score.
    auto pm = [](double v, const std::optional<JudgeScore::Errors>& se,
                 double JudgeScore::Errors::*f) {
        if (!se || !std::isfinite(v) || v == 0 || !std::isfinite((*se).*f)) return std::string();
        return " ± " + formatNumber(100.0 * (*se).*f / std::abs(v), 2) + " %";
    };
    for (const OptimizeRun& r : s.runs)
        if (r.judged) {
            // The figure the answer is chosen on, when the judge has it: the least visible
            // defect kind's JND.
            size_t least = 0;
            const double jnd = leastVisibleJnd(r.judged->visibility, &least);
            const std::string jndPart =
                std::isfinite(jnd)
                    ? ", JND " + formatNumber(jnd, 3) +
                          pm(jnd, r.judged->se, &JudgeScore::Errors::leastVisibleJnd) +
                          " (least visible: " + r.judged->visibility[least].label.name + ")"
                    : std::string();
            std::printf(
                "judge (lambda %g, %d spp): eq2 %.4f%s, U %.4f%s%s, mean E %.4f, %.0f%% texels "
                "dark%s\n",
                r.lambda, r.judged->spp, r.judged->eq2.total,
                pm(r.judged->eq2.total, r.judged->se, &JudgeScore::Errors::eq2).c_str(),
                r.judged->unbiased.total,
                pm(r.judged->unbiased.total, r.judged->se, &JudgeScore::Errors::unbiased).c_str(),
                jndPart.c_str(), r.judged->meanE, 100.0 * r.judged->sparsity,
                r.start.empty() ? "" : (", best start " + r.start).c_str());
            // The lights it is compared with, each score with its standard error (their rounds:
            // app/pipeline/Judge.h JudgeStopRule).
            std::string refs;
            for (const std::optional<JudgeScore>* x :
                 {&r.judgedLamp, &r.judgedPaper, &r.judgedOptimized}) {
                if (!*x) continue;
                const JudgeScore& j = **x;
                const double jj = leastVisibleJnd(j.visibility);
                refs += (refs.empty() ? "" : "; ") + j.name + " U " +
                        formatNumber(j.unbiased.total, 4) +
                        pm(j.unbiased.total, j.se, &JudgeScore::Errors::unbiased) +
                        (std::isfinite(jj) ? ", JND " + formatNumber(jj, 3) +
                                                 pm(jj, j.se, &JudgeScore::Errors::leastVisibleJnd)
                                           : std::string());
            }
            if (!refs.empty())
                std::printf("judge (lambda %g), compared with: %s\n", r.lambda, refs.c_str());
        }
    // The report's first sentence (app/report/Report.h), here too.
    for (const OptimizeRun& r : s.runs) {
        std::string prefix;
        if (s.runs.size() > 1) prefix = "lambda " + formatNumber(r.lambda) + ": ";
        std::printf("%s%s\n", prefix.c_str(), optimizeHeadlineOf(r.dir).c_str());
    }
    spdlog::info("wrote {}/ (open {}/report.html)", a.out, a.out);
    // --keep-interrupted: the best light so far is written, and the exit code still says that
    // the run was cut short (core/Interrupt.h).
    if (s.interrupted || (!s.runs.empty() && s.runs.back().interrupted))
        return 128 + interruptSignal();
    return kOk;
}

}  // namespace

void registerOptimize(CLI::App& app, std::function<int()>& run) {
    auto a = std::make_shared<OptimizeArgs>();
    OptimizeJobOptions& j = a->job;
    CLI::App* c = app.add_subcommand(
        "optimize", "Optimize the env map so the part's scratches show (paper eq. 1-3)");
    c->add_option("input", a->input,
                  "Scene file (.json, T is traced and cached), .tm, or a .shards list (under "
                  "mpirun: one shard per rank, docs/CLUSTER.md)")
        ->required();
    addRendererOptions(c, j.renderer, j.external);
    addChoice(c, "--optimizer", j.optimizer.method, optimizerMethodTable(),
              std::string("Optimizer (default: ") + methodName(optimizeDefaults().method) +
                  "; budget: --iterations)");
    c->add_option("--fd-step", j.blackBox.fd.h, "fd-adam: finite-difference step h")
        ->check(positiveNumber())
        ->capture_default_str();
    c->add_option("--spsa-q", j.blackBox.spsa.q, "spsa: estimates averaged per step")
        ->check(inRange(1, 100000))
        ->capture_default_str();
    c->add_option("--spsa-c", j.blackBox.spsa.c, "spsa: perturbation size")
        ->check(positiveNumber())
        ->capture_default_str();
    std::string lambdaDefault;
    for (const double l : j.lambdas)
        lambdaDefault += (lambdaDefault.empty() ? "" : ",") + formatNumber(l);
    c->add_option_function<std::vector<std::string>>(
         "--lambda",
         [&j](const std::vector<std::string>& v) { j.lambdas = parseNumberList(v, "--lambda"); },
         "Regulariser weight(s) A,B,...; several run a sweep")
        ->default_str(lambdaDefault);
    c->add_option("--reg", a->reg, "L2 regulariser on the env map or on the image")
        ->check(CLI::IsMember({"envmap", "image"}))
        ->capture_default_str();
    auto* init = addParsed(
        c, "--init", j.starts,
        [](const std::string& v, const std::string& flag) {
            return std::vector<InitialState>{parseInitialState(v, flag)};
        },
        "Initial env map: " + initialSpecForms() +
            " (default: " + optimizeDefaults().starts.front() + ")");
    c->add_flag_function(
        "--no-figures", [&j](std::int64_t) { j.figures = false; },
        "Do not draw the report's figures (the report says they were not asked for)");
    c->add_option("--compare", j.compare,
                  "The lamp you use now, the report's \"before\": " + lightSpecForms() +
                      " (default: studio)");
    addParsed(
        c, "--mask", j.mask,
        [](const std::string& v, const std::string&) { return parseLossMask(v); },
        "Region of the loss, always within the part: object (default), scratch (the paper's "
        "scratch map) or a PNG/EXR in image space (white = inside)");
    c->add_flag("--trace-mask-only", j.traceMaskOnly,
                "Trace only the --mask region's pixels: the same loss and E* for the region's "
                "rays (renders from T are dark outside it)");
    c->add_option("--scratch-kernel", j.scratch.kernel, "Scratch map: detrending kernel")
        ->check(inRange(1, 100000))
        ->capture_default_str();
    c->add_option("--scratch-patch", j.scratch.patch, "Scratch map: patch size")
        ->check(inRange(1, 100000))
        ->capture_default_str();
    c->add_option("--scratch-threshold", j.scratch.threshold,
                  "Scratch map: max-min threshold of a patch (of the [0,1] detrended range)")
        ->check(numberInRange(0, 1))  // before the trace (detect/ScratchMap.h checks too)
        ->capture_default_str();
    c->add_option("--truth", j.truth,
                  "Ground-truth defect mask in height-map space (e.g. part-truth.png): "
                  "adds the defect contrast to the metrics");
    addDefectRegionOptions(c, j.defects, j.reference);
    c->add_flag("--rgb", j.rgb, "Optimize an RGB env map (needs/creates an RGB T)");
    c->add_flag("--keep-interrupted", j.keepInterrupted,
                "On Ctrl-C, write the best light so far into OUTDIR (marked interrupted, exit "
                "130) instead of leaving the previous OUTDIR as it was");
    c->add_flag("--smooth-abs", j.objective.smoothAbs, "Use sqrt(x²+ε²)−ε for |x|");
    const OptimizeDefaults d = optimizeDefaults();
    std::string objectiveHelp = "Objective (default: ";
    objectiveHelp += objectiveKindName(d.objectiveWithDefects);
    objectiveHelp += " when --truth or --defects names the defects, else ";
    objectiveHelp += objectiveKindName(d.objective);
    objectiveHelp += "; paper for a .tm without halves; paper trains at >= ";
    objectiveHelp += std::to_string(d.paperMinSpp) + " spp unless --spp)";
    addChoice(c, "--objective", j.objectiveKind, objectiveKindTable(), objectiveHelp);
    addChoice(c, "--defects-measure", j.objective.defectMeasure, defectMeasureTable(),
              std::string("What the defects objective makes large (default: ") +
                  defectMeasureName(ObjectiveOptions{}.defectMeasure) + ")");
    std::string heldOutHelp = "Held-out estimate every result is scored on:";
    for (const HeldOutModeRow& r : heldOutModeTable())
        heldOutHelp += std::string("\n    ") + r.name + ": " + r.help;
    addParsed(c, "--heldout", j.heldOut, parseHeldOutSource, heldOutHelp);
    c->add_option("--heldout-spp", j.heldOutSpp,
                  "spp of the judge's held-out estimate (0: the judge's 1024)")
        ->check(inRange(0, 1 << 20))
        ->capture_default_str();
    c->add_option("--heldout-every", j.heldOutEvery, "Held-out score every N iterations")
        ->check(inRange(1, 1000000))
        ->capture_default_str();
    std::string budgetHelp = "Budget (default: the method's); one iteration is:";
    for (const OptimizerMethodRow& r : optimizerMethodTable())
        budgetHelp += std::string("\n    ") + r.name + ": " + r.iteration + " (default " +
                      std::to_string(r.defaultBudget) + ")";
    c->add_option("--iterations", j.optimizer.iterations, budgetHelp)->check(inRange(1, 1000000));
    c->add_option("--ftol,--relative-function-tolerance", j.optimizer.relativeFunctionTolerance,
                  "NLopt/Ceres: stop when the loss changes by less than this fraction (0: off)")
        ->check(nonNegativeNumber())
        ->capture_default_str();
    c->add_option("--lr,--learning-rate", j.optimizer.learningRate, "Adam learning rate")
        ->check(positiveNumber())
        ->capture_default_str();
    c->add_option("--estimates,--planes", j.estimates,
                  "Independent estimates of T (seeds seed+k) cycled by the optimizer, one "
                  "per step (stochastic, as the paper's loop; default: the method's, 1, "
                  "paper-loop " +
                      std::to_string(methodRow(OptimizerMethod::PaperLoop).defaultEstimates) +
                      "; --planes, its old name, is still accepted)")
        ->check(inRange(1, 1000));
    c->add_option_function<std::vector<std::string>>(
         "--starts",
         [&j](const std::vector<std::string>& specs) {
             j.starts.clear();
             for (const std::string& spec : specs)
                 j.starts.push_back(parseInitialState(spec, "--starts"));
         },
         "Multistart: optimize from each; E* is the lowest training loss, and the self-check "
         "chooses among every start's light on the validation estimate (" +
             initialSpecForms() + ")")
        ->delimiter(',')
        ->excludes(init);
    c->add_option("--continuation", j.continuation,
                  "λ factors optimized in turn before λ itself (e.g. 4,2)")
        ->delimiter(',');
    addChoice(c, "--preset", a->preset, optimizePresetTable(),
              "Settings fixed together (they override the options they fix)");
    addTraceOptions(c, j.precompute, j.sceneOverrides, true);
    c->add_option(
         "--max-spp", j.noiseMaxSpp,
         "--spp auto: the most training spp it traces (default: " +
             std::to_string(TrainingNoiseOptions{}.maxSpp) +
             " at 256x256 pixels and above; a smaller image up to " +
             std::to_string(kMaxSppCapScale) + "x that, for the same samples: 128x128 takes " +
             std::to_string(sppCapForImage(TrainingNoiseOptions{}.maxSpp, 128 * 128)) + ")")
        ->check(inRange(1, 1 << 20));
    c->add_option_function<std::string>(
         "--light-grid", [&j](const std::string& v) { j.lightGrid = parseLightGrid(v); },
         "Search the light on a grid of WxH nodes interpolated onto the env map, or "
         "'texels' (one value per texel); default: the noise rule's, per texel unless the "
         "train/validation gap stays large at --max-spp, then coarser (fewer degrees of "
         "freedom fit less of T's noise)")
        ->type_name("WxH|texels");
    c->add_option("--defect-spp-scale", j.defectSppScale,
                  "--objective defects: the defect pixels take N times the training spp "
                  "(their few pixel pairs are the noisiest part of the objective); 0: the "
                  "rule (up to 32 per label, the smallest labels first, within half the part's "
                  "samples), 1: off")
        ->check(inRange(0, kMaxSppScale))
        ->capture_default_str();
    c->add_flag_function(
        "--no-self-check", [&j](std::int64_t) { j.selfCheck = false; },
        "Return the optimized light even when your lamp, a uniform dome or the paper's light "
        "shows the defects better on the validation estimate (by default the best of them is "
        "the answer and the optimized light is kept beside it)");
    addCacheOptions(c, j.cache);
    c->add_option("-o,--output", a->out, "Output directory")->capture_default_str();
    c->callback([a, &run] { run = [a] { return runOptimize(*a); }; });
}

}  // namespace sl::cli
