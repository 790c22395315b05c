// scratchlight gen-surface OUT.exr|OUT.png|OUT.x3p [--part NAME | --process NAME] [--width N
// --height N]
//                         [--pitch P] [tool, defect and noise options] [--seed S]
//                         [--scene SCENE.json]
// Writes a synthetic NC-machined height map, its ground-truth labels (<stem>-truth.png,
// height-map space, with the legend <stem>-truth.json) and optionally a scene file that renders
// it. The spec starts from the named test part (--part) or the process's defaults
// (synth/SurfaceGenerator.h processDefaults); every option given on the command line overrides
// it, so without new options the surface is the one gen-surface has always made.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <utility>
#include <vector>

#include "app/jobs/PartFiles.h"
#include "cli/Commands.h"
#include "cli/Common.h"
#include "core/Error.h"
#include "io/AtomicFile.h"
#include "io/ImageIO.h"
#include "synth/SurfaceGenerator.h"

namespace sl::cli {

namespace {
struct GenArgs {
    std::string out = "part.exr", scene;
    SurfaceSpec::Process process = SurfaceSpec::Process::BallEndRaster;
    std::optional<TestPart> part;
    bool noPocket = false;
    int imageSize = 0, spp = 64, maxDepth = 4;  // the scene file's camera and render section
    SurfaceSpec spec;                           // what the options wrote (defaults: SurfaceSpec{})
    // The spec options: each copies its field into the part's or process's spec when given.
    std::vector<std::pair<CLI::Option*, std::function<void(SurfaceSpec&, const SurfaceSpec&)>>>
        given;
};

int runGen(GenArgs a) {
    std::filesystem::path out = a.out;
    std::string ext = out.extension().string();
    if (ext != ".exr" && ext != ".png" && ext != ".x3p")
        throw UsageError("output '" + a.out +
                         "' must end in .exr (float32), .png (16-bit) or .x3p (X3P)");
    SurfaceSpec spec = a.part ? testPartSpec(*a.part) : processDefaults(a.process);
    for (const auto& [option, apply] : a.given)
        if (option->count() > 0) apply(spec, a.spec);
    if (a.noPocket) spec.pocketEdge = false;
    PartFileOptions po;
    po.scene = a.scene;
    po.imageSize = a.imageSize;
    po.spp = a.spp;
    po.maxDepth = a.maxDepth;
    checkPartFiles(out, po);  // before the work
    GeneratedSurface g = generateSurface(spec);

    const PartFiles f = writePartFiles(g, out, po);
    const double lo = f.lo, hi = f.hi;
    const std::filesystem::path truth = f.truth;
    if (!a.scene.empty()) std::printf("wrote %s\n", a.scene.c_str());
    std::printf("%s\nwrote %s (%dx%d, pitch %g mm, heights %.6g..%.6g mm) and %s\n",
                g.description.c_str(), out.string().c_str(), g.width, g.height, g.pitch, lo, hi,
                truth.string().c_str());
    return kOk;
}

/// An option that sets one SurfaceSpec field (shown with SurfaceSpec{}'s default).
template <class T>
CLI::Option* addSpec(CLI::App* c, GenArgs& a, const std::string& flag, T SurfaceSpec::*field,
                     const std::string& help) {
    CLI::Option* o = c->add_option(flag, a.spec.*field, help)->capture_default_str();
    a.given.emplace_back(
        o, [field](SurfaceSpec& dst, const SurfaceSpec& src) { dst.*field = src.*field; });
    return o;
}
}  // namespace

void registerGenSurface(CLI::App& app, std::function<int()>& run) {
    auto a = std::make_shared<GenArgs>();
    GenArgs& g = *a;
    CLI::App* c = app.add_subcommand(
        "gen-surface", "Generate a synthetic NC-machined height map and its ground-truth labels");
    c->add_option("-o,--output", a->out,
                  "Height map to write: .exr (float32 mm), .png (16-bit) or .x3p (X3P with its "
                  "pitch)")
        ->capture_default_str();
    CLI::Option* process =
        addChoice(c, "--process", a->process, processTable(),
                  "Machining process (default ballend; its tool defaults apply unless given)");
    addChoice(c, "--part", a->part, testPartTable(),
              "A labelled test part (1024x1024 at 0.01 mm, every defect kind); the options "
              "given override its settings")
        ->excludes(process);
    addSpec(c, g, "--width", &SurfaceSpec::width, "Samples per row")->check(inRange(2, 32767));
    addSpec(c, g, "--height", &SurfaceSpec::height, "Rows")->check(inRange(2, 32767));
    addSpec(c, g, "--pitch", &SurfaceSpec::pitch, "Sample spacing in mm");
    addSpec(c, g, "--tool-radius", &SurfaceSpec::toolRadius,
            "Tool radius in mm (ball, face-mill cutter or flat end mill; ground: grit tip)");
    addSpec(c, g, "--stepover", &SurfaceSpec::stepover,
            "Path or pass spacing in mm (ground: mean spacing of the grit tracks)");
    addSpec(c, g, "--grit-depth", &SurfaceSpec::gritDepth,
            "Ground: the grits' mean depth of cut in mm");
    addSpec(c, g, "--grit-length", &SurfaceSpec::gritLength,
            "Ground: the grit tracks' mean length along the lay in mm");
    addSpec(c, g, "--feed,--feed-per-tooth", &SurfaceSpec::feedPerTooth,
            "Feed per tooth in mm (per revolution for turned; flatend: 0 = no feed marks)");
    addSpec(c, g, "--nose-radius,--insert-nose-radius", &SurfaceSpec::insertNoseRadius,
            "Insert nose radius in mm (facemill, turned)");
    addSpec(c, g, "--tool-corner-radius", &SurfaceSpec::toolCornerRadius,
            "Flat end mill corner radius in mm");
    addSpec(c, g, "--raster-angle,--raster-angle-deg", &SurfaceSpec::rasterAngleDeg,
            "Direction of the tool paths, degrees from +x toward +z");
    addSpec(c, g, "--turn-centre-x", &SurfaceSpec::turnCentreX,
            "Turned: x of the spiral's centre in mm (map centre 0)");
    addSpec(c, g, "--turn-centre-z", &SurfaceSpec::turnCentreZ,
            "Turned: z of the spiral's centre in mm (map centre 0)");
    addSpec(c, g, "--scratches,--scratch-count", &SurfaceSpec::scratchCount,
            "Number of random scratches");
    addSpec(c, g, "--scratch-depth", &SurfaceSpec::scratchDepth, "Deepest scratch in mm");
    addSpec(c, g, "--scratch-depth-min", &SurfaceSpec::scratchDepthMin,
            "Shallowest scratch as a fraction of --scratch-depth");
    addSpec(c, g, "--scratch-width", &SurfaceSpec::scratchWidth, "Widest scratch in mm");
    addSpec(c, g, "--scratch-width-min", &SurfaceSpec::scratchWidthMin,
            "Narrowest scratch as a fraction of --scratch-width");
    addSpec(c, g, "--scratch-direction,--scratch-direction-deg", &SurfaceSpec::scratchDirectionDeg,
            "Mean scratch direction, degrees from +x toward +z");
    addSpec(c, g, "--scratch-direction-spread,--scratch-direction-spread-deg",
            &SurfaceSpec::scratchDirectionSpreadDeg,
            "Scratch directions spread over this many degrees (180: any direction)");
    CLI::Option* lips = c->add_flag("--label-scratch-lips", a->spec.labelScratchLips,
                                    "Label the scratches' raised lips as burr (160)");
    a->given.emplace_back(lips, [](SurfaceSpec& dst, const SurfaceSpec& src) {
        dst.labelScratchLips = src.labelScratchLips;
    });
    addSpec(c, g, "--gouges,--gouge-count", &SurfaceSpec::gougeCount,
            "Number of random gouges (label 255)");
    addSpec(c, g, "--dents,--dent-count", &SurfaceSpec::dentCount,
            "Number of random dents (label 224)");
    addSpec(c, g, "--dent-depth", &SurfaceSpec::dentDepth, "Deepest dent in mm");
    addSpec(c, g, "--dent-radius", &SurfaceSpec::dentRadius, "Dent indenter radius in mm");
    addSpec(c, g, "--cracks,--crack-count", &SurfaceSpec::crackCount,
            "Number of random cracks: meandering, branching fissures with no rim (label 232)");
    addSpec(c, g, "--crack-length", &SurfaceSpec::crackLength,
            "Longest crack's trunk in mm, along its path");
    addSpec(c, g, "--crack-width", &SurfaceSpec::crackWidth, "Widest crack opening in mm");
    addSpec(c, g, "--crack-depth", &SurfaceSpec::crackDepth, "Deepest crack in mm");
    addSpec(c, g, "--crack-branches", &SurfaceSpec::crackBranches, "Branches of each crack");
    addSpec(c, g, "--burr,--pocket-burr-height", &SurfaceSpec::pocketBurrHeight,
            "Burr height on the pocket edge in mm (0: none; label 160)");
    addSpec(c, g, "--tool-change-step", &SurfaceSpec::toolChangeStep,
            "Tool-change step in mm, lower beyond --tool-change-at (0: none; label 192)");
    addSpec(c, g, "--tool-change-at", &SurfaceSpec::toolChangeAt,
            "Across-path position (turned: radius) of the tool-change step in mm");
    addSpec(c, g, "--chatter,--chatter-amplitude", &SurfaceSpec::chatterAmplitude,
            "Chatter amplitude in mm (0: none)");
    addSpec(c, g, "--chatter-start,--chatter-start-fraction", &SurfaceSpec::chatterStartFraction,
            "Chatter only from this fraction of the width in +x (0.5: the right half, "
            "labelled 128 in the truth)");
    addSpec(c, g, "--chatter-bands", &SurfaceSpec::chatterBands,
            "Number of chatter bands along the paths (rings for turned; label 144)");
    addSpec(c, g, "--chatter-band-width", &SurfaceSpec::chatterBandWidth,
            "Width of a chatter band across the paths in mm");
    addSpec(c, g, "--chatter-band-amplitude", &SurfaceSpec::chatterBandAmplitude,
            "Chatter amplitude inside the bands in mm");
    addSpec(c, g, "--noise,--noise-rms", &SurfaceSpec::noiseRms,
            "Measurement noise: white noise RMS in mm (0: none; not labelled)");
    addSpec(c, g, "--spikes,--spike-count", &SurfaceSpec::spikeCount,
            "Measurement noise: single-sample spikes (not labelled)");
    addSpec(c, g, "--spike-height", &SurfaceSpec::spikeHeight, "Largest spike in mm");
    c->add_flag("--no-pocket", a->noPocket, "Leave out the pocket edge (step)");
    addSpec(c, g, "--seed", &SurfaceSpec::seed, "Random seed");
    c->add_option("--image-size", a->imageSize,
                  "Scene file: camera image width and height in pixels (default: the scene's)")
        ->check(inRange(1, 16384));
    c->add_option("--spp", a->spp, "Scene file: render.spp")
        ->check(inRange(1, 1 << 20))
        ->capture_default_str();
    c->add_option("--max-depth", a->maxDepth, "Scene file: render.max_depth")
        ->check(inRange(1, 64))
        ->capture_default_str();
    c->add_option("--scene", a->scene, "Also write a scene file (JSON) that renders the map");
    c->callback([a, &run] { run = [a] { return runGen(*a); }; });
}

}  // namespace sl::cli
