#include "app/pipeline/InitialState.h"

#include <algorithm>
#include <cmath>

#include "app/pipeline/Cache.h"
#include "core/Color.h"
#include "core/Error.h"
#include "core/Hash.h"
#include "core/Registry.h"
#include "core/Rng.h"
#include "io/EnvMapIO.h"
#include "optimize/SpecularInit.h"
#include "scene/EnvMapPresets.h"
#include "scene/EnvMapToE.h"

namespace sl {

namespace {

// clang-format off
constexpr InitialKindRow kKinds[] = {
    {InitialKind::Constant, "const", "V", "every texel V in [0, 1] (the paper: 0.5)"},
    {InitialKind::EnvMapFile, "envmap", "FILE",
     "an equirectangular image, area-resampled; colour becomes gray by L*/100"},
    {InitialKind::Random, "random", "SEED", "uniform in [0, 1] from PCG32(SEED)"},
    {InitialKind::Studio, "studio", "", "the built-in studio map, by L*/100"},
    {InitialKind::Specular, "specular", "", "the paper's specular state (traces the scene)"},
};
// clang-format on

[[noreturn]] void bad(const std::string& where, std::string_view spec, const std::string& why) {
    throw inputError(where + " " + std::string(spec), why, "use " + initialSpecForms());
}

}  // namespace

std::span<const InitialKindRow> initialKindTable() {
    return kKinds;
}

std::string initialSpecForms() {
    std::string s = "FILE";  // a bare path: envmap:FILE (parseInitialState)
    for (const InitialKindRow& r : kKinds) {
        if (!s.empty()) s += " | ";
        s += r.name;
        if (*r.argument) s += std::string(":") + r.argument;
    }
    return s;
}

InitialState parseInitialState(std::string_view spec, const std::string& where) {
    const auto colon = spec.find(':');
    const std::string_view kind = spec.substr(0, colon);
    const std::string arg(colon == std::string_view::npos ? "" : spec.substr(colon + 1));
    const InitialKindRow* row = findRegistryRow(initialKindTable(), kind);
    if (!row && colon == std::string_view::npos &&
        spec.find_first_of("./") != std::string_view::npos) {
        InitialState s;  // a bare path (it has a '.' or a '/'): envmap:FILE
        s.kind = InitialKind::EnvMapFile;
        s.file = std::string(spec);
        s.spec = "envmap:" + std::string(spec);
        return s;
    }
    if (!row) bad(where, spec, "unknown kind '" + std::string(kind) + "'");
    if (*row->argument && colon == std::string_view::npos) bad(where, spec, "missing ':'");
    if (!*row->argument && colon != std::string_view::npos)
        bad(where, spec, std::string(row->name) + " takes no argument");
    InitialState s;
    s.kind = row->value;
    s.spec = std::string(spec);
    switch (s.kind) {
        case InitialKind::Constant:
            try {
                size_t used = 0;
                s.value = std::stod(arg, &used);
                if (used != arg.size()) throw std::invalid_argument(arg);
            } catch (const std::exception&) {
                bad(where, spec, "'" + arg + "' is not a number");
            }
            if (!(s.value >= 0.0 && s.value <= 1.0))
                bad(where, spec, "the value must be in [0, 1]");
            break;
        case InitialKind::Random:
            try {
                size_t used = 0;
                if (!arg.empty() && arg[0] == '-') throw std::invalid_argument(arg);
                s.seed = std::stoull(arg, &used);
                if (used != arg.size()) throw std::invalid_argument(arg);
            } catch (const std::exception&) {
                bad(where, spec, "'" + arg + "' is not a non-negative whole number");
            }
            break;
        case InitialKind::EnvMapFile:
            if (arg.empty()) bad(where, spec, "no file given");
            s.file = arg;
            break;
        case InitialKind::Studio:
        case InitialKind::Specular:
            break;
    }
    return s;
}

std::vector<double> initialEnvMapFrom(const EnvMap& m, bool rgb) {
    std::vector<double> e;
    if (m.channels == 3 && !rgb) {  // a colour photo: gray by CIE L*/100, the paper's start
        e.resize(m.texelCount());
        for (size_t t = 0; t < e.size(); ++t) {
            const float* c = &m.texels[3 * t];
            e[t] = lightnessLStar01(c[0], c[1], c[2]);
        }
    } else {
        e = envMapToE(m, rgb ? 3 : 1);  // as a light (scene/EnvMapToE.h)
    }
    for (double& v : e) v = std::clamp(v, 0.0, 1.0);  // the optimizer's box
    return e;
}

std::vector<double> initialEnvMap(const InitialState& start, int width, int height, bool rgb,
                                  const Scene* scene, int maxDepth) {
    if (start.kind != InitialKind::Specular) return initialEnvMap(start, width, height, rgb);
    if (!scene) bad(option("init"), start.spec, "needs the scene");
    return specularInitialEnvMap(*scene, maxDepth, rgb);
}

namespace {

/// The specular start's key in the cache beside T.
std::string specularKey(bool rgb, int maxDepth, const std::string& fingerprint) {
    const std::string what = "specular start 1; T " + fingerprint + "; rgb " + std::to_string(rgb) +
                             "; max_depth " + std::to_string(maxDepth);
    return hexKey128(what);
}

}  // namespace

std::vector<double> initialEnvMap(const InitialState& start, int width, int height, bool rgb,
                                  const Scene* scene, int maxDepth,
                                  const std::filesystem::path& cacheDir,
                                  const std::string& fingerprint) {
    if (start.kind != InitialKind::Specular || cacheDir.empty() || fingerprint.empty())
        return initialEnvMap(start, width, height, rgb, scene, maxDepth);
    const std::string key = specularKey(rgb, maxDepth, fingerprint);
    const size_t n = static_cast<size_t>(width) * static_cast<size_t>(height) * (rgb ? 3 : 1);
    if (auto cached = readCachedLight(cacheDir, key); cached && cached->size() == n) return *cached;
    std::vector<double> e = initialEnvMap(start, width, height, rgb, scene, maxDepth);
    if (e.size() == n) writeCachedLight(cacheDir, key, "specular start on T " + fingerprint, e);
    return e;
}

bool initialEnvMapNeedsScene(const InitialState& start, int width, int height, bool rgb,
                             int maxDepth, const std::filesystem::path& cacheDir,
                             const std::string& fingerprint) {
    if (start.kind != InitialKind::Specular) return false;
    if (cacheDir.empty() || fingerprint.empty()) return true;
    const auto cached = readCachedLight(cacheDir, specularKey(rgb, maxDepth, fingerprint));
    return !cached || cached->size() !=
                          static_cast<size_t>(width) * static_cast<size_t>(height) * (rgb ? 3 : 1);
}

std::vector<double> initialEnvMap(const InitialState& start, int width, int height, bool rgb) {
    const size_t texels = static_cast<size_t>(width) * height, n = texels * (rgb ? 3 : 1);
    switch (start.kind) {
        case InitialKind::Constant:
            return std::vector<double>(n, start.value);
        case InitialKind::Random: {
            Pcg32 rng(mix64(start.seed), 0x5eed);
            std::vector<double> e(n);
            for (double& v : e) v = rng.nextDouble();
            return e;
        }
        case InitialKind::EnvMapFile:
            // A gray file (what `optimize` writes as envmap.exr) is E itself, so a result loads
            // back unchanged; a colour map becomes gray by CIE L*/100 as in the paper (or stays
            // RGB).
            return initialEnvMapFrom(loadEnvMap(start.file, width, height, 0), rgb);
        case InitialKind::Studio:
            return initialEnvMapFrom(studioEnvMap(width, height), rgb);
        case InitialKind::Specular:
            break;
    }
    bad(option("init"), start.spec, "needs the scene");
}

}  // namespace sl
