#include "app/bench/TransportBench.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <tuple>
#include <utility>
#include <vector>

#include "app/bench/RenderBench.h"
#include "app/host/Plot.h"
#include "app/pipeline/InitialState.h"
#include "core/Error.h"
#include "core/Interrupt.h"
#include "core/Progress.h"
#include "core/Stats.h"
#include "core/Stopwatch.h"
#include "io/SceneFile.h"
#include "objective/TransportLoss.h"
#include "objective/UnbiasedObjective.h"
#include "optimize/Optimizer.h"
#include "render/Render.h"
#include "scene/Scene.h"
#include "transport/TransportColumns.h"
#include "transport/TransportGram.h"
#include "transport/TransportSink.h"
#include "transport/TransportSlices.h"

namespace sl {

namespace {

template <typename F>
double medianSeconds(int repeats, F&& f) {
    std::vector<double> t;
    for (int i = 0; i < repeats; ++i) {
        throwIfInterrupted();
        t.push_back(timeSeconds(f));
    }
    return median(t);
}

/// Medians of f and g timed alternately (f, g, f, g, ...): both see the same load.
template <typename F, typename G>
std::pair<double, double> medianSecondsInterleaved(int repeats, F&& f, G&& g) {
    std::vector<double> a, b;
    for (int i = 0; i < repeats; ++i) {
        throwIfInterrupted();
        a.push_back(timeSeconds(f));
        b.push_back(timeSeconds(g));
    }
    return {median(a), median(b)};
}

/// Medians of the process CPU seconds of f and g, each timed over batches of `batch` calls,
/// alternately; per call.
template <typename F, typename G>
std::pair<double, double> medianCpuInterleaved(int repeats, int batch, F&& f, G&& g) {
    std::vector<double> a, b;
    auto time = [&](auto&& h) {
        const CpuStopwatch clock;
        for (int k = 0; k < batch; ++k) h();
        return clock.seconds() / batch;
    };
    for (int i = 0; i < repeats; ++i) {
        throwIfInterrupted();
        a.push_back(time(f));
        b.push_back(time(g));
    }
    return {median(a), median(b)};
}

}  // namespace

double TransportBenchResult::precomputeRatio() const {
    const double r = renderer.raysPerSecond();
    return r > 0 ? precompute.raysPerSecond() / r : 0;
}

double TransportBenchResult::precomputeVsBare() const {
    const double b = bare.raysPerSecond();
    return b > 0 ? precompute.raysPerSecond() / b : 0;
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
    std::vector<ThroughputRow> ren, pre, bare;
    TransportMatrix T;
    {
        ProgressTask task("bench transport: tracing", 3.0 * a.repeats);
        for (int i = 0; i < a.repeats; ++i) {
            ren.push_back(benchRenderer(*scene, opt));
            task.advance();
            bare.push_back(benchBareEmbree(*scene, opt));
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
    r.bare = medianThroughput(bare);
    T.threads = a.threads;
    r.width = T.width;
    r.height = T.height;
    r.sparse = T.storage == TransportStorage::Sparse;
    r.nnz = T.nnz();
    r.bytes = T.bytes();
    r.density = T.density();

    // 2. Products and the optimizer on T, on the CSR arrays and on the slices layout.
    r.stride = T.stride();
    ObjectiveOptions oo;
    ImageObjective obj(T.width, T.height, T.objectMask, oo);
    TransportLoss csr(T, obj, false), blk(T, obj, false);
    csr.setLayout(TransportLayout::Csr);
    blk.setLayout(TransportLayout::Slices);
    const ProgressTask products("bench transport: products and Adam on T");
    r.slicesBuild = timeSeconds([&] { blk.slices(); });
    const TransportSlices& B = blk.slices();
    r.slicesBytes = B.bytes();
    r.slicesPadding = B.padding();
    std::vector<double> e = initialEnvMap(InitialState{}, T.envWidth, T.envHeight, false);
    std::vector<double> g(csr.dimension());
    r.productRepeats = std::max(5, 4 * a.repeats + 1);
    const int reps = r.productRepeats;
    volatile double sink = 0;
    r.streamingRead = medianSeconds(reps, [&] { sink = sink + streamingRead(T); });
    std::tie(r.iterationTwoPass, r.iterationTwoPassSlices) = medianSecondsInterleaved(
        reps, [&] { sink = sink + csr.evaluate(e, g).total; },
        [&] { sink = sink + blk.evaluate(e, g).total; });
    std::tie(r.iterationFused, r.iterationFusedSlices) = medianSecondsInterleaved(
        reps, [&] { sink = sink + csr.evaluateFused(e, g).total; },
        [&] { sink = sink + blk.evaluateFused(e, g).total; });
    std::vector<double> y(T.rows());
    std::tie(r.apply, r.applySlices) = medianSecondsInterleaved(
        reps, [&] { T.applyLuminance(e, y); },
        [&] { B.applyLuminance(e, y, TransportMatrix::kMeanPlane, T.threads); });
    {
        const TransportColumns C(T);
        r.columnsBytes = C.bytes();
        std::vector<double> gy(T.rows());
        for (size_t i = 0; i < gy.size(); ++i) gy[i] = y[i] - 0.25;  // a gradient-like image
        std::vector<double> out(T.cols());
        std::tie(r.transposeSlices, r.transposeColumns) = medianSecondsInterleaved(
            reps,
            [&] { B.applyTransposeLuminance(gy, out, TransportMatrix::kMeanPlane, T.threads); },
            [&] { C.transposeAll(gy, out, TransportMatrix::kMeanPlane, T.threads); });
    }
    auto adam = [&](const TransportLoss& loss) {
        std::vector<double> x = e;
        OptimizerOptions oopt;
        oopt.iterations = a.iterations;
        oopt.callback = [](const IterationRecord&, std::span<const double>) {
            return !interruptRequested();  // Ctrl-C: stop at this iteration, then throw
        };
        minimize(loss.problem(), x, oopt);
        throwIfInterrupted();
    };
    std::tie(r.adam, r.adamSlices) = medianSecondsInterleaved(
        a.repeats, [&] { adam(csr); }, [&] { adam(blk); });

    // 3. The unbiased objective on the halves: the slices' products against the Gram.
    {
        const ProgressTask halves("bench transport: the unbiased objective on T's halves");
        RenderOptions two = opt;
        two.sampleSets = 2;
        two.spp = std::max(2, opt.spp + opt.spp % 2);  // two sets need an even spp
        TransportMatrix H = precomputeTransport(*scene, two, 1).matrix;
        H.threads = a.threads;
        r.halvesNnz = H.nnz();
        r.halvesBytes = H.bytes();
        r.halvesRead = medianSeconds(reps, [&] { sink = sink + streamingRead(H); });
        UnbiasedObjective unb(H.width, H.height, H.objectMask, oo);
        TransportLoss viaSlices(H, unb, false), viaGram(H, unb, false);
        viaSlices.setLayout(TransportLayout::Slices);
        viaGram.setLayout(TransportLayout::Gram);
        viaSlices.slices();
        if (viaGram.gramEligible()) {
            r.gramBuildWork = TransportGram::buildWork(H, unb.pairMask(), unb.usesProducts());
            {
                const CpuStopwatch cpu;
                r.gramBuild = timeSeconds([&] { viaGram.gram(); });
                r.gramBuildCpu = cpu.seconds();
            }
            r.gramBytes = viaGram.gram().bytes();
            std::tie(r.unbiasedSlices, r.unbiasedGram) = medianSecondsInterleaved(
                reps, [&] { sink = sink + viaSlices.evaluateFused(e, g).total; },
                [&] { sink = sink + viaGram.evaluateFused(e, g).total; });
            std::tie(r.unbiasedSlicesCpu, r.unbiasedGramCpu) = medianCpuInterleaved(
                reps, 10, [&] { sink = sink + viaSlices.evaluateFused(e, g).total; },
                [&] { sink = sink + viaGram.evaluateFused(e, g).total; });
            RenderOptions other = two;
            other.seed = two.seed + 1;
            TransportMatrix V = precomputeTransport(*scene, other, 1).matrix;
            V.threads = a.threads;
            TransportLoss heldOut(V, unb, false);
            heldOut.setLayout(TransportLayout::Csr);
            auto lbfgs = [&](const TransportLoss& loss, std::vector<double>& x) {
                x = e;
                OptimizerOptions oopt;
                oopt.method = OptimizerMethod::Lbfgs;
                oopt.iterations = 2000;  // optimize's default budget for lbfgs
                const CpuStopwatch cpu;
                const OptimizerSummary sum = minimize(loss.problem(), x, oopt);
                const double cpuSeconds = cpu.seconds();
                throwIfInterrupted();
                TransportBenchResult::LbfgsRun run;
                run.seconds = sum.seconds;
                run.cpuSeconds = cpuSeconds;
                run.evaluations = sum.evaluations;
                run.finalLoss = sum.finalLoss;
                run.heldOutLoss = heldOut.evaluate(x, {}).total;
                return run;
            };
            std::vector<double> xs, xg;
            r.lbfgsSlices = lbfgs(viaSlices, xs);
            r.lbfgsGram = lbfgs(viaGram, xg);
            for (size_t i = 0; i < xs.size(); ++i)
                r.lbfgsMaxDifference = std::max(r.lbfgsMaxDifference, std::abs(xs[i] - xg[i]));
        }
    }
    return r;
}

double TransportBenchResult::nonZerosRead() const {
    if (bytes == 0) return 0;
    const double nzBytes = static_cast<double>(nnz) * (2.0 + 4.0 * stride);
    return streamingRead * nzBytes / static_cast<double>(bytes);
}

std::string TransportBenchResult::csv() const {
    std::ostringstream os;
    os << "scene,width,height,spp,renderer_rays_per_s,precompute_rays_per_s,precompute_ratio,"
          "bare_embree_rays_per_s,precompute_vs_bare_embree,"
          "storage,nnz,density,bytes,slices_bytes,slices_padding,slices_build_s,streaming_read_s,"
          "nonzeros_read_s,apply_s,apply_slices_s,iteration_two_pass_s,"
          "iteration_two_pass_slices_s,iteration_fused_s,iteration_fused_slices_s,"
          "iteration_fused_ratio,iteration_fused_slices_ratio,"
          "evaluation_slices_vs_nonzeros_read,adam_iterations,adam_s,adam_slices_s,"
          "transpose_slices_s,transpose_columns_s,columns_bytes,halves_nnz,halves_bytes,"
          "halves_read_s,unbiased_slices_s,unbiased_gram_s,gram_build_s,gram_build_work,"
          "gram_bytes,lbfgs_slices_s,lbfgs_slices_evaluations,lbfgs_slices_loss,"
          "lbfgs_slices_heldout_loss,lbfgs_gram_s,lbfgs_gram_evaluations,lbfgs_gram_loss,"
          "lbfgs_gram_heldout_loss,lbfgs_max_abs_difference,unbiased_slices_cpu_s,"
          "unbiased_gram_cpu_s,gram_build_cpu_s,lbfgs_slices_cpu_s,lbfgs_gram_cpu_s\n";
    os << options.scene.string() << ',' << width << ',' << height << ',' << options.spp << ','
       << renderer.raysPerSecond() << ',' << precompute.raysPerSecond() << ',' << precomputeRatio()
       << ',' << bare.raysPerSecond() << ',' << precomputeVsBare() << ','
       << (sparse ? "csr" : "dense") << ',' << nnz << ',' << density << ',' << bytes << ','
       << slicesBytes << ',' << slicesPadding << ',' << slicesBuild << ',' << streamingRead << ','
       << nonZerosRead() << ',' << apply << ',' << applySlices << ',' << iterationTwoPass << ','
       << iterationTwoPassSlices << ',' << iterationFused << ',' << iterationFusedSlices << ','
       << iterationFused / streamingRead << ',' << iterationFusedSlices / streamingRead << ','
       << iterationFusedSlices / nonZerosRead() << ',' << options.iterations << ',' << adam << ','
       << adamSlices << ',' << transposeSlices << ',' << transposeColumns << ',' << columnsBytes
       << ',' << halvesNnz << ',' << halvesBytes << ',' << halvesRead << ',' << unbiasedSlices
       << ',' << unbiasedGram << ',' << gramBuild << ',' << gramBuildWork << ',' << gramBytes << ','
       << lbfgsSlices.seconds << ',' << lbfgsSlices.evaluations << ',' << lbfgsSlices.finalLoss
       << ',' << lbfgsSlices.heldOutLoss << ',' << lbfgsGram.seconds << ',' << lbfgsGram.evaluations
       << ',' << lbfgsGram.finalLoss << ',' << lbfgsGram.heldOutLoss << ',' << lbfgsMaxDifference
       << ',' << unbiasedSlicesCpu << ',' << unbiasedGramCpu << ',' << gramBuildCpu << ','
       << lbfgsSlices.cpuSeconds << ',' << lbfgsGram.cpuSeconds << '\n';
    return os.str();
}

}  // namespace sl
