// EnvMap → E: the one rule by which a light (a file, a preset, a constant, a saved E*) becomes
// the vector E that T multiplies, everywhere a light is rendered, scored or fitted: the user's
// lamp and the paper's light in optimize, the judge (app/pipeline/Judge.h envVector), the
// viewer's lights and lamps' target.
//
// CONVENTION (colour, core/Color.h): a gray map drives R, G and B equally, so on an RGB T it is
// three equal values a texel; a colour map on a gray T is its luminance Y (the linear rule: the
// render of a gray T under it is T·Y for a neutral material). Values are taken as they are, not
// clamped: a light is scored as it shines.
//
// A start is not a light: app/pipeline/InitialState.h initialEnvMapFrom clamps E0 into the
// optimizer's box [0, 1] and turns a colour photo gray by CIE L*/100, the paper's rule for its
// initial state; it calls this rule for everything else.
#pragma once

#include <vector>

#include "scene/EnvMap.h"

namespace sl {

/// E of `env` for a T of `channels` (1 gray, 3 RGB): width·height·channels values, row-major,
/// channels interleaved (scene/EnvMap.h). Throws std::invalid_argument for other channels.
std::vector<double> envMapToE(const EnvMap& env, int channels);

}  // namespace sl
