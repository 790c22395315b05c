#include "app/OptimizeJob.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/Error.h"
#include "io/AtomicFile.h"
#include "io/EnvMapIO.h"
#include "io/ImageIO.h"
#include "objective/TransportLoss.h"
#include "optimize/InitialState.h"

namespace sl {

namespace {

using json = nlohmann::ordered_json;

void writeText(const std::filesystem::path& file, const std::string& text) {
    writeAtomically(file, [&](const std::filesystem::path& tmp) {
        std::ofstream os(tmp, std::ios::binary);
        os << text;
        os.flush();
        if (!os) throw inputError(file.string(), "cannot write");
    });
}

std::string lambdaName(double lambda) {
    std::ostringstream s;
    s << "lambda-" << lambda;
    return s.str();
}

EnvMap toEnvMap(const std::vector<double>& e, const TransportMatrix& t, bool rgb) {
    EnvMap m = EnvMap::constant(t.envWidth, t.envHeight, 0.0f, rgb ? 3 : 1);
    for (size_t i = 0; i < e.size(); ++i) m.texels[i] = static_cast<float>(e[i]);
    return m;
}

json partsJson(const LossParts& p) {
    return {{"loss", p.total},
            {"L_grad", p.lGrad},
            {"L_reg", p.lReg},
            {"G", p.G},
            {"clamped", p.clamped}};
}

/// The render a person looks at: RGB when T is RGB, else luminance.
std::vector<double> renderImage(const TransportMatrix& t, const std::vector<double>& e) {
    std::vector<double> out(t.rows() * (t.channels == 3 ? 3 : 1));
    if (t.channels == 3)
        t.applyRgb(e, out);
    else
        t.applyLuminance(e, out);
    return out;
}

}  // namespace

void writeRender(const std::filesystem::path& exr, const std::vector<double>& image, int width,
                 int height, int channels) {
    Image img(width, height, channels);
    for (size_t i = 0; i < image.size(); ++i) img.data[i] = static_cast<float>(image[i]);
    writeExr(exr, img);
    auto png = exr;
    png.replace_extension(".png");
    writePng(png, img);
}

OptimizeJobSummary runOptimizeJob(const OptimizeJobOptions& o) {
    if (o.lambdas.empty()) throw inputError("--lambda", "no value given");
    for (double l : o.lambdas)
        if (!(l >= 0) || !std::isfinite(l))
            throw inputError("--lambda", "must be >= 0", "give e.g. --lambda 30 or 10,30,100");

    OptimizeJobSummary job;
    if (isTransportFile(o.input)) {
        auto t0 = std::chrono::steady_clock::now();
        job.transport.file = readTransportFile(o.input);
        job.transport.path = o.input;
        job.transport.secondsTotal =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    } else {
        PrecomputeOptions p = o.precompute;
        p.rgb = o.rgb;
        auto cacheDir = std::filesystem::absolute(o.outDir).parent_path() / ".scratchlight-cache";
        job.transport = transportForScene(o.input, p, cacheDir);
    }
    const TransportMatrix& t = job.transport.file.matrix;
    if (o.rgb && t.channels != 3)
        throw inputError(o.input.string(), "is a gray transport matrix; --rgb needs an RGB one",
                         "precompute it with --rgb");

    std::vector<uint8_t> mask = t.objectMask;
    if (!o.mask.empty()) mask = intersectMasks(mask, loadImageMask(o.mask, t.width, t.height));
    for (uint8_t m : mask) job.maskPixels += m != 0;

    const std::vector<double> e0 = initialEnvMap(o.init, t.envWidth, t.envHeight, o.rgb);
    const bool sweep = o.lambdas.size() > 1;
    std::ostringstream sweepCsv;
    sweepCsv << "lambda,optimizer,iterations,evaluations,initial_loss,final_loss,final_L_grad,"
                "final_L_reg,seconds\n";

    for (double lambda : o.lambdas) {
        ObjectiveOptions oo = o.objective;
        oo.lambda = lambda;
        ImageObjective objective(t.width, t.height, mask, oo);
        TransportLoss loss(t, objective, o.rgb);

        OptimizeRun run;
        run.lambda = lambda;
        run.dir = sweep ? o.outDir / lambdaName(lambda) : o.outDir;
        std::vector<double> e = e0;
        run.initial = loss.evaluate(e, {});

        std::ostringstream csv;
        csv << std::setprecision(10) << "iteration,evaluations,loss,L_grad,L_reg,seconds\n";
        OptimizerOptions opt = o.optimizer;
        LossParts last;  // parts of the most recent evaluation, usually the reported iterate
        opt.callback = [&](const IterationRecord& r, std::span<const double> x) {
            LossParts p = r.loss == last.total ? last : loss.evaluate(x, {});
            csv << r.iteration << ',' << r.evaluations << ',' << p.total << ',' << p.lGrad << ','
                << p.lReg << ',' << r.seconds << '\n';
            return o.optimizer.callback ? o.optimizer.callback(r, x) : true;
        };
        run.optimizer = minimize(loss.problem(&last), e, opt);
        run.final = loss.evaluate(e, {});
        spdlog::info("lambda {}: {}", lambda, run.optimizer.briefReport());

        std::filesystem::create_directories(run.dir);
        writeEnvMap(run.dir / "envmap.exr", toEnvMap(e, t, o.rgb));
        writePng(run.dir / "envmap.png", envMapPreview(toEnvMap(e, t, o.rgb), 16));
        const int ch = t.channels == 3 ? 3 : 1;
        writeRender(run.dir / "render.exr", renderImage(t, e), t.width, t.height, ch);
        {
            std::vector<double> img0 = renderImage(t, e0);
            Image i0(t.width, t.height, ch);
            for (size_t i = 0; i < img0.size(); ++i) i0.data[i] = static_cast<float>(img0[i]);
            writePng(run.dir / "initial.png", i0);
        }
        writeText(run.dir / "loss.csv", csv.str());

        const auto& prov = job.transport.file.provenance;
        json s;
        s["optimizer"] = run.optimizer.method;
        s["lambda"] = lambda;
        s["reg"] = oo.reg == RegTarget::EnvMap ? "envmap" : "image";
        s["smooth_abs"] = oo.smoothAbs;
        s["init"] = o.init;
        s["rgb"] = o.rgb;
        s["mask"] = o.mask.empty() ? "object" : o.mask;
        s["mask_pixels"] = job.maskPixels;
        s["iterations"] = run.optimizer.iterations;
        s["evaluations"] = run.optimizer.evaluations;
        s["termination"] = run.optimizer.termination;
        s["initial_loss"] = run.initial.total;
        s["final_loss"] = run.final.total;
        s["initial"] = partsJson(run.initial);
        s["final"] = partsJson(run.final);
        s["seconds_precompute"] =
            job.transport.cacheHit || isTransportFile(o.input) ? 0.0 : job.transport.secondsTotal;
        s["seconds_load_transport"] = job.transport.secondsTotal;
        s["transport_cache_hit"] = job.transport.cacheHit;
        s["seconds_optimize"] = run.optimizer.seconds;
        s["transport"] = {{"file", job.transport.path.string()},
                          {"fingerprint", prov.fingerprint},
                          {"spp", prov.spp},
                          {"seed", prov.seed},
                          {"max_depth", prov.maxDepth},
                          {"channels", t.channels},
                          {"storage", t.storage == TransportStorage::Sparse ? "csr" : "dense"},
                          {"nnz", t.nnz()},
                          {"density", t.density()},
                          {"bytes", t.bytes()},
                          {"image", {t.width, t.height}},
                          {"envmap", {t.envWidth, t.envHeight}}};
        writeText(run.dir / "summary.json", s.dump(2) + "\n");
        sweepCsv << std::setprecision(10) << lambda << ',' << run.optimizer.method << ','
                 << run.optimizer.iterations << ',' << run.optimizer.evaluations << ','
                 << run.initial.total << ',' << run.final.total << ',' << run.final.lGrad << ','
                 << run.final.lReg << ',' << run.optimizer.seconds << '\n';
        job.runs.push_back(std::move(run));
    }
    if (sweep) writeText(o.outDir / "sweep.csv", sweepCsv.str());
    return job;
}

}  // namespace sl
