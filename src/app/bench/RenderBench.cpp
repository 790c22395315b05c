#include "app/bench/RenderBench.h"

#include <sstream>

#include "core/Error.h"
#include "core/Interrupt.h"
#include "core/Progress.h"
#include "core/Stats.h"
#include "core/Stopwatch.h"
#include "io/SceneFile.h"
#include "render/Render.h"
#include "scene/Scene.h"
#include "synth/SurfaceGenerator.h"

namespace sl {

namespace {

RenderBenchRow measure(const Scene& scene, const std::string& name, double genSeconds,
                       const RenderBenchOptions& o) {
    RenderOptions all = renderOptionsFor(scene);
    all.spp = o.spp;
    all.threads = o.threads;
    all.cullBackground = false;  // every pixel's camera rays, in both loops: the same rays
    RenderOptions part = all;
    part.cullBackground = true;  // the footprint's pixels, in both loops
    RenderBenchRow r;
    r.map = name;
    r.genSeconds = genSeconds;
    r.heightfield = scene.surface->stats();
    // Interleaved, so that all four see the same machine state.
    std::vector<ThroughputRow> ren, bare, renPart, barePart;
    for (int i = 0; i < o.repeats; ++i) {
        throwIfInterrupted();
        ren.push_back(benchRenderer(scene, all));
        bare.push_back(benchBareEmbree(scene, all));
        renPart.push_back(benchRenderer(scene, part));
        barePart.push_back(benchBareEmbree(scene, part));
    }
    r.renderer = medianThroughput(ren);
    r.bare = medianThroughput(bare);
    r.rendererFootprint = medianThroughput(renPart);
    r.bareFootprint = medianThroughput(barePart);
    return r;
}

}  // namespace

ThroughputRow medianThroughput(const std::vector<ThroughputRow>& rows) {
    if (rows.empty()) return {};
    std::vector<double> seconds;
    for (const ThroughputRow& r : rows) seconds.push_back(r.seconds);
    ThroughputRow m = rows.front();
    m.seconds = median(seconds);
    return m;
}

namespace {

double throughputRatio(const ThroughputRow& renderer, const ThroughputRow& bare) {
    const double b = bare.raysPerSecond();
    return b > 0 ? renderer.raysPerSecond() / b : 0;
}

}  // namespace

double RenderBenchRow::ratio() const {
    return throughputRatio(renderer, bare);
}

double RenderBenchRow::footprintRatio() const {
    return throughputRatio(rendererFootprint, bareFootprint);
}

RenderBenchResult runRenderBench(const RenderBenchOptions& o) {
    if (o.repeats < 1) throw inputError("repeats", "is " + std::to_string(o.repeats), "use >= 1");
    if (o.spp < 1) throw inputError("spp", "is " + std::to_string(o.spp), "use >= 1");
    if (o.resolution < 1)
        throw inputError(option("size"), "is " + std::to_string(o.resolution), "use >= 1");
    for (int n : o.sizes)
        if (n < 2)
            throw inputError("sizes", "contains " + std::to_string(n),
                             "use sizes of at least 2 samples");
    RenderBenchResult result;
    result.options = o;
    result.options.log = nullptr;
    ProgressTask task("bench render", static_cast<double>(o.sizes.size() + !o.scene.empty()));
    if (!o.scene.empty()) {
        SceneDesc d = readSceneFile(o.scene, o.sceneOverrides);
        d.camera.width = d.camera.height = o.resolution;
        auto scene = loadScene(d);
        result.rows.push_back(measure(*scene, o.scene.filename().string(), 0, o));
        task.advance();
    }
    for (int n : o.sizes) {
        SurfaceSpec spec;
        spec.width = spec.height = n;
        spec.pitch = 10.0 / (n - 1);  // a 10 mm part at every size
        const Stopwatch clock;
        GeneratedSurface g = generateSurface(spec);
        const double gen = clock.seconds();
        SceneDesc d;
        d.heightmap.pitch = g.pitch;
        d.material.params.ior = ComplexIor{Rgb{1.0f}, Rgb{7.0f}};  // a bright metal
        d.camera.width = d.camera.height = o.resolution;
        Scene scene(d, g.width, g.height, std::move(g.heights));
        result.rows.push_back(measure(scene, std::to_string(n) + "x" + std::to_string(n), gen, o));
        task.advance();
        if (o.log) o.log("measured " + std::to_string(n) + "x" + std::to_string(n));
    }
    return result;
}

std::string RenderBenchResult::csv() const {
    std::ostringstream os;
    os << "height_map,generate_s,build_s,vertex_bytes,embree_bytes,embree_peak_bytes,"
          "image,spp,renderer_rays,renderer_s,renderer_rays_per_s,bare_rays,bare_s,"
          "bare_rays_per_s,ratio,footprint_renderer_rays,footprint_renderer_s,"
          "footprint_renderer_rays_per_s,footprint_bare_rays,footprint_bare_s,"
          "footprint_bare_rays_per_s,footprint_ratio\n";
    for (const RenderBenchRow& r : rows)
        os << r.map << ',' << r.genSeconds << ',' << r.heightfield.buildSeconds << ','
           << r.heightfield.vertexBytes << ',' << r.heightfield.embreeBytes << ','
           << r.heightfield.embreePeakBytes << ',' << options.resolution << ',' << options.spp
           << ',' << r.renderer.rays << ',' << r.renderer.seconds << ','
           << r.renderer.raysPerSecond() << ',' << r.bare.rays << ',' << r.bare.seconds << ','
           << r.bare.raysPerSecond() << ',' << r.ratio() << ',' << r.rendererFootprint.rays << ','
           << r.rendererFootprint.seconds << ',' << r.rendererFootprint.raysPerSecond() << ','
           << r.bareFootprint.rays << ',' << r.bareFootprint.seconds << ','
           << r.bareFootprint.raysPerSecond() << ',' << r.footprintRatio() << '\n';
    return os.str();
}

}  // namespace sl
