// scratchlight view (part.tm | SCENE.json | OUTDIR) [--port 8080] [--host H] [--open] [-o DIR]
//                   [--lamps lamps.json]
// scratchlight bench view [SCENE.json] [--size 512,2048] [--spp 1] [--repeats 20] [-o CSV]
// The live relighting viewer (app/viewer/ViewerSession.h, ViewerApi.h, ViewerServer.h) and its
// latency benchmark (app/bench/ViewerBench.h).
#include <signal.h>

#include <cstdio>
#include <cstdlib>
#include <memory>

#include "app/bench/ViewerBench.h"
#include "app/viewer/ViewerApi.h"
#include "app/viewer/ViewerServer.h"
#include "cli/Commands.h"
#include "cli/Common.h"

namespace sl::cli {

namespace {

struct ViewArgs {
    ViewerOptions o;
    int port = 8080;
    std::string host;
    bool open = false, noJudge = false;
};

int runView(const ViewArgs& a) {
    ViewerOptions o = a.o;
    o.judge = !a.noJudge;
    const std::string host = a.host.empty() ? "127.0.0.1" : a.host;
    if (!a.host.empty() && a.host != "127.0.0.1" && a.host != "localhost" && a.host != "::1")
        std::fprintf(stderr,
                     "warning: --host %s: the viewer is reachable from other machines; it has no "
                     "authentication and anyone who reaches it can change the light and save "
                     "files into %s\n",
                     a.host.c_str(), o.outDir.string().c_str());
    checkViewerPort(host, a.port);  // before minutes of tracing, not after
    ViewerSession session(o);
    const auto& t = session.transport();
    ViewerServer server(session, host, a.port);
    // A browser closing a connection mid-transfer must not end the process.
    signal(SIGPIPE, SIG_IGN);
    std::printf("viewer: %dx%d px, env map %dx%d, judge: %s; saves into %s/\n", t.width, t.height,
                t.envWidth, t.envHeight, session.hasJudge() ? "yes" : "no (no estimate)",
                o.outDir.string().c_str());
    std::printf("open %s (Ctrl-C to stop)\n", server.url().c_str());
    if (a.open) {
        std::string cmd = "xdg-open '";
        cmd += server.url();
        cmd += "' >/dev/null 2>&1 &";
        if (std::system(cmd.c_str()) != 0)
            std::fprintf(stderr, "warning: could not start a browser (xdg-open); open the URL\n");
    }
    server.run();
    return kOk;
}

int runBenchView(const ViewerBenchOptions& o) {
    signal(SIGPIPE, SIG_IGN);
    const auto rows = runViewerBench(o);
    std::printf("%s", formatViewerBench(rows).c_str());
    std::printf(
        "image: GET /api/image.png (relight + PNG encode + transfer, httplib client on "
        "127.0.0.1), median of %d; light: POST /api/light (E as JSON)\nwrote %s\n",
        o.repeats, o.csv.string().c_str());
    return kOk;
}

}  // namespace

void registerView(CLI::App& app, std::function<int()>& run) {
    auto a = std::make_shared<ViewArgs>();
    CLI::App* c = app.add_subcommand(
        "view",
        "A live relighting viewer in the browser: paint the light or drag lamps, see T·E and the "
        "judge, run the optimizer");
    c->add_option("input", a->o.input,
                  "A transport matrix (.tm), a scene file (.json), or an optimize or lamps output "
                  "directory")
        ->required();
    c->add_option("--port", a->port, "TCP port (0: any free port)")
        ->check(inRange(0, 65535))
        ->capture_default_str();
    c->add_option("--host", a->host,
                  "Address to listen on (default 127.0.0.1 only; anything else is reachable "
                  "from other machines and prints a warning)");
    c->add_flag("--open", a->open, "Open the page in the default browser (xdg-open)");
    c->add_option("--spp", a->o.spp, "Samples per pixel of T for a scene (default: the scene's)")
        ->check(inRange(1, 1 << 20));
    c->add_option("--heldout-spp", a->o.judgeSpp,
                  "Samples per pixel of the judge's estimate of a scene (two halves)")
        ->check(inRange(2, 1 << 20))
        ->capture_default_str();
    c->add_flag("--no-judge", a->noJudge, "No judge numbers (no estimate is traced)");
    c->add_option("--truth", a->o.truth,
                  "Truth label mask in height-map space: per-region visibility and the defect "
                  "overlay");
    c->add_option("--lamps", a->o.lamps,
                  "lamps.json (written by `scratchlight lamps`): the preset \"lamps\", handles "
                  "on the hemisphere (default: OUTDIR/lamps.json when there is one)");
    addSceneOverrides(c, a->o.sceneOverrides, true);
    addCacheOptions(c, a->o.cache);
    c->add_option("--threads", a->o.threads, "Worker threads (0: all cores)")
        ->check(inRange(0, 4096));
    c->add_option("-o,--output", a->o.outDir,
                  "Output directory: the only place the viewer writes (saved lights and lamps)")
        ->capture_default_str();
    c->callback([a, &run] { run = [a] { return runView(*a); }; });
}

void addViewBench(CLI::App* v, std::function<int()>& run) {
    auto b = std::make_shared<ViewerBenchOptions>();
    v->add_option("scene", b->scene, "Scene file (default: the bundled scenes/default)");
    v->add_option("--size", b->sizes, "Image sizes (square), e.g. --size 512,2048")
        ->delimiter(',')
        ->capture_default_str();
    v->add_option("--spp", b->spp, "Samples per pixel of T")
        ->check(inRange(1, 1 << 20))
        ->capture_default_str();
    v->add_option("--repeats", b->repeats, "Requests per size (the median is reported)")
        ->check(inRange(1, 100000))
        ->capture_default_str();
    addSceneOverrides(v, b->sceneOverrides, false);
    addCacheOptions(v, b->cache);
    v->add_option("--threads", b->threads, "Worker threads (0: all cores)")
        ->check(inRange(0, 4096));
    v->add_option("-o,--output", b->csv, "CSV file")->capture_default_str();
    v->callback([b, &run] { run = [b] { return runBenchView(*b); }; });
}

}  // namespace sl::cli
