// RadianceSink: turns escaped paths into an image under a given env map, I = Σ w · E(d).
#pragma once

#include <vector>

#include "core/Image.h"
#include "render/PathSink.h"
#include "scene/EnvMap.h"
#include "scene/EnvMapBasis.h"

namespace sl {

class RadianceSink : public PathSink {
  public:
    /// env must be on basis's grid (1 channel: gray, drives R, G, B; 3: RGB).
    RadianceSink(const EnvMapBasis& basis, const EnvMap& env, int width, int height);
    void consume(const PixelPaths& pixel) override;

    /// The RGB image (linear), accumulated in double, returned as float.
    Image image() const;
    /// Radiance of one escaped direction: Σ_k w_k E_k, per channel.
    Vec3d lookup(const Vec3f& direction) const;

  private:
    const EnvMapBasis& basis_;
    const EnvMap& env_;
    int width_, height_;
    std::vector<Vec3d> sum_;
};

}  // namespace sl
