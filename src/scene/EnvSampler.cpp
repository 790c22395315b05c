// EnvSampler: see EnvSampler.h for the density and why it is one.
#include "scene/EnvSampler.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace sl {

namespace {

/// t in [0, 1] with density proportional to a(1 − t) + b t (a, b >= 0, a + b > 0), by
/// inverting its CDF in the form that is stable for a ≈ b.
double sampleLinear(double a, double b, double u) {
    const double den = a + std::sqrt(std::max(0.0, (1.0 - u) * a * a + u * b * b));
    return den > 0 ? std::clamp(u * (a + b) / den, 0.0, 1.0) : u;
}

}  // namespace

EnvSampler::EnvSampler(const EnvMapBasis& basis, std::span<const float> guide)
    : basis_(basis), W_(basis.width()), H_(basis.height()) {
    const size_t n = static_cast<size_t>(basis.texelCount());
    if (!guide.empty() && guide.size() != n)
        throw std::invalid_argument("EnvSampler: the guide needs one value per texel");
    g_.resize(n);
    for (int j = 0; j < H_; ++j) {
        const double sinTheta = std::sin(std::numbers::pi * j / (H_ - 1));
        for (int i = 0; i < W_; ++i) {
            const size_t t = static_cast<size_t>(j) * W_ + i;
            const float v = guide.empty() ? 1.0f : guide[t];
            if (!(v >= 0.0f) || !std::isfinite(v))
                throw std::invalid_argument("EnvSampler: guide values must be finite and >= 0");
            // Exact zeros at the poles (sin π = 1.2e-16 would otherwise leave a sliver).
            g_[t] = j == 0 || j == H_ - 1 ? 0.0f : static_cast<float>(v * sinTheta);
        }
    }
    cdf_.assign(static_cast<size_t>(W_) * (H_ - 1) + 1, 0.0);
    for (int j = 0; j < H_ - 1; ++j) {
        for (int i = 0; i < W_; ++i) {
            const int i1 = i + 1 == W_ ? 0 : i + 1;
            const double m = 0.25 * (static_cast<double>(g_[j * W_ + i]) + g_[j * W_ + i1] +
                                     g_[(j + 1) * W_ + i] + g_[(j + 1) * W_ + i1]);
            const size_t c = static_cast<size_t>(j) * W_ + i;
            cdf_[c + 1] = cdf_[c] + m;
        }
    }
    const double z = cdf_.back();
    if (!(z > 0)) throw std::invalid_argument("EnvSampler: the guide is zero everywhere");
    for (double& c : cdf_) c /= z;
    cdf_.back() = 1.0;
    scale_ = static_cast<double>(W_) * (H_ - 1) / (2.0 * std::numbers::pi * std::numbers::pi * z);
}

EnvSampler::Sample EnvSampler::sample(float u1, float u2) const {
    // The cell: the first whose cumulative mass exceeds u1 (zero-mass cells are never chosen).
    const double u = u1;
    const auto it = std::upper_bound(cdf_.begin() + 1, cdf_.end(), u);
    const size_t c = std::min(static_cast<size_t>(it - cdf_.begin()) - 1, cdf_.size() - 2);
    const double lo = cdf_[c], hi = cdf_[c + 1];
    const double ur = hi > lo ? std::clamp((u - lo) / (hi - lo), 0.0, 1.0) : 0.5;
    const int j = static_cast<int>(c / W_), i = static_cast<int>(c % W_);
    const int i1 = i + 1 == W_ ? 0 : i + 1;
    const double g00 = g_[j * W_ + i], g10 = g_[j * W_ + i1], g01 = g_[(j + 1) * W_ + i],
                 g11 = g_[(j + 1) * W_ + i1];
    const double fy = sampleLinear(g00 + g10, g01 + g11, ur);
    const double fx = sampleLinear(g00 * (1 - fy) + g01 * fy, g10 * (1 - fy) + g11 * fy, u2);
    // Back through EnvMapBasis' mapping: x = frac(u − ½/W)·W, y = v·(H−1).
    const double uu = (i + fx + 0.5) / W_, vv = (j + fy) / (H_ - 1);
    const Vec3d d = EnvMapBasis::uvToDirection(uu, vv);
    Sample s;
    s.direction =
        normalize(Vec3f(static_cast<float>(d.x), static_cast<float>(d.y), static_cast<float>(d.z)));
    s.pdf = pdf(s.direction);
    return s;
}

float EnvSampler::pdf(const Vec3f& d) const {
    const double sinTheta = std::sqrt(std::max(0.0, 1.0 - static_cast<double>(d.y) * d.y));
    if (!(sinTheta > 0)) return 0.0f;
    const TexelWeights tw = basis_.weights(d);
    double pxy = 0;
    for (int k = 0; k < 4; ++k) pxy += static_cast<double>(tw.weight[k]) * g_[tw.index[k]];
    return static_cast<float>(pxy * scale_ / sinTheta);
}

}  // namespace sl
