// Initial env maps for the optimizers (optimize's option 'init' and 'starts'):
//   const:V        every texel V (the paper's default: 0.5)
//   envmap:FILE    an equirectangular image, area-resampled to the env-map grid; a colour image
//                  becomes gray by CIE L* (LUV lightness)/100 of each texel, as the paper does
//                  (RGB kept with rgb=true); a one-channel image is E itself (so the envmap.exr
//                  that `optimize` writes loads back unchanged); values clamped to [0, 1]
//   random:SEED    uniform in [0, 1], from PCG32(SEED)
//   studio         the built-in studio map (scene/EnvMapPresets.h), by L*/100 like a photo
//   specular       the paper's §5.2 state (optimize/SpecularInit.h): needs the scene
#pragma once

#include <string>
#include <vector>

#include "scene/EnvMap.h"

namespace sl {

struct Scene;

/// E0 for an env map of width×height texels, 1 value per texel (gray) or 3 (rgb, interleaved),
/// for every spec above but `specular`. Throws InputError naming option 'init' and the accepted
/// forms for a malformed spec.
std::vector<double> initialEnvMap(const std::string& spec, int width, int height, bool rgb);

/// Every spec above, `specular` included (it traces `scene` with T's path length maxDepth;
/// InputError when scene is null).
std::vector<double> initialEnvMap(const std::string& spec, int width, int height, bool rgb,
                                  const Scene* scene, int maxDepth);

/// E0 from an env map as `envmap:FILE` takes a loaded file: a one-channel map is E itself, a
/// colour map becomes gray by CIE L*/100 (or stays RGB with rgb); clamped to [0, 1].
std::vector<double> initialEnvMapFrom(const EnvMap& map, bool rgb);

}  // namespace sl
