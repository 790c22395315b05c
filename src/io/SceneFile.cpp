#include "io/SceneFile.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <system_error>

#include "core/Error.h"
#include "core/Progress.h"
#include "core/Registry.h"
#include "core/Text.h"
#include "io/HeightmapIO.h"
#include "io/InputFile.h"
#include "scene/EnvMapBasis.h"
#include "scene/Materials.h"
#include "transport/TransportMatrix.h"

namespace sl {

namespace {

using json = nlohmann::json;

const char* cameraTypeName(CameraDesc::Type t) {
    return t == CameraDesc::Type::Perspective ? "perspective" : "orthographic";
}

/// Reads the fields of one JSON object, remembering which were used, so that anything left
/// over is reported as an unknown field (with the list of valid ones).
class Fields {
  public:
    Fields(const json& obj, std::string where, std::string prefix)
        : obj_(obj), where_(std::move(where)), prefix_(std::move(prefix)) {
        if (!obj.is_object()) throw inputError(where_, name("") + " must be a JSON object");
    }
    std::string name(const std::string& key) const {
        return key.empty() ? (prefix_.empty() ? "the scene" : prefix_)
                           : (prefix_.empty() ? key : prefix_ + "." + key);
    }
    const json* get(const std::string& key) {
        known_.insert(key);
        auto it = obj_.find(key);
        return it == obj_.end() ? nullptr : &*it;
    }
    [[noreturn]] void fail(const std::string& key, const std::string& problem,
                           const std::string& fix = {}) const {
        throw inputError(where_ + ": " + name(key), problem, fix);
    }
    double number(const std::string& key, double def) {
        const json* v = get(key);
        if (!v) return def;
        if (!v->is_number()) fail(key, "must be a number, got " + jsonExcerpt(*v));
        double d = v->get<double>();
        if (!std::isfinite(d)) fail(key, "must be finite");
        return d;
    }
    double positive(const std::string& key, double def) {
        double d = number(key, def);
        if (!(d > 0)) fail(key, "must be > 0, got " + formatNumber(d));
        return d;
    }
    int integer(const std::string& key, int def, int lo, int hi) {
        const json* v = get(key);
        if (!v) return def;
        if (!v->is_number_integer()) fail(key, "must be a whole number, got " + jsonExcerpt(*v));
        auto i = v->get<long long>();
        if (i < lo || i > hi)
            fail(key, "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " +
                          std::to_string(i));
        return static_cast<int>(i);
    }
    std::string string(const std::string& key, const std::string& def) {
        const json* v = get(key);
        if (!v) return def;
        if (!v->is_string()) fail(key, "must be a string, got " + jsonExcerpt(*v));
        return v->get<std::string>();
    }
    std::string choice(const std::string& key, const std::string& def,
                       const std::vector<std::string>& options) {
        std::string s = string(key, def);
        for (const auto& o : options)
            if (o == s) return s;
        std::string list;
        for (const auto& o : options) list += (list.empty() ? "" : ", ") + o;
        fail(key, "unknown value \"" + s + "\"", "use one of: " + list);
    }
    std::optional<Vec3d> vec3(const std::string& key) {
        const json* v = get(key);
        if (!v) return std::nullopt;
        if (!v->is_array() || v->size() != 3)
            fail(key, "must be an array of 3 numbers, got " + jsonExcerpt(*v));
        Vec3d r;
        for (int i = 0; i < 3; ++i) {
            if (!(*v)[i].is_number() || !std::isfinite((*v)[i].get<double>()))
                fail(key, "must be an array of 3 finite numbers, got " + jsonExcerpt(*v));
            r[i] = (*v)[i].get<double>();
        }
        return r;
    }
    /// A number (all channels) or [r, g, b].
    std::optional<Rgb> rgb(const std::string& key) {
        const json* v = get(key);
        if (!v) return std::nullopt;
        if (v->is_number()) return Rgb(v->get<float>());
        known_.erase(key);
        auto r = vec3(key);
        known_.insert(key);
        return Rgb(*r);
    }
    std::optional<Fields> object(const std::string& key) {
        const json* v = get(key);
        if (!v) return std::nullopt;
        return Fields(*v, where_, name(key));
    }
    void rejectUnknown() const {
        for (auto it = obj_.begin(); it != obj_.end(); ++it) {
            if (known_.count(it.key())) continue;
            std::string list;
            for (const auto& k : known_) list += (list.empty() ? "" : ", ") + k;
            fail(it.key(), "unknown field", "valid fields here are: " + list);
        }
    }

