#include "app/bench/JndBench.h"

#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <sstream>

#include "app/pipeline/Judge.h"
#include "app/jobs/OptimizeJob.h"
#include "app/host/Plot.h"
#include "app/pipeline/Transport.h"
#include "app/pipeline/Truth.h"
#include "core/Error.h"
#include "core/Interrupt.h"
#include "core/Progress.h"
#include "core/Stats.h"
#include "core/Stopwatch.h"
#include "io/SceneFile.h"
#include "objective/DefectObjective.h"
#include "objective/JndObjective.h"
#include "objective/TransportLoss.h"
#include "scene/Scene.h"

namespace sl {

namespace {

std::vector<std::string> sizeOverrides(int n) {
    return {"camera.width=" + std::to_string(n), "camera.height=" + std::to_string(n)};
}

std::filesystem::path bundledTruth() {
    return bundledDefaultScene().parent_path() / "part-truth.png";
}

JndEvaluationRow evaluationRow(int size, const JndBenchOptions& o,
                               const std::filesystem::path& cache) {
    const std::unique_ptr<Scene> scene = loadScene(bundledDefaultScene(), sizeOverrides(size));
    PrecomputeOptions po;
    po.spp = o.evaluationSpp;
    po.sampleSets = 2;
    const TransportSource src = transportForScene(*scene, po, cache);
    const TransportMatrix& t = src.file.matrix;
    const std::vector<uint8_t> defects = projectTruth(*scene, bundledTruth()).labels;
    const std::vector<uint8_t>& part = t.objectMask;
    ObjectiveOptions oo;
    JndObjectiveOptions j;
    j.view = viewingFor(*scene);
    j.band.whiteMean = whiteFurnaceMean(t, part);
    j.gaussians = GaussianMethod::Direct;
    const JndObjective direct(t.width, t.height, part, defects, {}, oo, j);
    j.gaussians = GaussianMethod::Fourier;
    const JndObjective fourier(t.width, t.height, part, defects, {}, oo, j);
    oo.defectMeasure = DefectMeasure::Ratio;
    const DefectObjective ratio(t.width, t.height, part, defects, {}, oo, j.band);
    const TransportLoss lossDirect(t, direct, false), lossFourier(t, fourier, false),
        lossRatio(t, ratio, false);
    const size_t texels = static_cast<size_t>(t.envWidth) * t.envHeight;
    const std::vector<double> e(texels, 0.5);
    std::vector<double> grad(texels);
    std::vector<double> sd, sf, sr;
    auto timed = [&](const TransportLoss& loss) {
        const Stopwatch clock;
        loss.evaluate(e, grad);
        return clock.seconds();
    };
    for (int k = 0; k < o.evaluations; ++k) {
        throwIfInterrupted();
        sd.push_back(timed(lossDirect));
        sf.push_back(timed(lossFourier));
        sr.push_back(timed(lossRatio));
    }
    JndEvaluationRow r;
    r.size = size;
    r.secondsDirect = median(sd);
    r.secondsFourier = median(sf);
    r.secondsRatio = median(sr);
    // The two filters' losses and image gradients on the same half images.
    const size_t n = t.rows();
    std::vector<double> ya(n), yb(n), da(n), db(n), fa(n), fb(n), dE(texels);
    t.applyLuminanceHalves(e, ya, yb);
    const LossParts pd = direct.evaluate(ya, yb, e, da, db, dE);
    const LossParts pf = fourier.evaluate(ya, yb, e, fa, fb, dE);
    r.lossDifference = std::abs(pf.total - pd.total) / std::max(std::abs(pd.total), 1e-300);
    double diff = 0, scale = 0;
    for (size_t p = 0; p < n; ++p) {
        diff = std::max({diff, std::abs(fa[p] - da[p]), std::abs(fb[p] - db[p])});
        scale = std::max({scale, std::abs(da[p]), std::abs(db[p])});
    }
    r.gradientDifference = scale > 0 ? diff / scale : diff;
    return r;
}

/// User + system CPU seconds of this process so far (every thread).
double cpuSeconds() {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    auto sec = [](const timeval& t) {
        return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec);
    };
    return sec(u.ru_utime) + sec(u.ru_stime);
}

double worstJnd(const std::optional<JudgeScore>& s) {
    double worst = std::numeric_limits<double>::quiet_NaN();
    if (!s) return worst;
    for (const RegionVisibility& v : s->visibility)
        if (std::isfinite(v.jnd)) worst = std::isnan(worst) ? v.jnd : std::min(worst, v.jnd);
    return worst;
}

JndOptimizeSample optimizeOnce(DefectMeasure measure, const JndBenchOptions& o,
                               const std::filesystem::path& work) {
    const std::filesystem::path cache = work / "optimize-cache";
    std::filesystem::remove_all(cache);  // a first run: nothing traced yet
    OptimizeJobOptions j;
    j.input = bundledDefaultScene();
    j.sceneOverrides = sizeOverrides(o.optimizeSize);
    j.truth = bundledTruth();
    j.objective.defectMeasure = measure;
    j.outDir = work / ("optimize-" + std::string(defectMeasureName(measure)));
    j.cache.dir = cache;
    j.commandLine = "bench jnd";
    const Stopwatch clock;
    const double cpu0 = cpuSeconds();
    const OptimizeJobSummary s = runOptimizeJob(j);
    JndOptimizeSample x;
    x.seconds = clock.seconds();
    x.cpuSeconds = cpuSeconds() - cpu0;
    const OptimizeRun& run = s.runs.front();
    x.trace = run.secondsTrace;
    x.search = run.secondsSearch;
    for (const TrainingNoiseRound& nr : run.noise.rounds) x.gapError += nr.secondsGapError;
    x.answer = run.answer ? run.answer->seconds : 0.0;
    x.judge = run.secondsJudge;
    x.rest = x.seconds - x.trace - x.search - x.gapError - x.answer - x.judge;
    x.spp = run.noise.spp();
    x.rounds = static_cast<int>(run.noise.rounds.size());
    x.jnd = worstJnd(run.judged);
    x.lampJnd = worstJnd(run.judgedLamp);
    return x;
}

}  // namespace

