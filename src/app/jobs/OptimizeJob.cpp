#include "app/jobs/OptimizeJob.h"

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
#include "app/jobs/OptimizeOutputs.h"
#include "app/jobs/OptimizePlan.h"
#include "app/jobs/OptimizeStages.h"
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
#include "optimize/SpecularInit.h"
#include "render/Footprint.h"
#include "render/Render.h"
#include "scene/EnvMapBasis.h"
#include "scene/EnvMapPresets.h"
#include "scene/EnvMapToE.h"
#include "scene/Scene.h"

namespace sl {

using namespace optimizejob;

OptimizeJobSummary runOptimizeJob(const OptimizeJobOptions& options) {
    Plan p = plan(options);
    // OUTDIR is checked before any work and written as a unit: a failure or Ctrl-C leaves the
    // previous results as they were. Over MPI ranks, rank 0 alone writes it.
    std::optional<StagedDirectory> out;
    if (p.writes()) {
        out.emplace(p.o.outDir);
        p.o.outDir = out->target();
        p.writeDir = out->path();
    }
    OptimizeJobSummary job;
    try {
        Inputs in;
        in.ranks = p.ranks;
        // Context first, as each piece is known (the results follow the work).
        // T at `spp` (unset: the scene's or the given one), its validation estimate, and what
        // depends on T; the scene is loaded once.
        double secondsTrace = 0, secondsSearch = 0;  // every round's (OptimizeRun)
        auto load = [&](int spp) {
            Inputs kept = std::move(in);
            in = Inputs{};
            in.ranks = p.ranks;
            in.scene = std::move(kept.scene);  // loaded once
            in.part = std::move(kept.part);
            if (kept.sceneParts) {  // what does not depend on T: computed once
                in.defects = std::move(kept.defects);
                in.reference = std::move(kept.reference);
                in.unjudgedRegions = kept.unjudgedRegions;
                in.unjudgedShare = kept.unjudgedShare;
                in.truth = std::move(kept.truth);
                in.truthLabels = std::move(kept.truthLabels);
                in.lampName = std::move(kept.lampName);
                in.lampE = std::move(kept.lampE);
                in.sceneParts = true;
            }
            in.sppScale = std::move(kept.sppScale);  // chosen with the regions, on the first load
            job.extraEstimates.clear();
            const Stopwatch traceClock;
            loadTraining(p, in, job, spp);
            secondsTrace += traceClock.seconds();
            if (job.transport.autoDepth && spp == 0)
                spdlog::info("max_depth {}: {}", job.transport.autoDepth->maxDepth,
                             job.transport.autoDepth->reason);
            spdlog::info("{}", describeTransport(job.transport));
            const Stopwatch validationClock;
            loadValidation(p, in, job);
            secondsTrace += validationClock.seconds();
            prepareRuns(p, in, job);
            prepareComparisons(p, in, job);
        };
        Stopwatch round;
        double notInRound = 0;  // the judge's estimate is not part of a training round
        load(0);
        // The rule's spp caps are a budget of samples (app/pipeline/TrainingNoise.h
        // sppCapForImage): a small image may trace more spp for what a 256² trace costs.
        p.noise = p.noise.forImage(static_cast<size_t>(job.transport.file.matrix.width) *
                                       static_cast<size_t>(job.transport.file.matrix.height),
                                   p.o.noiseMaxSpp > 0);
        {
            const Stopwatch judgeClock;
            loadHeldOut(p, in, job);
            if (job.heldOut)
                spdlog::info("judge estimate (held out): {} ({} spp, seed {})",
                             job.heldOut->path.empty() ? std::string("not stored")
                                                       : job.heldOut->path.string(),
                             job.heldOut->file.provenance.spp, job.heldOut->file.provenance.seed);
            if (job.validation && job.heldOut &&
                job.validation->file.provenance.seed == job.heldOut->file.provenance.seed)
                throw inputError(option("seed"), "the validation estimate's seed is the judge's",
                                 "use another " + option("seed"));
            notInRound = judgeClock.seconds();
        }
        const double secondsHeldOut = notInRound;  // the judge's first estimate
        if (!p.cacheDir.empty() && (!p.tmInput || p.o.heldOut.mode == HeldOutMode::Judge))
            spdlog::info("cache {}", describeCache(cacheContents(p.cacheDir)));
        spdlog::info("mask: {} pixels; writing {}", job.maskPixels, p.o.outDir.string());
        std::vector<ReportRun> reportRuns;
        TrainingNoiseSummary noise;
        noise.maxGap = p.noise.maxGap;
        noise.adapted = p.noise.adapt;
        noise.gridAdapted = p.noise.adaptGrid;
        for (double lambda : p.o.lambdas) {
            Stopwatch searchClock;
            LambdaResult r = optimizeLambda(p, in, job, lambda);
            secondsSearch += searchClock.seconds();
            // Noise-aware training (app/pipeline/TrainingNoise.h), on the first λ: E* on T and on
            // V; the spp is raised (T, V and the comparisons traced again) while the gap is large.
            while (noise.rounds.size() < 16 && job.runs.empty() && r.run.validationFinal &&
                   !p.blackBox && !r.run.interrupted) {
                TrainingNoiseRound nr;
                nr.spp = job.transport.file.provenance.spp;
                nr.grid = p.o.lightGrid.value_or(LightGrid{});
                nr.validationSpp = job.validation->file.provenance.spp;
                nr.training = trainingFigure(in.kind, r.run.final);
                nr.validation = trainingFigure(in.kind, *r.run.validationFinal);
                nr.gap = trainingGap(in.kind, nr.training, nr.validation);
                // The gap's standard error, V's own noise (step 3).
                const ObjectiveOnT onV =
                    validationObjective(in, job, objectiveAt(p, in, lambda), p.o.rgb);
                const Stopwatch gapClock;
                nr.gapError = trainingGapError(
                    in.kind, *onV.loss, r.e, job.validation->file.provenance.seed, kJudgeReplicates,
                    dynamic_cast<const UnbiasedObjective*>(onV.halves.get()));
                nr.secondsGapError = gapClock.seconds();
                // Step 4: V's noise: more V (T's spp for eq. 2, whose V must keep T's spp);
                // over-fit or above the tolerance: more T, then a coarser light (step 5).
                const GapDecision next =
                    decideAfterRound(nr, in.kind, p.noise, job.transport.file.matrix.envWidth,
                                     job.transport.file.matrix.envHeight);
                nr.verdict = next.verdict;
                nr.seconds = round.seconds() - notInRound;
                noise.met = nr.verdict == GapVerdict::Within;
                noise.unresolved = next.unresolved;
                nr.decision = next.describe();
                noise.rounds.push_back(nr);
                spdlog::info(
                    "training noise: {} spp, {}, V {} spp, E*'s {} {} on T and {} on the "
                    "validation estimate: gap {} % ± {} % ({}): {}",
                    nr.spp, nr.grid.name(), nr.validationSpp,
                    figureHigherIsBetter(in.kind) ? "visibility" : "loss",
                    formatNumber(nr.training, 4), formatNumber(nr.validation, 4),
                    formatNumber(100.0 * nr.gap, 3), formatNumber(100.0 * nr.gapError, 3),
                    gapVerdictName(nr.verdict), nr.decision);
                if (next.nextValidation > 0) {
                    // The same T and E*, scored again on V at more spp: this round goes on.
                    p.validationSpp = next.nextValidation;
                    noise.rounds.back().seconds = 0;  // counted in the round that goes on
                    const Stopwatch validationClock;
                    loadValidation(p, in, job);
                    secondsTrace += validationClock.seconds();
                    r.run.validationFinal =
                        validationObjective(in, job, objectiveAt(p, in, lambda), p.o.rgb)
                            .loss->evaluate(r.e, {});
                    continue;
                }
                if (next.nextTraining == 0 && !next.coarser) break;
                noise.secondsAdded += nr.seconds;
                round.restart();
                notInRound = 0;
                std::vector<std::pair<std::string, std::vector<double>>> finer;
                if (next.nextTraining > 0) {
                    load(next.nextTraining);
                } else {
                    finer = std::move(r.finer);
                    finer.emplace_back("optimized on " + nr.grid.name() + " (gap " +
                                           formatNumber(100.0 * nr.gap, 3) + " %)",
                                       r.optimizedE.empty() ? r.e : r.optimizedE);
                    p.o.lightGrid = *next.coarser;
                }
                searchClock.restart();
                r = optimizeLambda(p, in, job, lambda);
                secondsSearch += searchClock.seconds();
                r.finer = std::move(finer);
            }
            // Ctrl-C keeps nothing (the previous OUTDIR stays) unless the user asked to keep
            // the best so far (core/Interrupt.h).
            if (!p.o.keepInterrupted) throwIfInterrupted();
            noise.reason = describeTrainingNoise(noise);
            // The seconds are printed here and recorded as seconds_added, not in the reason
            // (summary.json's text stays the same for any run of the same inputs).
            if (!noise.rounds.empty())
                spdlog::info("training spp: {}{}", noise.reason,
                             noise.rounds.size() > 1
                                 ? "; the rule added " + formatNumber(noise.secondsAdded, 3) + " s"
                                 : std::string());
            r.run.noise = noise;
            checkAnswer(p, in, job, r);
            // V's first round may be below T's spp (app/pipeline/TrainingNoise.h step 1): a
            // choice within V's noise there is made again on V at T's spp.
            if (r.run.answer && job.validation && !noise.rounds.empty() &&
                job.validation->file.provenance.spp < job.transport.file.provenance.spp &&
                !answerDecided(*r.run.answer, noise.rounds.back().gapError)) {
                p.validationSpp = job.transport.file.provenance.spp;
                spdlog::info(
                    "lambda {}: the answer is within {} standard errors on V at {} spp: V at {} "
                    "spp",
                    lambda, formatNumber(kAnswerMarginSigmas, 2),
                    job.validation->file.provenance.spp, p.validationSpp);
                const Stopwatch validationClock;
                loadValidation(p, in, job);
                secondsTrace += validationClock.seconds();
                if (!r.optimizedE.empty()) r.e = std::exchange(r.optimizedE, {});
                checkAnswer(p, in, job, r);
            }
            const Stopwatch judgeClock;
            judgeRun(p, in, job, r);
            r.run.secondsJudge = secondsHeldOut + judgeClock.seconds();
            r.run.secondsTrace = secondsTrace;
            r.run.secondsSearch = secondsSearch;
            const Stopwatch outputsClock;
            reportRuns.push_back(writeRunOutputs(p, in, job, r));
            spdlog::info(
                "lambda {}: seconds: tracing T and V {}, searching {}, self-check {}, judge {}, "
                "figures and report {}",
                r.run.lambda, formatNumber(r.run.secondsTrace, 3),
                formatNumber(r.run.secondsSearch, 3),
                formatNumber(r.run.answer ? r.run.answer->seconds : 0.0, 3),
                formatNumber(r.run.secondsJudge, 3), formatNumber(outputsClock.seconds(), 3));
            job.runs.push_back(std::move(r.run));
            if (job.runs.back().interrupted) {  // the λs after it are not run
                job.interrupted = true;
                break;
            }
        }
        if (p.o.lambdas.size() > 1 && p.writes()) writeSweep(p, in, job, reportRuns);
    } catch (const InputError& e) {
        if (out) throw InputError(out->explain(e.what()));
        throw;
    }
    if (out) out->commit(/*evenIfInterrupted=*/p.o.keepInterrupted);
    return job;
}

}  // namespace sl
