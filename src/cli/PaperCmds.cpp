// scratchlight scratchmap / report: see cli/PaperCmds.h, detect/ScratchMap.h, app/report/Report.h.
//
// report --spec FIGURES.json (paths relative to the spec file):
//   {"title": "...", "notes": ["..."], "settings": {...},
//    "figures": [{"title": "...", "caption": "...", "loss_plot": false,
//                 "runs": [{"dir": "OUTDIR", "title": "...", "caption": "...",
//                           "state": "final" | "initial",
//                           "images": [{"png": "FILE.png", "caption": "..."}],
//                           "metrics": {...}, "settings": {...}}]}]}
// A run needs "dir" (an optimize OUTDIR) or "images" (e.g. a `render` PNG) or both; its
// "metrics"/"settings" are merged over what the OUTDIR provides.
#include "cli/PaperCmds.h"

#include <spdlog/spdlog.h>

#include <memory>
#include <optional>
#include <sstream>

#include "app/report/Report.h"
#include "cli/Common.h"
#include "core/Error.h"
#include "core/Interrupt.h"
#include "detect/ScratchMap.h"
#include "io/AtomicFile.h"
#include "io/EnvMapIO.h"
#include "io/ImageIO.h"
#include "io/InputFile.h"
#include "io/SceneFile.h"
#include "objective/ImageSpace.h"
#include "scene/EnvMapPresets.h"
#include "scene/Scene.h"

