#include "app/bench/GradCheck.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "app/pipeline/InitialState.h"
#include "core/Error.h"
#include "core/Interrupt.h"
#include "core/Progress.h"
#include "core/Stats.h"
#include "core/Stopwatch.h"
#include "core/Text.h"
#include "io/AtomicFile.h"
#include "io/SceneFile.h"
#include "objective/Autodiff.h"
#include "objective/TransportLoss.h"
#include "render/Render.h"
#include "scene/Scene.h"
#include "transport/TransportSink.h"

namespace sl {

namespace {

/// Everything the measurements share: the scene, T, the recorded paths, the objective, E0 and
/// the reference gradient.
struct Lab {
    std::unique_ptr<Scene> scene;
    RenderOptions render;
    TransportMatrix t;
    double secondsPrecompute = 0;
    std::unique_ptr<PathRecording> rec;
    std::unique_ptr<ImageObjective> objective;
    std::unique_ptr<RenderLoss> box;
    std::unique_ptr<TransportLoss> exact;
    std::vector<double> E0;
    AutodiffGradient reference;
    int threads = 0;
};

std::unique_ptr<Lab> makeLab(const GradientSetup& s, int repeats) {
    auto lab = std::make_unique<Lab>();
    SceneDesc d = readSceneFile(s.scene, s.sceneOverrides);
    if (s.width) d.camera.width = *s.width;
    if (s.height) d.camera.height = *s.height;
    if (s.spp) d.render.spp = *s.spp;
    if (s.maxDepth) d.render.maxDepth = *s.maxDepth;
    if (s.seed) d.render.seed = *s.seed;
    if (d.render.spp < 1)
        throw inputError(option("spp"), "is " + std::to_string(d.render.spp), "use a count >= 1");
    lab->scene = loadScene(d);
    lab->threads = s.threads;
    lab->render = renderOptionsFor(*lab->scene);
    lab->render.threads = s.threads;
    std::vector<double> times;
    for (int r = 0; r < std::max(1, repeats); ++r) {
        const Stopwatch clock;
        PrecomputeResult p = precomputeTransport(*lab->scene, lab->render, 1);
        times.push_back(clock.seconds());
        lab->t = std::move(p.matrix);
    }
    lab->secondsPrecompute = median(times);
    lab->rec = std::make_unique<PathRecording>(recordPaths(*lab->scene, lab->render));
    lab->objective = std::make_unique<ImageObjective>(lab->t.width, lab->t.height,
                                                      lab->t.objectMask, s.objective);
    lab->box = std::make_unique<RenderLoss>(*lab->scene, lab->render, *lab->objective, false,
                                            /*interruptible=*/true);  // it keeps nothing
    lab->exact = std::make_unique<TransportLoss>(lab->t, *lab->objective, false);
    lab->E0 = initialEnvMap(s.init, lab->t.envWidth, lab->t.envHeight, false);
    lab->reference = autodiffThroughPaths(*lab->rec, *lab->objective, lab->E0, s.threads);
    return lab;
}

/// Runs `gradient` `repeats` times (it returns the gradient and its render count); the row gets
/// the median time and the median error against the reference.
template <typename F>
GradCheckRow measure(const Lab& lab, const std::string& method, const std::string& settings,
                     int repeats, F&& gradient) {
    GradCheckRow row;
    row.method = method;
    row.settings = settings;
    row.repeats = repeats;
    std::vector<double> secs, errs, coss;
    for (int r = 0; r < repeats; ++r) {
        throwIfInterrupted();
        long renders = 0;
        const Stopwatch clock;
        const std::vector<double> g = gradient(r, renders);
        secs.push_back(clock.seconds());
        const GradientError e = compareGradients(g, lab.reference.gradient);
        errs.push_back(e.relativeL2);
        coss.push_back(e.cosine);
        row.renders = renders;
    }
    row.seconds = median(secs);
    row.relativeError = median(errs);
    row.cosine = median(coss);
    return row;
}

int fastRepeats(int repeats) {
    return std::max(repeats, 21);
}

GradCheckRow measureExact(const Lab& lab, int repeats, bool withPrecompute) {
    GradCheckRow row = measure(
        lab, withPrecompute ? "exact+precompute" : "exact",
        withPrecompute ? "T traced once + one Tᵀ·dL/dY" : "Tᵀ·dL/dY, fused pass, T amortised",
        fastRepeats(repeats), [&](int, long&) {
            std::vector<double> g(lab.E0.size());
            lab.exact->evaluateFused(lab.E0, g);
            return g;
        });
    if (withPrecompute) row.seconds += lab.secondsPrecompute;
    return row;
}

GradCheckRow measureAutodiff(const Lab& lab, int repeats, bool throughT) {
    return measure(
        lab, throughT ? "autodiff-T" : "autodiff",
        throughT ? "ceres::Jet<double,32> through T (float entries)"
                 : "ceres::Jet<double,32> through the recorded paths (reference)",
        repeats, [&](int, long&) {
            return throughT
                       ? autodiffThroughMatrix(lab.t, *lab.objective, lab.E0, lab.threads).gradient
                       : autodiffThroughPaths(*lab.rec, *lab.objective, lab.E0, lab.threads)
                             .gradient;
        });
}

GradCheckRow measureFd(const Lab& lab, int repeats, FdOptions fd, const std::string& method) {
    fd.texels.clear();
    if (fd.threads == 0) fd.threads = lab.threads;
    const std::string settings = std::string(fd.central ? "central" : "forward") +
                                 ", h=" + formatNumber(fd.h) +
                                 (fd.commonRandomNumbers ? ", CRN" : ", fresh seeds");
    GradCheckRow row = measure(lab, method, settings, repeats, [&](int r, long& renders) {
        GradientEstimate g =
            finiteDifferenceGradient(*lab.box, lab.E0, fd, static_cast<uint64_t>(r) + 1);
        renders = g.evaluations;
        return g.gradient;
    });
    row.parameter = fd.h;
    row.crn = fd.commonRandomNumbers;
    return row;
}

GradCheckRow measureSpsa(const Lab& lab, int repeats, const SpsaOptions& sp, int q) {
    Pcg32 rng(sp.seed, 0x2545f4914f6cdd1dULL);
    const std::string settings = "q=" + std::to_string(q) + ", c=" + formatNumber(sp.c) +
                                 (sp.commonRandomNumbers ? ", CRN" : ", fresh seeds");
    GradCheckRow row = measure(lab, "spsa", settings, repeats, [&](int r, long& renders) {
        GradientEstimate g =
            spsaGradient(*lab.box, lab.E0, sp.c, q, rng, sp.commonRandomNumbers,
                         static_cast<uint64_t>(r) + 1, sp.threads > 0 ? sp.threads : lab.threads);
        renders = g.evaluations;
        return g.gradient;
    });
    row.parameter = q;
    row.crn = sp.commonRandomNumbers;
    return row;
}

GradCheckReport reportHeader(const Lab& lab, const GradientSetup& s) {
    GradCheckReport rep;
    rep.scene = s.scene.string();
    rep.width = lab.t.width;
    rep.height = lab.t.height;
    rep.spp = lab.render.spp;
    rep.maxDepth = lab.render.maxDepth;
    rep.seed = lab.render.seed;
    rep.texels = static_cast<int>(lab.t.cols());
    rep.maskPixels = static_cast<size_t>(lab.objective->maskSize());
    rep.nnz = lab.t.nnz();
    rep.paths = lab.rec->pathCount();
    rep.loss = lab.reference.loss;
    rep.secondsPrecompute = lab.secondsPrecompute;
    std::vector<double> g(lab.E0.size());
    lab.exact->evaluateFused(lab.E0, g);
    const AutodiffGradient adT = autodiffThroughMatrix(lab.t, *lab.objective, lab.E0, lab.threads);
    rep.exactVsAutodiffT = compareGradients(g, adT.gradient).relativeL2;
    rep.exactVsAutodiffPaths = compareGradients(g, lab.reference.gradient).relativeL2;
    return rep;
}

}  // namespace

std::vector<std::string> gradCheckMethods() {
    return {"exact", "exact+precompute", "autodiff", "autodiff-T",
            "fd",    "fd-forward",       "fd-fresh", "spsa"};
}

GradCheckReport runGradCheck(const GradCheckOptions& o) {
    const auto valid = gradCheckMethods();
    for (const std::string& m : o.methods)
        if (std::find(valid.begin(), valid.end(), m) == valid.end()) {
            std::string list;
            for (const auto& v : valid) list += (list.empty() ? "" : ", ") + v;
            throw inputError(option("methods"), "unknown method '" + m + "'",
                             "use some of: " + list);
        }
    if (o.repeats < 1)
        throw inputError(option("repeats"), "is " + std::to_string(o.repeats), "use a count >= 1");
    const auto lab = makeLab(o.setup, o.repeats);
    GradCheckReport rep = reportHeader(*lab, o.setup);
    ProgressTask task("gradcheck", static_cast<double>(o.methods.size()));
    for (const std::string& m : o.methods) {
        task.detail(m);
        if (m == "exact" || m == "exact+precompute") {
            rep.rows.push_back(measureExact(*lab, o.repeats, m == "exact+precompute"));
        } else if (m == "autodiff" || m == "autodiff-T") {
            rep.rows.push_back(measureAutodiff(*lab, o.repeats, m == "autodiff-T"));
        } else if (m == "spsa") {
            rep.rows.push_back(measureSpsa(*lab, o.repeats, o.spsa, o.spsa.q));
        } else {
            FdOptions fd = o.fd;
            fd.central = m != "fd-forward";
            fd.commonRandomNumbers = m != "fd-fresh";
            rep.rows.push_back(measureFd(*lab, o.repeats, fd, m));
        }
        task.advance();
    }
    return rep;
}

std::string GradCheckReport::table() const {
    std::ostringstream s;
    char buf[512];
    std::snprintf(buf, sizeof buf,
                  "scene %s: %dx%d px, %d spp, max_depth %d, seed %llu, %d texels, mask %zu px, "
                  "T nnz %zu, %zu paths, loss %.6g\n",
                  scene.c_str(), width, height, spp, maxDepth,
                  static_cast<unsigned long long>(seed), texels, maskPixels, nnz, paths, loss);
    s << buf;
    std::snprintf(buf, sizeof buf,
                  "exact vs autodiff through T: %.3g relative; vs autodiff through the paths: "
                  "%.3g (T is float32)\n",
                  exactVsAutodiffT, exactVsAutodiffPaths);
    s << buf;
    std::snprintf(buf, sizeof buf, "%-17s %-62s %12s %9s %12s %12s\n", "method", "settings",
                  "s/gradient", "renders", "rel. error", "cosine");
    s << buf;
    for (const GradCheckRow& r : rows) {
        const std::string renders = r.renders > 0 ? std::to_string(r.renders) : "-";
        std::snprintf(buf, sizeof buf, "%-17s %-62s %12.4g %9s %12.3g %12.9f\n", r.method.c_str(),
                      r.settings.c_str(), r.seconds, renders.c_str(), r.relativeError, r.cosine);
        s << buf;
    }
    return s.str();
}

std::string GradCheckReport::json() const {
    nlohmann::json j;
    j["scene"] = scene;
    j["width"] = width;
    j["height"] = height;
    j["spp"] = spp;
    j["max_depth"] = maxDepth;
    j["seed"] = seed;
    j["texels"] = texels;
    j["mask_pixels"] = maskPixels;
    j["nnz"] = nnz;
    j["paths"] = paths;
    j["loss"] = loss;
    j["seconds_precompute"] = secondsPrecompute;
    j["exact_vs_autodiff_T"] = exactVsAutodiffT;
    j["exact_vs_autodiff_paths"] = exactVsAutodiffPaths;
    j["reference"] = "autodiff through the recorded paths (ceres::Jet<double,32>)";
    nlohmann::json rs = nlohmann::json::array();
    for (const GradCheckRow& r : rows) {
        rs.push_back({{"method", r.method},
                      {"settings", r.settings},
                      {"parameter", r.parameter},
                      {"crn", r.crn},
                      {"seconds_per_gradient", r.seconds},
                      {"renders_per_gradient", r.renders},
                      {"relative_error", r.relativeError},
                      {"cosine", r.cosine},
                      {"repeats", r.repeats}});
    }
    j["methods"] = rs;
    return j.dump(2) + "\n";
}

// --- bench gradients ----------------------------------------------------------------------------

namespace {

/// Records (seconds, noise-free loss) of every iterate of one optimization; the time spent
/// evaluating the loss for the plot is excluded. Stops at the budget.
struct Tracer {
    const TransportLoss& exact;
    std::vector<BenchTracePoint>& out;
    std::string method;
    double budget;
    bool blackBox = false;  // evaluations are renders
    double overhead = 0;