  private:
    const json& obj_;
    std::string where_, prefix_;
    std::set<std::string> known_;
};

/// heightmap.levelling: "auto", "none", "plane", "polynomial:N", "cylinder:x|y", or
/// {"mode": ..., "degree": N, "axis": "x"|"y"}.
LevellingDesc parseLevelling(Fields& parent, const json& v) {
    using M = LevellingDesc::Mode;
    const char* const forms =
        "give \"auto\", \"none\", \"plane\", \"polynomial:3\", \"cylinder:y\", or "
        "{\"mode\": \"polynomial\", \"degree\": 3} / {\"mode\": \"cylinder\", \"axis\": "
        "\"y\"}";
    LevellingDesc d;
    std::string mode;
    std::optional<int> degree;
    std::optional<std::string> axis;
    if (v.is_string()) {
        const std::string t = v.get<std::string>();
        const size_t colon = t.find(':');
        mode = t.substr(0, colon);
        if (colon != std::string::npos) {
            const std::string arg = t.substr(colon + 1);
            if (mode == "polynomial") {
                int n = -1;
                const auto r = std::from_chars(arg.data(), arg.data() + arg.size(), n);
                if (r.ec != std::errc() || r.ptr != arg.data() + arg.size())
                    parent.fail("levelling", "the degree in \"" + t + "\" is not a whole number",
                                forms);
                degree = n;
            } else if (mode == "cylinder") {
                axis = arg;
            } else {
                parent.fail("levelling", "\"" + t + "\" takes no argument after ':'", forms);
            }
        }
    } else if (v.is_object()) {
        Fields lf = *parent.object("levelling");
        mode = lf.choice("mode", "plane", {"auto", "none", "plane", "polynomial", "cylinder"});
        if (lf.get("degree")) degree = lf.integer("degree", 1, -1000000, 1000000);
        if (lf.get("axis")) axis = lf.string("axis", "y");
        lf.rejectUnknown();
    } else {
        parent.fail("levelling", "must be a string or an object, got " + v.dump(), forms);
    }
    if (mode == "auto")
        d.mode = M::Auto;
    else if (mode == "none")
        d.mode = M::None;
    else if (mode == "plane")
        d.mode = M::Plane;
    else if (mode == "polynomial")
        d.mode = M::Polynomial;
    else if (mode == "cylinder")
        d.mode = M::Cylinder;
    else
        parent.fail("levelling", "unknown mode \"" + mode + "\"", forms);
    if (degree && d.mode != M::Polynomial)
        parent.fail("levelling", "a degree is for \"polynomial\" only", forms);
    if (axis && d.mode != M::Cylinder)
        parent.fail("levelling", "an axis is for \"cylinder\" only", forms);
    if (d.mode == M::Polynomial) {
        if (!degree)
            parent.fail("levelling", "\"polynomial\" needs its degree",
                        "give \"polynomial:3\" or {\"mode\": \"polynomial\", \"degree\": 3}");
        if (*degree < 0 || *degree > LevellingDesc::kMaxDegree)
            parent.fail(
                "levelling",
                "degree " + std::to_string(*degree) + " is not in [0, " +
                    std::to_string(LevellingDesc::kMaxDegree) + "]",
                "use a degree from 0 (the mean) to " + std::to_string(LevellingDesc::kMaxDegree));
        d.degree = *degree;
    }
    if (d.mode == M::Cylinder) {
        if (!axis)
            parent.fail("levelling",
                        "\"cylinder\" needs the direction its axis runs along (x or y)",
                        "give \"cylinder:y\" or {\"mode\": \"cylinder\", \"axis\": \"y\"}");
        if (*axis != "x" && *axis != "y")
            parent.fail("levelling", "axis \"" + *axis + "\" is not x or y",
                        "x: the axis runs along the map's columns' direction (+x); y: along "
                        "its rows' direction");
        d.axis = (*axis)[0];
    }
    return d;
}

void parseHeightmap(Fields& f, const std::filesystem::path& baseDir, HeightmapDesc& h) {
    const json* p = f.get("path");
    if (!p)
        f.fail("path", "is required",
               "name the height-map file (EXR, TIFF, PNG16, .npy, X3P or SDF)");
    if (!p->is_string() || p->get<std::string>().empty())
        f.fail("path", "must be a non-empty string");
    std::filesystem::path path = p->get<std::string>();
    h.path = path.is_absolute() ? path : baseDir / path;
    h.pitchGiven = f.get("pixel_pitch") != nullptr;
    h.pitch = f.positive("pixel_pitch", h.pitch);
    h.heightScale = f.number("height_scale", h.heightScale);
    if (!(h.heightScale != 0)) f.fail("height_scale", "must be non-zero");
    if (const json* l = f.get("levelling")) h.levelling = parseLevelling(f, *l);
    if (const json* c = f.get("channel")) {
        if (c->is_number_unsigned())
            h.channel = std::to_string(c->get<unsigned long long>());
        else if (c->is_string() && !c->get<std::string>().empty())
            h.channel = c->get<std::string>();
        else
            f.fail("channel",
                   "must be a channel's number (0, 1, ...) or title, got " + jsonExcerpt(*c),
                   "`scratchlight info FILE` lists an instrument file's channels");
    }
    if (const json* m = f.get("measured")) {
        if (!m->is_boolean())
            f.fail("measured", "must be true or false, got " + jsonExcerpt(*m),
                   "true: the map is a measurement (an instrument's); false: a simulator's");
        h.measured = m->get<bool>();
    }
    if (const json* r = f.get("height_range")) {
        if (!r->is_array() || r->size() != 2 || !(*r)[0].is_number() || !(*r)[1].is_number())
            f.fail("height_range", "must be [min, max], got " + jsonExcerpt(*r));
        double lo = (*r)[0].get<double>(), hi = (*r)[1].get<double>();
        if (!std::isfinite(lo) || !std::isfinite(hi) || !(hi > lo))
            f.fail("height_range", "must be [min, max] with max > min, got " + jsonExcerpt(*r));
        h.heightRange = std::array<double, 2>{lo, hi};
    }
    f.rejectUnknown();
}

void parseMaterial(Fields& f, MaterialDesc& m) {
    m.type = f.choice("type", m.type, {"roughconductor", "conductor"});
    ConductorParams& p = m.params;
    p.smooth = m.type == "conductor";
    std::string dist =
        f.choice("distribution", microfacetName(p.distribution), {"ggx", "beckmann"});
    p.distribution = dist == "ggx" ? Microfacet::GGX : Microfacet::Beckmann;
    // Roughness α: the microfacet slope's spread; past 1 a surface is rougher than any machined
    // metal (and a float overflows at 3.4e38), so (0, 1] is what the scene file admits.
    auto roughness = [&](const char* key, double def) {
        const double a = f.positive(key, def);
        if (a > 1)
            f.fail(key, "must be in (0, 1], got " + formatNumber(a),
                   "roughness alpha: about 0.01 polished, 0.1 ground, 0.5 very rough");
        return a;
    };
    double alpha = roughness("alpha", p.alphaU);
    p.alphaU = static_cast<float>(roughness("alpha_u", alpha));
    p.alphaV = static_cast<float>(roughness("alpha_v", alpha));
    auto eta = f.rgb("eta"), k = f.rgb("k");
    bool hasName = f.get("material") != nullptr;
    if (eta || k) {
        if (!eta || !k) f.fail(eta ? "k" : "eta", "is required when the other of eta/k is given");
        if (hasName) f.fail("material", "cannot be combined with eta/k", "give one or the other");
        m.name = "custom";
        p.ior = ComplexIor{*eta, *k};
    } else {
        m.name = f.string("material", m.name);
        try {
            p.ior = namedConductor(m.name);
        } catch (const InputError& e) {
            f.fail("material", e.what());
        }
    }
    f.rejectUnknown();
}

void parseCamera(Fields& f, CameraSpec& c) {
    c.type =
        f.choice("type", cameraTypeName(c.type), {"perspective", "orthographic"}) == "perspective"
            ? CameraDesc::Type::Perspective
            : CameraDesc::Type::Orthographic;
    c.origin = f.vec3("origin");
    c.target = f.vec3("target");
    c.up = f.vec3("up");
    c.fovDeg = f.positive("fov", c.fovDeg);
    if (c.fovDeg >= 180) f.fail("fov", "must be below 180 degrees");
    if (f.get("width_mm")) c.widthMm = f.positive("width_mm", 1.0);
    c.width = f.integer("width", c.width, 1, 16384);
    c.height = f.integer("height", c.height, 1, 16384);
    f.rejectUnknown();
}

void parseEnvmap(Fields& f, const std::filesystem::path& baseDir, EnvMapDesc& e) {
    e.width = f.integer("width", e.width, 2, 4096);
    e.height = f.integer("height", e.height, 3, 2048);
    // Checked here, not first by precompute: every command can trace the scene's T.
    if (static_cast<long long>(e.width) * e.height > kMaxTransportTexels)
        f.fail("width/height",
               std::to_string(e.width) + "x" + std::to_string(e.height) + " = " +
                   std::to_string(static_cast<long long>(e.width) * e.height) +
                   " texels is more than the limit of " + std::to_string(kMaxTransportTexels) +
                   " (a transport matrix's 16-bit column indices)",
               "use a smaller env-map grid, e.g. the default " +
                   std::to_string(kDefaultEnvMapGrid.width) + "x" +
                   std::to_string(kDefaultEnvMapGrid.height) + " or at most 362x181");
    std::string path = f.string("path", "");
    if (!path.empty())
        e.path = std::filesystem::path(path).is_absolute() ? std::filesystem::path(path)
                                                           : baseDir / path;
    if (f.get("constant")) {
        double v = f.number("constant", 1.0);
        if (v < 0) f.fail("constant", "must be >= 0");
        e.constant = static_cast<float>(v);
    }
    if (f.get("preset")) e.preset = f.choice("preset", "studio", {"studio"});
    int given = (!e.path.empty()) + (e.constant.has_value()) + (!e.preset.empty());
    if (given > 1) f.fail("", "give at most one of path, constant and preset");
    f.rejectUnknown();
}

void parseRender(Fields& f, RenderDesc& r) {
    r.spp = f.integer("spp", r.spp, 1, 1 << 20);
    r.maxDepth = f.integer("max_depth", r.maxDepth, 1, 64);
    const json* s = f.get("seed");
    if (s) {
        if (!s->is_number_unsigned() && !(s->is_number_integer() && s->get<long long>() >= 0))
            f.fail("seed", "must be a non-negative whole number");
        r.seed = s->get<uint64_t>();
    }
    if (f.get("sampling")) {
        std::vector<std::string> names;
        for (const SamplingRow& row : samplingTable()) names.emplace_back(row.name);
        const std::string name =
            f.choice("sampling", registryRow(samplingTable(), r.sampling).name, names);
        r.sampling = findRegistryRow(samplingTable(), name)->value;
    }
    f.rejectUnknown();
}

/// "viewing": how a person sees the images (perception/ViewingModel.h).
void parseViewing(Fields& f, ViewingDesc& v) {
    if (f.get("pixels_per_degree")) v.pixelsPerDegree = f.positive("pixels_per_degree", 1.0);
    v.distanceMm = f.positive("distance_mm", v.distanceMm);
    v.displayPixelMm = f.positive("display_pixel_mm", v.displayPixelMm);
    if (f.get("magnification")) v.magnification = f.positive("magnification", 1.0);
    v.whiteCdM2 = f.positive("white_cd_m2", v.whiteCdM2);
    f.rejectUnknown();
}

json parseJsonText(const std::string& text, const std::string& where) {
    return parseJsonInput(text, where);
}

SceneDesc parseSceneJson(const json& j, const std::filesystem::path& baseDir,
                         const std::string& where) {
    SceneDesc d;
    d.canonicalJson = j.dump();
    Fields top(j, where, "");
    auto hm = top.object("heightmap");
    if (!hm) top.fail("heightmap", "is required", "add {\"heightmap\": {\"path\": \"part.exr\"}}");
    parseHeightmap(*hm, baseDir, d.heightmap);
    // Omitted sections are parsed as {} so that every default is applied in one place.
    const json empty = json::object();
    auto section = [&](const char* key) {
        return top.object(key).value_or(Fields(empty, where, key));
    };
    auto material = section("material");
    parseMaterial(material, d.material);
    auto camera = section("camera");
    parseCamera(camera, d.camera);
    auto envmap = section("envmap");
    parseEnvmap(envmap, baseDir, d.envmap);
    auto render = section("render");
    parseRender(render, d.render);
    auto viewing = section("viewing");
    parseViewing(viewing, d.viewing);
    top.string("description", "");
    top.rejectUnknown();
    return d;
}

}  // namespace

SceneDesc parseScene(const std::string& text, const std::filesystem::path& baseDir,
                     const std::string& where) {
    return parseSceneJson(parseJsonText(text, where), baseDir, where);
}

void applySceneOverride(json& scene, const std::string& override, const std::string& where) {
    const size_t eq = override.find('=');
    const std::string key = override.substr(0, eq);
    if (eq == std::string::npos || key.empty() || key.front() == '.' || key.back() == '.' ||
        key.find("..") != std::string::npos)
        throw inputError("scene override '" + override + "'", "is not key=value",
                         "write e.g. -D material.alpha=0.1 or -D camera.width=256");
    if (!scene.is_object())
        throw inputError(where, "is not a JSON object", "a scene file is {\"heightmap\": ...}");
    const std::string text = override.substr(eq + 1);
    json value = jsonNestingDepth(text) > kMaxJsonDepth ? json(json::value_t::discarded)
                                                        : json::parse(text, nullptr, false);
    if (value.is_discarded()) value = text;  // a bare word: a string
    json* at = &scene;
    std::string walked;
    for (size_t start = 0;;) {
        const size_t dot = key.find('.', start);
        const std::string part = key.substr(start, dot == std::string::npos ? dot : dot - start);
        walked += (walked.empty() ? "" : ".") + part;
        if (dot == std::string::npos) {
            (*at)[part] = value;
            return;
        }
        json& next = (*at)[part];
        if (next.is_null()) next = json::object();
        if (!next.is_object())
            throw inputError("scene override '" + override + "'",
                             "'" + walked + "' is a value in " + where + ", not a section",
                             "name a field inside a section, e.g. material.alpha");
        at = &next;
        start = dot + 1;
    }
}

namespace {

/// A file given where a scene file is asked for that is not JSON: not named .json and not
/// starting (after blanks) with '{'. Such a file is read as a height map (readSceneFile).
bool isBareHeightMap(const std::filesystem::path& file) {
    if (lower(file.extension().string()) == ".json") return false;
    checkInputFile(file, "the scene file or height map", UINT64_MAX);
    std::ifstream in(file, std::ios::binary);
    char c = 0;
    while (in.get(c))
        if (!std::isspace(static_cast<unsigned char>(c))) return c != '{';
    return false;  // empty or blank: the JSON reader says so
}

}  // namespace

SceneDesc readSceneFile(const std::filesystem::path& file,
                        const std::vector<std::string>& overrides) {
    // A height map where a scene is asked for stands for the default scene around it:
    // {"heightmap": {"path": FILE}} (README "Quick start").
    const bool bare = isBareHeightMap(file);
    json j = bare ? json{{"heightmap", {{"path", file.filename().string()}}}}
                  : parseJsonText(readInputFile(file, "the scene file", kMaxJsonFileBytes,
                                                "check the path (scene files are JSON)"),
                                  file.string());
    if (bare)
        spdlog::info(
            "{}: a height map, not a scene file: the default scene around it (a scene "
            "file, {{\"heightmap\": {{\"path\": \"{}\"}}}} and more, sets the "
            "material, the camera and the rest)",
            file.filename().string(), file.filename().string());
    for (const std::string& o : overrides) applySceneOverride(j, o, file.string());
    std::string where = file.string();
    if (!overrides.empty()) {
        where += " (with";
        for (const std::string& o : overrides) where += " -D " + o;
        where += ")";
    }
    SceneDesc d = parseSceneJson(j, file.parent_path(), where);
    d.file = file;
    d.overrides = overrides;
    return d;
}

namespace {

/// Levels a loaded map in place (scene/Levelling.h) and says what loading did.
HeightmapLoad levelMap(HeightmapData& map, const LevellingDesc& levelling, double pitch,
                       const std::string& where) {
    HeightmapLoad load;
    load.format = map.format;
    load.invalidFilled = map.invalidFilled;
    load.resampling = map.resampling;
    load.channel = map.channel;
    load.warnings = map.warnings;
    load.levelling = levelHeights(map.heights, map.width, map.height, pitch, map.invalid, levelling,
                                  map.measured(), where);
    return load;
}

void reportLoad(const std::filesystem::path& file, const HeightmapLoad& load, int w, int h,
                double pitch) {
    for (const std::string& warning : load.warnings)
        spdlog::warn("{}: {}", file.filename().string(), warning);
    spdlog::info("{}: {}", file.filename().string(), load.text(w, h, pitch));
}

}  // namespace

std::vector<std::filesystem::path> sceneInputFiles(const SceneDesc& desc) {
    std::vector<std::filesystem::path> files;
    for (const auto& f : {desc.file, desc.heightmap.path, desc.envmap.path})
        if (!f.empty()) files.push_back(f);
    return files;
}

std::unique_ptr<Scene> loadScene(const SceneDesc& desc) {
    // A 5000² map takes seconds to read and build (core/Progress.h shows the elapsed time).
    const ProgressTask task("loading " + desc.heightmap.path.filename().string());
    HeightmapOptions opt;
    opt.heightRange = desc.heightmap.heightRange;
    opt.heightScale = desc.heightmap.heightScale;
    opt.channel = desc.heightmap.channel;
    HeightmapData map = loadHeightmap(desc.heightmap.path, opt);
    SceneDesc d = desc;
    const std::string sceneWhere =
        desc.file.empty() ? desc.heightmap.path.string() : desc.file.string();
    // A map without a pitch (EXR, TIFF, PNG, .npy) is refused unless the scene gives one: a
    // silent default was 6x off on a real part.
    if (!map.pitch && !desc.heightmap.pitchGiven) {
        const std::string file = desc.heightmap.path.filename().string() + " (" + map.format +
                                 ", " + std::to_string(map.width) + "x" +
                                 std::to_string(map.height) + ")";
        if (map.uncalibratedLateral)  // an instrument's heights on a grid without a length unit
            throw inputError(sceneWhere,
                             file + " holds heights whose lateral axes carry no calibration" +
                                 (map.channel.empty() ? std::string() : " (" + map.channel + ")") +
                                 ", and the scene gives no heightmap.pixel_pitch",
                             "Add \"pixel_pitch\": MM (the spacing of the samples in mm, from "
                             "the instrument's field of view over its points) to the scene's "
                             "heightmap section, or -D heightmap.pixel_pitch=MM");
        throw inputError(sceneWhere,
                         file +
                             " carries no sample spacing, and the scene gives no "
                             "heightmap.pixel_pitch",
                         "Add \"pixel_pitch\": MM (the spacing of the samples in mm) to the "
                         "scene's heightmap section, or accept the default " +
                             formatNumber(HeightmapDesc{}.pitch) + " mm with " +
                             option("assume-pitch"));
    }
    // A height map that carries its pitch (X3P, SDF) sets it unless the scene gives one; a scene
    // pitch that disagrees with the file's is refused rather than silently preferred.
    if (map.pitch) {
        const double filePitch = *map.pitch;
        if (!desc.heightmap.pitchGiven) {
            d.heightmap.pitch = filePitch;
        } else if (std::abs(desc.heightmap.pitch - filePitch) >
                   1e-6 * std::max(desc.heightmap.pitch, filePitch)) {
            throw inputError(sceneWhere,
                             "heightmap.pixel_pitch " + formatNumber(desc.heightmap.pitch) +
                                 " disagrees with the file's " + formatNumber(filePitch) + " mm (" +
                                 desc.heightmap.path.string() +
                                 "); remove pixel_pitch from the scene to use the file's");
        }
    }
    HeightmapLoad load = levelMap(map, d.heightmap.levelling, d.heightmap.pitch, sceneWhere);
    load.measured = d.heightmap.measured.value_or(map.measured());
    auto scene =
        std::make_unique<Scene>(std::move(d), map.width, map.height, std::move(map.heights));
    scene->load = std::move(load);
    scene->mapFormat = map.format;
    scene->invalidFilled = map.invalidFilled;
    spdlog::info("{}", describePart(*scene));
    reportLoad(desc.heightmap.path, scene->load, scene->mapWidth, scene->mapHeight,
               scene->desc.heightmap.pitch);
    return scene;
}

std::string describePart(const Scene& scene) {
    const HeightmapDesc& h = scene.desc.heightmap;
    const auto [lo, hi] = std::minmax_element(scene.heights.begin(), scene.heights.end());
    const double p = h.pitch;
    std::string s = "part " + h.path.filename().string();
    if (!scene.mapFormat.empty()) s += " (" + scene.mapFormat + ")";
    s += ": " + std::to_string(scene.mapWidth) + " x " + std::to_string(scene.mapHeight) +
         " samples, pitch " + formatNumber(p) + " mm" + (h.pitchGiven ? "" : " (the file's)") +
         ", " + formatNumber((scene.mapWidth - 1) * p, 4) + " x " +
         formatNumber((scene.mapHeight - 1) * p, 4) + " mm";
    if (lo != scene.heights.end())
        s += ", heights " + formatNumber(*lo, 4) + " .. " + formatNumber(*hi, 4) + " mm";
    s += ", " + std::to_string(scene.invalidFilled) + " invalid point" +
         (scene.invalidFilled == 1 ? "" : "s") + " filled";
    return s;
}

std::unique_ptr<Scene> loadScene(const std::filesystem::path& file,
                                 const std::vector<std::string>& overrides) {
    return loadScene(readSceneFile(file, overrides));
}

HeightSource loadHeightSource(const std::filesystem::path& file,
                              const std::vector<std::string>& overrides) {
    HeightSource s;
    // A scene file, or a bare map with overrides (-D heightmap.channel=..., levelling=...): the
    // default scene around it, as render reads one (readSceneFile).
    if (file.extension() == ".json" || !overrides.empty()) {
        s.scene = loadScene(file, overrides);
        return s;
    }
    HeightmapOptions o;
    o.defaultIntegerRange = std::array<double, 2>{0.0, 1.0};
    s.map = loadHeightmap(file, o);
    // A bare map is levelled by the default (auto: plane for a measured map, else none).
    s.load = levelMap(s.map, LevellingDesc{}, s.map.pitch.value_or(1.0), file.string());
    s.load.measured = s.map.measured();
    reportLoad(file, s.load, s.map.width, s.map.height, s.map.pitch.value_or(1.0));
    // What was read, as loadScene says it for a scene (describePart).
    const HeightmapData& m = s.map;
    std::string line = "part " + file.filename().string() + " (" + m.format +
                       "): " + std::to_string(m.width) + " x " + std::to_string(m.height) +
                       " samples";
    if (m.pitch)
        line += ", pitch " + formatNumber(*m.pitch) + " mm (the file's), " +
                formatNumber((m.width - 1) * *m.pitch, 4) + " x " +
                formatNumber((m.height - 1) * *m.pitch, 4) + " mm";
    else
        line += ", no pitch (a bare height map)";
    if (!m.heights.empty()) {
        const auto [lo, hi] = std::minmax_element(m.heights.begin(), m.heights.end());
        line += ", heights " + formatNumber(*lo, 4) + " .. " + formatNumber(*hi, 4);
    }
    line += ", " + std::to_string(m.invalidFilled) + " invalid point" +
            (m.invalidFilled == 1 ? "" : "s") + " filled";
    spdlog::info("{}", line);
    return s;
}

nlohmann::ordered_json heightmapLoadJson(const Scene& scene) {
    const HeightmapLoad& l = scene.load;
    const LevellingResult& r = l.levelling;
    nlohmann::ordered_json lev;
    lev["mode"] = levellingName(r.applied);
    lev["auto"] = r.automatic;
    if (r.applied.mode != LevellingDesc::Mode::None) {
        lev["points"] = r.points;
        lev["rms_before"] = r.rmsBefore;
        lev["rms_after"] = r.rmsAfter;
        if (r.applied.mode == LevellingDesc::Mode::Cylinder) lev["radius"] = r.radius;
    }
    nlohmann::ordered_json j;
    j["file"] = scene.desc.heightmap.path.string();
    j["format"] = l.format;
    j["size"] = {scene.mapWidth, scene.mapHeight};
    j["pitch"] = scene.desc.heightmap.pitch;
    j["invalid_filled"] = l.invalidFilled;
    j["resampling"] = l.resampling.empty() ? nlohmann::ordered_json(nullptr)
                                           : nlohmann::ordered_json(l.resampling);
    j["channel"] =
        l.channel.empty() ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(l.channel);
    j["levelling"] = lev;
    j["warnings"] = l.warnings;
    j["measured"] = l.measured;
    return j;
}

std::vector<SceneFileField> sceneFileFields() {
    const SceneDesc d;  // the defaults the parser starts from
    const ConductorParams& m = d.material.params;
    auto num = [](double v) { return formatNumber(v); };
    auto code = [](const std::string& s) { return "`" + s + "`"; };
    auto pair = [&](double a, double b) { return num(a) + " × " + num(b); };
    return {
        {"heightmap.path", "required",
         "EXR or TIFF (float32/float16/uint16), PNG (16- or 8-bit), NumPy `.npy` "
         "(float32/float64/uint16, C order), X3P (ISO 25178-72), SDF (ISO 25178-71, ASCII or "
         "binary), TrueMap `.tmd`, NanoFocus µsurf `.nms`, and the instrument formats Gwyddion "
         "reads (Wyko OPD, Sensofar PLU, Digital Surf SUR, Zygo DAT, …), recognised by content"},
        {"heightmap.pixel_pitch", "required (measured maps: the file's)",
         "sample spacing in scene units (mm); measured maps (X3P, SDF, instrument formats) carry "
         "their own (leave it out), except a grid without lateral calibration; non-square pixels "
         "are resampled onto the finer pitch; a map "
         "without one is refused unless given (or " +
             num(d.heightmap.pitch) + " accepted on the command line)"},
        {"heightmap.height_range", "required for integer maps",
         "`[min, max]`: the integer range normalised to [0,1] maps linearly onto it; not allowed "
         "for float, X3P and SDF maps"},
        {"heightmap.height_scale", num(d.heightmap.heightScale),
         "float maps: heights are multiplied by it"},
        {"heightmap.levelling", "`auto`",
         "form removal fitted on the valid points and subtracted: `none`, `plane`, "
         "`polynomial:N` (degree 0–10), `cylinder:x` or `cylinder:y` (the axis' direction; a "
         "circle arc across it), or `{\"mode\": \"cylinder\", \"axis\": \"y\"}`; `auto` is "
         "`plane` for measured maps (X3P, SDF, instrument formats), `none` for EXR, TIFF, PNG "
         "and .npy"},
        {"heightmap.channel", "the height channel",
         "instrument files of several channels (read through Gwyddion): the channel's number "
         "(`0`, `1`, ...) or title (any case, or a part of it naming one channel); unset, the "
         "lowest-numbered channel in metres whose title says height or topography, else the "
         "lowest in metres. `scratchlight info FILE` lists the channels"},
        {"heightmap.measured", "the file's",
         "`true`: the map is a measurement (an instrument's), `false`: a simulator's or a "
         "generator's; unset, X3P, SDF and instrument formats are measurements, EXR, TIFF, PNG "
         "and .npy are not. The defect map's `auto` follows it: the tool-path model on a "
         "simulator's part, `selfsim` on a measurement; insert-defects writes it"},
        {"material.type", code(d.material.type),
         "or `conductor` (smooth mirror) — Mitsuba 3's plugins"},
        {"material.distribution", code(microfacetName(m.distribution)),
         "or `beckmann` (visible-normal sampling, as Mitsuba)"},
        {"material.alpha", m.alphaU == m.alphaV ? num(m.alphaU) : pair(m.alphaU, m.alphaV),
         "roughness α in (0, 1]; `alpha_u` (along +x, the map's columns) and `alpha_v` (along z) "
         "for "
         "anisotropy"},
        {"material.material", code(d.material.name),
         "`none` (η=0, k=1: a perfect mirror), `Al`, `Cr`, `Fe`, `Cu`, `Au`, `Ag`; or explicit "
         "`eta` and `k` (a number or `[r, g, b]`)"},
        {"camera.type", code(cameraTypeName(d.camera.type)),
         "or `orthographic` (with `width_mm`, default " + num(CameraSpec::kWidthMmFactor) +
             " × the part's larger extent)"},
        {"camera.origin/target/up", "automatic",
         "omitted: looks at the part's centre from 45° above (+z side), framing all of it"},
        {"camera.fov", num(d.camera.fovDeg), "degrees along the image's horizontal axis"},
        {"camera.width/height", pair(d.camera.width, d.camera.height), "image size"},
        {"envmap.width/height", pair(d.envmap.width, d.envmap.height), "env-map texels"},
        {"envmap.path/constant/preset", code(EnvMapDesc::kDefaultPreset) + " preset",
         "the env map `render` uses when its command line names none"},
        {"render.spp", num(d.render.spp), "samples per pixel (stratified, box filter)"},
        {"render.max_depth", num(d.render.maxDepth),
         "Mitsuba's `max_depth`: 2 = one reflection, 3 = up to two"},
        {"render.seed", num(static_cast<double>(d.render.seed)), "random seed"},
        {"render.sampling", code(registryRow(samplingTable(), d.render.sampling).name),
         "direction sampling: `stratified` (BSDF samples spread over the pixel by a shifted "
         "Sobol' sequence), `bsdf` (independent BSDF samples), `mis` (BSDF and env-map sampling "
         "combined by MIS)"},
        {"description", "\"\"", "free text"},
    };
}

std::string sceneFileTable() {
    std::string t = "| field | default | meaning |\n|---|---|---|\n";
    for (const SceneFileField& f : sceneFileFields())
        t += "| `" + f.field + "` | " + f.defaultValue + " | " + f.meaning + " |\n";
    return t;
}

}  // namespace sl
