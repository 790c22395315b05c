#include "cli/Common.h"

#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <mutex>

#include "app/host/Plot.h"
#include "core/Error.h"
#include "core/Text.h"
#include "io/EnvMapIO.h"
#include "io/InputFile.h"
#include "io/SceneFile.h"
#include "scene/EnvMapPresets.h"
#include "scene/Scene.h"

namespace sl::cli {

EnvMap chooseEnvMap(const Scene& scene, const std::string& spec) {
    const int w = scene.basis.width(), h = scene.basis.height();
    if (!spec.empty()) return lightFromSpec(spec, w, h, 3, option("envmap"));
    const EnvMapDesc& e = scene.desc.envmap;
    if (!e.path.empty()) return loadEnvMap(e.path, w, h, 3);
    if (e.constant) return EnvMap::constant(w, h, *e.constant);
    return presetEnvMap(e.preset.empty() ? EnvMapDesc::kDefaultPreset : e.preset, w, h);
}

// --renderer, --renderer-cmd (implies --renderer command), --renderer-timeout.
void addRendererOptions(CLI::App* c, RendererKind& kind, ExternalRendererOptions& external) {
    addChoice(c, "--renderer", kind, rendererKindTable(), "Renderer (default builtin)");
    c->add_option_function<std::string>(
        "--renderer-cmd",
        [&kind, &external](const std::string& v) {
            external.command = v;
            if (kind == RendererKind::Builtin) kind = RendererKind::Command;
        },
        "External renderer command template with {scene} (a Mitsuba 3 scene.xml), {envmap}, "
        "{output} (implies --renderer command)");
    c->add_option("--renderer-timeout", external.timeoutSeconds,
                  "Seconds one external render may take")
        ->check(positiveNumber())
        ->capture_default_str();
}

void addCacheOptions(CLI::App* c, CacheLocation& cache) {
    auto* dir = c->add_option_function<std::string>(
        "--cache", [&cache](const std::string& d) { cache.dir = d; },
        "Folder of the transport-matrix cache (default: $SCRATCHLIGHT_CACHE, else "
        "~/.cache/scratchlight; `scratchlight cache` shows it)");
    auto* off = c->add_flag_function(
        "--no-cache", [&cache](std::int64_t) { cache.disabled = true; },
        "Trace every matrix; read and keep nothing in the cache");
    dir->excludes(off);
    c->add_option_function<std::string>(
         "--cache-max",
         [&cache](const std::string& text) { cache.maxBytes = parseByteSize(text, "--cache-max"); },
         "Size cap of the cache, e.g. 500MB or 8GB (default " +
             std::to_string(kDefaultCacheMaxBytes / 1000000000) +
             "GB): the least recently used matrices are removed first")
        ->type_name("SIZE");
}

void addDefectRegionOptions(CLI::App* c, RegionSpec& defects, RegionSpec& reference) {
    addParsed(c, "--defects", defects, parseRegionSpec,
              "--objective defects: the defect region in height-map space: MASK.png, "
              "TRUTH.png:LABEL[,LABEL...] (legend names or values), or auto (the defect map "
              "of the height map, as `scratchlight defectmap`; default: --truth, else auto)");
    addParsed(c, "--reference", reference, parseRegionSpec,
              "--objective defects: the reference region, as --defects (default: the part "
              "away from the defects; auto: what the defect map leaves unmarked). Region "
              "comparison: --defects part-truth.png:chatter --reference "
              "part-truth.png:none");
}

void addHeightSourceInput(CLI::App* c, std::filesystem::path& input,
                          std::vector<std::string>& overrides, const std::string& help) {
    c->add_option_function<std::string>(
         "input", [&input](const std::string& v) { input = v; }, help)
        ->required();
    addSceneOverrides(c, overrides, false);
}

void addSceneOverrides(CLI::App* c, std::vector<std::string>& overrides, bool image) {
    c->add_option_function<std::vector<std::string>>(
         "-D",
         [&overrides](const std::vector<std::string>& v) {
             overrides.insert(overrides.end(), v.begin(), v.end());
         },
         "Scene override key=value (repeatable), e.g. -D material.alpha=0.1 -D render.spp=16")
        ->type_name("KEY=VALUE")
        ->allow_extra_args(false);
    // A map without a pitch is refused (io/SceneFile.h loadScene); this accepts the default,
    // loudly: everything in mm (the part's size, its slopes, the camera's framing) follows.
    c->add_flag_callback(
        "--assume-pitch",
        [&overrides] {
            const std::string p = formatNumber(HeightmapDesc{}.pitch);
            std::fprintf(stderr,
                         "warning: --assume-pitch: the height map's samples are taken to be %s mm "
                         "apart, a guess, not your part's spacing (its size in mm, its slopes and "
                         "the camera's framing follow from it); give heightmap.pixel_pitch "
                         "when you know it\n",
                         p.c_str());
            overrides.push_back("heightmap.pixel_pitch=" + p);
        },
        "Accept the default pixel pitch (" + formatNumber(HeightmapDesc{}.pitch) +
            " mm) for a height map that carries none (EXR, TIFF, PNG, .npy) when the scene "
            "gives no heightmap.pixel_pitch");
    if (!image) return;
    auto camera = [&overrides](const char* field) {
        return [&overrides, field](int v) {
            overrides.push_back(std::string("camera.") + field + "=" + std::to_string(v));
        };
    };
    c->add_option_function<int>("--width", camera("width"), "Image width in pixels (camera.width)")
        ->check(inRange(1, 16384));
    c->add_option_function<int>("--height", camera("height"),
                                "Image height in pixels (camera.height)")
        ->check(inRange(1, 16384));
    c->add_option_function<int>(
         "--size",
         [&overrides](int v) {
             overrides.push_back("camera.width=" + std::to_string(v));
             overrides.push_back("camera.height=" + std::to_string(v));
         },
         "Image width and height in pixels (a square image)")
        ->check(inRange(1, 16384));
}

std::filesystem::path siblingPath(const std::filesystem::path& out, const std::string& ext,
                                  const std::string& siblingExt) {
    if (out.extension() != ext)
        throw UsageError("output '" + out.string() + "' must end in " + ext);
    std::filesystem::path p = out;
    p.replace_extension(siblingExt);
    return p;
}

void refuseOutputDirOverInputs(const std::filesystem::path& outDir,
                               const std::filesystem::path& input,
                               const std::vector<std::string>& sceneOverrides,
                               std::vector<std::filesystem::path> others) {
    others.push_back(input);
    // The scene's own files matter only when OUTDIR exists (a new one holds nothing).
    if (input.extension() == ".json" && std::filesystem::exists(input) &&
        std::filesystem::exists(outDir))
        for (const auto& f : sceneInputFiles(readSceneFile(input, sceneOverrides)))
            others.push_back(f);
    refuseOutputOverInput(outDir, "output directory", others, true);
}

int runPlot(const std::string& script, const std::vector<std::string>& args, bool run) {
    std::fflush(stdout);
    const PlotOutcome p = runPlotScript(script, args, run);
    const std::string command = shellQuoted(p.command);
    if (!run) {
        std::printf("plot with: %s\n", command.c_str());
    } else if (!p.ran) {
        std::printf("no plot: %s; plot with: %s\n", p.message.c_str(), command.c_str());
    } else if (p.exitCode != 0) {
        throw std::runtime_error("the plot script failed (exit code " + std::to_string(p.exitCode) +
                                 "): " + command);
    }
    return kOk;
}

namespace {

CLI::Validator numberAtLeast(bool allowZero) {
    return CLI::Validator(
        [allowZero](std::string& text) -> std::string {
            const char* bound = allowZero ? ">= 0" : "> 0";
            const std::optional<double> v = parseFiniteNumber(text);
            if (!v || !(allowZero ? *v >= 0 : *v > 0))
                return std::string("must be a finite number ") + bound + ", got '" + text + "'";
            return {};
        },
        allowZero ? "NUMBER >= 0" : "NUMBER > 0");
}

}  // namespace

CLI::Validator positiveNumber() {
    return numberAtLeast(false);
}

CLI::Validator integerInRange(long long lo, long long hi) {
    const std::string range = std::to_string(lo) + ".." + std::to_string(hi);
    return CLI::Validator(
        [lo, hi, range](std::string& text) -> std::string {
            long long v = 0;
            const char* end = text.data() + text.size();
            const auto [ptr, ec] = std::from_chars(text.data(), end, v);
            if (text.empty() || ec != std::errc() || ptr != end || v < lo || v > hi)
                return "must be an integer in " + range + ", got '" + text + "'";
            return {};
        },
        "in " + range);
}

CLI::Validator numberInRange(double lo, double hi) {
    const std::string range = formatNumber(lo) + ".." + formatNumber(hi);
    return CLI::Validator(
        [lo, hi, range](std::string& text) -> std::string {
            const std::optional<double> v = parseFiniteNumber(text);
            if (!v || *v < lo || *v > hi)
                return "must be a number in " + range + ", got '" + text + "'";
            return {};
        },
        "in " + range);
}

uintmax_t parseByteSize(const std::string& text, const std::string& flag) {
    size_t digits = 0;
    while (digits < text.size() &&
           (std::isdigit(static_cast<unsigned char>(text[digits])) || text[digits] == '.'))
        ++digits;
    const std::optional<double> v = parseFiniteNumber(text.substr(0, digits));
    std::string unit = lower(text.substr(digits));
    while (!unit.empty() && unit.front() == ' ') unit.erase(unit.begin());
    static const std::pair<const char*, double> units[] = {
        {"", 1.0},       {"b", 1.0},  {"kb", 1e3},     {"kib", 1024.0}, {"mb", 1e6},
        {"mib", 0x1p20}, {"gb", 1e9}, {"gib", 0x1p30}, {"tb", 1e12},    {"tib", 0x1p40}};
    for (const auto& [name, factor] : units)
        if (v && unit == name && *v * factor < 0x1p63) return static_cast<uintmax_t>(*v * factor);
    throw CLI::ValidationError(flag, "'" + text +
                                         "' is not a size; give bytes with a unit, e.g. 500MB, "
                                         "8GB or 2GiB");
}

CLI::Validator nonNegativeNumber() {
    return numberAtLeast(true);
}

std::vector<double> parseNumberList(const std::vector<std::string>& texts,
                                    const std::string& flag) {
    std::vector<double> values;
    for (const std::string& text : texts) {
        size_t start = 0;
        for (;;) {
            const size_t comma = text.find(',', start);
            const std::string item =
                text.substr(start, comma == std::string::npos ? comma : comma - start);
            const std::optional<double> v = parseFiniteNumber(item);
            if (!v)
                throw CLI::ValidationError(
                    flag, "'" + text + "': " +
                              (item.empty() ? std::string("an empty entry")
                                            : "'" + item + "' is not a finite number") +
                              "; give numbers separated by commas, e.g. 10,30,100");
            values.push_back(*v);
            if (comma == std::string::npos) break;
            start = comma + 1;
        }
    }
    return values;
}

namespace {

/// The option of `app` or a subcommand that answers to `flag` (nullptr: none).
const CLI::Option* findFlag(const CLI::App& app, const std::string& flag) {
    if (const CLI::Option* o = app.get_option_no_throw(flag)) return o;
    for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; }))
        if (const CLI::Option* o = findFlag(*sub, flag)) return o;
    return nullptr;
}

}  // namespace

std::string withFlags(const CLI::App& app, const std::string& message) {
    static const std::string open = "option '";
    std::string out;
    size_t pos = 0;
    for (size_t at; (at = message.find(open, pos)) != std::string::npos;) {
        const size_t nameStart = at + open.size(), end = message.find('\'', nameStart);
        if (end == std::string::npos) break;
        const std::string name = message.substr(nameStart, end - nameStart);
        const std::string flag = (name.size() == 1 ? "-" : "--") + name;  // -D, --width
        out += message.substr(pos, at - pos);
        // The flag's first name: an option may also answer to the library's name of it
        // (--lr, --learning-rate), and the user knows it by the first.
        const CLI::Option* o = findFlag(app, flag);
        const std::string first = o ? o->get_name() : std::string();  // "" when hidden
        out += !first.empty() ? first : o ? flag : message.substr(at, end + 1 - at);
        pos = end + 1;
    }
    return out + message.substr(pos);
}

}  // namespace sl::cli
