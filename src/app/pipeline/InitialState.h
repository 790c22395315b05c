// Initial env maps for the optimizers (optimize's option 'init' and 'starts'):
//   const:V        every texel V (the paper's default: 0.5)
//   envmap:FILE    an equirectangular image, area-resampled to the env-map grid (a bare FILE
//                  with a '.' or '/' in it means the same); a colour image
//                  becomes gray by CIE L* (LUV lightness)/100 of each texel, as the paper does
//                  (RGB kept with rgb=true); a one-channel image is E itself (so the envmap.exr
//                  that `optimize` writes loads back unchanged); values clamped to [0, 1]
//   random:SEED    uniform in [0, 1], from PCG32(SEED)
//   studio         the built-in studio map (scene/EnvMapPresets.h), by L*/100 like a photo
//   specular       the paper's §5.2 state (optimize/SpecularInit.h): needs the scene
// The kinds are one registry (core/Registry.h); a spec is parsed once into an InitialState.
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/Error.h"
#include "scene/EnvMap.h"

namespace sl {

struct Scene;

enum class InitialKind { Constant, EnvMapFile, Random, Studio, Specular };

struct InitialKindRow {
    InitialKind value;
    const char* name;
    const char* argument;  // after "name:" ("" = none)
    const char* help;
};
std::span<const InitialKindRow> initialKindTable();
/// "FILE | const:V | envmap:FILE | random:SEED | studio | specular", from the table.
std::string initialSpecForms();

/// One parsed start.
struct InitialState {
    InitialKind kind = InitialKind::Constant;
    double value = 0.5;              // const
    uint64_t seed = 0;               // random
    std::filesystem::path file;      // envmap
    std::string spec = "const:0.5";  // as written (its name in reports and summaries)
};

/// Parses one spec; InputError naming `where` (the option it came from) and the accepted forms
/// for a malformed one. A constant must lie in [0, 1]; a seed is a non-negative whole number.
InitialState parseInitialState(std::string_view spec, const std::string& where = option("init"));

/// E0 for an env map of width×height texels, 1 value per texel (gray) or 3 (rgb, interleaved),
/// for every kind but `specular` (InputError naming option 'init' for that one).
std::vector<double> initialEnvMap(const InitialState& start, int width, int height, bool rgb);

/// Every kind, `specular` included (it traces `scene` with T's path length maxDepth;
/// InputError when scene is null).
std::vector<double> initialEnvMap(const InitialState& start, int width, int height, bool rgb,
                                  const Scene* scene, int maxDepth);

/// The same, with the `specular` start kept in the cache beside T (app/pipeline/Cache.h
/// readCachedLight, keyed by T's fingerprint, which covers the scene, its camera and maxDepth,
/// and by rgb): a run on a cached T then traces no ray (the same values, bit for bit). Empty
/// cacheDir or fingerprint: as above.
std::vector<double> initialEnvMap(const InitialState& start, int width, int height, bool rgb,
                                  const Scene* scene, int maxDepth,
                                  const std::filesystem::path& cacheDir,
                                  const std::string& fingerprint);

/// Whether the E0 above needs `scene`: a `specular` start that the cache does not hold.
bool initialEnvMapNeedsScene(const InitialState& start, int width, int height, bool rgb,
                             int maxDepth, const std::filesystem::path& cacheDir,
                             const std::string& fingerprint);

/// E0 from an env map as `envmap:FILE` takes a loaded file: a one-channel map is E itself, a
/// colour map becomes gray by CIE L*/100 (or stays RGB with rgb); clamped to [0, 1].
std::vector<double> initialEnvMapFrom(const EnvMap& map, bool rgb);

}  // namespace sl
