#include "app/bench/NoiseBench.h"

#include <map>
#include <tuple>

#include "app/pipeline/HeldOut.h"
#include "app/pipeline/InitialState.h"
#include "core/Error.h"
#include "core/Interrupt.h"
#include "core/Progress.h"
#include "core/Registry.h"
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

// The shared held-out estimate of the bench: the training seed + this offset.
constexpr uint64_t kHeldOutSeedOffset = 0x9E3779B97F4A7C15ULL;

[[noreturn]] void badOptimizers(const std::string& spec, const std::string& why) {
    throw inputError(option("optimizers") + " " + spec, why,
                     "give METHOD[:BUDGET] items separated by commas, e.g. adam:100,lbfgs:2000");
}

}  // namespace

std::vector<NoiseBenchOptimizer> parseNoiseBenchOptimizers(const std::string& spec) {
    std::vector<NoiseBenchOptimizer> out;
    size_t start = 0;
    while (start <= spec.size()) {
        const size_t comma = std::min(spec.find(',', start), spec.size());
        const std::string item = spec.substr(start, comma - start);
        start = comma + 1;
        if (item.empty()) badOptimizers(spec, "an item is empty");
        const size_t colon = item.find(':');
        NoiseBenchOptimizer o;
        const std::string name = item.substr(0, colon);
        const OptimizerMethodRow* row = findRegistryRow(optimizerMethodTable(), name);
        if (!row || row->gradient != GradientSource::Exact || row->runs != row->value)
            badOptimizers(spec, "'" + name + "' is not an optimizer that runs on T");
        o.method = row->value;
        o.budget = row->defaultBudget;
        if (colon != std::string::npos) {
            const std::string b = item.substr(colon + 1);
            try {
                size_t used = 0;
                o.budget = std::stoi(b, &used);
                if (used != b.size()) throw std::invalid_argument(b);
            } catch (const std::exception&) {
                badOptimizers(spec, "budget '" + b + "' is not a whole number");
            }
            if (o.budget < 1) badOptimizers(spec, "budget '" + b + "' must be >= 1");
        }
        out.push_back(o);
        if (comma == spec.size()) break;
    }
    return out;
}

std::vector<NoiseBenchGroup> summarizeNoiseBench(const std::vector<NoiseBenchRow>& rows) {
    using Key = std::tuple<std::string, std::string, int>;  // objective, optimizer, spp
    std::map<Key, std::vector<const NoiseBenchRow*>> byKey;
    for (const NoiseBenchRow& r : rows) byKey[{r.objective, r.optimizer, r.spp}].push_back(&r);
    std::vector<NoiseBenchGroup> groups;
    for (const auto& [key, members] : byKey) {
        NoiseBenchGroup g;
        std::tie(g.objective, g.optimizer, g.spp) = key;
        g.runs = static_cast<int>(members.size());
        std::vector<double> secs, train, held, paper, gap;
        for (const NoiseBenchRow* r : members) {
            g.converged += r->converged ? 1 : 0;
            secs.push_back(r->seconds());
            train.push_back(r->trainLoss);
            held.push_back(r->heldOutLoss);
            paper.push_back(r->heldOutPaper);
            gap.push_back((r->trainLoss - r->heldOutLoss) / r->heldOutLoss);
        }
        g.seconds = median(secs);
        g.trainLoss = median(train);
        g.heldOutLoss = median(held);
        g.heldOutPaper = median(paper);
        g.trainGap = median(gap);
        groups.push_back(g);
    }
    // Relative to the same objective and optimizer at the largest spp (map order: spp last).
    for (NoiseBenchGroup& g : groups) {
        const NoiseBenchGroup* top = nullptr;
        for (const NoiseBenchGroup& h : groups)
            if (h.objective == g.objective && h.optimizer == g.optimizer &&
                (!top || h.spp > top->spp))
                top = &h;
        g.relToTop = (g.heldOutLoss - top->heldOutLoss) / top->heldOutLoss;
        g.relToTopMin = g.relToTopMax = g.relToTop;
        for (const NoiseBenchRow* r : byKey[{g.objective, g.optimizer, g.spp}]) {
            const double rel = (r->heldOutLoss - top->heldOutLoss) / top->heldOutLoss;
            g.relToTopMin = std::min(g.relToTopMin, rel);
            g.relToTopMax = std::max(g.relToTopMax, rel);
        }
    }
    return groups;
}

