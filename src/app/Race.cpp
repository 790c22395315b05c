#include "app/Race.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

#include "app/Judge.h"
#include "app/OptimizeJob.h"
#include "app/PartFiles.h"
#include "app/Transport.h"
#include "core/Error.h"
#include "core/Progress.h"
#include "core/Registry.h"
#include "core/Stats.h"
#include "core/Stopwatch.h"
#include "io/AtomicFile.h"
#include "io/SceneFile.h"
#include "scene/Scene.h"

namespace sl {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

RaceConfig config(const std::string& name, ObjectiveKind objective, OptimizerMethod method,
                  int iterations, int spp, int planes = 1,
                  const std::vector<std::string>& starts = {"const:0.5"},
                  std::vector<double> continuation = {}) {
    RaceConfig c;
    c.name = name;
    c.spp = spp;
    c.search.objective = objective;
    c.search.optimizer.method = method;
    c.search.optimizer.iterations = iterations;
    c.search.planes = planes;
    c.search.starts.clear();
    for (const std::string& spec : starts) c.search.starts.push_back(parseInitialState(spec));
    c.search.continuation = std::move(continuation);
    return c;
}

SurfaceSpec partSpec(const std::string& name) {
    SurfaceSpec s;
    s.width = s.height = 512;
    s.pitch = 0.01;
    s.seed = 1;
    if (name == "ballend-chatter") {
        s.chatterStartFraction = 0.5;
        s.pocketEdge = false;
    } else if (name == "facemill-scratches") {
        s.process = SurfaceSpec::Process::FaceMillFeed;
        s.toolRadius = 4.0;
        s.stepover = 3.0;
        s.chatterAmplitude = 0.0;
        s.scratchCount = 6;
        s.gougeCount = 0;
        s.pocketEdge = false;
    } else if (name == "pocket") {
        s.chatterAmplitude = 0.0;
        s.stepover = 0.3;
        s.rasterAngleDeg = 30.0;
    } else {
        throw inputError(option("parts"), "unknown part '" + name + "'",
                         "use ballend-chatter, facemill-scratches or pocket");
    }
    return s;
}

double regionVisibility(const JudgeScore& s, const std::string& name) {
    for (const auto& r : s.visibility)
        if (r.label.name == name) return r.visibility;
    return kNaN;
}

RaceRow medianRow(const std::vector<const RaceRow*>& rows) {
    RaceRow m = *rows.front();
    m.seed = -1;
    auto med = [&](double RaceRow::*f) {
        std::vector<double> v;
        for (const RaceRow* r : rows)
            if (!std::isnan(r->*f)) v.push_back(r->*f);
        return v.empty() ? kNaN : median(v);
    };
    for (double RaceRow::*f :
         {&RaceRow::secondsPrecompute, &RaceRow::secondsSearch, &RaceRow::seconds, &RaceRow::eq2,
          &RaceRow::unbiased, &RaceRow::meanE, &RaceRow::sparsity, &RaceRow::visDefect,
          &RaceRow::visChatter, &RaceRow::trainLoss, &RaceRow::heldOwn, &RaceRow::ratioU,
          &RaceRow::ratioEq2, &RaceRow::ratioSeconds})
        m.*f = med(f);
    std::vector<double> ev;
    for (const RaceRow* r : rows) ev.push_back(r->evaluations);
    m.evaluations = static_cast<int>(median(ev));
    return m;
}

}  // namespace

std::vector<std::string> raceParts() {
    return {"ballend-chatter", "facemill-scratches", "pocket"};
}

PartFiles writeRacePart(const std::string& name, const std::filesystem::path& dir) {
    const auto known = raceParts();
    if (std::find(known.begin(), known.end(), name) == known.end())
        throw inputError(option("parts"), "no race part named '" + name + "'",
                         "use ballend-chatter, facemill-scratches or pocket");
    std::filesystem::create_directories(dir);
    PartFileOptions pf;
    pf.scene = dir / "scene.json";
    pf.imageSize = 256;
    pf.spp = 16;
    pf.maxDepth = 3;
    return writePartFiles(generateSurface(partSpec(name)), dir / "part.exr", pf);
}

