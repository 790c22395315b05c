// scratchlight gen-surface OUT.exr|OUT.png [--size N] [--pitch P] [--process ballend|facemill]
//                         [--seed S] [--scene SCENE.json]
// Writes a synthetic NC-machined height map, its ground-truth defect mask (<stem>-truth.png,
// height-map space) and optionally a scene file that renders it.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <memory>
#include <nlohmann/json.hpp>

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

    Image hm(g.width, g.height, 1);
    auto [mn, mx] = std::minmax_element(g.heights.begin(), g.heights.end());
    double lo = *mn, hi = *mx > *mn ? *mx : *mn + 1e-6;
    if (ext == ".exr") {
        hm.data = g.heights;
        writeExr(out, hm);
    } else {
        for (size_t i = 0; i < g.heights.size(); ++i)
            hm.data[i] = static_cast<float>((g.heights[i] - lo) / (hi - lo));
        writePng16(out, hm);
    }
    std::filesystem::path truth = out.parent_path() / (out.stem().string() + "-truth.png");
    // The legend of the truth labels (judge --truth reads it to name the regions).
    nlohmann::ordered_json legend;
    legend["labels"] = nlohmann::ordered_json::array();
    legend["labels"].push_back({{"value", kTruthDefect}, {"name", "defect"}});
    if (std::count(g.truth.begin(), g.truth.end(), kTruthChatter) > 0)
        legend["labels"].push_back({{"value", kTruthChatter}, {"name", "chatter"}});
    std::filesystem::path legendPath = truth;
    legendPath.replace_extension(".json");
    writeMaskPng(truth, g.truth, g.width, g.height);
    writeTextAtomically(legendPath, legend.dump(2) + "\n");

    if (!a.scene.empty()) {
        std::filesystem::path scenePath = a.scene;
        nlohmann::ordered_json hmj;
        hmj["path"] = std::filesystem::relative(std::filesystem::absolute(out),
                                                std::filesystem::absolute(scenePath).parent_path())
                          .generic_string();
        hmj["pixel_pitch"] = g.pitch;
        if (ext == ".png") hmj["height_range"] = {lo, hi};
        nlohmann::ordered_json j;
        j["description"] = g.description;
        j["heightmap"] = hmj;
        j["material"] = {{"type", "roughconductor"},
                         {"distribution", "ggx"},
                         {"alpha", 0.05},
                         {"material", "Al"}};
        if (a.imageSize > 0) j["camera"] = {{"width", a.imageSize}, {"height", a.imageSize}};
        j["envmap"] = {{"width", 50}, {"height", 25}};
        j["render"] = {{"spp", a.spp}, {"max_depth", a.maxDepth}, {"seed", 0}};
        writeTextAtomically(scenePath, j.dump(2) + "\n");
        std::printf("wrote %s\n", scenePath.string().c_str());
    }
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
