// Mitsuba 3 export: the scene as a Mitsuba 3 XML scene, so a user with Mitsuba 3 can render the
// identical scene and compare (`scratchlight export-mitsuba SCENE.json OUTDIR [--envmap FILE]`).
//
// OUTDIR/scene.xml, OUTDIR/heightfield.ply, OUTDIR/envmap.exr. Render with a `scalar_rgb` (or
// llvm_/cuda_ad_rgb) variant: `mitsuba -m scalar_rgb scene.xml`. Every choice below follows a
// convention of this code base (README "Conventions") and was checked against the Mitsuba 3
// sources (github.com/mitsuba-renderer/mitsuba3):
//
//   height field  `ply` shape, binary little endian: vertex x, y, z, u, v (float32), face
//                 `vertex_indices` (uchar count, int indices). Sample (row j, col i) at
//                 x = (i − (W−1)/2)·p, y = h, z = (j − (H−1)/2)·p (scene/Heightfield.h);
//                 u = i/(W−1) along +x, v = j/(H−1) along +z, so Mitsuba's shading frame
//                 (s = dp/du projected onto the tangent plane, t = n × s) is ours and
//                 alpha_u acts along +x. Each cell (v0=(i,j), v1=(i+1,j), v2=(i+1,j+1),
//                 v3=(i,j+1)) is split as Embree's grid: triangles {v0,v1,v3} and {v2,v3,v1},
//                 written with the winding (v0,v3,v1), (v2,v1,v3) whose Mitsuba face normal
//                 normalize(cross(p1 − p0, p2 − p0)) points to +Y (conductors are one-sided).
//                 `face_normals` = true: the geometric normals we shade with (without it Mitsuba
//                 would compute smooth vertex normals).
//   camera        `perspective`: to_world = lookat(origin, target, up), `fov` with
//                 fov_axis="x"; `orthographic`: to_world = lookat · scale(w/2, w/2, 1) (the XML
//                 applies transform operations in the order written: scale, then lookat).
//                 near_clip small (our camera has none), far_clip large.
//   film/sampler  `hdrfilm` with our width × height, pixel_format rgb, rfilter `box` (one pixel,
//                 our box filter); `independent` sampler with our spp (Mitsuba's own random
//                 numbers: same estimator, different samples — compare means, not noise).
//   integrator    `path`, same max_depth, hide_emitters = true (background 0), rr_depth =
//                 max(5, max_depth) (we have no Russian roulette; Mitsuba's starts at depth 5).
//   env map       `envmap` emitter reading envmap.exr, the texel grid itself (50×25 RGB,
//                 gray maps channel-replicated), which Mitsuba reads with the convention of
//                 scene/EnvMapBasis.h; identity to_world, scale 1.
//   material      `roughconductor` (distribution always written: Mitsuba's default is beckmann,
//                 ours ggx; alpha_u, alpha_v) or `conductor`; eta and k always as explicit
//                 `<rgb>` values, never Mitsuba material names (its RGB reduction of the named
//                 spectra differs between versions; "Fe" is not a Mitsuba material at all).
//                 Values > 1 are accepted: Mitsuba's XML parser creates the `srgb` texture of an
//                 `<rgb>` named eta, k, int_ior or ext_ior outside an emitter with
//                 unbounded = true (xml.cpp create_texture_from_rgb / is_unbounded_spectrum),
//                 and in RGB variants that texture returns the value as given. In spectral
//                 variants the value would be upsampled to a spectrum: use an RGB variant.
#pragma once

#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "scene/EnvMap.h"

namespace sl {

struct Scene;

struct MitsubaExport {
    std::filesystem::path xml, ply, envmap;
    std::vector<std::string> notes;  // things the user should know (variant, noise, ...)
};

/// Writes OUTDIR/scene.xml, OUTDIR/heightfield.ply and OUTDIR/envmap.exr (each atomically).
/// env must be on the scene's env-map grid (1 or 3 channels).
MitsubaExport exportMitsuba(const Scene& scene, const EnvMap& env,
                            const std::filesystem::path& outDir);

/// The XML text (file names relative to the XML file).
std::string mitsubaSceneXml(const Scene& scene, const std::string& plyName,
                            const std::string& envmapName);

/// The height field as a binary little-endian PLY (see the header comment), streamed.
void writeHeightfieldPly(const std::filesystem::path& file, int width, int height, double pitch,
                         std::span<const float> heights);

}  // namespace sl
