// scratchlight envmap-preset [studio] [--width 50 --height 25] [-o studio.exr]
// A built-in env map (scene/EnvMapPresets.h) as EXR + PNG preview.
#include <cstdio>
#include <memory>

#include "cli/Commands.h"
#include "cli/Common.h"
#include "io/EnvMapIO.h"
#include "io/ImageIO.h"
#include "scene/EnvMapPresets.h"
#include "scene/Scene.h"

namespace sl::cli {

namespace {

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

void registerEnvMapPreset(CLI::App& app, std::function<int()>& run) {
    auto a = std::make_shared<PresetArgs>();
    CLI::App* c =
        app.add_subcommand("envmap-preset",
                           "Write a built-in env map (e.g. studio) as EXR + PNG preview, for "
                           "`optimize --init FILE` or `render --envmap FILE`");
    c->add_option("name", a->name, "Preset name")->capture_default_str();
    c->add_option("--width", a->width, "Texels")->capture_default_str()->check(inRange(1, 100000));
    c->add_option("--height", a->height, "Texels")
        ->capture_default_str()
        ->check(inRange(2, 100000));
    c->add_option("-o,--output", a->out, "EXR file")->capture_default_str();
    c->callback([a, &run] { run = [a] { return runPreset(*a); }; });
}

}  // namespace sl::cli
