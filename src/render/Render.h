// render(): the path tracer with a RadianceSink — the image of a scene under one env map.
#pragma once

#include "core/Image.h"
#include "render/PathTracer.h"
#include "scene/EnvMap.h"
#include "scene/RenderDesc.h"

namespace sl {

struct Scene;

struct RenderResult {
    Image image;  // linear RGB, background 0
    TraceSummary summary;
};

RenderResult render(const Scene& scene, const EnvMap& env, const RenderOptions& options);

/// RenderOptions from the scene's `render` section.
RenderOptions renderOptionsFor(const Scene& scene);
RenderOptions renderOptionsFor(const RenderDesc& render);

}  // namespace sl
