#include "scene/EnvMapBasis.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "core/Error.h"

namespace sl {

EnvMapBasis::EnvMapBasis(int width, int height) : width_(width), height_(height) {
    // Mitsuba requires at least 2×3 texels; the bilinear rows need H >= 2.
    if (width < 2 || height < 3)
        throw inputError(
            "envmap",
            "size " + std::to_string(width) + "x" + std::to_string(height) + " is too small",
            "use width >= 2 and height >= 3 (default " + std::to_string(kDefaultEnvMapGrid.width) +
                "x" + std::to_string(kDefaultEnvMapGrid.height) + ")");
}

std::array<double, 2> EnvMapBasis::directionToUv(const Vec3d& d) {
    double u = std::atan2(d.x, -d.z) * (0.5 * std::numbers::inv_pi);
    double v = std::acos(std::clamp(d.y, -1.0, 1.0)) * std::numbers::inv_pi;
    return {u, v};
}

Vec3d EnvMapBasis::uvToDirection(double u, double v) {
    double theta = v * std::numbers::pi, phi = u * 2.0 * std::numbers::pi;
    double st = std::sin(theta);
    return {std::sin(phi) * st, std::cos(theta), -std::cos(phi) * st};
}

TexelWeights EnvMapBasis::weights(const Vec3f& d) const {
    // Same float arithmetic as Mitsuba's scalar path where it matters: u shifted by half a
    // texel, wrapped with floor, scaled by W (the padded width minus one) and H-1.
    float u = std::atan2(d.x, -d.z) * (0.5f * std::numbers::inv_pi_v<float>);
    float v = std::acos(std::clamp(d.y, -1.0f, 1.0f)) * std::numbers::inv_pi_v<float>;
    u -= 0.5f / static_cast<float>(width_);
    u -= std::floor(u);
    float x = u * static_cast<float>(width_);
    float y = v * static_cast<float>(height_ - 1);
    int i0 = std::min(static_cast<int>(x), width_ - 1);
    int j0 = std::min(static_cast<int>(y), height_ - 2);
    float fx = x - static_cast<float>(i0), fy = y - static_cast<float>(j0);
    int i1 = i0 + 1 == width_ ? 0 : i0 + 1;  // the padded column is a copy of column 0
    auto idx = [&](int j, int i) { return static_cast<uint32_t>(j * width_ + i); };
    TexelWeights w;
    w.index = {idx(j0, i0), idx(j0, i1), idx(j0 + 1, i0), idx(j0 + 1, i1)};
    w.weight = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
    return w;
}

Vec3d EnvMapBasis::texelDirection(int row, int col) const {
    double v = static_cast<double>(row) / (height_ - 1);
    double u = (col + 0.5) / width_;
    return uvToDirection(u, v);
}

}  // namespace sl
