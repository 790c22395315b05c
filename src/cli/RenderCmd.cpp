// scratchlight render SCENE.json [--envmap SPEC] [--spp N] [--threads N] [--renderer
// povray|command]
// [-o OUT.exr]
#include <spdlog/spdlog.h>

#include <algorithm>
#include <memory>

#include "app/host/ExternalRenderer.h"
#include "app/pipeline/AutoDepth.h"
#include "cli/Commands.h"
#include "cli/Common.h"
#include "core/Interrupt.h"
#include "core/Progress.h"
#include "core/Stopwatch.h"
#include "io/EnvMapIO.h"
#include "io/ImageIO.h"
#include "io/InputFile.h"
#include "io/SceneFile.h"
#include "render/Render.h"
#include "scene/Scene.h"

namespace sl::cli {

namespace {
struct RenderArgs {
    std::string scene, envmap, out = "render.exr";
    std::vector<std::string> overrides;
    std::optional<int> spp, maxDepth;
    std::optional<uint64_t> seed;
    int threads = 0;
    float exposure = 1.0f;
    bool autoDepth = false;
    RendererKind renderer = RendererKind::Builtin;
    ExternalRendererOptions external;
};

/// Both outputs checked before the work: neither may be a directory (the EXR would be written,
/// then the PNG refused).
void checkOutputs(const std::filesystem::path& exr, const std::filesystem::path& png) {
    for (const auto& p : {exr, png})
        if (std::filesystem::is_directory(p))
            throw InputError(p.string() + ": is a directory, not an output file. Give another " +
                             "output name");
}

/// A render without one lit pixel says so, and when the heights dwarf the part (heights of 1e30,
/// a map in other units) says that too: the camera frames the part by its extent.
void warnIfBlack(const Image& img, const Scene& scene) {
    if (std::any_of(img.data.begin(), img.data.end(), [](float v) { return v != 0; })) return;
    const auto [lo, hi] = std::minmax_element(scene.heights.begin(), scene.heights.end());
    const double span = lo == scene.heights.end() ? 0 : double(*hi) - double(*lo);
    const double extent = std::max(scene.mapWidth, scene.mapHeight) * scene.desc.heightmap.pitch;
    if (span > 100 * extent)
        spdlog::warn(
            "the render is black: the heights span {:.3g} mm over a part {:.3g} mm wide; check "
            "the height map's units (heightmap.height_scale, height_range)",
            span, extent);
    else
        spdlog::warn(
            "the render is black: no light reaches the camera (check the env map and "
            "the camera)");
}

/// The same scene and light through an external renderer (app/host/ExternalRenderer.h).
int renderExternal(const RenderArgs& a, const Scene& scene, const EnvMap& env, uint64_t seed) {
    if (a.autoDepth || a.maxDepth || a.spp)
        throw UsageError(
            "--spp, --max-depth and --auto-depth set our tracer's samples and path "
            "length; an external renderer keeps its own: drop them");
    const auto pngPath = siblingPath(a.out, ".exr", ".png");
    checkOutputs(a.out, pngPath);
    const ExternalRenderer r(scene, externalRendererOptions(a.renderer, a.external));
    const Stopwatch clock;
    Image img;
    {
        ProgressTask task("render (" + r.name() + ")");
        img = r.render(env, seed, a.threads);
    }
    enterCommit();  // Ctrl-C before the files appear: none does; after: both (core/Interrupt.h)
    writeExr(a.out, img);
    writePng(pngPath, img, a.exposure);
    spdlog::info("rendered {}x{} with {} in {:.3f} s", img.width, img.height, r.name(),
                 clock.seconds());
    spdlog::info("wrote {} and {}", a.out, pngPath.string());
    return kOk;
}

int runRender(const RenderArgs& a) {
    const auto pngPath = siblingPath(a.out, ".exr", ".png");
    checkOutputs(a.out, pngPath);
    SceneDesc desc = readSceneFile(a.scene, a.overrides);
    // Neither output may replace what this run reads (the scene's height map, say).
    std::vector<std::filesystem::path> inputs = sceneInputFiles(desc);
    inputs.push_back(a.envmap.rfind("envmap:", 0) == 0 ? a.envmap.substr(7) : a.envmap);
    refuseOutputOverInput(a.out, "output", inputs);
    refuseOutputOverInput(pngPath, "preview", inputs);
    if (a.spp) desc.render.spp = *a.spp;
    if (a.maxDepth) desc.render.maxDepth = *a.maxDepth;
    if (a.seed) desc.render.seed = *a.seed;
    auto scene = loadScene(desc);
    const HeightfieldStats& hs = scene->surface->stats();
    spdlog::info("Embree grid built in {:.3f} s, {:.1f} MB", hs.buildSeconds,
                 static_cast<double>(hs.embreeBytes) / 1e6);
    EnvMap env = chooseEnvMap(*scene, a.envmap);
    if (a.renderer != RendererKind::Builtin)
        return renderExternal(a, *scene, env, desc.render.seed);

    RenderOptions opt = renderOptionsFor(*scene);
    opt.threads = a.threads;
    if (a.autoDepth) {
        const DepthChoice c = autoMaxDepth(*scene, AutoDepthOptions{.threads = a.threads});
        opt.maxDepth = c.maxDepth;
        spdlog::info("max_depth {}: {}", c.maxDepth, c.reason);
    }
    ProgressTask task("render", 1);
    opt.progress = task.fraction();
    RenderResult r = render(*scene, env, opt);
    warnIfBlack(r.image, *scene);
    enterCommit();  // Ctrl-C before the files appear: none does; after: both (core/Interrupt.h)
    writeExr(a.out, r.image);
    writePng(pngPath, r.image, a.exposure);
    const TraceSummary& s = r.summary;
    spdlog::info("rendered {}x{} at {} spp (max_depth {}) in {:.3f} s: {:.2f} Mrays/s", s.width,
                 s.height, s.spp, opt.maxDepth, s.seconds, s.raysPerSecond() / 1e6);
    spdlog::info("wrote {} and {}", a.out, pngPath.string());
    return kOk;
}
}  // namespace

void registerRender(CLI::App& app, std::function<int()>& run) {
    auto a = std::make_shared<RenderArgs>();
    CLI::App* c = app.add_subcommand("render", "Render a scene under an environment map");
    c->add_option("scene", a->scene, "Scene file (JSON)")->required();
    c->add_option("--envmap", a->envmap,
                  "The light: " + lightSpecForms() +
                      " (default: the scene's envmap section, else studio); a file is resampled "
                      "to the scene's env-map grid");
    addSceneOverrides(c, a->overrides, true);
    c->add_option("--spp", a->spp, "Samples per pixel (overrides render.spp)")
        ->check(inRange(1, 1 << 20));
    auto* depth =
        c->add_option("--max-depth", a->maxDepth, "Mitsuba max_depth (overrides render.max_depth)")
            ->check(inRange(1, 64));
    c->add_flag("--auto-depth", a->autoDepth,
                "Pick max_depth: the first path length whose next bounce adds < 0.1 % of the "
                "image under a white light (measured on a lattice of pixels; prints the reason)")
        ->excludes(depth);
    c->add_option("--seed", a->seed, "Random seed (overrides render.seed)");
    c->add_option("--threads", a->threads, "Worker threads (0: all cores)")
        ->check(inRange(0, 4096));
    c->add_option("-o,--output", a->out, "Output EXR (linear); a PNG preview is written beside it")
        ->capture_default_str();
    addRendererOptions(c, a->renderer, a->external);
    c->add_option("--exposure", a->exposure, "Scale applied to the PNG preview only")
        ->check(positiveNumber());
    c->callback([a, &run] { run = [a] { return runRender(*a); }; });
}

}  // namespace sl::cli
