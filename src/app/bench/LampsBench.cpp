#include "app/bench/LampsBench.h"

#include <cmath>
#include <cstdio>
#include <sstream>

#include "app/bench/Race.h"
#include "app/host/Plot.h"
#include "app/jobs/LampsJob.h"
#include "core/Error.h"
#include "core/Interrupt.h"
#include "core/Progress.h"

namespace sl {

namespace {

struct BenchPart {
    std::filesystem::path scene, truth;
};

BenchPart preparePart(const std::string& name, const std::filesystem::path& workDir) {
    if (name == "bundled") {
        const std::filesystem::path scene = bundledDefaultScene();
        return {scene, scene.parent_path() / "part-truth.png"};
    }
    const PartFiles files = writeRacePart(name, workDir / name);
    return {files.scene, files.truth};
}

}  // namespace

LampsBenchResult runLampsBench(const LampsBenchOptions& o) {
    if (o.parts.empty()) throw inputError(option("parts"), "none given", "use e.g. bundled");
    if (o.objectives.empty())
        throw inputError(option("objectives"), "none given", "use e.g. unbiased");
    LampsBenchResult result;
    ProgressTask task("bench lamps", static_cast<double>(o.parts.size() * o.objectives.size()));
    const std::filesystem::path cache = std::filesystem::absolute(o.workDir) / ".cache";
    for (const std::string& partName : o.parts) {
        const BenchPart part = preparePart(partName, o.workDir);
        for (ObjectiveKind kind : o.objectives) {
            throwIfInterrupted();
            task.detail(partName + " " + objectiveKindName(kind));
            LampsJobOptions j;
            j.input = part.scene;
            j.sceneOverrides = {"camera.width=" + std::to_string(o.size),
                                "camera.height=" + std::to_string(o.size)};
            j.objectiveKind = kind;
            j.truth = part.truth;
            j.fit.count = o.count;
            j.figures = false;
            j.cache.dir = cache;
            j.commandLine = "bench lamps";
            LampsBenchRow row;
            row.part = partName;
            row.objective = kind;
            // The baseline first (products over all of T, no judge), then the default.
            j.outDir = o.workDir / "runs" / (partName + "-" + objectiveKindName(kind) + "-rows");
            j.fit.columnProducts = false;
            j.judge = false;
            const LampFitResult baseline = runLampsJob(j).fit;
            row.secondsRows = baseline.seconds;
            row.cpuRows = baseline.cpuSeconds;
            j.outDir = o.workDir / "runs" / (partName + "-" + objectiveKindName(kind));
            j.fit.columnProducts = true;
            j.judge = true;
            const LampsJobSummary s = runLampsJob(j);
            row.secondsColumns = s.fit.seconds;
            row.cpuColumns = s.fit.cpuSeconds;
            row.secondsTarget = s.secondsTarget;
            row.speedup = row.secondsRows / std::max(row.secondsColumns, 1e-9);
            row.trainRatio = s.fit.steps.back().loss / s.targetLoss;
            if (s.judgement) {
                row.judgeTarget = s.judgement->target;
                row.judgeLamps = s.judgement->lamps;
                row.judgeStudio = s.judgement->studio;
                row.gap = s.judgement->gap;
                row.measure = s.judgement->measure;
                for (size_t r = 0; r < s.judgedTarget->visibility.size(); ++r) {
                    if (s.judgedTarget->visibility[r].pixels == 0) continue;
                    row.region = s.judgedTarget->visibility[r].label.name;
                    row.visTarget = s.judgedTarget->visibility[r].visibility;
                    row.visLamps = s.judgedLamps->visibility[r].visibility;
                    row.visStudio = s.judgedStudio->visibility[r].visibility;
                    break;
                }
            }
            result.rows.push_back(row);
            task.advance();
        }
    }
    return result;
}

std::string LampsBenchResult::csv() const {
    std::ostringstream s;
    s.precision(10);
    s << "part,objective,measure,seconds_target,seconds_fit_rows,seconds_fit_columns,speedup,"
         "cpu_fit_rows,cpu_fit_columns,train_ratio,judge_target,judge_lamps,judge_studio,gap,"
         "region,vis_target,vis_lamps,"
         "vis_studio\n";
    for (const LampsBenchRow& r : rows)
        s << r.part << ',' << objectiveKindName(r.objective) << ',' << r.measure << ','
          << r.secondsTarget << ',' << r.secondsRows << ',' << r.secondsColumns << ',' << r.speedup
          << ',' << r.cpuRows << ',' << r.cpuColumns << ',' << r.trainRatio << ',' << r.judgeTarget
          << ',' << r.judgeLamps << ',' << r.judgeStudio << ',' << r.gap << ',' << r.region << ','
          << r.visTarget << ',' << r.visLamps << ',' << r.visStudio << '\n';
    return s.str();
}

std::string LampsBenchResult::table() const {
    std::ostringstream s;
    char line[400];
    std::snprintf(
        line, sizeof line, "%-19s %-9s %7s %8s %8s %6s %8s %6s %-18s %10s %10s %10s %8s  %s\n",
        "part", "objective", "E* s", "fit all", "fit cols", "ratio", "cpu cols", "ratio",
        "judge measure", "E*", "lamps", "studio", "gap", "visibility E* / lamps / studio");
    s << line;
    for (const LampsBenchRow& r : rows) {
        std::snprintf(line, sizeof line,
                      "%-19s %-9s %7.2f %8.2f %8.2f %5.2fx %8.2f %5.2fx %-18s %10.4g %10.4g "
                      "%10.4g %+7.1f%%  %s %.3g / %.3g / %.3g\n",
                      r.part.c_str(), objectiveKindName(r.objective), r.secondsTarget,
                      r.secondsRows, r.secondsColumns, r.speedup, r.cpuColumns,
                      r.cpuRows / std::max(r.cpuColumns, 1e-9), r.measure.c_str(), r.judgeTarget,
                      r.judgeLamps, r.judgeStudio, 100 * r.gap, r.region.c_str(), r.visTarget,
                      r.visLamps, r.visStudio);
        s << line;
    }
    return s.str();
}

}  // namespace sl
