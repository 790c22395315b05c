#include "render/Render.h"

#include "render/RadianceSink.h"
#include "scene/Scene.h"

namespace sl {

RenderResult render(const Scene& scene, const EnvMap& env, const RenderOptions& options) {
    RadianceSink sink(scene.basis, env, scene.camera.width(), scene.camera.height());
    RenderResult r;
    r.summary = PathTracer(scene).trace(options, sink);
    r.image = sink.image();
    return r;
}

RenderOptions renderOptionsFor(const Scene& scene) {
    RenderOptions o;
    o.spp = scene.desc.render.spp;
    o.maxDepth = scene.desc.render.maxDepth;
    o.seed = scene.desc.render.seed;
    o.sampling = scene.desc.render.sampling;
    return o;
}

}  // namespace sl
