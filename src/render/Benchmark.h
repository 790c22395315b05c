// Renderer throughput against bare Embree closest-hit queries on the same height field,
// measured side by side in one run (see `scratchlight bench render`).
#pragma once

#include <cstdint>
#include <string>

#include "render/PathTracer.h"

namespace sl {

struct Scene;

struct ThroughputRow {
    std::string workload;
    uint64_t rays = 0;
    double seconds = 0;
    double raysPerSecond() const { return seconds > 0 ? static_cast<double>(rays) / seconds : 0; }
};

/// The renderer (path tracer + radiance sink, scene material) at options.spp.
ThroughputRow benchRenderer(const Scene& scene, const RenderOptions& options);
/// Bare rtcIntersect1 on the same camera rays (same jitter, same threads, and with
/// options.cullBackground the same pixels: those of the part's footprint, render/Footprint.h),
/// then, for rays that hit, the mirror-reflected ray, up to options.maxDepth-1 bounces: the
/// renderer's ray distribution for a smooth surface with no BSDF sampling and no sink.
ThroughputRow benchBareEmbree(const Scene& scene, const RenderOptions& options);

}  // namespace sl
