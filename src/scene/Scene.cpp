#include "scene/Scene.h"

#include <algorithm>
#include <cstdio>
#include <utility>

namespace sl {

CameraDesc resolveCamera(const CameraSpec& spec, const Heightfield& s) {
    CameraDesc c = defaultCameraFor(s.extentX(), s.extentZ(), s.minHeight(), s.maxHeight(),
                                    spec.fovDeg, spec.width, spec.height);
    c.type = spec.type;
    if (spec.origin) c.origin = *spec.origin;
    if (spec.target) c.target = *spec.target;
    if (spec.up) c.up = *spec.up;
    c.widthMm =
        spec.widthMm.value_or(CameraSpec::kWidthMmFactor * std::max(s.extentX(), s.extentZ()));
    return c;
}

Scene::Scene(SceneDesc d, int w, int h, std::vector<float> hs)
    : desc(std::move(d)),
      mapWidth(w),
      mapHeight(h),
      heights(std::move(hs)),
      surface(std::make_unique<Heightfield>(w, h, desc.heightmap.pitch, heights)),
      camera(resolveCamera(desc.camera, *surface)),
      bsdf(desc.material.params),
      basis(desc.envmap.width, desc.envmap.height) {}

std::string HeightmapLoad::text(int width, int height, double pitch) const {
    char b[96];
    std::snprintf(b, sizeof b, "%dx%d samples at %.6g mm", width, height, pitch);
    std::string t = b;
    if (!format.empty()) t += ", " + format;
    if (!channel.empty()) t += "; " + channel;
    if (!resampling.empty()) t += "; " + resampling;
    t += "; levelling: " + levelling.text();
    return t;
}

}  // namespace sl
