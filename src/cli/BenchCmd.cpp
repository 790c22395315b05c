// scratchlight bench render [SCENE.json] [--sizes 1024,5000] [--resolution R] [--spp N] [--csv F]
// Prints a table and writes CSV: renderer rays/s next to bare Embree closest-hit rays/s on the
// same height field in the same run, and the height field's build time and memory.
#include <spdlog/spdlog.h>

#include <chrono>
#include <memory>
#include <sstream>

#include "app/NoiseBench.h"
#include "cli/Commands.h"
#include "cli/Common.h"
#include "io/AtomicFile.h"
#include "io/SceneFile.h"
#include "objective/TransportLoss.h"
#include "optimize/InitialState.h"
#include "render/Benchmark.h"
#include "render/Render.h"
#include "scene/EnvMapPresets.h"
#include "scene/Scene.h"
#include "synth/SurfaceGenerator.h"
#include "transport/TransportSink.h"

namespace sl::cli {

namespace {
struct BenchArgs {
    std::string scene, csv = "bench-render.csv";
    std::vector<int> sizes{1024, 5000};
    int resolution = 256, spp = 16, threads = 0, repeats = 3;
};

struct Row {
    std::string map;
    double genSeconds = 0;
    HeightfieldStats hs;
    ThroughputRow renderer, bare;
};

double mb(size_t b) {
    return static_cast<double>(b) / 1e6;
}

/// The run of median time (the rays are identical across repeats).
ThroughputRow median(std::vector<ThroughputRow> rows) {
    std::sort(rows.begin(), rows.end(),
              [](const auto& x, const auto& y) { return x.seconds < y.seconds; });
    return rows[rows.size() / 2];
}

Row measure(const Scene& scene, const std::string& name, double genSeconds, const BenchArgs& a) {
    RenderOptions opt = renderOptionsFor(scene);
    opt.spp = a.spp;
    opt.threads = a.threads;
    Row r{name, genSeconds, scene.surface->stats(), {}, {}};
    // Interleave so that both see the same machine state.
    std::vector<ThroughputRow> ren, bare;
    for (int i = 0; i < a.repeats; ++i) {
        ren.push_back(benchRenderer(scene, opt));
        bare.push_back(benchBareEmbree(scene, opt));
    }
    r.renderer = median(std::move(ren));
    r.bare = median(std::move(bare));
    return r;
}

int runBench(const BenchArgs& a) {
    std::vector<Row> rows;
    if (!a.scene.empty()) {
        SceneDesc d = readSceneFile(a.scene);
        d.camera.width = d.camera.height = a.resolution;
        auto scene = loadScene(d);
        rows.push_back(measure(*scene, std::filesystem::path(a.scene).filename().string(), 0, a));
    }
    for (int n : a.sizes) {
        SurfaceSpec spec;
        spec.width = spec.height = n;
        spec.pitch = 10.0 / (n - 1);  // a 10 mm part at every size
        auto t0 = std::chrono::steady_clock::now();
        GeneratedSurface g = generateSurface(spec);
        double gen = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        SceneDesc d;
        d.heightmap.pitch = g.pitch;
        d.material.params.alphaU = d.material.params.alphaV = 0.05f;
        d.material.params.ior = ComplexIor{Rgb{1.0f}, Rgb{7.0f}};  // a bright metal
        d.camera.width = d.camera.height = a.resolution;
        Scene scene(d, g.width, g.height, std::move(g.heights));
        rows.push_back(measure(scene, std::to_string(n) + "x" + std::to_string(n), gen, a));
        spdlog::info("measured {}x{}", n, n);
    }

    std::printf("%-14s %8s %9s %10s %10s %10s | %14s %14s %7s\n", "height map", "gen s", "build s",
                "vertex MB", "embree MB", "peak MB", "renderer Mr/s", "bare Mr/s", "ratio");
    for (const Row& r : rows)
        std::printf("%-14s %8.2f %9.3f %10.1f %10.1f %10.1f | %14.2f %14.2f %6.1f%%\n",
                    r.map.c_str(), r.genSeconds, r.hs.buildSeconds, mb(r.hs.vertexBytes),
                    mb(r.hs.embreeBytes), mb(r.hs.embreePeakBytes),
                    r.renderer.raysPerSecond() / 1e6, r.bare.raysPerSecond() / 1e6,
                    100.0 * r.renderer.raysPerSecond() / r.bare.raysPerSecond());
    std::printf("(%dx%d image, %d spp, median of %d interleaved runs; ratio = renderer/bare)\n",
                a.resolution, a.resolution, a.spp, a.repeats);

    std::ostringstream os;
    {
        os << "height_map,generate_s,build_s,vertex_bytes,embree_bytes,embree_peak_bytes,"
              "image,spp,renderer_rays,renderer_s,renderer_rays_per_s,bare_rays,bare_s,"
              "bare_rays_per_s,ratio\n";
        for (const Row& r : rows)
            os << r.map << ',' << r.genSeconds << ',' << r.hs.buildSeconds << ','
               << r.hs.vertexBytes << ',' << r.hs.embreeBytes << ',' << r.hs.embreePeakBytes << ','
               << a.resolution << ',' << a.spp << ',' << r.renderer.rays << ','
               << r.renderer.seconds << ',' << r.renderer.raysPerSecond() << ',' << r.bare.rays
               << ',' << r.bare.seconds << ',' << r.bare.raysPerSecond() << ','
               << r.renderer.raysPerSecond() / r.bare.raysPerSecond() << '\n';
    }
    writeTextAtomically(a.csv, os.str());
    std::printf("wrote %s\n", a.csv.c_str());
    return kOk;
}
struct TransportBenchArgs {
    std::string scene = "scenes/default/scene.json", csv = "bench-transport.csv";
    int resolution = 512, spp = 64, iterations = 100, repeats = 3, threads = 0;
};

template <typename F>
double medianSeconds(int repeats, F&& f) {
    std::vector<double> t;
    for (int i = 0; i < repeats; ++i) {
        auto t0 = std::chrono::steady_clock::now();
        f();
        t.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    std::sort(t.begin(), t.end());
    return t[t.size() / 2];
}

int runTransportBench(const TransportBenchArgs& a) {
    SceneDesc d = readSceneFile(a.scene);
    d.camera.width = d.camera.height = a.resolution;
    d.render.spp = a.spp;
    auto scene = loadScene(d);
    RenderOptions opt = renderOptionsFor(*scene);
    opt.threads = a.threads;

    // 1. Tracing: renderer (radiance sink) and precompute (transport sink), interleaved.
    std::vector<ThroughputRow> ren, pre;
    TransportMatrix T;
    for (int i = 0; i < a.repeats; ++i) {
        ren.push_back(benchRenderer(*scene, opt));
        PrecomputeResult p = precomputeTransport(*scene, opt, 1);
        pre.push_back(
            {"precompute (path tracer + transport sink)", p.summary.rays, p.summary.seconds});
        if (i == 0) T = std::move(p.matrix);
    }
    ThroughputRow r = median(ren), p = median(pre);
    T.threads = a.threads;

    // 2. Products and the optimizer on T.
    ObjectiveOptions oo;
    ImageObjective obj(T.width, T.height, T.objectMask, oo);
    TransportLoss loss(T, obj, false);
    std::vector<double> e = initialEnvMap("const:0.5", T.envWidth, T.envHeight, false);
    std::vector<double> g(loss.dimension());
    const int reps = std::max(5, 4 * a.repeats + 1);
    volatile double sink = 0;
    double tRead = medianSeconds(reps, [&] { sink = sink + streamingRead(T); });
    double tIter = medianSeconds(reps, [&] { sink = sink + loss.evaluate(e, g).total; });
    double tFused = medianSeconds(reps, [&] { sink = sink + loss.evaluateFused(e, g).total; });
    std::vector<double> y(T.rows());
    double tApply = medianSeconds(reps, [&] { T.applyLuminance(e, y); });
    double tAdam = medianSeconds(a.repeats, [&] {
        std::vector<double> x = e;
        OptimizerOptions oopt;
        oopt.iterations = a.iterations;
        minimize(loss.problem(), x, oopt);
    });

    std::printf("scene %s at %dx%d, %d spp, max_depth %d\n", a.scene.c_str(), T.width, T.height,
                a.spp, opt.maxDepth);
    std::printf("  %-44s %12.2f Mrays/s\n", r.workload.c_str(), r.raysPerSecond() / 1e6);
    std::printf("  %-44s %12.2f Mrays/s   (%.1f%% of the renderer)\n", p.workload.c_str(),
                p.raysPerSecond() / 1e6, 100.0 * p.raysPerSecond() / r.raysPerSecond());
    std::printf("  T: %s, nnz %zu, density %.4f, %.1f MB\n",
                T.storage == TransportStorage::Sparse ? "CSR" : "dense", T.nnz(), T.density(),
                static_cast<double>(T.bytes()) / 1e6);
    std::printf("  %-44s %12.3f ms\n", "streaming read of T's bytes", tRead * 1e3);
    std::printf("  %-44s %12.3f ms   (%.2f x the streaming read)\n", "T.E (luminance product)",
                tApply * 1e3, tApply / tRead);
    std::printf("  %-44s %12.3f ms   (%.2f x the streaming read; %.2f Gnnz/s)\n",
                "one iteration, two passes (T.E then T'.g)", tIter * 1e3, tIter / tRead,
                2.0 * static_cast<double>(T.nnz()) / tIter / 1e9);
    std::printf("  %-44s %12.3f ms   (%.2f x the streaming read)\n",
                "one iteration, fused single pass", tFused * 1e3, tFused / tRead);
    std::printf("  %-44s %12.3f s\n",
                ("Adam, " + std::to_string(a.iterations) + " iterations").c_str(), tAdam);
    std::printf("(medians: tracing of %d interleaved runs, products of %d runs)\n", a.repeats,
                reps);

    std::ostringstream os;
    {
        os << "scene,width,height,spp,renderer_rays_per_s,precompute_rays_per_s,precompute_ratio,"
              "storage,nnz,density,bytes,streaming_read_s,apply_s,iteration_two_pass_s,"
              "iteration_two_pass_ratio,iteration_fused_s,iteration_fused_ratio,adam_iterations,"
              "adam_s\n";
        os << a.scene << ',' << T.width << ',' << T.height << ',' << a.spp << ','
           << r.raysPerSecond() << ',' << p.raysPerSecond() << ','
           << p.raysPerSecond() / r.raysPerSecond() << ','
           << (T.storage == TransportStorage::Sparse ? "csr" : "dense") << ',' << T.nnz() << ','
           << T.density() << ',' << T.bytes() << ',' << tRead << ',' << tApply << ',' << tIter
           << ',' << tIter / tRead << ',' << tFused << ',' << tFused / tRead << ',' << a.iterations
           << ',' << tAdam << '\n';
    }
    writeTextAtomically(a.csv, os.str());
    std::printf("wrote %s\n", a.csv.c_str());
    return kOk;
}

struct NoiseArgs {
    NoiseBenchOptions o;
    std::string optimizers = "adam:100,lbfgs:2000";
    std::string csv = "out/bench-noise/bench-noise.csv";
    std::string groupsCsv() const {
        const auto dot = csv.rfind(".csv");
        return (dot == std::string::npos ? csv : csv.substr(0, dot)) + "-median.csv";
    }
};

int runNoiseBenchCmd(NoiseArgs a) {
    a.o.optimizers = parseNoiseBenchOptimizers(a.optimizers);
    a.o.log = [](const std::string& m) { spdlog::info("{}", m); };
    NoiseBenchResult r = runNoiseBench(a.o);
    std::printf("medians over %d training seed(s); held-out = E* scored on the shared estimate\n",
                a.o.seeds);
    std::printf("%6s %-9s %-12s %5s %10s %11s %11s %14s %10s %26s\n", "spp", "objective",
                "optimizer", "conv", "seconds", "train loss", "held-out", "held-out eq.2",
                "gap tr-ho", "vs top spp (min..max)");
    for (const NoiseBenchGroup& g : r.groups)
        std::printf(
            "%6d %-9s %-12s %2d/%-2d %10.3f %11.5g %11.5g %14.5g %+9.2f%% %+8.2f%% "
            "(%+.2f..%+.2f)\n",
            g.spp, g.objective.c_str(), g.optimizer.c_str(), g.converged, g.runs, g.seconds,
            g.trainLoss, g.heldOutLoss, g.heldOutPaper, 100.0 * g.trainGap, 100.0 * g.relToTop,
            100.0 * g.relToTopMin, 100.0 * g.relToTopMax);
    std::printf(
        "(shared held-out estimate: %d spp, traced in %.1f s; image %dx%d; seconds = "
        "precompute + optimize)\n",
        r.heldOutSpp, r.heldOutSeconds, a.o.resolution, a.o.resolution);
    std::ostringstream os;
    os << "spp,seed,objective,optimizer,iterations,converged,precompute_s,optimize_s,total_s,"
          "train_loss,heldout_loss,heldout_paper_loss,heldout_spp\n";
    for (const NoiseBenchRow& row : r.rows)
        os << row.spp << ',' << row.seed << ',' << row.objective << ',' << row.optimizer << ','
           << row.iterations << ',' << (row.converged ? 1 : 0) << ',' << row.precomputeSeconds
           << ',' << row.optimizeSeconds << ',' << row.seconds() << ',' << row.trainLoss << ','
           << row.heldOutLoss << ',' << row.heldOutPaper << ',' << r.heldOutSpp << '\n';
    std::ostringstream og;
    og << "spp,objective,optimizer,runs,converged,total_s,train_loss,heldout_loss,"
          "heldout_paper_loss,train_gap,rel_to_top,rel_to_top_min,rel_to_top_max,heldout_spp\n";
    for (const NoiseBenchGroup& g : r.groups)
        og << g.spp << ',' << g.objective << ',' << g.optimizer << ',' << g.runs << ','
           << g.converged << ',' << g.seconds << ',' << g.trainLoss << ',' << g.heldOutLoss << ','
           << g.heldOutPaper << ',' << g.trainGap << ',' << g.relToTop << ',' << g.relToTopMin
           << ',' << g.relToTopMax << ',' << r.heldOutSpp << '\n';
    writeTextAtomically(a.csv, os.str());
    writeTextAtomically(a.groupsCsv(), og.str());
    std::printf("wrote %s and %s (plot: /usr/bin/python3 scripts/plot_noise.py %s)\n",
                a.csv.c_str(), a.groupsCsv().c_str(), a.csv.c_str());
    return kOk;
}

}  // namespace

void registerBench(CLI::App& app, std::function<int()>& run) {
    CLI::App* bench = app.add_subcommand("bench", "Benchmarks (print a table, write CSV)");
    bench->require_subcommand(1);
    auto a = std::make_shared<BenchArgs>();
    CLI::App* c = bench->add_subcommand(
        "render", "Renderer rays/s vs bare Embree closest-hit rays/s; height-field build cost");
    c->add_option("scene", a->scene, "Also measure this scene (optional)");
    c->add_option("--sizes", a->sizes, "Synthetic height-map sizes (N for NxN)")
        ->delimiter(',')
        ->capture_default_str();
    c->add_option("--resolution", a->resolution, "Image width and height")
        ->check(CLI::Range(8, 4096))
        ->capture_default_str();
    c->add_option("--spp", a->spp, "Samples per pixel")
        ->check(CLI::Range(1, 4096))
        ->capture_default_str();
    c->add_option("--repeats", a->repeats, "Runs per measurement (median)")
        ->check(CLI::Range(1, 50))
        ->capture_default_str();
    c->add_option("--threads", a->threads, "Worker threads (0: all)")->capture_default_str();
    c->add_option("--csv", a->csv, "CSV output")->capture_default_str();
    c->callback([a, &run] { run = [a] { return runBench(*a); }; });

    auto b = std::make_shared<TransportBenchArgs>();
    CLI::App* t = bench->add_subcommand(
        "transport", "Precompute vs render rays/s; Adam on T; one iteration vs a read of T");
    t->add_option("scene", b->scene, "Scene file")->capture_default_str();
    t->add_option("--resolution", b->resolution, "Image width and height")
        ->check(CLI::Range(8, 4096))
        ->capture_default_str();
    t->add_option("--spp", b->spp, "Samples per pixel")
        ->check(CLI::Range(1, 65536))
        ->capture_default_str();
    t->add_option("--iterations", b->iterations, "Adam iterations")->capture_default_str();
    t->add_option("--repeats", b->repeats, "Runs per tracing measurement (median)")
        ->check(CLI::Range(1, 50))
        ->capture_default_str();
    t->add_option("--threads", b->threads, "Worker threads (0: all)")->capture_default_str();
    t->add_option("--csv", b->csv, "CSV output")->capture_default_str();
    t->callback([b, &run] { run = [b] { return runTransportBench(*b); }; });

    auto n = std::make_shared<NoiseArgs>();
    CLI::App* nc = bench->add_subcommand(
        "noise",
        "Speed against quality: spp sweep over training seeds, paper vs noise-unbiased "
        "objective, each optimizer's budget, scored on one shared high-spp independent "
        "estimate");
    nc->add_option("scene", n->o.scene, "Scene file")->required();
    nc->add_option("--resolution", n->o.resolution, "Image width and height")
        ->check(CLI::Range(8, 4096))
        ->capture_default_str();
    nc->add_option("--spps", n->o.spps, "Training spp values (even)")
        ->delimiter(',')
        ->capture_default_str();
    nc->add_option("--heldout-spp", n->o.heldOutSpp, "spp of the shared held-out estimate")
        ->capture_default_str();
    nc->add_option("--seeds", n->o.seeds, "Training seeds per spp (medians over them)")
        ->check(CLI::Range(1, 100))
        ->capture_default_str();
    nc->add_option("--optimizers", n->optimizers,
                   "METHOD[:BUDGET],... (budget: adam steps, NLopt evaluations, Ceres "
                   "iterations)")
        ->capture_default_str();
    nc->add_option("--threads", n->o.threads, "Worker threads (0: all)")->capture_default_str();
    nc->add_option("--csv", n->csv, "CSV output")->capture_default_str();
    nc->callback([n, &run] { run = [n] { return runNoiseBenchCmd(*n); }; });
}

}  // namespace sl::cli