NoiseBenchResult runNoiseBench(const NoiseBenchOptions& o) {
    for (int spp : o.spps)
        if (spp < 2 || spp % 2)
            throw inputError(option("spps"), "every spp must be even and >= 2 (two sample sets)");
    if (o.spps.empty()) throw inputError(option("spps"), "no spp given");
    if (o.heldOutSpp < 2 || o.heldOutSpp % 2)
        throw inputError(option("heldout-spp"), "must be even and >= 2");
    if (o.seeds < 1) throw inputError(option("seeds"), "must be >= 1");
    if (o.optimizers.empty()) throw inputError(option("optimizers"), "no optimizer given");
    auto log = [&](const std::string& m) {
        if (o.log) o.log(m);
    };
    SceneDesc d = readSceneFile(o.scene, o.sceneOverrides);
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
    Stopwatch clock;
    log("tracing the shared held-out estimate at " + std::to_string(o.heldOutSpp) + " spp");
    const TransportMatrix held = precomputeTransport(*scene, ho, 1).matrix;
    res.heldOutSeconds = clock.seconds();

    const ObjectiveOptions oo;  // the paper's λ = 30 on E
    ProgressTask task("bench noise",
                      static_cast<double>(o.spps.size() * o.optimizers.size()) * o.seeds * 2);
    for (int spp : o.spps) {
        for (int s = 0; s < o.seeds; ++s) {
            RenderOptions ro = base;
            ro.spp = spp;
            ro.seed = base.seed + static_cast<uint64_t>(s);
            clock.restart();
            const TransportMatrix t = precomputeTransport(*scene, ro, 1).matrix;
            const double pre = clock.seconds();
            log("spp " + std::to_string(spp) + ", seed " + std::to_string(ro.seed) +
                ": T traced in " + std::to_string(pre) + " s");
            for (const char* kind : {"paper", "unbiased"}) {
                const bool unbiased = std::string(kind) == "unbiased";
                ImageObjective paper(t.width, t.height, t.objectMask, oo);
                UnbiasedObjective unb(t.width, t.height, t.objectMask, oo);
                TransportLoss loss =
                    unbiased ? TransportLoss(t, unb, false) : TransportLoss(t, paper, false);
                const HeldOutScorer scorer(
                    held, t.objectMask, oo,
                    unbiased ? ObjectiveKind::Unbiased : ObjectiveKind::Paper, false);
                for (const NoiseBenchOptimizer& m : o.optimizers) {
                    std::vector<double> e =
                        initialEnvMap(InitialState{}, t.envWidth, t.envHeight, false);  // 0.5
                    OptimizerOptions opt;
                    opt.method = m.method;
                    opt.iterations = m.budget;
                    opt.callback = [](const IterationRecord&, std::span<const double>) {
                        return !interruptRequested();  // Ctrl-C: stop here, then throw
                    };
                    const OptimizerSummary sum = minimize(loss.problem(), e, opt);
                    throwIfInterrupted();
                    task.advance();
                    const HeldOutScore h = scorer.score(e);
                    NoiseBenchRow row;
                    row.spp = spp;
                    row.seed = ro.seed;
                    row.objective = kind;
                    row.optimizer = methodName(m.method);
                    row.iterations = sum.iterations;
                    const bool steps = methodRow(m.method).budget == BudgetUnit::Steps;
                    row.converged =
                        (steps ? sum.iterations : sum.evaluations) < m.budget && !sum.failed;
                    row.precomputeSeconds = pre;
                    row.optimizeSeconds = sum.seconds;
                    row.trainLoss = sum.finalLoss;
                    row.heldOutLoss = h.own.total;
                    row.heldOutPaper = h.paper.total;
                    res.rows.push_back(row);
                }
            }
        }
    }
    res.groups = summarizeNoiseBench(res.rows);
    return res;
}

}  // namespace sl
