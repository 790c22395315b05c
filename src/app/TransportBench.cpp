#include "app/TransportBench.h"

#include <algorithm>
#include <sstream>
#include <vector>

#include "app/InitialState.h"
#include "app/Plot.h"
#include "app/RenderBench.h"
#include "core/Error.h"
#include "core/Progress.h"
#include "core/Stats.h"
#include "core/Stopwatch.h"
#include "io/SceneFile.h"
#include "objective/TransportLoss.h"
#include "optimize/Optimizer.h"
#include "render/Render.h"
#include "scene/Scene.h"
#include "transport/TransportSink.h"

namespace sl {

namespace {

template <typename F>
double medianSeconds(int repeats, F&& f) {
    std::vector<double> t;
    for (int i = 0; i < repeats; ++i) t.push_back(timeSeconds(f));
    return median(t);
}

}  // namespace

double TransportBenchResult::precomputeRatio() const {
    const double r = renderer.raysPerSecond();
    return r > 0 ? precompute.raysPerSecond() / r : 0;
}

TransportBenchResult runTransportBench(const TransportBenchOptions& a) {
    if (a.repeats < 1) throw inputError("repeats", "is " + std::to_string(a.repeats), "use >= 1");
    if (a.iterations < 1)
        throw inputError("iterations", "is " + std::to_string(a.iterations), "use >= 1");
    SceneDesc d =
        readSceneFile(a.scene.empty() ? bundledDefaultScene() : a.scene, a.sceneOverrides);
    d.camera.width = d.camera.height = a.resolution;
    d.render.spp = a.spp;
    auto scene = loadScene(d);
    RenderOptions opt = renderOptionsFor(*scene);
    opt.threads = a.threads;

    TransportBenchResult r;
    r.options = a;
    r.maxDepth = opt.maxDepth;
    // 1. Tracing: renderer (radiance sink) and precompute (transport sink), interleaved.
    std::vector<ThroughputRow> ren, pre;
    TransportMatrix T;
    {
        ProgressTask task("bench transport: tracing", 2.0 * a.repeats);
        for (int i = 0; i < a.repeats; ++i) {
            ren.push_back(benchRenderer(*scene, opt));
            task.advance();
            PrecomputeResult p = precomputeTransport(*scene, opt, 1);
            pre.push_back(
                {"precompute (path tracer + transport sink)", p.summary.rays, p.summary.seconds});
            task.advance();
            if (i == 0) T = std::move(p.matrix);
        }
    }
    r.renderer = medianThroughput(ren);
    r.precompute = medianThroughput(pre);
    T.threads = a.threads;
    r.width = T.width;
    r.height = T.height;
    r.sparse = T.storage == TransportStorage::Sparse;
    r.nnz = T.nnz();
    r.bytes = T.bytes();
    r.density = T.density();

    // 2. Products and the optimizer on T.
    ObjectiveOptions oo;
    ImageObjective obj(T.width, T.height, T.objectMask, oo);
    TransportLoss loss(T, obj, false);
    std::vector<double> e = initialEnvMap(InitialState{}, T.envWidth, T.envHeight, false);
    std::vector<double> g(loss.dimension());
    r.productRepeats = std::max(5, 4 * a.repeats + 1);
    const int reps = r.productRepeats;
    volatile double sink = 0;
    const ProgressTask products("bench transport: products and Adam on T");
    r.streamingRead = medianSeconds(reps, [&] { sink = sink + streamingRead(T); });
    r.iterationTwoPass = medianSeconds(reps, [&] { sink = sink + loss.evaluate(e, g).total; });
    r.iterationFused = medianSeconds(reps, [&] { sink = sink + loss.evaluateFused(e, g).total; });
    std::vector<double> y(T.rows());
    r.apply = medianSeconds(reps, [&] { T.applyLuminance(e, y); });
    r.adam = medianSeconds(a.repeats, [&] {
        std::vector<double> x = e;
        OptimizerOptions oopt;
        oopt.iterations = a.iterations;
        minimize(loss.problem(), x, oopt);
    });
    return r;
}

std::string TransportBenchResult::csv() const {
    std::ostringstream os;
    os << "scene,width,height,spp,renderer_rays_per_s,precompute_rays_per_s,precompute_ratio,"
          "storage,nnz,density,bytes,streaming_read_s,apply_s,iteration_two_pass_s,"
          "iteration_two_pass_ratio,iteration_fused_s,iteration_fused_ratio,adam_iterations,"
          "adam_s\n";
    os << options.scene.string() << ',' << width << ',' << height << ',' << options.spp << ','
       << renderer.raysPerSecond() << ',' << precompute.raysPerSecond() << ',' << precomputeRatio()
       << ',' << (sparse ? "csr" : "dense") << ',' << nnz << ',' << density << ',' << bytes << ','
       << streamingRead << ',' << apply << ',' << iterationTwoPass << ','
       << iterationTwoPass / streamingRead << ',' << iterationFused << ','
       << iterationFused / streamingRead << ',' << options.iterations << ',' << adam << '\n';
    return os.str();
}

}  // namespace sl
