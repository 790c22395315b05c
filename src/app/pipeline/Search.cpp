#include "app/pipeline/Search.h"

#include <limits>
#include <memory>
#include <optional>

#include "app/pipeline/Cache.h"
#include "app/pipeline/InitialState.h"
#include "core/Error.h"
#include "core/Stopwatch.h"
#include "objective/BothMeasuresObjective.h"
#include "objective/CoarseLight.h"
#include "objective/DefectObjective.h"
#include "objective/JndObjective.h"
#include "objective/TransportLoss.h"
#include "objective/UnbiasedObjective.h"
#include "scene/EnvMapPresets.h"
#include "scene/EnvMapToE.h"

namespace sl {

std::vector<double> defaultLampE(int envWidth, int envHeight, bool rgb) {
    return envMapToE(studioEnvMap(envWidth, envHeight), rgb ? 3 : 1);
}

ObjectiveOnT objectiveOnT(ObjectiveKind kind, const TransportMatrix& t, const SearchInputs& in,
                          const ObjectiveOptions& oo) {
    ObjectiveOnT r;
    switch (kind) {
        case ObjectiveKind::Paper: {
            auto paper = std::make_unique<ImageObjective>(t.width, t.height, in.mask, oo);
            r.loss = std::make_unique<TransportLoss>(t, *paper, in.rgb);
            r.paper = std::move(paper);
            break;
        }
        case ObjectiveKind::Unbiased:
            r.halves = std::make_unique<UnbiasedObjective>(t.width, t.height, in.mask, oo);
            r.loss = std::make_unique<TransportLoss>(t, *r.halves, in.rgb);
            break;
        case ObjectiveKind::Defects: {
            DefectObjectiveOptions d;
            d.whiteMean = whiteFurnaceMean(t, in.mask, in.shard);
            JndObjectiveOptions j;
            j.view = oo.viewing.pixelsPerDegree > 0 ? oo.viewing : defaultViewing();
            j.band = d;
            if (oo.defectMeasure == DefectMeasure::Jnd) {
                r.halves = std::make_unique<JndObjective>(t.width, t.height, in.mask, in.defects,
                                                          in.reference, oo, j);
            } else if (oo.defectMeasure == DefectMeasure::Both) {
                auto both = std::make_unique<BothMeasuresObjective>(
                    t.width, t.height, in.mask, in.defects, in.reference, oo, j);
                // The user's lamp; without one, the studio preset (as optimize's comparison).
                const std::vector<double> anchor =
                    oo.anchorLight.empty() ? defaultLampE(t.envWidth, t.envHeight, in.rgb)
                                           : oo.anchorLight;
                both->setAnchors(measureAnchors(t, *both, anchor, in.rgb, in.shard));
                r.halves = std::move(both);
            } else {
                r.halves = std::make_unique<DefectObjective>(t.width, t.height, in.mask, in.defects,
                                                             in.reference, oo, d);
            }
            r.loss = std::make_unique<TransportLoss>(t, *r.halves, in.rgb);
            break;
        }
    }
    r.loss->distribute(in.shard);
    return r;
}

namespace {

/// The losses of one stage (one λ) on every estimate.
struct StageLosses {
    std::vector<ObjectiveOnT> parts;
    std::unique_ptr<CyclingLoss> cycling;

