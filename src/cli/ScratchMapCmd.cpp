// scratchlight scratchmap (HEIGHTMAP | SCENE.json) [--kernel K] [--patch P] [--threshold T]
//                         [-o map.png] [--image-output MASK.png]
// The paper's cutting-scratch map (detect/ScratchMap.h).
#include <spdlog/spdlog.h>

#include <memory>
#include <optional>
#include <sstream>

#include "cli/Commands.h"
#include "cli/Common.h"
#include "core/Error.h"
#include "core/Interrupt.h"
#include "detect/ScratchMap.h"
#include "io/AtomicFile.h"
#include "io/HeightmapIO.h"
#include "io/ImageIO.h"
#include "io/InputFile.h"
#include "io/SceneFile.h"
#include "objective/ImageSpace.h"
#include "scene/Scene.h"

namespace sl::cli {

namespace {

struct ScratchArgs {
    std::filesystem::path input;
    std::string out = "scratchmap.png", imageMask;
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

}  // namespace

void registerScratchMap(CLI::App& app, std::function<int()>& run) {
    auto a = std::make_shared<ScratchArgs>();
    CLI::App* c = app.add_subcommand(
        "scratchmap",
        "Cutting-scratch map (paper 5.1): detrend by a moving average, scale to [0,1], mark "
        "patches whose max-min >= threshold");
    addHeightSourceInput(c, a->input, a->overrides,
                         "Height map (EXR/TIFF/PNG/.npy) or a scene file (JSON: its height map, "
                         "and its camera for --image-output)");
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

}  // namespace sl::cli
