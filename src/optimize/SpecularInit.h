// The `specular` initial env map of the paper's §5.2 (Fig. 7(d)): where camera rays end up
// after reflecting off the part as off a mirror.
//
// Definition:
//  * one ray per pixel (spp = 1), through the pixel CENTRE: camera.generateRay(x + 0.5, y + 0.5)
//    (no jitter, so the map is deterministic and does not depend on the scene's seed);
//  * at each surface hit the ray is reflected as by the smooth `conductor` (a mirror) about the
//    hit's geometric normal n: r = d − 2(d·n)n, whatever the scene's material or roughness;
//    a ray arriving from below the surface (d·n ≥ 0) is absorbed (conductors are one-sided);
//  * bounces follow the renderer's path-length rule (render/PathTracer.h, Mitsuba's max_depth):
//    a path that hits the surface at depth maxDepth − 1 ends without light, so with maxDepth = 2
//    only singly reflected rays escape; camera rays that miss the part count for nothing;
//  * each escaping direction adds 1 (not its Fresnel throughput: a histogram of directions) to
//    the texels EnvMapBasis::weights gives it, split bilinearly (weights summing to 1), so it is
//    the env-map basis the renderer reads;
//  * the histogram is divided by its largest texel, so the map is in [0, 1] with max 1.
#pragma once

#include <vector>

namespace sl {

struct Scene;

/// E0 on scene.basis (width*height values, or 3 per texel interleaved with the same value in
/// every channel when rgb). Throws InputError when no ray escapes (no camera ray hits the part,
/// or maxDepth < 2), saying which.
std::vector<double> specularInitialEnvMap(const Scene& scene, int maxDepth, bool rgb);

}  // namespace sl
