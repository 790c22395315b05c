#include "app/jobs/OptimizePlan.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <utility>

#include "app/host/Version.h"
#include "app/pipeline/Cache.h"
#include "app/pipeline/InitialState.h"
#include "app/pipeline/JudgeEstimate.h"
#include "app/pipeline/Search.h"
#include "app/pipeline/Truth.h"
#include "app/report/OptimizeFigures.h"
#include "app/report/PartSummary.h"
#include "app/report/Preview.h"
#include "app/report/Report.h"
#include "core/Color.h"
#include "core/Error.h"
#include "core/Hash.h"
#include "core/Interrupt.h"
#include "core/Progress.h"
#include "core/Registry.h"
#include "core/Stopwatch.h"
#include "core/Text.h"
#include "io/AtomicFile.h"
#include "io/EnvMapIO.h"
#include "io/ImageIO.h"
#include "io/MaskIO.h"
#include "io/OptimizeOutDir.h"
#include "io/SceneFile.h"
#include "io/StagedDirectory.h"
#include "io/TransportFile.h"
#include "objective/ImageSpace.h"
#include "objective/Metrics.h"
#include "objective/TransportLoss.h"
#include "objective/UnbiasedObjective.h"
#include "optimize/PaperSetup.h"
#include "optimize/SpecularInit.h"
#include "render/Footprint.h"
#include "render/Render.h"
#include "scene/EnvMapBasis.h"
#include "scene/EnvMapPresets.h"
#include "scene/EnvMapToE.h"
#include "scene/Scene.h"

namespace sl::optimizejob {

Plan plan(const OptimizeJobOptions& options) {
    if (options.lambdas.empty()) throw inputError(option("lambda"), "no value given");
    for (double l : options.lambdas)
        if (!(l >= 0) || !std::isfinite(l))
            throw inputError(option("lambda"), "must be >= 0",
                             "give e.g. 30, or 10,30,100 for a sweep");
    if (options.estimates < 0) throw inputError(option("estimates"), "must be >= 1");
    if (options.heldOutEvery < 1) throw inputError(option("heldout-every"), "must be >= 1");
    Plan p;
    p.o = options;
    OptimizeJobOptions& o = p.o;
    p.requested = o.optimizer.method;
    const OptimizerMethodRow& row = methodRow(p.requested);
    if (p.requested == OptimizerMethod::PaperLoop) {
        // The paper's loop on T (optimize/PaperSetup.h): eq. 2, Adam, a fresh sample set
        // (estimate of T) every step, from the paper's E0.
        o.objectiveKind = kPaperSetup.objective;
        if (o.starts.empty()) o.starts = {parseInitialState(kPaperSetup.startSpec)};
    }
    if (p.requested != OptimizerMethod::PaperLoop && row.gradient == GradientSource::Renderer) {
        // A black box minimizes eq. 2 through the renderer (optimize/BlackBox.h RenderLoss): the
        // run's loss is that objective, and nothing else is reported as its loss.
        if (o.objectiveKind && *o.objectiveKind != ObjectiveKind::Paper)
            throw inputError(
                option("objective") + " " + objectiveKindName(*o.objectiveKind),
                std::string("the black-box optimizer ") + row.name +
                    " minimizes the paper's eq. 2 through the renderer",
                "drop " + option("objective") + ", or optimize on T (e.g. the default optimizer)");
        o.objectiveKind = ObjectiveKind::Paper;
    }
    if (o.starts.empty())
        for (const std::string& spec : optimizeDefaults().starts)
            o.starts.push_back(parseInitialState(spec));
    p.requestedOptimizer = o.optimizer;
    o.optimizer = resolveOptimizer(o.optimizer);  // the method that runs; iterations 0: its budget
    if (o.estimates == 0) o.estimates = row.defaultEstimates;
    p.blackBox = row.gradient == GradientSource::Renderer;
    p.tmInput = isTransportFile(o.input);
    if (p.tmInput && !o.sceneOverrides.empty())
        throw inputError(o.input.string(),
                         "is a traced transport matrix: scene overrides (" + option("D") + ", " +
                             option("width") + ", " + option("height") + ", " + option("size") +
                             ") cannot change it",
                         "pass the scene file with the overrides instead of the .tm");
    if (o.renderer != RendererKind::Builtin && !p.blackBox)
        throw inputError(
            option("renderer") + " " + registryRow(rendererKindTable(), o.renderer).name,
            "only the black-box optimizers (fd-adam, spsa) render through it",
            "use " + option("optimizer") +
                " spsa or fd-adam, or build its T with "
                "precompute " +
                option("renderer") + " and optimize the .tm");
    if (o.renderer != RendererKind::Builtin) (void)externalRendererOptions(o.renderer, o.external);
    if (p.blackBox && p.tmInput)
        throw inputError(option("optimizer") + " " + row.name,
                         "renders the scene for every gradient, so it needs the scene file",
                         "pass SCENE.json instead of the .tm");
    if (p.tmInput && o.estimates > 1)
        throw inputError(option("estimates") + " " + std::to_string(o.estimates),
                         "needs independent estimates of T traced from the scene",
                         "pass SCENE.json instead of the .tm, or " + option("estimates") + " 1");
    p.cacheDir = cacheDirectory(o.cache);
    // Noise-aware training: spp auto (the default) adapts; a given spp is measured and kept.
    p.noise.maxGap = o.precompute.sppTolerance;
    if (o.noiseMaxSpp) p.noise.maxSpp = o.noiseMaxSpp;  // else scaled to the image when loaded
    if (!(p.noise.maxGap > 0 && p.noise.maxGap < 1))
        throw inputError(option("tolerance"), "is " + formatNumber(p.noise.maxGap, 3),
                         "use a relative train/validation gap in (0, 1), e.g. 0.05");
    if (p.noise.maxSpp < 1) throw inputError(option("max-spp"), "must be >= 1");
    p.noise.adapt = !p.tmInput && (o.precompute.autoSpp || !o.precompute.spp);
    o.precompute.autoSpp = false;  // the rule replaces the gradient-noise pilot here
    const bool distributed = o.ranks && o.ranks->distributed();
    p.validate =
        !distributed && p.requested != OptimizerMethod::PaperLoop && (o.selfCheck || !p.blackBox);
    if (p.blackBox || o.estimates > 1 || !p.validate) p.noise.adapt = false;
    // A given T (.tm, .shards) keeps its per-texel light as the spp it was traced at, so one
    // process and MPI ranks (which cannot validate) return the same light from it.
    p.noise.adaptGrid = !o.lightGrid && !p.blackBox && o.estimates == 1 && p.validate && !p.tmInput;
    p.superSampleDefects = !p.blackBox && !distributed;
    if (o.ranks && o.ranks->distributed()) {
        p.ranks = o.ranks;
        const std::string over = "over " + std::to_string(p.ranks->size()) + " MPI ranks";
        if (o.input.extension() != ".shards")
            throw inputError(
                o.input.string(),
                over + " optimize needs a .shards list of T's row shards, one per rank",
                "trace the shards with `precompute " + option("rows") +
                    " A:B` and list them (docs/CLUSTER.md)");
        if (o.heldOut.mode != HeldOutMode::None)
            throw inputError(option("heldout"),
                             over +
                                 " the held-out estimate is not supported (it is a whole T, "
                                 "traced or read in one process)",
                             "pass " + option("heldout") +
                                 " none, and judge E* afterwards with "
                                 "`scratchlight judge`");
    }
    return p;
}

}  // namespace sl::optimizejob
