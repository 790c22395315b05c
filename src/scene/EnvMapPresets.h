// Built-in env maps, defined directly on the EnvMapBasis grid (so they need no resampling).
//   "studio": a dim sky-to-ground gradient, a softbox 65° up toward −z (its lower
//   edge crosses what the default 45° camera sees reflected) and a narrow
//   strip light low toward +x: a generic inspection-booth lamp, a stand-in for the paper's
//   "common environment map" when the user has no HDR photo at hand.
#pragma once

#include <string>
#include <vector>

#include "scene/EnvMap.h"

namespace sl {

EnvMap studioEnvMap(int width, int height);
/// The preset names, "studio" first.
const std::vector<std::string>& presetNames();
/// By name; throws InputError listing the presets for an unknown name.
EnvMap presetEnvMap(const std::string& name, int width, int height);

}  // namespace sl
