#include "scene/EnvMapPresets.h"

#include <algorithm>
#include <cmath>

#include "core/Error.h"
#include "scene/EnvMapBasis.h"

namespace sl {

EnvMap studioEnvMap(int width, int height) {
    EnvMapBasis basis(width, height);
    EnvMap e = EnvMap::constant(width, height, 0.0f, 1);
    const Vec3d softbox = normalize(Vec3d{0.0, 0.9, -0.42});  // 65° up, toward -z
    const Vec3d strip = normalize(Vec3d{1.0, 0.25, 0.0});     // low, toward +x
    for (int j = 0; j < height; ++j) {
        for (int i = 0; i < width; ++i) {
            Vec3d d = basis.texelDirection(j, i);
            double v = d.y > 0 ? 0.05 + 0.15 * d.y : 0.03;  // sky gradient / ground
            if (dot(d, softbox) > std::cos(0.33)) v = 1.0;
            double alongStrip = std::abs(std::asin(std::clamp(d.y, -1.0, 1.0)) - 0.25);
            if (dot(d, strip) > std::cos(0.7) && alongStrip < 0.1) v = std::max(v, 0.8);
            e.texels[static_cast<size_t>(j) * width + i] = static_cast<float>(v);
        }
    }
    return e;
}

const std::vector<std::string>& presetNames() {
    static const std::vector<std::string> names{"studio"};
    return names;
}

EnvMap presetEnvMap(const std::string& name, int width, int height) {
    if (name == "studio") return studioEnvMap(width, height);
    throw inputError("envmap.preset", "unknown preset \"" + name + "\"", "use one of: studio");
}

}  // namespace sl
