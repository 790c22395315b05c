#include "cli/Common.h"

#include <unistd.h>

#include <cstdio>
#include <mutex>

#include "app/Plot.h"
#include "core/Error.h"
#include "io/EnvMapIO.h"
#include "scene/EnvMapPresets.h"
#include "scene/Scene.h"

namespace sl::cli {

EnvMap chooseEnvMap(const Scene& scene, const std::string& envmapFile,
                    std::optional<float> constant) {
    const int w = scene.basis.width(), h = scene.basis.height();
    if (!envmapFile.empty() && constant)
        throw UsageError("give either --envmap or --constant, not both");
    if (!envmapFile.empty()) return loadEnvMap(envmapFile, w, h, 3);
    if (constant) {
        if (!(*constant >= 0)) throw UsageError("--constant must be >= 0");
        return EnvMap::constant(w, h, *constant);
    }
    const EnvMapDesc& e = scene.desc.envmap;
    if (!e.path.empty()) return loadEnvMap(e.path, w, h, 3);
    if (e.constant) return EnvMap::constant(w, h, *e.constant);
    return presetEnvMap(e.preset.empty() ? EnvMapDesc::kDefaultPreset : e.preset, w, h);
}

std::filesystem::path siblingPath(const std::filesystem::path& out, const std::string& ext,
                                  const std::string& siblingExt) {
    if (out.extension() != ext)
        throw UsageError("output '" + out.string() + "' must end in " + ext);
    std::filesystem::path p = out;
    p.replace_extension(siblingExt);
    return p;
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

bool hasFlag(const CLI::App& app, const std::string& flag) {
    if (app.get_option_no_throw(flag)) return true;
    for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; }))
        if (hasFlag(*sub, flag)) return true;
    return false;
}

}  // namespace

std::string withFlags(const CLI::App& app, const std::string& message) {
    static const std::string open = "option '";
    std::string out;
    size_t pos = 0;
    for (size_t at; (at = message.find(open, pos)) != std::string::npos;) {
        const size_t nameStart = at + open.size(), end = message.find('\'', nameStart);
        if (end == std::string::npos) break;
        const std::string flag = "--" + message.substr(nameStart, end - nameStart);
        out += message.substr(pos, at - pos);
        out += hasFlag(app, flag) ? flag : message.substr(at, end + 1 - at);
        pos = end + 1;
    }
    return out + message.substr(pos);
}

}  // namespace sl::cli