std::vector<RaceConfig> defaultRaceConfigs() {
    using K = ObjectiveKind;
    using M = OptimizerMethod;
    std::vector<RaceConfig> c;
    const OptimizerMethodRow& loop = methodRow(M::PaperLoop);
    c.push_back(config(loop.name, K::Paper, loop.runs, loop.defaultBudget, 16, loop.defaultPlanes));
    c.push_back(config("paper-adam", K::Paper, M::Adam, 100, 16));
    c.push_back(config("paper-lbfgs-16", K::Paper, M::Lbfgs, 2000, 16));
    c.push_back(config("unbiased-adam-planes8", K::Unbiased, M::Adam, 300, 16, 8));
    c.push_back(config("unbiased-lbfgs-16", K::Unbiased, M::Lbfgs, 2000, 16));
    c.push_back(config("unbiased-lbfgs-32", K::Unbiased, M::Lbfgs, 2000, 32));
    // optimize's defaults (app/OptimizeJob.h optimizeDefaults), for each objective.
    const OptimizeDefaults d = optimizeDefaults();
    c.push_back(config("default-unbiased", K::Unbiased, d.method, methodRow(d.method).defaultBudget,
                       16, 1, d.starts));
    c.push_back(config("default-paper", K::Paper, d.method, methodRow(d.method).defaultBudget,
                       d.paperMinSpp, 1, d.starts));
    // ... and with the defects named (the part's truth): the defects objective.
    c.push_back(config("default-defects", d.objectiveWithDefects, d.method,
                       methodRow(d.method).defaultBudget, 16, 1, d.starts));
    c.push_back(config("unbiased-lbfgs-16-multistart", K::Unbiased, M::Lbfgs, 2000, 16, 1,
                       {"const:0.5", "specular", "studio"}));
    c.push_back(config("unbiased-lbfgs-16-continuation", K::Unbiased, M::Lbfgs, 2000, 16, 1,
                       {"const:0.5"}, {4.0, 2.0}));
    c.push_back(config("unbiased-mlsl-16", K::Unbiased, M::Mlsl, 1500, 16));
    return c;
}

std::vector<RaceConfig> settingsRaceConfigs(const std::vector<int>& spps,
                                            const std::vector<Sampling>& samplings,
                                            const std::vector<int>& maxDepths) {
    const OptimizeDefaults d = optimizeDefaults();
    auto make = [&](int spp, Sampling sampling, int depth) {
        RaceConfig c =
            config("", d.objective, d.method, methodRow(d.method).defaultBudget, spp, 1, d.starts);
        c.sampling = sampling;
        c.maxDepth = depth;
        c.name = "spp" + std::to_string(spp) + "-" + registryRow(samplingTable(), sampling).name +
                 "-d" + std::to_string(depth);
        return c;
    };
    std::vector<RaceConfig> c{make(16, RenderDesc{}.sampling, 3)};  // the parts' own setting
    for (int spp : spps)
        for (Sampling sampling : samplings)
            for (int depth : maxDepths) {
                RaceConfig k = make(spp, sampling, depth);
                if (k.name != c.front().name) c.push_back(std::move(k));
            }
    return c;
}

