#include "render/Renderer.h"

#include <cmath>
#include <stdexcept>

#include "render/Render.h"
#include "scene/Scene.h"

namespace sl {

BuiltinRenderer::BuiltinRenderer(const Scene& scene, RenderOptions options)
    : scene_(scene), options_(std::move(options)) {
    options_.progress = {};
}

Image BuiltinRenderer::render(const EnvMap& env, uint64_t seed, int threads) const {
    RenderOptions o = options_;
    o.seed = seed;
    o.threads = threads;
    return sl::render(scene_, env, o).image;
}

int BuiltinRenderer::width() const {
    return scene_.camera.width();
}

int BuiltinRenderer::height() const {
    return scene_.camera.height();
}

double linearityError(const Renderer& renderer, const EnvMap& e1, const EnvMap& e2, uint64_t seed,
                      int threads) {
    if (e1.texels.size() != e2.texels.size() || e1.width != e2.width || e1.height != e2.height ||
        e1.channels != e2.channels)
        throw std::invalid_argument("linearityError: the two env maps differ in shape");
    EnvMap sum = e1;
    for (size_t i = 0; i < sum.texels.size(); ++i) sum.texels[i] += e2.texels[i];
    const Image a = renderer.render(e1, seed, threads);
    const Image b = renderer.render(e2, seed, threads);
    const Image s = renderer.render(sum, seed, threads);
    if (a.data.size() != s.data.size() || b.data.size() != s.data.size())
        throw std::runtime_error("linearityError: the renders differ in size");
    double num = 0, den = 0;
    for (size_t i = 0; i < s.data.size(); ++i) {
        const double d = static_cast<double>(s.data[i]) - a.data[i] - b.data[i];
        num += d * d;
        den += static_cast<double>(s.data[i]) * s.data[i];
    }
    return den > 0 ? std::sqrt(num / den) : 0.0;
}

}  // namespace sl
