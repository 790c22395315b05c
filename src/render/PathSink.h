// PathSink: where the path tracer delivers its escaped paths, one pixel at a time.
// One tracer feeds every sink (radiance image, transport matrix, ...), so the sinks agree
// by construction: same seeds, same samples, same paths.
#pragma once

#include <cstdint>
#include <span>

#include "core/Vec3.h"

namespace sl {

/// A path that left the scene toward the env map: its throughput already divided by spp
/// (so a pixel's value is the plain sum over its paths of weight · E(direction)).
struct EscapedPath {
    Rgb weight;
    Vec3f direction;   // unit world direction the path travels when it escapes
    uint32_t set = 0;  // sample set of the camera sample (RenderOptions::sampleSets)
};

struct PixelPaths {
    uint32_t pixel = 0;                  // y * width + x
    uint32_t primaryHits = 0;            // samples whose camera ray hit the part (of spp)
    std::span<const EscapedPath> paths;  // in sample order
};

class PathSink {
  public:
    virtual ~PathSink() = default;
    /// Called exactly once per pixel, possibly concurrently for different pixels.
    virtual void consume(const PixelPaths& pixel) = 0;
};

}  // namespace sl
