#include "app/bench/SamplingBench.h"

#include <cmath>
#include <sstream>

#include "app/host/Plot.h"
#include "core/Color.h"
#include "core/Error.h"
#include "core/Progress.h"
#include "core/Registry.h"
#include "io/EnvMapIO.h"
#include "io/SceneFile.h"
#include "render/Render.h"
#include "scene/Scene.h"

namespace sl {

namespace {

std::string alphaName(double alpha) {
    std::ostringstream os;
    os << "alpha=" << alpha;
    return os.str();
}

}  // namespace

RelativeError relativeError(const std::vector<float>& a, const std::vector<float>& ref,
                            const std::vector<uint8_t>& mask) {
    double se = 0, sa = 0, sr = 0;
    size_t n = 0;
    for (size_t p = 0; p < mask.size(); ++p) {
        if (!mask[p]) continue;
        const double ya = luminance<double>(a[3 * p], a[3 * p + 1], a[3 * p + 2]);
        const double yr = luminance<double>(ref[3 * p], ref[3 * p + 1], ref[3 * p + 2]);
        se += (ya - yr) * (ya - yr);
        sa += ya;
        sr += yr;
        ++n;
    }
    RelativeError e;
    if (n == 0 || !(sr > 0)) return e;
    e.refMean = sr / static_cast<double>(n);
    e.rmse = std::sqrt(se / static_cast<double>(n)) / e.refMean;
    e.meanDiff = (sa - sr) / sr;
    return e;
}

const SamplingBenchRow* SamplingBenchResult::find(const std::string& part, Sampling s,
                                                  int spp) const {
    for (const SamplingBenchRow& r : rows)
        if (r.part == part && r.sampling == s && r.spp == spp) return &r;
    return nullptr;
}

SamplingBenchResult runSamplingBench(const SamplingBenchOptions& o) {
    if (o.resolution < 1)
        throw inputError(option("size"), "is " + std::to_string(o.resolution), "use >= 1");
    if (o.referenceSpp < 2 || o.referenceSpp % 2 != 0)
        throw inputError(option("reference-spp"), "is " + std::to_string(o.referenceSpp),
                         "use an even number >= 2 (two halves)");
    if (o.spps.empty()) throw inputError(option("spps"), "is empty", "give e.g. 64,1024");
    for (int spp : o.spps)
        if (spp < 1)
            throw inputError(option("spps"), "contains " + std::to_string(spp), "use spp >= 1");
    if (o.alphas.empty()) throw inputError(option("alphas"), "is empty", "give e.g. 0,0.02");
    for (double a : o.alphas)
        if (!(a >= 0) || !std::isfinite(a))
            throw inputError(option("alphas"), "contains " + std::to_string(a),
                             "use 0 (the scene's material) or a roughness > 0");
    SamplingBenchResult result;
    result.options = o;
    result.options.log = nullptr;
    const std::filesystem::path file = o.scene.empty() ? bundledDefaultScene() : o.scene;
    double work = 0;
    for (int spp : o.spps) work += static_cast<double>(samplingTable().size()) * spp;
    work = (work + o.referenceSpp) * static_cast<double>(o.alphas.size());
    ProgressTask task("bench sampling", work);
    for (double alpha : o.alphas) {
        std::vector<std::string> overrides = o.sceneOverrides;
        if (alpha > 0) {
            std::ostringstream os;
            os << "material.alpha=" << alpha;
            overrides.push_back(os.str());
        }
        SceneDesc d = readSceneFile(file, overrides);
        d.camera.width = d.camera.height = o.resolution;
        auto scene = loadScene(d);
        const EnvMap env = lightFromSpec(o.envmap, scene->basis.width(), scene->basis.height(), 3,
                                         option("envmap"));
        SamplingBenchPart part;
        part.part = alpha > 0 ? alphaName(alpha) : "scene";
        part.alpha = scene->bsdf.params().alphaU;
        RenderOptions base = renderOptionsFor(*scene);
        base.threads = o.threads;

        // The reference: two independent halves; their difference measures its noise.
        RenderOptions ro = base;
        ro.sampling = kReferenceSampling;
        ro.spp = o.referenceSpp / 2;
        ro.seed = base.seed + 1000;
        const RenderResult ra = render(*scene, env, ro);
        task.advance(ro.spp);
        ro.seed = base.seed + 1001;
        const RenderResult rb = render(*scene, env, ro);
        task.advance(ro.spp);
        part.referenceSeconds = ra.summary.seconds + rb.summary.seconds;
        std::vector<float> ref(ra.image.data.size()), halfDiff(ra.image.data.size());
        for (size_t i = 0; i < ref.size(); ++i) {
            ref[i] = 0.5f * (ra.image.data[i] + rb.image.data[i]);
            halfDiff[i] = 0.5f * (ra.image.data[i] - rb.image.data[i]);
        }
        std::vector<uint8_t> mask(ra.summary.objectMask.size());
        for (size_t p = 0; p < mask.size(); ++p)
            mask[p] = ra.summary.objectMask[p] && rb.summary.objectMask[p];
        for (uint8_t m : mask) part.pixels += m;
        {
            // RMSE of (A − B)/2 relative to the reference's mean.
            const RelativeError r = relativeError(ref, ref, mask);
            double se = 0;
            for (size_t p = 0; p < mask.size(); ++p) {
                if (!mask[p]) continue;
                const double y =
                    luminance<double>(halfDiff[3 * p], halfDiff[3 * p + 1], halfDiff[3 * p + 2]);
                se += y * y;
            }
            part.referenceNoise = part.pixels && r.refMean > 0
                                      ? std::sqrt(se / static_cast<double>(part.pixels)) / r.refMean
                                      : 0;
        }
        if (o.log)
            o.log(part.part + ": reference " + std::to_string(o.referenceSpp) + " spp in " +
                  std::to_string(part.referenceSeconds) + " s");

        for (int spp : o.spps) {
            for (const SamplingRow& sr : samplingTable()) {
                const Sampling s = sr.value;
                RenderOptions r = base;
                r.sampling = s;
                r.spp = spp;
                r.seed = base.seed + 1;
                const RenderResult rr = render(*scene, env, r);
                task.advance(spp);
                const RelativeError e = relativeError(rr.image.data, ref, mask);
                SamplingBenchRow row;
                row.part = part.part;
                row.sampling = s;
                row.spp = spp;
                row.seconds = rr.summary.seconds;
                row.rays = rr.summary.rays;
                row.shadowRays = rr.summary.shadowRays;
                row.relRmse = e.rmse;
                row.relRmseNet = std::sqrt(
                    std::max(0.0, e.rmse * e.rmse - part.referenceNoise * part.referenceNoise));
                row.relMeanDiff = e.meanDiff;
                result.rows.push_back(row);
            }
        }
        result.parts.push_back(part);
    }
    return result;
}

std::string SamplingBenchResult::csv() const {
    std::ostringstream os;
    os << "part,alpha,sampling,spp,image,seconds,rays,shadow_rays,rays_per_s,rel_rmse,"
          "rel_rmse_net,rel_mean_diff,reference_spp,reference_rel_noise\n";
    for (const SamplingBenchRow& r : rows) {
        const SamplingBenchPart* p = nullptr;
        for (const SamplingBenchPart& q : parts)
            if (q.part == r.part) p = &q;
        os << r.part << ',' << (p ? p->alpha : 0) << ','
           << registryRow(samplingTable(), r.sampling).name << ',' << r.spp << ','
           << options.resolution << ',' << r.seconds << ',' << r.rays << ',' << r.shadowRays << ','
           << r.raysPerSecond() << ',' << r.relRmse << ',' << r.relRmseNet << ',' << r.relMeanDiff
           << ',' << options.referenceSpp << ',' << (p ? p->referenceNoise : 0) << '\n';
    }
    return os.str();
}

}  // namespace sl