    std::function<bool(const IterationRecord&, std::span<const double>)> callback() {
        return [this](const IterationRecord& r, std::span<const double> x) {
            const Stopwatch clock;
            BenchTracePoint p;
            p.method = method;
            p.iteration = r.iteration;
            p.seconds = r.seconds - overhead;
            p.loss = exact.evaluate(x, {}).total;
            p.renders = blackBox ? r.evaluations : 0;
            out.push_back(p);
            overhead += clock.seconds();
            return p.seconds < budget && !interruptRequested();  // Ctrl-C: see run() below
        };
    }
};

std::string csvQuote(const std::string& s) {
    return "\"" + s + "\"";
}

}  // namespace

BenchGradientsReport runBenchGradients(const BenchGradientsOptions& o) {
    if (o.repeats < 1)
        throw inputError(option("repeats"), "is " + std::to_string(o.repeats), "use a count >= 1");
    const auto lab = makeLab(o.setup, o.repeats);
    BenchGradientsReport rep;
    GradCheckReport& g = rep.gradients;
    g = reportHeader(*lab, o.setup);
    ProgressTask task("bench gradients",
                      static_cast<double>(4 + o.fdSteps.size() + o.fdFreshSteps.size() +
                                          o.spsaC.size() * o.spsaQ.size()));
    auto add = [&](GradCheckRow row) {
        g.rows.push_back(std::move(row));
        task.advance();
    };
    add(measureExact(*lab, o.repeats, false));
    add(measureExact(*lab, o.repeats, true));
    add(measureAutodiff(*lab, o.repeats, false));
    add(measureAutodiff(*lab, o.repeats, true));
    for (double h : o.fdSteps) {
        FdOptions fd;
        fd.h = h;
        add(measureFd(*lab, o.repeats, fd, "fd"));
    }
    for (double h : o.fdFreshSteps) {
        FdOptions fd;
        fd.h = h;
        fd.commonRandomNumbers = false;
        add(measureFd(*lab, o.repeats, fd, "fd-fresh"));
    }
    for (double c : o.spsaC) {
        SpsaOptions sp = o.spsa;
        sp.c = c;
        for (int q : o.spsaQ) add(measureSpsa(*lab, o.repeats, sp, q));
    }

    std::ostringstream csv;
    csv << "method,settings,parameter,crn,seconds_per_gradient,renders_per_gradient,"
           "relative_error,cosine,repeats\n";
    for (const GradCheckRow& r : g.rows) {
        char buf[256];
        std::snprintf(buf, sizeof buf, ",%.6g,%d,%.6g,%ld,%.6g,%.12g,%d\n", r.parameter,
                      r.crn ? 1 : 0, r.seconds, r.renders, r.relativeError, r.cosine, r.repeats);
        csv << r.method << "," << csvQuote(r.settings) << buf;
    }
    rep.gradientsCsv = o.outDir / "gradients.csv";

    if (o.optimizations) {
        const Lab& L = *lab;
        auto run = [&](const std::string& method, auto&& body) {
            Tracer tr{*L.exact, rep.trace, method, o.budgetSeconds,
                      method.rfind("fd", 0) == 0 || method.rfind("spsa", 0) == 0};
            std::vector<double> E = L.E0;
            body(E, tr.callback());
            throwIfInterrupted();  // the optimizer stopped at the iteration a Ctrl-C came
        };
        OptimizerOptions adam;
        adam.method = OptimizerMethod::Adam;
        adam.iterations = o.iterations;
        adam.learningRate = o.learningRate;
        run("exact (Adam)", [&](std::vector<double>& E, auto cb) {
            OptimizerOptions a = adam;
            a.callback = cb;
            minimize(L.exact->problem(), E, a);
        });
        run("autodiff (Adam)", [&](std::vector<double>& E, auto cb) {
            Problem p;
            p.dimension = E.size();
            p.evaluate = [&](std::span<const double> x, std::span<double> grad) {
                if (grad.empty()) return lossThroughPaths<double>(*L.rec, *L.objective, x);
                AutodiffGradient ad = autodiffThroughPaths(*L.rec, *L.objective, x, L.threads);
                std::copy(ad.gradient.begin(), ad.gradient.end(), grad.begin());
                return ad.loss;
            };
            OptimizerOptions a = adam;
            a.callback = cb;
            minimize(p, E, a);
        });
        run("fd-adam (h=1e-3, CRN)", [&](std::vector<double>& E, auto cb) {
            OptimizerOptions a = adam;
            a.method = OptimizerMethod::FdAdam;
            a.callback = cb;
            BlackBoxOptions bb;
            bb.fd.h = 1e-3;
            bb.fd.threads = L.threads;
            minimizeBlackBox(*L.box, E, a, bb);
        });
        for (int q : {1, 8}) {
            run("spsa (q=" + std::to_string(q) + ", CRN)", [&](std::vector<double>& E, auto cb) {
                OptimizerOptions a = adam;
                a.method = OptimizerMethod::Spsa;
                a.iterations = o.spsaIterations;
                a.callback = cb;
                BlackBoxOptions bb;
                bb.spsa = o.spsa;
                bb.spsa.q = q;
                bb.spsa.threads = L.threads;
                minimizeBlackBox(*L.box, E, a, bb);
            });
        }
        std::ostringstream oc;
        oc << "method,iteration,seconds,loss,renders\n";
        for (const BenchTracePoint& p : rep.trace) {
            char buf[160];
            std::snprintf(buf, sizeof buf, ",%d,%.6g,%.9g,%ld\n", p.iteration, p.seconds, p.loss,
                          p.renders);
            oc << csvQuote(p.method) << buf;
        }
        rep.optimizationCsv = o.outDir / "optimization.csv";
        enterCommit();  // both CSVs or neither (core/Interrupt.h)
        writeTextAtomically(rep.gradientsCsv, csv.str());
        writeTextAtomically(rep.optimizationCsv, oc.str());
    } else {
        enterCommit();
        writeTextAtomically(rep.gradientsCsv, csv.str());
    }
    return rep;
}

}  // namespace sl