    StageLosses(const SearchInputs& in, ObjectiveKind kind, const ObjectiveOptions& oo,
                size_t count) {
        std::vector<const TransportLoss*> ptrs;
        for (size_t k = 0; k < count; ++k) {
            parts.push_back(objectiveOnT(kind, *in.set[k], in, oo));
            ptrs.push_back(parts.back().loss.get());
        }
        cycling = std::make_unique<CyclingLoss>(ptrs);
    }
    /// The problem of one run; every run starts its cycle at the first estimate, so a start's
    /// result does not depend on the starts before it.
    Problem problem(LossParts* last) {
        cycling->restart();
        return parts.size() == 1 ? parts.front().loss->problem(last) : cycling->problem(last);
    }
    LossParts value(std::span<const double> e) { return cycling->evaluate(e, {}); }
};

}  // namespace

SearchResult search(const SearchInputs& in, const SearchOptions& o) {
    if (o.estimates < 1) throw inputError(option("estimates"), "must be >= 1", "use 1 for one T");
    if (in.set.size() < static_cast<size_t>(o.estimates))
        throw std::invalid_argument("search: fewer estimates of T than asked for");
    if (o.starts.empty())
        throw inputError(option("starts"), "no start given", "use e.g. const:0.5");
    for (double f : o.continuation)
        if (!(f > 0) || !std::isfinite(f))
            throw inputError(option("continuation"), "λ factors must be > 0", "use e.g. 4,2");
    const Stopwatch clock;
    const TransportMatrix& t = *in.set.front();
    const auto count = static_cast<size_t>(o.estimates);
    std::optional<CoarseLight> grid;
    if (!o.lightGrid.perTexel() &&
        (o.lightGrid.width != t.envWidth || o.lightGrid.height != t.envHeight))
        grid.emplace(t.envWidth, t.envHeight, o.lightGrid.width, o.lightGrid.height,
                     in.rgb ? 3 : 1);

    // The final stage's losses judge the starts; earlier stages are built per run.
    StageLosses finalStage(in, o.objective, in.objective, count);
    // set[0]'s Gram matrices from the cache when kept there; held for the whole search, so
    // every stage's loss on set[0] reads the same ones.
    const std::shared_ptr<const TransportGram> gram =
        cachedGram(in.gramCache, in.fingerprint, *finalStage.parts.front().loss);
    std::vector<double> stages = o.continuation;
    stages.push_back(1.0);

    SearchResult best;
    best.training.total = std::numeric_limits<double>::infinity();
    int iterationBase = 0, evaluations = 0, iterations = 0;
    bool stopped = false;
    if (!in.startValues.empty() && in.startValues.size() != o.starts.size())
        throw std::invalid_argument("search: startValues do not match the starts");
    for (size_t k = 0; k < o.starts.size() && !stopped; ++k) {
        const InitialState& start = o.starts[k];
        std::vector<double> e =
            in.startValues.empty()
                ? initialEnvMap(start, t.envWidth, t.envHeight, in.rgb, in.scene, in.maxDepth)
                : in.startValues[k];
        OptimizerSummary last;
        for (double factor : stages) {
            ObjectiveOptions oo = in.objective;
            oo.lambda = in.objective.lambda * factor;
            std::unique_ptr<StageLosses> own;
            StageLosses* stage = &finalStage;
            if (factor != 1.0) {
                own = std::make_unique<StageLosses>(in, o.objective, oo, count);
                stage = own.get();
            }
            OptimizerOptions opt = o.optimizer;
            const int base = iterationBase;
            opt.callback = [&](const IterationRecord& r, std::span<const double> x) {
                if (!in.callback) return true;
                IterationRecord shifted = r;
                shifted.iteration += base;
                const bool go =
                    grid ? in.callback(shifted, grid->prolong(x)) : in.callback(shifted, x);
                if (!go) stopped = true;
                return go;
            };
            if (grid) {
                std::vector<double> theta = grid->project(e);
                last = minimize(grid->over(stage->problem(nullptr)), theta, opt);
                e = grid->prolong(theta);
            } else {
                last = minimize(stage->problem(nullptr), e, opt);
            }
            iterationBase += last.iterations + 1;
            iterations += last.iterations;
            evaluations += last.evaluations;
            if (stopped) break;
        }
        const LossParts value = finalStage.value(e);
        best.startLosses.emplace_back(start.spec, value.total);
        best.startResults.push_back(e);
        if (value.total < best.training.total) {
            best.training = value;
            best.e = e;
            best.start = start.spec;
            best.optimizer = last;
        }
    }
    best.optimizer.iterations = iterations;
    best.optimizer.evaluations = evaluations;
    best.optimizer.seconds = clock.seconds();
    best.optimizer.finalLoss = best.training.total;
    return best;
}

}  // namespace sl
