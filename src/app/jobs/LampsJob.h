// The `lamps` job: from an optimized env map E* to K physical lamps an inspector can mount,
// fitted through T (optimize/LampFit.h), with what each extra lamp buys and the judge's word on
// them.
//
// OUTDIR (replaced as a unit, io/StagedDirectory.h) holds:
//   lamps.json          per lamp: kind, azimuth/elevation in degrees in the part's frame
//                       (scene/Lamp.h: azimuth 0° toward −z, 90° toward +x, elevation 90° = +Y),
//                       angular size, radiance relative to the brightest lamp and absolute (E's
//                       units), and at `distance` mm from the part's centre the position (x, y,
//                       z in the scene's frame, mm) and physical size (mm) of the source
//   lamps-envmap.exr/png   the lamps rasterized on the env-map grid (E of the lamps)
//   target-envmap.exr/png  E* (the env map the lamps imitate)
//   render-lamps.exr/png, render-target.exr/png   T·E under each; renders.png: the two side by
//                       side (left E*, right the lamps), one exposure (E*'s)
//   greedy.csv          k, loss, loss relative to E*'s, seconds, one row per k = 1..K
//   summary.json        the options, T's facts, the losses, the self-checked answer (which K,
//                       or the studio lamp, is best on a validation estimate), the judge's scores
//                       (E*, the lamps, the studio lamp: the objective itself on the judge's
//                       held-out estimate, and eq. 2, U, brightness and per-region visibility) when
//                       the judge's estimate is available, the timings (seconds_phases: load,
//                       target, fit, judge, self_check, outputs)
//   plot-lamps.json, plot-lamps.png   the polar hemisphere plot of the lamps over E*, drawn
//                       in-process (app/report/LampsFigure.h; scripts/plot_lamps.py draws the
//                       same from plot-lamps.json by hand)
//   report.html         the renders side by side, the plot, the table
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "app/pipeline/Answer.h"
#include "app/pipeline/Cache.h"
#include "app/pipeline/Judge.h"
#include "app/pipeline/Transport.h"
#include "app/pipeline/Truth.h"
#include "objective/Objective.h"
#include "objective/ObjectiveKind.h"
#include "optimize/LampFit.h"

namespace sl {

struct LampsJobOptions {
    std::filesystem::path input;              // scene (.json) or transport matrix (.tm)
    std::vector<std::string> sceneOverrides;  // -D key=value (io/SceneFile.h)
    std::filesystem::path outDir = "out/lamps";
    /// E*: a light spec (io/EnvMapIO.h lightFromSpec); empty: optimized here on T with
    /// optimize's method (L-BFGS) from the specular start (const:0.5 without a scene).
    std::string from;
    /// unset: unbiased (needs T's halves), paper for a .tm without halves; defects when the
    /// defects are named (truth or defects), as optimize.
    std::optional<ObjectiveKind> objectiveKind;
    /// The defects objective's regions, as optimize's (app/jobs/OptimizeJob.h): the truth (labels
    /// in height-map space, also what the judge's per-region visibility is of), the defect region
    /// (empty: the truth, else auto) and the reference (empty: the part off the defects).
    std::filesystem::path truth;
    RegionSpec defects, reference;
    ObjectiveOptions objective;  // λ 30 by default (optimize's)
    LampFitOptions fit;
    double distanceMm = 500;  // where the lamps are mounted, from the part's centre
    bool judge = true;        // score E*, the lamps and the studio lamp on the judge's estimate
    /// The self-checked answer (app/pipeline/Answer.h): the lamps of every K and the studio lamp
    /// scored on a validation estimate (the training trace again with its own seed); the best
    /// eligible one is the answer, said first. Needs the scene.
    bool selfCheck = true;
    bool figures = true;  // plot-lamps.png (app/report/LampsFigure.h)
    std::string commandLine;
    PrecomputeOptions precompute;
    CacheLocation cache;
};

/// The judge's word on E*, the lamps and the studio lamp for the objective fitted: for paper and
/// unbiased the objective itself on the held-out estimate (eq. 2, U; lower is better), for
/// defects the defect region's visibility on it (higher is better; the defects objective is
/// −log visibility² plus exposure terms, so its values cross zero and a ratio of them means
/// nothing). gap: how much worse the lamps are than E*, relative (> 0: worse).
struct LampsJudgement {
    std::string measure;  // "U", "eq. 2" or "defect visibility"
    bool higherIsBetter = false;
    double target = 0, lamps = 0, studio = 0;
    double gap = 0;
    /// How the lamps compare with E* in words: "within 5 % of", "worse than" or "better than".
    const char* verdict() const {
        return gap >= -0.05 && gap <= 0.05 ? "within 5 % of"
                                           : (gap > 0 ? "worse than" : "better than");
    }
};

/// Where a lamps run's wall seconds went (summary.json "seconds_phases").
struct LampsPhases {
    double load = 0;       // T (from the file or the cache, or traced) and the scene
    double target = 0;     // E* (optimized on T, or read)
    double fit = 0;        // the lamps, K = 1..count
    double judge = 0;      // the judge's estimate and its scores
    double selfCheck = 0;  // the validation estimate and the candidates' scores
    double outputs = 0;    // the files and the figure (the summary and the report after it)
};

struct LampsJobSummary {
    ObjectiveKind objective = ObjectiveKind::Unbiased;
    TransportSource transport;
    LampFitResult fit;
    double targetLoss = 0;
    double secondsTarget = 0;  // optimizing E* (0 with `from`)
    std::optional<JudgeScore> judgedTarget, judgedLamps, judgedStudio;
    std::optional<LampsJudgement> judgement;
    std::string plotMessage;  // why the plot is missing ("" when made)
    /// The self-check (with a scene and selfCheck): candidates "K lamps" for every K, and
    /// "studio preset"; answerLine says what the answer is, first.
    std::optional<AnswerChoice> answer;
    std::string answerLine;
    LampsPhases phases;
};

LampsJobSummary runLampsJob(const LampsJobOptions& options);

}  // namespace sl
