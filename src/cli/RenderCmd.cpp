// scratchlight render SCENE.json [--envmap SPEC] [--spp N] [--threads N] [--renderer
// povray|command]
// [-o OUT.exr]
#include <spdlog/spdlog.h>

#include <memory>

#include "app/DepthBench.h"
#include "app/ExternalRenderer.h"
#include "cli/Commands.h"
#include "cli/Common.h"
#include "core/Progress.h"
#include "core/Stopwatch.h"
#include "io/EnvMapIO.h"
#include "io/ImageIO.h"
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

/// The same scene and light through an external renderer (app/ExternalRenderer.h).
int renderExternal(const RenderArgs& a, const Scene& scene, const EnvMap& env, uint64_t seed) {
    if (a.autoDepth || a.maxDepth || a.spp)
        throw UsageError(
            "--spp, --max-depth and --auto-depth set our tracer's samples and path "
            "length; an external renderer keeps its own: drop them");
    const auto pngPath = siblingPath(a.out, ".exr", ".png");
    const ExternalRenderer r(scene, externalRendererOptions(a.renderer, a.external));
    const Stopwatch clock;
    Image img;
    {
        ProgressTask task("render (" + r.name() + ")");
        img = r.render(env, seed, a.threads);
    }
    writeExr(a.out, img);
    writePng(pngPath, img, a.exposure);
    spdlog::info("rendered {}x{} with {} in {:.3f} s", img.width, img.height, r.name(),
                 clock.seconds());
    spdlog::info("wrote {} and {}", a.out, pngPath.string());
    return kOk;
}

int runRender(const RenderArgs& a) {
    const auto pngPath = siblingPath(a.out, ".exr", ".png");
    SceneDesc desc = readSceneFile(a.scene, a.overrides);
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
        ->check(CLI::Range(1, 1 << 20));
    auto* depth =
        c->add_option("--max-depth", a->maxDepth, "Mitsuba max_depth (overrides render.max_depth)")
            ->check(CLI::Range(1, 64));
    c->add_flag("--auto-depth", a->autoDepth,
                "Pick max_depth: the first path length whose next bounce adds < 0.1 % of the "
                "image under a white light (measured on a lattice of pixels; prints the reason)")
        ->excludes(depth);
    c->add_option("--seed", a->seed, "Random seed (overrides render.seed)");
    c->add_option("--threads", a->threads, "Worker threads (0: all cores)")
        ->check(CLI::Range(0, 4096));
    c->add_option("-o,--output", a->out, "Output EXR (linear); a PNG preview is written beside it")
        ->capture_default_str();
    addRendererOptions(c, a->renderer, a->external);
    c->add_option("--exposure", a->exposure, "Scale applied to the PNG preview only")
        ->check(CLI::PositiveNumber);
    c->callback([a, &run] { run = [a] { return runRender(*a); }; });
}

}  // namespace sl::cli
