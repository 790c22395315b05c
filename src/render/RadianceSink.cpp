#include "render/RadianceSink.h"

#include <stdexcept>

namespace sl {

RadianceSink::RadianceSink(const EnvMapBasis& basis, const EnvMap& env, int width, int height)
    : basis_(basis),
      env_(env),
      width_(width),
      height_(height),
      sum_(static_cast<size_t>(width) * height, Vec3d{0.0}) {
    if (env.width != basis.width() || env.height != basis.height() ||
        (env.channels != 1 && env.channels != 3) ||
        env.texels.size() != env.texelCount() * env.channels)
        throw std::invalid_argument("RadianceSink: env map does not match the env-map basis");
}

Vec3d RadianceSink::lookup(const Vec3f& d) const {
    TexelWeights tw = basis_.weights(d);
    Vec3d r{0.0};
    for (int k = 0; k < 4; ++k) {
        const double w = tw.weight[k];
        if (env_.channels == 1) {
            r += Vec3d(w * env_.texels[tw.index[k]]);
        } else {
            const float* e = &env_.texels[static_cast<size_t>(tw.index[k]) * 3];
            r += Vec3d{w * e[0], w * e[1], w * e[2]};
        }
    }
    return r;
}

void RadianceSink::consume(const PixelPaths& px) {
    Vec3d acc{0.0};
    for (const EscapedPath& p : px.paths) acc += Vec3d(p.weight) * lookup(p.direction);
    sum_[px.pixel] = acc;
}

Image RadianceSink::image() const {
    Image img(width_, height_, 3);
    for (size_t i = 0; i < sum_.size(); ++i) {
        img.data[3 * i + 0] = static_cast<float>(sum_[i].x);
        img.data[3 * i + 1] = static_cast<float>(sum_[i].y);
        img.data[3 * i + 2] = static_cast<float>(sum_[i].z);
    }
    return img;
}

}  // namespace sl
