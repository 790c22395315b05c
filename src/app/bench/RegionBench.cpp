#include "app/bench/RegionBench.h"

#include <algorithm>
#include <sstream>

#include "app/host/Plot.h"
#include "app/pipeline/AutoDepth.h"
#include "app/pipeline/LossMask.h"
#include "core/Error.h"
#include "core/Interrupt.h"
#include "core/Progress.h"
#include "core/Stats.h"
#include "core/Stopwatch.h"
#include "io/SceneFile.h"
#include "objective/ImageSpace.h"
#include "render/Render.h"
#include "scene/Scene.h"
#include "transport/TransportSink.h"

namespace sl {

namespace {

bool sameMatrix(TransportMatrix a, TransportMatrix b) {
    a.toSparse();
    b.toSparse();
    return a.rowPtr == b.rowPtr && a.colIdx == b.colIdx && a.values == b.values &&
           a.objectMask == b.objectMask;
}

}  // namespace

std::string RegionBenchResult::csv() const {
    std::ostringstream s;
    s.precision(10);
    s << "setting,detail,width,height,spp,max_depth,pixels,camera_rays,rays,nnz,bytes,seconds,"
         "ratio_rays,ratio_bytes,ratio_seconds,same_as_baseline\n";
    const RegionBenchRow& b = rows.front();
    for (const RegionBenchRow& r : rows)
        s << r.name << ",\"" << r.detail << "\"," << width << ',' << height << ',' << options.spp
          << ',' << r.maxDepth << ',' << r.pixels << ',' << r.cameraRays << ',' << r.rays << ','
          << r.nnz << ',' << r.bytes << ',' << r.seconds << ','
          << static_cast<double>(r.rays) / static_cast<double>(b.rays) << ','
          << static_cast<double>(r.bytes) / static_cast<double>(b.bytes) << ','
          << r.seconds / b.seconds << ',' << (r.sameAsBaseline ? 1 : 0) << '\n';
    return s.str();
}

RegionBenchResult runRegionBench(const RegionBenchOptions& o) {
    if (o.resolution < 8)
        throw inputError(option("size"), "is " + std::to_string(o.resolution), "use >= 8");
    if (o.spp < 2 || o.spp % 2)
        throw inputError(option("spp"), "is " + std::to_string(o.spp),
                         "use an even number >= 2 (two halves)");
    if (o.repeats < 1)
        throw inputError(option("repeats"), "is " + std::to_string(o.repeats), "use >= 1");
    SceneDesc d =
        readSceneFile(o.scene.empty() ? bundledDefaultScene() : o.scene, o.sceneOverrides);
    d.camera.width = d.camera.height = o.resolution;
    auto scene = loadScene(d);
    RegionBenchResult r;
    r.options = o;
    r.width = r.height = o.resolution;

    RenderOptions base = renderOptionsFor(*scene);
    base.spp = o.spp;
    base.sampleSets = 2;
    base.threads = o.threads;
    struct Setting {
        RegionBenchRow row;
        RenderOptions ro;
        bool autoDepth = false;
    };
    std::vector<Setting> settings(4);
    settings[0].row = {"every pixel", "no culling: the baseline"};
    settings[0].ro = base;
    settings[0].ro.cullBackground = false;
    settings[1].row = {"footprint", "the default: pixels that cannot see the part skipped"};
    settings[1].ro = base;
    settings[2].row = {"mask only", "footprint + the scratch map's pixels only"};
    settings[2].ro = base;
    settings[2].ro.pixels =
        lossMaskRegion(LossMaskSpec{LossMaskKind::Scratch, {}}, *scene, ScratchMapOptions{});
    settings[3].row = {"max_depth auto", ""};
    settings[3].ro = base;
    settings[3].autoDepth = true;

    std::vector<std::vector<double>> seconds(settings.size());
    TransportMatrix baseline;
    ProgressTask task("bench regions", static_cast<double>(o.repeats * settings.size()));
    for (int rep = 0; rep < o.repeats; ++rep)
        for (size_t k = 0; k < settings.size(); ++k) {
            throwIfInterrupted();
            Setting& s = settings[k];
            const Stopwatch clock;
            RenderOptions ro = s.ro;
            if (s.autoDepth) {
                AutoDepthOptions a;
                a.threads = o.threads;
                const DepthChoice c = autoMaxDepth(*scene, a);
                ro.maxDepth = c.maxDepth;
                s.row.detail = "footprint + " + c.reason;
            }
            PrecomputeResult p = precomputeTransport(*scene, ro, 1);
            seconds[k].push_back(clock.seconds());
            RegionBenchRow& row = s.row;
            row.rays = p.summary.rays;
            row.cameraRays = p.summary.cameraRays;
            row.pixels = p.summary.cameraRays / static_cast<uint64_t>(o.spp);
            row.nnz = p.matrix.nnz();
            row.bytes = p.matrix.bytes();
            row.maxDepth = ro.maxDepth;
            if (k == 0 && rep == 0) baseline = p.matrix;
            if (k == 1 && rep == 0) row.sameAsBaseline = sameMatrix(p.matrix, baseline);
            task.advance();
        }
    for (size_t k = 0; k < settings.size(); ++k) {
        settings[k].row.seconds = median(seconds[k]);
        r.rows.push_back(settings[k].row);
    }
    return r;
}

}  // namespace sl
