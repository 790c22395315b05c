#include "app/InitialState.h"

#include <algorithm>
#include <cmath>

#include "core/Color.h"
#include "core/Error.h"
#include "core/Rng.h"
#include "io/EnvMapIO.h"
#include "optimize/SpecularInit.h"
#include "scene/EnvMapPresets.h"

namespace sl {

namespace {
[[noreturn]] void bad(const std::string& spec, const std::string& why) {
    throw inputError(option("init") + " " + spec, why,
                     "use const:V, envmap:FILE, random:SEED, studio or specular");
}
}  // namespace

std::vector<double> initialEnvMapFrom(const EnvMap& m, bool rgb) {
    const size_t texels = m.texelCount(), n = texels * (rgb ? 3 : 1);
    std::vector<double> e(n);
    for (size_t t = 0; t < texels; ++t) {
        const float* c = &m.texels[t * static_cast<size_t>(m.channels)];
        if (m.channels == 1) {
            const double v = std::clamp<double>(c[0], 0.0, 1.0);
            for (int k = 0; k < (rgb ? 3 : 1); ++k) e[(rgb ? 3 * t : t) + k] = v;
        } else if (rgb) {
            for (int k = 0; k < 3; ++k) e[3 * t + k] = std::clamp<double>(c[k], 0.0, 1.0);
        } else {
            e[t] = std::clamp(lightnessLStar01(c[0], c[1], c[2]), 0.0, 1.0);
        }
    }
    return e;
}

std::vector<double> initialEnvMap(const std::string& spec, int width, int height, bool rgb,
                                  const Scene* scene, int maxDepth) {
    if (spec != "specular") return initialEnvMap(spec, width, height, rgb);
    if (!scene) bad(spec, "needs the scene");
    return specularInitialEnvMap(*scene, maxDepth, rgb);
}

std::vector<double> initialEnvMap(const std::string& spec, int width, int height, bool rgb) {
    if (spec == "studio") return initialEnvMapFrom(studioEnvMap(width, height), rgb);
    const size_t texels = static_cast<size_t>(width) * height, n = texels * (rgb ? 3 : 1);
    const auto colon = spec.find(':');
    if (colon == std::string::npos) bad(spec, "missing ':'");
    const std::string kind = spec.substr(0, colon), arg = spec.substr(colon + 1);
    if (kind == "const") {
        double v = 0;
        try {
            size_t used = 0;
            v = std::stod(arg, &used);
            if (used != arg.size()) throw std::invalid_argument(arg);
        } catch (const std::exception&) {
            bad(spec, "'" + arg + "' is not a number");
        }
        if (!(v >= 0.0 && v <= 1.0)) bad(spec, "the value must be in [0, 1]");
        return std::vector<double>(n, v);
    }
    if (kind == "random") {
        uint64_t seed = 0;
        try {
            size_t used = 0;
            seed = std::stoull(arg, &used);
            if (used != arg.size()) throw std::invalid_argument(arg);
        } catch (const std::exception&) {
            bad(spec, "'" + arg + "' is not a non-negative whole number");
        }
        Pcg32 rng(mix64(seed), 0x5eed);
        std::vector<double> e(n);
        for (double& v : e) v = rng.nextDouble();
        return e;
    }
    if (kind == "envmap") {
        if (arg.empty()) bad(spec, "no file given");
        // A gray file (what `optimize` writes as envmap.exr) is E itself, so a result loads back
        // unchanged; a colour map becomes gray by CIE L*/100 as in the paper (or stays RGB).
        return initialEnvMapFrom(loadEnvMap(arg, width, height, 0), rgb);
    }
    bad(spec, "unknown kind '" + kind + "'");
}

}  // namespace sl
