// EnvMap: the environment map's texel values on the EnvMapBasis grid
// (see scene/EnvMapBasis.h for the direction <-> texel convention).
// channels == 1: grayscale E, drives R, G and B equally. channels == 3: linear RGB.
#pragma once

#include <cstddef>
#include <vector>

#include "core/Image.h"
#include "scene/EnvMapBasis.h"

namespace sl {

/// The brightest radiance a light may give, relative to the optimizer's [0, 1] (1 is its
/// brightest texel): a constant light (`const:V`) and a lamp in lamps.json are refused above it.
/// float overflows at 3.4e38, and a render sums many texels, so far below that.
constexpr double kMaxRadiance = 1e6;

struct EnvMap {
    int width = kDefaultEnvMapGrid.width, height = kDefaultEnvMapGrid.height, channels = 1;
    std::vector<float> texels;  // row-major, row 0 = +Y (top), channels interleaved

    static EnvMap constant(int w, int h, float value, int channels = 1) {
        EnvMap e;
        e.width = w;
        e.height = h;
        e.channels = channels;
        e.texels.assign(static_cast<size_t>(w) * h * channels, value);
        return e;
    }
    size_t texelCount() const { return static_cast<size_t>(width) * height; }
    Image toImage() const {
        Image img(width, height, channels);
        img.data = texels;
        return img;
    }
};

}  // namespace sl
