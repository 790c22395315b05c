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
    return renderOptionsFor(scene.desc.render);
}

RenderOptions renderOptionsFor(const RenderDesc& render) {
    RenderOptions o;
    o.spp = render.spp;
    o.maxDepth = render.maxDepth;
    o.seed = render.seed;
    o.sampling = render.sampling;
    return o;
}

}  // namespace sl
