#include "objective/CoarseLight.h"

#include <charconv>
#include <memory>
#include <stdexcept>

#include "core/Error.h"
#include "scene/EnvMapBasis.h"

namespace sl {

CoarseLight::CoarseLight(int envWidth, int envHeight, int width, int height, int channels)
    : width_(width),
      height_(height),
      channels_(channels),
      identity_(width == envWidth && height == envHeight) {
    if (channels != 1 && channels != 3)
        throw std::invalid_argument("CoarseLight: channels must be 1 or 3");
    if (envWidth < 1 || envHeight < 2 || width < 1 || height < 2 || width > envWidth ||
        height > envHeight)
        throw inputError(option("light-grid"),
                         "a grid of " + std::to_string(width) + "x" + std::to_string(height) +
                             " nodes does not fit the " + std::to_string(envWidth) + "x" +
                             std::to_string(envHeight) + " env map",
                         "use a grid of at least 1x2 and at most the env map's size");
    const EnvMapBasis fine(envWidth, envHeight), coarse(width, height);
    rows_.resize(static_cast<size_t>(envWidth) * envHeight);
    columnSum_.assign(static_cast<size_t>(width) * height, 0.0);
    for (int j = 0; j < envHeight; ++j)
        for (int i = 0; i < envWidth; ++i) {
            Row& r = rows_[static_cast<size_t>(j) * envWidth + i];
            if (identity_) {
                r = Row{{static_cast<uint32_t>(j * envWidth + i), 0, 0, 0}, {1.0f, 0, 0, 0}};
            } else {
                const TexelWeights w = coarse.weights(Vec3f(fine.texelDirection(j, i)));
                for (int k = 0; k < 4; ++k) {
                    r.node[k] = w.index[k];
                    r.weight[k] = w.weight[k];
                }
            }
            for (int k = 0; k < 4; ++k) columnSum_[r.node[k]] += r.weight[k];
        }
}

std::vector<double> CoarseLight::prolong(std::span<const double> theta) const {
    if (theta.size() != parameters())
        throw std::invalid_argument("CoarseLight::prolong: θ has the wrong size");
    std::vector<double> e(envValues(), 0.0);
    const auto c = static_cast<size_t>(channels_);
    for (size_t t = 0; t < rows_.size(); ++t)
        for (int k = 0; k < 4; ++k)
            for (size_t ch = 0; ch < c; ++ch)
                e[t * c + ch] += rows_[t].weight[k] * theta[rows_[t].node[k] * c + ch];
    return e;
}

std::vector<double> CoarseLight::gradientInNodes(std::span<const double> g) const {
    if (g.size() != envValues())
        throw std::invalid_argument(
            "CoarseLight::gradientInNodes: the gradient has the wrong size");
    std::vector<double> r(parameters(), 0.0);
    const auto c = static_cast<size_t>(channels_);
    for (size_t t = 0; t < rows_.size(); ++t)
        for (int k = 0; k < 4; ++k)
            for (size_t ch = 0; ch < c; ++ch)
                r[rows_[t].node[k] * c + ch] += rows_[t].weight[k] * g[t * c + ch];
    return r;
}

std::vector<double> CoarseLight::project(std::span<const double> e) const {
    std::vector<double> theta = gradientInNodes(e);
    const auto c = static_cast<size_t>(channels_);
    for (size_t n = 0; n < columnSum_.size(); ++n)
        for (size_t ch = 0; ch < c; ++ch)
            theta[n * c + ch] = columnSum_[n] > 0 ? theta[n * c + ch] / columnSum_[n] : 0.0;
    return theta;
}

Problem CoarseLight::over(Problem fine) const {
    if (fine.dimension != envValues())
        throw std::invalid_argument("CoarseLight::over: the problem is not over this env map");
    Problem p;
    p.dimension = parameters();
    p.lower = fine.lower;
    p.upper = fine.upper;
    auto self = std::make_shared<const CoarseLight>(*this);
    auto f = std::make_shared<Problem>(std::move(fine));
    p.evaluate = [self, f](std::span<const double> theta, std::span<double> grad) {
        const std::vector<double> e = self->prolong(theta);
        if (grad.empty()) return f->evaluate(e, {});
        std::vector<double> g(e.size());
        const double value = f->evaluate(e, g);
        const std::vector<double> r = self->gradientInNodes(g);
        std::copy(r.begin(), r.end(), grad.begin());
        return value;
    };
    return p;
}

std::string LightGrid::name() const {
    return perTexel() ? std::string("texels")
                      : std::to_string(width) + "x" + std::to_string(height) + " nodes";
}

LightGrid parseLightGrid(std::string_view text) {
    if (text == "texels") return LightGrid{};
    int w = 0, h = 0;
    const char* end = text.data() + text.size();
    auto r = std::from_chars(text.data(), end, w);
    const bool sep = r.ec == std::errc() && r.ptr != end && *r.ptr == 'x';
    if (sep) r = std::from_chars(r.ptr + 1, end, h);
    if (!sep || r.ec != std::errc() || r.ptr != end || w < 1 || h < 2)
        throw inputError(option("light-grid"),
                         "'" + std::string(text.substr(0, 40)) + (text.size() > 40 ? "..." : "") +
                             "' is not a grid",
                         "use WxH nodes (W >= 1, H >= 2), e.g. 24x12, or 'texels'");
    return LightGrid{w, h};
}

std::string CoarseLight::name() const {
    return std::to_string(width_) + "x" + std::to_string(height_);
}

}  // namespace sl