JndOptimizeSample JndOptimizeRow::median() const {
    JndOptimizeSample m;
    auto col = [&](auto field) {
        std::vector<double> v;
        for (const JndOptimizeSample& s : samples) v.push_back(static_cast<double>(s.*field));
        return v.empty() ? 0.0 : sl::median(v);
    };
    m.seconds = col(&JndOptimizeSample::seconds);
    m.cpuSeconds = col(&JndOptimizeSample::cpuSeconds);
    m.trace = col(&JndOptimizeSample::trace);
    m.search = col(&JndOptimizeSample::search);
    m.gapError = col(&JndOptimizeSample::gapError);
    m.answer = col(&JndOptimizeSample::answer);
    m.judge = col(&JndOptimizeSample::judge);
    m.rest = col(&JndOptimizeSample::rest);
    m.spp = static_cast<int>(col(&JndOptimizeSample::spp));
    m.rounds = static_cast<int>(col(&JndOptimizeSample::rounds));
    m.jnd = col(&JndOptimizeSample::jnd);
    m.lampJnd = col(&JndOptimizeSample::lampJnd);
    return m;
}

JndBenchResult runJndBench(const JndBenchOptions& o) {
    if (o.evaluations < 1)
        throw inputError(option("evaluations"), "is " + std::to_string(o.evaluations), "use >= 1");
    if (o.repeats < 1)
        throw inputError(option("repeats"), "is " + std::to_string(o.repeats), "use >= 1");
    JndBenchResult result;
    result.options = o;
    const std::filesystem::path work = std::filesystem::absolute(o.workDir);
    std::filesystem::create_directories(work);
    {
        ProgressTask task("bench jnd: one evaluation", static_cast<double>(o.sizes.size()));
        for (int n : o.sizes) {
            result.evaluations.push_back(evaluationRow(n, o, work / ".cache"));
            task.advance();
        }
    }
    if (o.optimizeSize > 0) {
        ProgressTask task("bench jnd: optimize with the truth labels", 2.0 * o.repeats);
        result.optimize = {{"jnd", {}}, {"ratio", {}}};
        for (int k = 0; k < o.repeats; ++k) {
            throwIfInterrupted();
            result.optimize[0].samples.push_back(optimizeOnce(DefectMeasure::Jnd, o, work));
            task.advance();
            result.optimize[1].samples.push_back(optimizeOnce(DefectMeasure::Ratio, o, work));
            task.advance();
        }
    }
    return result;
}

