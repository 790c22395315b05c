// The scene file's `render` section (io/SceneFile.h). Its defaults are the only definition of
// the default sample count, path length and seed; the renderer's RenderOptions
// (render/PathTracer.h) start from them.
#pragma once

#include <cstdint>

namespace sl {

struct RenderDesc {
    int spp = 64;       // samples per pixel
    int maxDepth = 4;   // Mitsuba's max_depth: 2 = one reflection, 3 = up to two
    uint64_t seed = 0;  // random seed
};

}  // namespace sl
