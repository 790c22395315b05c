// The scene file's `render` section (io/SceneFile.h). Its defaults are the only definition of
// the default sample count, path length, seed and direction sampling; the renderer's
// RenderOptions (render/PathTracer.h) start from them.
#pragma once

#include <array>
#include <cstdint>
#include <span>

namespace sl {

/// How the path tracer picks directions at a surface vertex (render/PathTracer.h has the maths).
enum class Sampling { Bsdf, Stratified, Mis };
struct SamplingRow {
    Sampling value;
    const char* name;
    const char* help;
};
inline std::span<const SamplingRow> samplingTable() {
    static constexpr std::array<SamplingRow, 3> rows{{
        {Sampling::Bsdf, "bsdf", "BSDF sampling only (visible-normal GGX); the older sampler"},
        {Sampling::Stratified, "stratified",
         "BSDF sampling with the pixel's samples spread jointly over the film and the first two "
         "bounces (a randomly shifted Sobol' sequence per pixel)"},
        {Sampling::Mis, "mis",
         "BSDF sampling and env-map (emitter) sampling with a shadow ray, combined by the power "
         "heuristic"},
    }};
    return rows;
}

struct RenderDesc {
    int spp = 64;       // samples per pixel
    int maxDepth = 4;   // Mitsuba's max_depth: 2 = one reflection, 3 = up to two
    uint64_t seed = 0;  // random seed
    Sampling sampling = Sampling::Stratified;  // direction sampling (samplingTable)
};

}  // namespace sl
