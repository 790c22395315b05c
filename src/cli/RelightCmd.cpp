// scratchlight relight part.tm --envmap SPEC [-o OUT.exr]
#include <spdlog/spdlog.h>

#include <memory>
#include <vector>

#include "app/report/Preview.h"
#include "cli/Commands.h"
#include "cli/Common.h"
#include "core/Error.h"
#include "io/EnvMapIO.h"
#include "io/TransportFile.h"
#include "scene/EnvMapToE.h"

namespace sl::cli {

namespace {

struct RelightArgs {
    std::string tm, envmap, out = "relight.exr";
};

int runRelight(const RelightArgs& a) {
    const auto png = siblingPath(a.out, ".exr", ".png");
    TransportFile f = readTransportFile(a.tm);
    const TransportMatrix& t = f.matrix;
    const EnvMap m =
        lightFromSpec(a.envmap, t.envWidth, t.envHeight, t.channels == 3 ? 3 : 1, option("envmap"));
    if (t.channels == 1 && a.envmap.rfind("const:", 0) != 0)
        spdlog::warn(
            "gray transport matrix: the env map is used as its luminance; the result equals a "
            "render only for gray maps (precompute with --rgb)");
    const int ch = t.channels == 3 ? 3 : 1;
    const std::vector<double> e = envMapToE(m, ch);
    std::vector<double> img(t.rows() * ch);
    if (ch == 3)
        t.applyRgb(e, img);
    else
        t.applyLuminance(e, img);
    writeRender(a.out, img, t.width, t.height, ch);
    spdlog::info("relit {}x{} ({}) from {}", t.width, t.height, ch == 3 ? "RGB" : "luminance",
                 a.tm);
    spdlog::info("wrote {} and {}", a.out, png.string());
    return kOk;
}

}  // namespace

void registerRelight(CLI::App& app, std::function<int()>& run) {
    auto a = std::make_shared<RelightArgs>();
    CLI::App* c = app.add_subcommand(
        "relight", "Render I = T·E from a transport matrix, without tracing a ray");
    c->add_option("transport", a->tm, "Transport-matrix file (.tm)")->required();
    c->add_option("--envmap", a->envmap, "The light: " + lightSpecForms())->required();
    c->add_option("-o,--output", a->out, "Output EXR; a PNG preview is written beside it")
        ->capture_default_str();
    c->callback([a, &run] { run = [a] { return runRelight(*a); }; });
}

}  // namespace sl::cli
