// scratchlight gradcheck SCENE.json [--methods exact,autodiff,fd,spsa] [-o REPORT.json] ...
// scratchlight bench gradients [SCENE.json] [-o DIR] ...
// Gradients by every method against autodiff (app/bench/GradCheck.h): the check, and its
// benchmark (a row of cli/BenchCmd.cpp's table), which share the set-up's options.
#include <spdlog/spdlog.h>

#include <cstdio>
#include <filesystem>
#include <memory>

#include "app/bench/GradCheck.h"
#include "app/host/Plot.h"
#include "cli/Commands.h"
#include "cli/Common.h"
#include "core/Error.h"
#include "core/Interrupt.h"
#include "io/AtomicFile.h"

namespace sl::cli {

namespace {

struct SetupArgs {
    int size = 32;
    int spp = 8;
};

void addSetupOptions(CLI::App* c, GradientSetup& s, SetupArgs& a) {
    addSceneOverrides(c, s.sceneOverrides, false);
    c->add_option("--size", a.size,
                  "Image N×N pixels (replaces the scene's camera size; 0 keeps it). Autodiff and "
                  "finite differences need small images")
        ->check(inRange(0, 4096))
        ->capture_default_str();
    c->add_option("--width", s.width, "Image width in pixels (overrides --size)")
        ->check(inRange(1, 4096));
    c->add_option("--height", s.height, "Image height in pixels (overrides --size)")
        ->check(inRange(1, 4096));
    c->add_option("--spp", a.spp, "Samples per pixel (0 keeps render.spp)")
        ->check(inRange(0, 1 << 20))
        ->capture_default_str();
    c->add_option("--max-depth", s.maxDepth, "Mitsuba max_depth (overrides render.max_depth)")
        ->check(inRange(1, 64));
    c->add_option("--seed", s.seed, "Random seed (overrides render.seed)");
    c->add_option("--threads", s.threads, "Worker threads (0: all cores)")->check(inRange(0, 4096));
    c->add_option("--lambda", s.objective.lambda, "Regulariser weight λ")
        ->check(nonNegativeNumber())
        ->capture_default_str();
    c->add_flag("--smooth-abs", s.objective.smoothAbs, "Use sqrt(x²+ε²)−ε for |x|");
    addParsed(c, "--init", s.init, parseInitialState,
              "E where the gradient is taken: const:V | envmap:FILE | random:SEED (default "
              "const:0.5)");
}

void applySetup(GradientSetup& s, const SetupArgs& a) {
    if (a.size > 0) {
        if (!s.width) s.width = a.size;
        if (!s.height) s.height = a.size;
    }
    if (a.spp > 0) s.spp = a.spp;
}

struct GradCheckArgs {
    GradCheckOptions o;
    SetupArgs setup;
    std::string scene, out;
};

int runGradCheckCmd(GradCheckArgs a) {
    a.o.setup.scene = a.scene;
    applySetup(a.o.setup, a.setup);
    if (a.o.methods.empty()) throw UsageError("--methods is empty");
    const GradCheckReport r = runGradCheck(a.o);
    std::fputs(r.table().c_str(), stdout);
    if (!a.out.empty()) {
        enterCommit();  // the last safe point (core/Interrupt.h)
        writeTextAtomically(a.out, r.json());
        std::printf("wrote %s\n", a.out.c_str());
    }
    return kOk;
}

struct BenchArgs {
    BenchGradientsOptions o;
    SetupArgs setup;
    std::string scene, out = "out/bench-gradients";
    std::string script = "plot_gradients.py";
    bool noOptimize = false, noPlot = false;
};

int runBenchGradientsCmd(BenchArgs a) {
    a.o.setup.scene = a.scene.empty() ? bundledDefaultScene() : std::filesystem::path(a.scene);
    applySetup(a.o.setup, a.setup);
    a.o.outDir = a.out;
    a.o.optimizations = !a.noOptimize;
    const BenchGradientsReport r = runBenchGradients(a.o);
    std::fputs(r.gradients.table().c_str(), stdout);
    if (a.o.optimizations) {
        std::printf("\n%-24s %6s %10s %14s %9s\n", "optimization", "iters", "seconds", "final loss",
                    "renders");
        for (size_t i = 0; i < r.trace.size(); ++i) {
            const BenchTracePoint& p = r.trace[i];
            if (i + 1 < r.trace.size() && r.trace[i + 1].method == p.method) continue;
            std::printf("%-24s %6d %10.3f %14.6g %9ld\n", p.method.c_str(), p.iteration, p.seconds,
                        p.loss, p.renders);
        }
    }
    std::printf("wrote %s", r.gradientsCsv.string().c_str());
    if (!r.optimizationCsv.empty()) std::printf(" and %s", r.optimizationCsv.string().c_str());
    std::printf("\n");
    return runPlot(a.script, {a.out}, !a.noPlot);
}

}  // namespace

void registerGradCheck(CLI::App& app, std::function<int()>& run) {
    auto a = std::make_shared<GradCheckArgs>();
    CLI::App* c = app.add_subcommand(
        "gradcheck",
        "Gradients of the loss by every method against autodiff (ceres::Jet): seconds per "
        "gradient, relative L2 error, cosine similarity");
    c->add_option("scene", a->scene, "Scene file (JSON)")->required();
    addSetupOptions(c, a->o.setup, a->setup);
    c->add_option("--methods", a->o.methods,
                  "Methods: exact, exact+precompute, autodiff, autodiff-T, fd, fd-forward, "
                  "fd-fresh, spsa")
        ->delimiter(',')
        ->check(CLI::IsMember(gradCheckMethods()))
        ->capture_default_str();
    c->add_option("--fd-step", a->o.fd.h, "Finite-difference step h (E units)")
        ->check(inRange(1e-12, 0.49))
        ->capture_default_str();
    c->add_option("--spsa-c", a->o.spsa.c, "SPSA perturbation size c")
        ->check(positiveNumber())
        ->capture_default_str();
    c->add_option("--spsa-q", a->o.spsa.q, "SPSA estimates averaged per gradient")
        ->check(inRange(1, 1 << 20))
        ->capture_default_str();
    c->add_option("--repeats", a->o.repeats, "Repeats (medians of time and error)")
        ->check(inRange(1, 1000))
        ->capture_default_str();
    c->add_option("-o,--output", a->out, "Also write the report to this JSON file");
    c->callback([a, &run] { run = [a] { return runGradCheckCmd(*a); }; });
}

void addGradientsBench(CLI::App* c, std::function<int()>& run) {
    auto a = std::make_shared<BenchArgs>();
    BenchGradientsOptions& o = a->o;
    c->add_option("scene", a->scene, "Scene file (default: the bundled scenes/default)");
    addSetupOptions(c, o.setup, a->setup);
    c->add_option("--fd-step", o.fdSteps, "Central-FD steps h (common random numbers)")
        ->delimiter(',')
        ->capture_default_str();
    c->add_option("--fd-fresh-step", o.fdFreshSteps, "Central-FD steps h with fresh seeds")
        ->delimiter(',')
        ->capture_default_str();
    c->add_option("--spsa-q", o.spsaQ, "SPSA averaging counts q")
        ->delimiter(',')
        ->capture_default_str();
    c->add_option("--spsa-c", o.spsaC, "SPSA perturbation sizes c of the q sweep")
        ->delimiter(',')
        ->capture_default_str();
    c->add_option("--spsa-opt-c", o.spsa.c, "SPSA c of the whole optimizations")
        ->check(positiveNumber())
        ->capture_default_str();
    c->add_option("--repeats", o.repeats, "Repeats per measurement (medians)")
        ->check(inRange(1, 1000))
        ->capture_default_str();
    c->add_option("--iterations", o.iterations, "Adam iterations (exact, autodiff, fd-adam)")
        ->check(inRange(1, 1000000))
        ->capture_default_str();
    c->add_option("--spsa-iterations", o.spsaIterations, "SPSA iterations")
        ->check(inRange(1, 100000000))
        ->capture_default_str();
    c->add_option("--budget", o.budgetSeconds, "Wall-clock budget per optimization (s)")
        ->check(positiveNumber())
        ->capture_default_str();
    c->add_flag("--no-optimize", a->noOptimize, "Skip the whole optimizations");
    c->add_option("-o,--output", a->out, "Output directory")->capture_default_str();
    c->add_option("--plot-script", a->script,
                  "The plotting script: a path, or a name found beside the executable "
                  "(../scripts, ../share/scratchlight/scripts)")
        ->capture_default_str();
    c->add_flag("--no-plot", a->noPlot, "Do not run the plotting script");
    c->callback([a, &run] { run = [a] { return runBenchGradientsCmd(*a); }; });
}

}  // namespace sl::cli
