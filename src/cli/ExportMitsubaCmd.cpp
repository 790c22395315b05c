// scratchlight export-mitsuba SCENE.json [--envmap SPEC | --lamps lamps.json] [-o OUTDIR]
// The scene as a Mitsuba 3 scene (io/MitsubaExport.h), for a cross-renderer check.
#include <spdlog/spdlog.h>

#include <filesystem>
#include <memory>

#include "cli/Commands.h"
#include "cli/Common.h"
#include "io/EnvMapIO.h"
#include "io/LampsFile.h"
#include "io/MitsubaExport.h"
#include "io/SceneFile.h"
#include "scene/Scene.h"

namespace sl::cli {

namespace {

struct ExportArgs {
    std::string scene, outDir = "mitsuba", envmap, lamps;
    std::vector<std::string> overrides;
};

int runExportCmd(const ExportArgs& a) {
    auto scene = loadScene(std::filesystem::path(a.scene), a.overrides);
    EnvMap env = chooseEnvMap(*scene, a.envmap);
    LampsFile lamps;
    if (!a.lamps.empty()) {  // the lamps are the only light (io/LampsFile.h)
        lamps = readLampsFile(a.lamps);
        std::fill(env.texels.begin(), env.texels.end(), 0.0f);
    }
    const MitsubaExport e = exportMitsuba(*scene, env, a.outDir);
    if (!a.lamps.empty()) addLampsToMitsubaScene(e.xml, lamps);
    spdlog::info("wrote {}, {} and {}{}", e.xml.string(), e.ply.string(), e.envmap.string(),
                 a.lamps.empty() ? "" : " (with the lamps of " + a.lamps + ")");
    spdlog::info("render with Mitsuba 3: mitsuba -m scalar_rgb {}", e.xml.string());
    for (const std::string& n : e.notes) spdlog::info("note: {}", n);
    return kOk;
}

}  // namespace

void registerExportMitsuba(CLI::App& app, std::function<int()>& run) {
    auto a = std::make_shared<ExportArgs>();
    CLI::App* c = app.add_subcommand(
        "export-mitsuba",
        "Write the scene as a Mitsuba 3 scene (XML + PLY height field + EXR env map) for a "
        "cross-renderer check");
    c->add_option("scene", a->scene, "Scene file (JSON)")->required();
    c->add_option(
         "--envmap", a->envmap,
         "The light: " + lightSpecForms() + " (default: the scene's envmap section, else studio)")
        ->excludes(c->add_option("--lamps", a->lamps,
                                 "lamps.json of `scratchlight lamps`: the lamps as area "
                                 "emitters, the only light"));
    addSceneOverrides(c, a->overrides, true);
    c->add_option("-o,--output", a->outDir, "Output directory")->capture_default_str();
    c->callback([a, &run] { run = [a] { return runExportCmd(*a); }; });
}

}  // namespace sl::cli
