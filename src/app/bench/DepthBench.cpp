#include "app/bench/DepthBench.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "app/host/Plot.h"
#include "app/pipeline/AutoDepth.h"
#include "core/Color.h"
#include "core/Error.h"
#include "core/Progress.h"
#include "io/SceneFile.h"
#include "render/Render.h"
#include "scene/Scene.h"

namespace sl {

DepthBenchResult runDepthBench(const DepthBenchOptions& o) {
    if (o.resolution < 1)
        throw inputError(option("size"), "is " + std::to_string(o.resolution), "use >= 1");
    if (o.spp < 1) throw inputError(option("spp"), "is " + std::to_string(o.spp), "use >= 1");
    if (o.maxDepth < 3 || o.maxDepth > 64)
        throw inputError(option("max-depth"), "is " + std::to_string(o.maxDepth),
                         "use 3 .. 64 (max_depth 2 is one reflection)");
    if (!(o.threshold > 0 && o.threshold < 1))
        throw inputError(option("threshold"), "is " + std::to_string(o.threshold),
                         "use a share in (0, 1), e.g. 0.001");
    DepthBenchResult r;
    r.options = o;
    SceneDesc d =
        readSceneFile(o.scene.empty() ? bundledDefaultScene() : o.scene, o.sceneOverrides);
    d.camera.width = d.camera.height = o.resolution;
    auto scene = loadScene(d);
    r.sceneMaxDepth = scene->desc.render.maxDepth;
    RenderOptions ro = renderOptionsFor(*scene);
    ro.spp = o.spp;
    ro.threads = o.threads;
    std::vector<double> energy(static_cast<size_t>(o.maxDepth) + 1, 0.0);
    ProgressTask task("bench depth", o.maxDepth);
    for (int depth = 1; depth <= o.maxDepth; ++depth) {
        TraceSummary sum;
        const double e = whiteEnergy(*scene, ro, depth, &sum);
        energy[static_cast<size_t>(depth)] = e;
        DepthBenchRow row;
        row.maxDepth = depth;
        row.energy = e;
        row.added = e > 0 ? (e - energy[static_cast<size_t>(depth) - 1]) / e : 0;
        row.seconds = sum.seconds;
        row.rays = sum.rays;
        r.rows.push_back(row);
        task.advance();
    }
    r.choice = chooseMaxDepth(energy, o.threshold);
    return r;
}

std::string DepthBenchResult::csv() const {
    std::ostringstream os;
    os << "max_depth,energy,added_share,seconds,rays,image,spp,threshold,chosen_max_depth\n";
    for (const DepthBenchRow& row : rows)
        os << row.maxDepth << ',' << row.energy << ',' << row.added << ',' << row.seconds << ','
           << row.rays << ',' << options.resolution << ',' << options.spp << ','
           << options.threshold << ',' << choice.maxDepth << '\n';
    return os.str();
}

}  // namespace sl