RaceSummary runRace(const RaceOptions& o) {
    if (o.seeds < 1) throw inputError(option("seeds"), "must be >= 1");
    if (o.configs.empty()) throw inputError(option("configs"), "none given");
    auto log = [&](const std::string& s) {
        if (o.log) o.log(s);
    };
    const auto cacheDir = std::filesystem::absolute(o.workDir) / ".scratchlight-cache";
    RaceSummary sum;
    ProgressTask task("race", static_cast<double>(o.parts.size() * o.configs.size()) * o.seeds);
    for (const std::string& partName : o.parts) {
        const auto dir = o.workDir / partName;
        const PartFiles files = writeRacePart(partName, dir);
        auto scene = loadScene(files.scene);
        JudgeOptions jo;
        jo.spp = o.judgeSpp;
        jo.objective.lambda = o.lambda;
        jo.truth = files.truth;
        jo.cacheDir = cacheDir;
        jo.maxDepth = o.judgeMaxDepth;
        log(partName + ": judge estimate (" + std::to_string(o.judgeSpp) + " spp)");
        const Judge judge(*scene, jo);
        // the truth's labelled pixels (every label), from the judge's projection of it
        std::vector<uint8_t> truthRegion(judge.labels().size());
        std::transform(judge.labels().begin(), judge.labels().end(), truthRegion.begin(),
                       [](uint8_t v) { return v ? uint8_t{255} : uint8_t{0}; });

        for (int seed = 0; seed < o.seeds; ++seed) {
            std::vector<RaceRow> rows;
            for (const RaceConfig& c : o.configs) {
                const bool unb = c.search.objective == ObjectiveKind::Unbiased;
                const bool defects = c.search.objective == ObjectiveKind::Defects;
                PrecomputeOptions p;
                p.spp = c.spp;
                p.seed = static_cast<uint64_t>(seed) * 1000;
                p.sampleSets = c.search.objective != ObjectiveKind::Paper ? 2 : 1;
                p.sampling = c.sampling;
                p.maxDepth = c.maxDepth;
                const Stopwatch precompute;
                const std::vector<TransportSource> set =
                    transportSetForScene(*scene, p, c.search.planes, {});
                RaceRow r;
                r.part = partName;
                r.config = c.name;
                r.seed = seed;
                r.secondsPrecompute = precompute.seconds();
                SearchInputs in;
                for (const auto& s : set) in.set.push_back(&s.file.matrix);
                in.mask = set.front().file.matrix.objectMask;  // as optimize: T's part mask
                in.objective.lambda = o.lambda;
                in.scene = scene.get();
                in.maxDepth = set.front().file.provenance.maxDepth;
                if (defects) in.defects = truthRegion;  // the truth names the defects
                const Stopwatch searching;
                const SearchResult sr = search(in, c.search);
                r.secondsSearch = searching.seconds();
                r.seconds = r.secondsPrecompute + r.secondsSearch;
                r.evaluations = sr.optimizer.evaluations;
                const JudgeScore js = judge.score(sr.e, c.name);
                r.eq2 = js.eq2.total;
                r.unbiased = js.unbiased.total;
                r.meanE = js.meanE;
                r.sparsity = js.sparsity;
                r.visDefect = regionVisibility(js, "defect");
                r.visChatter = regionVisibility(js, "chatter");
                r.trainLoss = sr.training.total;
                // Own objective on the judge's estimate: U or eq. 2; the defects objective is
                // read from its visibility columns instead (NaN here).
                r.heldOwn = defects ? kNaN : (unb ? r.unbiased : r.eq2);
                char buf[256];
                std::snprintf(buf, sizeof buf, "%s seed %d %-30s %6.2f s  eq2 %8.4f  U %8.4f",
                              partName.c_str(), seed, c.name.c_str(), r.seconds, r.eq2, r.unbiased);
                log(buf);
                task.advance();
                rows.push_back(r);
            }
            const RaceRow& base = rows.front();  // paper-loop (the first config)
            for (RaceRow& r : rows) {
                r.ratioU = r.unbiased / base.unbiased;
                r.ratioEq2 = r.eq2 / base.eq2;
                r.ratioSeconds = r.seconds / base.seconds;
                sum.rows.push_back(r);
            }
        }
    }
    std::map<std::pair<std::string, std::string>, std::vector<const RaceRow*>> byPart;
    std::map<std::string, std::vector<const RaceRow*>> byConfig;
    for (const RaceRow& r : sum.rows) {
        byPart[{r.part, r.config}].push_back(&r);
        byConfig[r.config].push_back(&r);
    }
    for (const std::string& part : o.parts)
        for (const RaceConfig& c : o.configs)
            sum.medians.push_back(medianRow(byPart[{part, c.name}]));
    for (const RaceConfig& c : o.configs) {
        RaceRow m = medianRow(byConfig[c.name]);
        m.part = "all";
        sum.overall.push_back(m);
    }
    return sum;
}

void writeRaceCsv(const std::filesystem::path& file, const std::vector<RaceRow>& rows) {
    std::ostringstream s;
    s.precision(10);
    s << "part,config,seed,seconds_precompute,seconds_search,seconds,evaluations,eq2,unbiased,"
         "mean_E,sparsity,visibility_defect,visibility_chatter,train_loss,heldout_own,"
         "ratio_U,ratio_eq2,ratio_seconds\n";
    for (const RaceRow& r : rows)
        s << r.part << ',' << r.config << ',' << r.seed << ',' << r.secondsPrecompute << ','
          << r.secondsSearch << ',' << r.seconds << ',' << r.evaluations << ',' << r.eq2 << ','
          << r.unbiased << ',' << r.meanE << ',' << r.sparsity << ',' << r.visDefect << ','
          << r.visChatter << ',' << r.trainLoss << ',' << r.heldOwn << ',' << r.ratioU << ','
          << r.ratioEq2 << ',' << r.ratioSeconds << '\n';
    writeTextAtomically(file, s.str());
}

std::string formatRaceTable(const std::vector<RaceRow>& rows) {
    std::ostringstream out;
    char buf[512];
    std::snprintf(buf, sizeof buf, "%-18s %-31s %7s %6s %8s %8s %7s %7s %7s %6s %6s %7s\n", "part",
                  "config", "seconds", "evals", "eq2", "U", "U/pl", "eq2/pl", "t/pl", "vis-d",
                  "vis-c", "gap");
    out << buf;
    for (const RaceRow& r : rows) {
        // The defects objective has no held-out own loss here (its visibility columns are).
        char g[32] = "n/a";
        if (std::isfinite(r.heldOwn))
            std::snprintf(g, sizeof g, "%+6.1f%%", 100.0 * (r.heldOwn / r.trainLoss - 1.0));
        const std::string gap = g;
        std::snprintf(buf, sizeof buf,
                      "%-18s %-31s %7.3f %6d %8.4f %8.4f %7.3f %7.3f %7.3f %6.2f %6.2f %7s\n",
                      r.part.c_str(), r.config.c_str(), r.seconds, r.evaluations, r.eq2, r.unbiased,
                      r.ratioU, r.ratioEq2, r.ratioSeconds, r.visDefect, r.visChatter, gap.c_str());
        out << buf;
    }
    return out.str();
}

}  // namespace sl
