#include "scene/EnvMapToE.h"

#include <stdexcept>

#include "core/Color.h"

namespace sl {

std::vector<double> envMapToE(const EnvMap& env, int channels) {
    if ((channels != 1 && channels != 3) || (env.channels != 1 && env.channels != 3))
        throw std::invalid_argument("envMapToE: channels must be 1 or 3");
    const size_t n = env.texelCount();
    if (env.channels == channels) return {env.texels.begin(), env.texels.end()};
    std::vector<double> e(n * static_cast<size_t>(channels));
    if (channels == 3) {  // a gray map on an RGB T: R, G and B alike
        for (size_t i = 0; i < 3 * n; ++i) e[i] = env.texels[i / 3];
    } else {  // a colour map on a gray T: its luminance
        for (size_t i = 0; i < n; ++i)
            e[i] = luminance(double(env.texels[3 * i]), double(env.texels[3 * i + 1]),
                             double(env.texels[3 * i + 2]));
    }
    return e;
}

}  // namespace sl
