// scratchlight gen-surface OUT.exr|OUT.png [--size N] [--pitch P] [--process ballend|facemill]
//                         [--seed S] [--scene SCENE.json]
// Writes a synthetic NC-machined height map, its ground-truth defect mask (<stem>-truth.png,
// height-map space) and optionally a scene file that renders it.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <memory>
#include <nlohmann/json.hpp>

#include "app/PartFiles.h"
#include "cli/Commands.h"
#include "cli/Common.h"
#include "core/Error.h"
#include "io/AtomicFile.h"
#include "io/ImageIO.h"
#include "synth/SurfaceGenerator.h"

namespace sl::cli {

namespace {
struct GenArgs {
    std::string out = "part.exr", scene, process = "ballend";
    int width = 1024, height = 1024;
    bool noPocket = false;
    int imageSize = 0, spp = 64, maxDepth = 4;  // the scene file's camera and render section
    SurfaceSpec spec;
};

int runGen(GenArgs a) {
    std::filesystem::path out = a.out;
    std::string ext = out.extension().string();
    if (ext != ".exr" && ext != ".png")
        throw UsageError("output '" + a.out + "' must end in .exr (float32) or .png (16-bit)");
    a.spec.width = a.width;
    a.spec.height = a.height;
    if (a.noPocket) a.spec.pocketEdge = false;
    a.spec.process = a.process == "facemill" ? SurfaceSpec::Process::FaceMillFeed
                                             : SurfaceSpec::Process::BallEndRaster;
    GeneratedSurface g = generateSurface(a.spec);

    PartFileOptions po;
    po.scene = a.scene;
    po.imageSize = a.imageSize;
    po.spp = a.spp;
    po.maxDepth = a.maxDepth;
    const PartFiles f = writePartFiles(g, out, po);
    const double lo = f.lo, hi = f.hi;
    const std::filesystem::path truth = f.truth;
    if (!a.scene.empty()) std::printf("wrote %s\n", a.scene.c_str());
    std::printf("%s\nwrote %s (%dx%d, pitch %g mm, heights %.6g..%.6g mm) and %s\n",
                g.description.c_str(), out.string().c_str(), g.width, g.height, g.pitch, lo, hi,
                truth.string().c_str());
    return kOk;
}
}  // namespace

void registerGenSurface(CLI::App& app, std::function<int()>& run) {
    auto a = std::make_shared<GenArgs>();
    CLI::App* c = app.add_subcommand(
        "gen-surface", "Generate a synthetic NC-machined height map and its ground-truth mask");
    c->add_option("output", a->out, "Height map to write: .exr (float32 mm) or .png (16-bit)")
        ->capture_default_str();
    c->add_option("--width", a->width, "Samples per row")
        ->check(CLI::Range(2, 32767))
        ->capture_default_str();
    c->add_option("--height", a->height, "Rows")
        ->check(CLI::Range(2, 32767))
        ->capture_default_str();
    c->add_option("--pitch", a->spec.pitch, "Sample spacing in mm")->capture_default_str();
    c->add_option("--process", a->process, "Machining process")
        ->check(CLI::IsMember({"ballend", "facemill"}))
        ->capture_default_str();
    c->add_option("--tool-radius", a->spec.toolRadius, "Tool radius in mm")->capture_default_str();
    c->add_option("--stepover", a->spec.stepover, "Ball-end path spacing in mm")
        ->capture_default_str();
    c->add_option("--scratches", a->spec.scratchCount, "Number of random scratches")
        ->capture_default_str();
    c->add_option("--chatter", a->spec.chatterAmplitude, "Chatter amplitude in mm (0: none)")
        ->capture_default_str();
    c->add_option("--chatter-start", a->spec.chatterStartFraction,
                  "Chatter only from this fraction of the width in +x (0.5: the right half, "
                  "labelled 128 in the truth)")
        ->capture_default_str();
    c->add_flag("--no-pocket", a->noPocket, "Leave out the pocket edge (step)");
    c->add_option("--seed", a->spec.seed, "Random seed")->capture_default_str();
    c->add_option("--image-size", a->imageSize,
                  "Scene file: camera image width and height in pixels (default: the scene's)")
        ->check(CLI::Range(1, 16384));
    c->add_option("--spp", a->spp, "Scene file: render.spp")
        ->check(CLI::Range(1, 1 << 20))
        ->capture_default_str();
    c->add_option("--max-depth", a->maxDepth, "Scene file: render.max_depth")
        ->check(CLI::Range(1, 64))
        ->capture_default_str();
    c->add_option("--scene", a->scene, "Also write a scene file (JSON) that renders the map");
    c->callback([a, &run] { run = [a] { return runGen(*a); }; });
}

}  // namespace sl::cli