namespace sl::cli {

namespace {

struct ScratchArgs {
    std::string input, out = "scratchmap.png", imageMask;
    std::vector<std::string> overrides;
    ScratchMapOptions opt;
};

int runScratchMap(const ScratchArgs& a) {
    std::filesystem::path in = a.input;
    if (std::filesystem::path(a.out).extension() != ".png")
        throw UsageError("-o '" + a.out + "' must end in .png");
    if (!a.imageMask.empty() && std::filesystem::path(a.imageMask).extension() != ".png")
        throw UsageError("--image-output '" + a.imageMask + "' must end in .png");
    const bool isScene = in.extension() == ".json";
    if (!a.imageMask.empty() && !isScene)
        throw UsageError("--image-output needs a scene file (its camera), not a bare height map");
    // Neither output replaces what this run reads; both are staged and appear together.
    std::vector<std::filesystem::path> inputs{in};
    if (isScene)
        for (const auto& f : sceneInputFiles(readSceneFile(in, a.overrides))) inputs.push_back(f);
    refuseOutputOverInput(a.out, "-o", inputs);
    refuseOutputOverInput(a.imageMask, "--image-output", inputs);
    AtomicOutput mapOut(a.out);
    std::optional<AtomicOutput> imageOut;
    if (!a.imageMask.empty()) imageOut.emplace(a.imageMask);
    const HeightSource src = loadHeightSource(in, a.overrides);
    const std::vector<float>& h = src.heights();
    const int W = src.width(), H = src.height();
    ScratchMap m = computeScratchMap(h, W, H, a.opt);
    writeMaskPng(mapOut.tempPath(), m.map, W, H);
    size_t inside = 0, partPixels = 0;
    int imageW = 0, imageH = 0;
    if (imageOut) {
        PrimaryHits hits = tracePrimaryHits(*src.scene);
        std::vector<uint8_t> img = projectToImage(hits, m.map);
        for (uint8_t v : img) inside += v != 0;
        partPixels = hits.hitCount();
        imageW = hits.width;
        imageH = hits.height;
        writeMaskPng(imageOut->tempPath(), img, hits.width, hits.height);
    }
    enterCommit();  // Ctrl-C before the files appear: none does; after: both (core/Interrupt.h)
    mapOut.commit();
    if (imageOut) imageOut->commit();
    std::printf(
        "scratch map of %dx%d samples (kernel %d, patch %d, threshold %g): %d of %d patches "
        "marked (%.1f%% of the map), detrended range %.6g, %.3f s\nwrote %s\n",
        W, H, a.opt.kernel, a.opt.patch, a.opt.threshold, m.patchesMarked, m.patchesX * m.patchesY,
        100.0 * m.markedFraction(), m.detrendedMax - m.detrendedMin, m.seconds, a.out.c_str());
    if (imageOut)
        std::printf("image-space mask %dx%d: %zu of %zu part pixels inside\nwrote %s\n", imageW,
                    imageH, inside, partPixels, a.imageMask.c_str());
    return kOk;
}

struct ReportArgs {
    std::vector<std::string> dirs, notes;
    std::string spec, out = "report.html", title = "scratchlight report";
    bool combinedLoss = false, initial = false;
};

int runReport(const ReportArgs& a) {
    if (a.spec.empty() == a.dirs.empty())
        throw UsageError("give either OUTDIR... or --spec FIGURES.json");
    ReportContent c;
    if (!a.spec.empty()) {
        c = readReportSpec(a.spec);
    } else {
        ReportFigure f;
        f.title = "Runs";
        f.combinedLossPlot = a.combinedLoss;
        for (const auto& d : a.dirs)
            f.runs.push_back(
                reportRunFromOutDir(d, "", a.initial ? RunState::Initial : RunState::Final));
        c.figures.push_back(std::move(f));
        c.title = a.title;
    }
    if (!a.spec.empty() && a.title != "scratchlight report") c.title = a.title;
    for (const auto& n : a.notes) c.notes.push_back(n);
    writeReport(a.out, c);
    size_t runs = 0;
    for (const auto& f : c.figures) runs += f.runs.size();
    std::printf("wrote %s (%zu figure(s), %zu run(s))\n", a.out.c_str(), c.figures.size(), runs);
    return kOk;
}

struct PresetArgs {
    std::string name = "studio", out = "studio.exr";
    int width = EnvMapDesc{}.width, height = EnvMapDesc{}.height;  // the scene file's default
};

int runPreset(const PresetArgs& a) {
    const auto png = siblingPath(a.out, ".exr", ".png");
    // Written as an RGB image: a preset stands in for a photographed environment, so
    // `--init envmap:FILE` turns it gray by CIE L*/100 as the paper does with photos (a
    // one-channel file would be taken as E itself).
    const EnvMap gray = presetEnvMap(a.name, a.width, a.height);
    EnvMap e = EnvMap::constant(gray.width, gray.height, 0.0f, 3);
    for (size_t t = 0; t < gray.texelCount(); ++t)
        for (size_t c = 0; c < 3; ++c)
            e.texels[3 * t + c] = gray.texels[t * static_cast<size_t>(gray.channels)];
    writeEnvMap(a.out, e);
    writePng(png, envMapPreview(e, 16));
    std::printf("wrote %s (%dx%d) and %s\n", a.out.c_str(), a.width, a.height,
                png.string().c_str());
    return kOk;
}

}  // namespace

void registerPaper(CLI::App& app, std::function<int()>& run) {
    {
        auto a = std::make_shared<ScratchArgs>();
        CLI::App* c = app.add_subcommand(
            "scratchmap",
            "Cutting-scratch map (paper 5.1): detrend by a moving average, scale to [0,1], mark "
            "patches whose max-min >= threshold");
        c->add_option("input", a->input,
                      "Height map (EXR/TIFF/PNG/.npy) or a scene file (JSON: its height map, and "
                      "its camera for --image-output)")
            ->required();
        addSceneOverrides(c, a->overrides, false);
        c->add_option("--kernel", a->opt.kernel, "Moving-average window, samples")
            ->capture_default_str()
            ->check(inRange(1, 1 << 20));
        c->add_option("--patch", a->opt.patch, "Patch side, samples")
            ->capture_default_str()
            ->check(inRange(1, 1 << 20));
        c->add_option("--threshold", a->opt.threshold,
                      "Max-min of a patch on the [0,1]-scaled detrended map that marks it")
            ->capture_default_str()
            ->check(inRange(0.0, 1.0));
        c->add_option("-o,--output", a->out, "Map in height-map space (8-bit PNG, 255 = marked)")
            ->capture_default_str();
        c->add_option("--image-output", a->imageMask,
                      "Also write the map projected into the scene camera's image (PNG), usable "
                      "as `optimize --mask`");
        c->callback([a, &run] { run = [a] { return runScratchMap(*a); }; });
    }
    {
        auto a = std::make_shared<ReportArgs>();
        CLI::App* c = app.add_subcommand(
            "report", "Assemble a self-contained report.html from optimize OUTDIRs");
        c->add_option("outdirs", a->dirs, "optimize OUTDIRs (one figure, one run each)");
        c->add_option("--spec", a->spec,
                      "JSON file grouping runs into figures with captions (see src/cli/"
                      "PaperCmds.cpp for the format)");
        c->add_option("-o,--output", a->out, "The HTML page")->capture_default_str();
        c->add_option("--title", a->title, "Page title")->capture_default_str();
        c->add_option("--note", a->notes, "A paragraph under the title (repeatable)");
        c->add_flag("--combined-loss", a->combinedLoss, "One loss plot for all runs");
        c->add_flag("--initial", a->initial, "Show the runs' initial state instead of the result");
        c->callback([a, &run] { run = [a] { return runReport(*a); }; });
    }
    {
        auto a = std::make_shared<PresetArgs>();
        CLI::App* c =
            app.add_subcommand("envmap-preset",
                               "Write a built-in env map (e.g. studio) as EXR + PNG preview, for "
                               "`optimize --init FILE` or `render --envmap FILE`");
        c->add_option("name", a->name, "Preset name")->capture_default_str();
        c->add_option("--width", a->width, "Texels")
            ->capture_default_str()
            ->check(inRange(1, 100000));
        c->add_option("--height", a->height, "Texels")
            ->capture_default_str()
            ->check(inRange(2, 100000));
        c->add_option("-o,--output", a->out, "EXR file")->capture_default_str();
        c->callback([a, &run] { run = [a] { return runPreset(*a); }; });
    }
}

}  // namespace sl::cli