std::string JndBenchResult::table() const {
    std::ostringstream os;
    char line[512];
    std::snprintf(line, sizeof line, "  %-8s %12s %12s %8s %12s %12s %12s\n", "size", "direct s",
                  "fourier s", "speedup", "ratio s", "loss diff", "grad diff");
    os << "one evaluation (loss and gradient through T's halves, median of " << options.evaluations
       << "):\n"
       << line;
    for (const JndEvaluationRow& r : evaluations) {
        std::snprintf(line, sizeof line, "  %-8s %12.4f %12.4f %7.2fx %12.4f %12.2e %12.2e\n",
                      (std::to_string(r.size) + "²").c_str(), r.secondsDirect, r.secondsFourier,
                      r.speedup(), r.secondsRatio, r.lossDifference, r.gradientDifference);
        os << line;
    }
    if (optimize.empty()) return os.str();
    std::snprintf(line, sizeof line, "  %-8s %8s %8s %8s %8s %8s %8s %8s %8s %6s %6s %8s %8s\n",
                  "measure", "total s", "cpu s", "trace", "search", "gap SE", "answer", "judge",
                  "rest", "spp", "rounds", "JND", "lamp JND");
    os << "optimize with the truth labels on the bundled part at " << options.optimizeSize
       << "², empty cache (" << options.repeats << " interleaved runs each, median per column):\n"
       << line;
    for (const JndOptimizeRow& row : optimize) {
        const JndOptimizeSample m = row.median();
        std::snprintf(
            line, sizeof line,
            "  %-8s %8.2f %8.2f %8.2f %8.2f %8.2f %8.2f %8.2f %8.2f %6d %6d %8.3g %8.3g\n",
            row.measure.c_str(), m.seconds, m.cpuSeconds, m.trace, m.search, m.gapError, m.answer,
            m.judge, m.rest, m.spp, m.rounds, m.jnd, m.lampJnd);
        os << line;
    }
    return os.str();
}

std::string JndBenchResult::csv() const {
    std::ostringstream os;
    os << "row,size,measure,repeat,seconds,cpu_s,direct_s,fourier_s,ratio_s,loss_diff,grad_diff,"
          "trace_s,"
          "search_s,gap_se_s,answer_s,judge_s,rest_s,spp,rounds,jnd,lamp_jnd\n";
    for (const JndEvaluationRow& r : evaluations)
        os << "evaluation," << r.size << ",jnd,," << r.secondsFourier << ",," << r.secondsDirect
           << ',' << r.secondsFourier << ',' << r.secondsRatio << ',' << r.lossDifference << ','
           << r.gradientDifference << ",,,,,,,,,,\n";
    for (const JndOptimizeRow& row : optimize)
        for (size_t k = 0; k < row.samples.size(); ++k) {
            const JndOptimizeSample& s = row.samples[k];
            os << "optimize," << options.optimizeSize << ',' << row.measure << ',' << k << ','
               << s.seconds << ',' << s.cpuSeconds << ",,,,,," << s.trace << ',' << s.search << ','
               << s.gapError << ',' << s.answer << ',' << s.judge << ',' << s.rest << ',' << s.spp
               << ',' << s.rounds << ',' << s.jnd << ',' << s.lampJnd << '\n';
        }
    return os.str();
}

}  // namespace sl
