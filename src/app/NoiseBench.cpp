#include "app/NoiseBench.h"

#include <chrono>

#include "app/HeldOut.h"
#include "core/Error.h"
#include "io/SceneFile.h"
#include "objective/TransportLoss.h"
#include "optimize/InitialState.h"
#include "render/Render.h"
#include "scene/Scene.h"
#include "transport/TransportSink.h"

namespace sl {

namespace {
double since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

NoiseBenchResult runNoiseBench(const NoiseBenchOptions& o) {
    for (int spp : o.spps)
        if (spp < 2 || spp % 2)
            throw inputError("--spps", "every spp must be even and >= 2 (two sample sets)");
    if (o.heldOutSpp < 2 || o.heldOutSpp % 2)
        throw inputError("--heldout-spp", "must be even and >= 2");
    auto log = [&](const std::string& m) {
        if (o.log) o.log(m);
    };
    SceneDesc d = readSceneFile(o.scene);
    d.camera.width = d.camera.height = o.resolution;
    auto scene = loadScene(d);
    RenderOptions base = renderOptionsFor(*scene);
    base.threads = o.threads;
    base.sampleSets = 2;

    NoiseBenchResult res;
    res.heldOutSpp = o.heldOutSpp;
    RenderOptions ho = base;
    ho.spp = o.heldOutSpp;
    ho.seed = base.seed + kHeldOutSeedOffset;
    auto t0 = std::chrono::steady_clock::now();
    log("tracing the shared held-out estimate at " + std::to_string(o.heldOutSpp) + " spp");
    TransportMatrix held = precomputeTransport(*scene, ho, 1).matrix;
    res.heldOutSeconds = since(t0);

    for (int spp : o.spps) {
        RenderOptions ro = base;
        ro.spp = spp;
        t0 = std::chrono::steady_clock::now();
        TransportMatrix t = precomputeTransport(*scene, ro, 1).matrix;
        const double pre = since(t0);
        log("spp " + std::to_string(spp) + ": T traced in " + std::to_string(pre) + " s");
        for (const char* kind : {"paper", "unbiased"}) {
            const bool unbiased = std::string(kind) == "unbiased";
            ObjectiveOptions oo;  // the paper's λ = 30 on E
            ImageObjective paper(t.width, t.height, t.objectMask, oo);
            UnbiasedObjective unb(t.width, t.height, t.objectMask, oo);
            TransportLoss loss =
                unbiased ? TransportLoss(t, unb, false) : TransportLoss(t, paper, false);
            std::vector<double> e = initialEnvMap("const:0.5", t.envWidth, t.envHeight, false);
            OptimizerOptions opt;
            opt.iterations = o.iterations;
            OptimizerSummary sum = minimize(loss.problem(), e, opt);
            HeldOutScore h = HeldOutScorer(held, t.objectMask, oo, unbiased, false).score(e);
            NoiseBenchRow row;
            row.spp = spp;
            row.objective = kind;
            row.precomputeSeconds = pre;
            row.optimizeSeconds = sum.seconds;
            row.trainLoss = sum.finalLoss;
            row.heldOutLoss = h.own.total;
            row.heldOutPaper = h.paper.total;
            res.rows.push_back(row);
        }
    }
    return res;
}

}  // namespace sl
