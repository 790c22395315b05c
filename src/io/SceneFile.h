// Scene files (JSON). Paths are relative to the scene file. Unknown fields are errors.
// Every field and its default (the README's "Scene file" section is generated from this list):
//
//   heightmap.path           (required) EXR/TIFF/PNG16/.npy height map, see io/HeightmapIO.h
//   heightmap.pixel_pitch    0.01        sample spacing, scene units (mm)
//   heightmap.height_range   (integer maps: required) [min, max] the [0,1] range maps onto
//   heightmap.height_scale   1.0         float maps: heights are multiplied by this
//   material.type            "roughconductor" | "conductor" (smooth mirror)
//   material.distribution    "ggx" | "beckmann"                         (default "ggx")
//   material.alpha           0.05        isotropic roughness (GGX/Beckmann α)
//   material.alpha_u/alpha_v α           anisotropic roughness along +x / along z
//   material.material        "Al"        none | Al | Cr | Fe | Cu | Au | Ag
//   material.eta, material.k (instead of material) RGB complex IOR, a number or [r, g, b]
//   camera.type              "perspective" | "orthographic"
//   camera.origin/target/up  automatic: looks at the part's centre from 45° above (+z side)
//   camera.fov               35          degrees along the image's horizontal axis
//   camera.width_mm          1.05 × the part's larger extent (orthographic view width)
//   camera.width/height      512 × 512   image size in pixels
//   envmap.width/height      50 × 25     env-map texels (Mitsuba 3 equirectangular convention)
//   envmap.path              (none)      default env map for `render` (EXR/HDR/PNG/JPEG)
//   envmap.constant          (none)      default constant env map for `render`
//   envmap.preset            (none)      built-in env map: "studio"
//   render.spp               64          samples per pixel
//   render.max_depth         4           Mitsuba's max_depth (2 = one reflection)
//   render.seed              0           random seed
//   description              ""          free text
#pragma once

#include <filesystem>
#include <memory>
#include <string>

#include "scene/Scene.h"

namespace sl {

/// Parse and validate a scene file. Throws InputError naming the file and field.
SceneDesc readSceneFile(const std::filesystem::path& file);
/// Parse a scene from JSON text; relative paths resolve against baseDir.
SceneDesc parseScene(const std::string& jsonText, const std::filesystem::path& baseDir,
                     const std::string& where = "scene");

/// Load the height map a SceneDesc names and build the Scene (Embree surface included).
std::unique_ptr<Scene> loadScene(const SceneDesc& desc);
std::unique_ptr<Scene> loadScene(const std::filesystem::path& file);

}  // namespace sl
