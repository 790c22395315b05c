// POV-Ray 3.7 export: the scene as a POV-Ray scene that renders our image (app/host/ExternalRenderer.h
// runs it). OUTDIR/scene.pov, OUTDIR/heightfield.png, OUTDIR/envmap.exr. Every choice was
// measured with POV-Ray 3.7.0.10 (Debian 12) and is checked by tests/test_povray.cpp:
//
//   height field  `height_field { png }` from a 16-bit gray PNG: value (h − hmin)/(hmax − hmin)
//                 × 65535, rounded (quantisation (hmax − hmin)/131070). POV-Ray puts image column
//                 i at x = i/(W−1) and image row r at z = 1 − r/(H−1) (the image's top row at
//                 z = 1), so the PNG's rows are written bottom-up (PNG row r = our row H−1−r):
//                 our row j lands at z = j/(H−1); then scale <(W−1)p, hmax − hmin, (H−1)p> and
//                 translate <−(W−1)p/2, hmin, −(H−1)p/2> give the world frame of
//                 scene/Heightfield.h exactly. POV-Ray splits each cell along (i+1, j)–(i, j+1),
//                 which after the flip is Embree's diagonal v1–v3: the same triangles.
//   camera        explicit vectors (no look_at, so POV-Ray's left-handedness plays no part):
//                 `location` = origin, `direction` = f, `right` = −left·2·tan(fov/2), `up` =
//                 up'·2·tan(fov/2)/aspect (perspective) or `right` = −left·width_mm, `up` =
//                 up'·width_mm/aspect (orthographic), in scene/Camera.h's terms: POV-Ray's ray
//                 through film position (x, y) is direction + (x/W − ½)·right + (½ − y/H)·up,
//                 our ray. No antialiasing in POV-Ray: the image is rendered at `supersample`
//                 times the size and box-filtered here (povrayDownsample), which is our box
//                 filter on a regular s×s grid (stratified, not random) and keeps the image
//                 exactly linear in the light (POV-Ray's adaptive antialiasing decides per pixel
//                 from colour differences, which is not linear).
//   env map       a huge sphere (radius 1e6 × the scene's size, centred at the origin) with
//                 `no_image` (invisible to camera rays, so the background is 0 as ours) and an
//                 emissive finish (emission 1, no ambient or diffuse), textured with an
//                 `image_map { exr map_type 1 }`. POV-Ray's spherical map (measured): image
//                 column c covers u_p = atan2(d.z, d.x)/2π ∈ [c/W', (c+1)/W') (0 at +x, ¼ at +z),
//                 image row r covers acos(d.y)/π ∈ [r/H', (r+1)/H') (row 0 at +Y); no
//                 interpolation. So envmap.exr is our env map sampled at the centre direction of
//                 each of its W' × H' = envScale·W × envScale·H pixels through EnvMapBasis::
//                 weights() (the bilinear lookup of scene/EnvMapBasis.h, the one convention),
//                 not a copy of the texels: POV-Ray's nearest lookup then reproduces our
//                 bilinear light to within half a fine pixel. Linear in E by construction.
//   material      a perfect specular reflection `reflection { rgb F }` with F = the
//                 conductor's Fresnel reflectance (scene/Conductor.h) at the angle between the
//                 camera's axis and +Y (a constant: POV-Ray's own `fresnel` is a dielectric's),
//                 no diffuse, ambient, specular or emission. Roughness α (√(α_u·α_v): isotropic)
//                 as an average of `roughSamples` textures, each with its own `bumps` normal
//                 perturbation of amount α·bumpsPerAlpha (a different translation per texture
//                 and per seed): every texture traces its own reflection ray, so a pixel averages
//                 supersample² × roughSamples mirror directions around the micro-normals. This
//                 is a blurred mirror, not GGX: the lobe's shape, shadowing-masking, the
//                 anisotropy α_u ≠ α_v and Fresnel's angle dependence are not matched;
//                 `conductor` (smooth) is matched up to F's angle dependence. bumpsPerAlpha 3
//                 was measured against our tracer (256 spp, a 64² wavy part, 48² px, a checker
//                 env map, 16 textures): relative L2 image difference 0.150, 0.130, 0.164 at
//                 α 0.05, 0.1, 0.2 (the best per α: 4 → 0.131, 3 → 0.130, 2 → 0.122; the
//                 uncalibrated 1 gave 0.369, 0.486, 0.412); tests/test_povray.cpp holds α 0.1.
//   light paths   max_trace_level = max_depth (POV-Ray counts the camera ray as level 1: 2 is
//                 one reflection, as Mitsuba's max_depth), adc_bailout 0 (no early path end),
//                 no light sources, no radiosity, assumed_gamma 1.0, File_Gamma 1.0, output
//                 OpenEXR (POV-Ray writes half floats: relative rounding 2⁻¹¹, which sets the
//                 smallest useful finite-difference step).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "core/Image.h"
#include "scene/EnvMap.h"

namespace sl {

struct Scene;
class EnvMapBasis;

/// How the POV-Ray scene is rendered (the defaults are the only definition).
struct PovraySettings {
    int supersample = 3;         // camera rays per pixel along each axis (s² per pixel)
    int roughSamples = 8;        // micro-normal textures averaged for a rough conductor
    int envScale = 16;           // env-map image pixels per texel along each axis
    double bumpsPerAlpha = 3.0;  // `bumps` amount per unit of α (measured: header comment)
};

struct PovrayFiles {
    std::filesystem::path scene, heightfield, envmap;
};

/// The scene text; `seed` shifts the micro-normal patterns (ignored for a smooth conductor).
std::string povraySceneText(const Scene& scene, const PovraySettings& settings, uint64_t seed,
                            const std::string& heightfieldName, const std::string& envmapName);

/// The height map as a 16-bit PNG (rows bottom-up, see the header comment).
void writePovrayHeightfield(const std::filesystem::path& file, const Scene& scene);

/// The env map sampled on POV-Ray's spherical map (see the header comment), as float EXR.
void writePovrayEnvMap(const std::filesystem::path& file, const EnvMap& env,
                       const EnvMapBasis& basis, int envScale);

/// Writes scene.pov, heightfield.png and envmap.exr into `dir`.
PovrayFiles exportPovray(const Scene& scene, const EnvMap& env, const PovraySettings& settings,
                         uint64_t seed, const std::filesystem::path& dir);

/// POV-Ray's command-line arguments (after the program) for rendering `sceneName` into the
/// OpenEXR `outputName` at the camera's size × supersample, with `threads` work threads (0:
/// POV-Ray's default).
std::vector<std::string> povrayArguments(const Scene& scene, const PovraySettings& settings,
                                         const std::string& sceneName,
                                         const std::string& outputName, int threads);

/// The box filter: the mean of each factor × factor block of `img` (whose size must be the
/// camera's times factor), as a 3-channel image (1 channel replicated; alpha dropped).
Image povrayDownsample(const Image& img, int factor);

}  // namespace sl
