#include "app/host/ExternalRenderer.h"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "core/Color.h"
#include "core/Error.h"
#include "core/Hash.h"
#include "core/Interrupt.h"
#include "core/Progress.h"
#include "core/Rng.h"
#include "core/Stopwatch.h"
#include "core/Text.h"
#include "io/AtomicFile.h"
#include "io/ExitCleanup.h"
#include "io/ImageIO.h"
#include "io/MitsubaExport.h"
#include "io/SceneFile.h"
#include "optimize/BlackBox.h"
#include "render/Render.h"
#include "scene/Scene.h"

extern char** environ;

namespace sl {

namespace {

/// A fresh directory under the system's temporary folder, removed with its contents.
class TempDir {
  public:
    TempDir() {
        std::string templ =
            (std::filesystem::temp_directory_path() / "scratchlight-render-XXXXXX").string();
        if (!mkdtemp(templ.data()))
            throw inputError(
                std::filesystem::temp_directory_path().string(),
                std::string("cannot create a temporary directory: ") + std::strerror(errno),
                "set TMPDIR to a writable folder");
        path_ = templ;
    }
    ~TempDir() {
        std::error_code ec;
        std::filesystem::remove_all(path_, ec);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;
    const std::filesystem::path& path() const { return path_; }

  private:
    std::filesystem::path path_;
};

/// The program's path on PATH (or as given when it has a slash); empty when not found.
std::string findProgram(const std::string& program) {
    if (program.empty()) return {};
    if (program.find('/') != std::string::npos)
        return access(program.c_str(), X_OK) == 0 ? program : std::string();
    const char* path = std::getenv("PATH");
    std::stringstream ss(path ? path : "/usr/bin:/bin");
    std::string dir;
    while (std::getline(ss, dir, ':')) {
        if (dir.empty()) dir = ".";
        const std::string p = dir + "/" + program;
        if (access(p.c_str(), X_OK) == 0) return p;
    }
    return {};
}

std::string tailOf(const std::string& s, size_t n = 1500) {
    return s.size() <= n ? s : "..." + s.substr(s.size() - n);
}

}  // namespace

int concurrentRenders(const ExternalRendererOptions& options) {
    if (options.concurrentRenders > 0) return options.concurrentRenders;
    return 4 * static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

std::span<const RendererKindRow> rendererKindTable() {
    static const RendererKindRow rows[] = {
        {RendererKind::Builtin, "builtin", "our Embree path tracer"},
        {RendererKind::Povray, "povray",
         "POV-Ray 3.7 as a black box (io/PovrayExport.h: blurred mirror, not GGX)"},
        {RendererKind::Command, "command",
         "any command line (a template with {scene}, {envmap}, {output})"},
    };
    return rows;
}

std::vector<std::string> expandCommand(const std::string& templ, const std::string& scene,
                                       const std::string& envmap, const std::string& output) {
    std::vector<std::string> words;
    std::string cur;
    bool inWord = false;
    char quote = 0;
    for (char c : templ) {
        if (quote) {
            if (c == quote)
                quote = 0;
            else
                cur += c;
        } else if (c == '\'' || c == '"') {
            quote = c;
            inWord = true;
        } else if (c == ' ' || c == '\t' || c == '\n') {
            if (inWord) words.push_back(cur);
            cur.clear();
            inWord = false;
        } else {
            cur += c;
            inWord = true;
        }
    }
    if (quote)
        throw inputError(option("renderer-cmd"), "has an unterminated quote", "close the quote");
    if (inWord) words.push_back(cur);
    if (words.empty())
        throw inputError(option("renderer-cmd"), "is empty",
                         "give a command such as \"mitsuba -m scalar_rgb {scene} -o {output}\"");
    bool hasOutput = false;
    for (std::string& w : words) {
        for (const auto& [key, value] :
             {std::pair<std::string, const std::string*>{"{scene}", &scene},
              {"{envmap}", &envmap},
              {"{output}", &output}}) {
            for (size_t p; (p = w.find(key)) != std::string::npos;) {
                w.replace(p, key.size(), *value);
                if (key == "{output}") hasOutput = true;
            }
        }
    }
    if (!hasOutput)
        throw inputError(option("renderer-cmd"), "'" + templ + "' has no {output}",
                         "write the image to {output}");
    return words;
}

ProcessResult runProcess(const std::vector<std::string>& argv, const std::filesystem::path& dir,
                         double timeoutSeconds) {
    if (argv.empty()) throw std::invalid_argument("runProcess: no program");
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addchdir_np(&fa, dir.c_str());
    posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&fa, 1, "render.log", O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&fa, 1, 2);
    // Its own process group: a timeout, Ctrl-C or SIGTERM ends the renderer and every process
    // it started (kill(-group)); a second Ctrl-C, which exits at once, too (io/ExitCleanup.h).
    posix_spawnattr_t attr;
    posix_spawnattr_init(&attr);
    posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETPGROUP);
    posix_spawnattr_setpgroup(&attr, 0);
    pid_t pid = 0;
    const int err = posix_spawnp(&pid, args[0], &fa, &attr, args.data(), environ);
    posix_spawn_file_actions_destroy(&fa);
    posix_spawnattr_destroy(&attr);
    if (err == 0) registerExitProcessGroup(pid);
    if (err != 0)
        throw inputError("renderer '" + argv[0] + "'",
                         std::string("cannot be started: ") + std::strerror(err),
                         "install it (scripts/install-deps installs povray) or check the command");
    ProcessResult r;
    const auto start = std::chrono::steady_clock::now();
    int status = 0;
    for (;;) {
        const pid_t w = waitpid(pid, &status, WNOHANG);
        if (w == pid) break;
        if (w < 0 && errno != EINTR) break;
        if (interruptRequested()) {
            // Ctrl-C or SIGTERM to us: the renderer stops too (SIGTERM, then SIGKILL after 2 s),
            // and nothing it wrote is used
            kill(-pid, SIGTERM);
            const auto asked = std::chrono::steady_clock::now();
            while (waitpid(pid, &status, WNOHANG) != pid) {
                if (std::chrono::steady_clock::now() - asked > std::chrono::seconds(2)) {
                    kill(-pid, SIGKILL);
                    waitpid(pid, &status, 0);
                    break;
                }
                std::this_thread::sleep_for(std::chrono::milliseconds(10));
            }
            kill(-pid, SIGKILL);  // what the renderer started and left running
            unregisterExitProcessGroup(pid);
            throw Interrupted();
        }
        const double elapsed =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        if (elapsed > timeoutSeconds) {
            kill(-pid, SIGKILL);
            waitpid(pid, &status, 0);
            r.timedOut = true;
            break;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(elapsed < 1 ? 2 : 20));
    }
    kill(-pid, SIGKILL);  // nothing the renderer started outlives its render
    unregisterExitProcessGroup(pid);
    if (!r.timedOut && WIFEXITED(status)) r.exitCode = WEXITSTATUS(status);
    std::ifstream log(dir / "render.log");
    std::stringstream ss;
    ss << log.rdbuf();
    r.log = tailOf(ss.str());
    return r;
}

ExternalRenderer::ExternalRenderer(const Scene& scene, ExternalRendererOptions options)
    : scene_(scene), options_(std::move(options)) {
    if (options_.command.empty()) {
        if (findProgram(options_.program).empty())
            throw inputError("renderer 'povray'",
                             "the program '" + options_.program + "' is not on the PATH",
                             "install POV-Ray 3.7 (scripts/install-deps installs povray)");
        const PovraySettings& p = options_.povray;
        if (p.supersample < 1 || p.roughSamples < 1 || p.envScale < 1)
            throw inputError("POV-Ray settings", "supersample, roughSamples, envScale must be >= 1",
                             "use the defaults of io/PovrayExport.h");
    } else {
        const std::vector<std::string> words = expandCommand(options_.command, "s", "e", "o");
        if (findProgram(words[0]).empty())
            throw inputError(option("renderer-cmd"), "the program '" + words[0] + "' is not found",
                             "install it or give its full path");
    }
    if (!(options_.timeoutSeconds > 0))
        throw inputError(option("renderer-timeout"), "must be > 0 seconds", "use e.g. 600");
}

bool ExternalRenderer::seeded() const {
    const ConductorParams& m = scene_.bsdf.params();
    return options_.command.empty() && !m.smooth && options_.povray.roughSamples > 1;
}

int ExternalRenderer::width() const {
    return scene_.camera.width();
}

int ExternalRenderer::height() const {
    return scene_.camera.height();
}

std::string ExternalRenderer::key() const {
    const PovraySettings& p = options_.povray;
    if (!options_.command.empty()) return "command:" + options_.command;
    return "povray:s" + std::to_string(p.supersample) + ":r" + std::to_string(p.roughSamples) +
           ":e" + std::to_string(p.envScale) + ":b" + formatNumber(p.bumpsPerAlpha, 9);
}

Image ExternalRenderer::render(const EnvMap& env, uint64_t seed, int threads) const {
    TempDir dir;
    const std::filesystem::path output = dir.path() / "output.exr";
    std::vector<std::string> argv;
    std::string who;
    if (options_.command.empty()) {
        exportPovray(scene_, env, options_.povray, seed, dir.path());
        argv.push_back(options_.program);
        for (std::string& a :
             povrayArguments(scene_, options_.povray, "scene.pov", "output.exr", threads))
            argv.push_back(std::move(a));
        who = "POV-Ray";
    } else {
        const MitsubaExport m = exportMitsuba(scene_, env, dir.path());
        argv = expandCommand(options_.command, m.xml.string(), m.envmap.string(), output.string());
        who = "renderer command '" + options_.command + "'";
    }
    ProcessResult r = runProcess(argv, dir.path(), options_.timeoutSeconds);
    // POV-Ray 3.7 gives up when its render thread does not start within its own time limit
    // on a loaded machine ("Timed out waiting for worker thread startup"): a transient
    // failure, run again (at most twice).
    for (int retry = 0;
         retry < 2 && r.exitCode != 0 && !r.timedOut &&
         r.log.find("Timed out waiting for worker thread startup") != std::string::npos;
         ++retry)
        r = runProcess(argv, dir.path(), options_.timeoutSeconds);
    if (r.timedOut)
        throw std::runtime_error(who + " did not finish within " +
                                 formatNumber(options_.timeoutSeconds) +
                                 " s and was stopped; raise the timeout or lower the image "
                                 "size. Its log ends:\n" +
                                 r.log);
    if (r.exitCode != 0)
        throw std::runtime_error(who + " failed (exit " + std::to_string(r.exitCode) +
                                 "). Its log ends:\n" + r.log);
    if (!std::filesystem::exists(output))
        throw std::runtime_error(who + " wrote no image to " + output.filename().string() +
                                 ". Its log ends:\n" + r.log);
    Image img;
    try {
        img = readImage(output);
    } catch (const std::exception& e) {
        throw std::runtime_error(who + " wrote an unreadable image: " + e.what());
    }
    const int factor = options_.command.empty() ? std::max(1, options_.povray.supersample) : 1;
    if (img.width != width() * factor || img.height != height() * factor)
        throw std::runtime_error(who + " wrote a " + std::to_string(img.width) + "x" +
                                 std::to_string(img.height) + " image, expected " +
                                 std::to_string(width() * factor) + "x" +
                                 std::to_string(height() * factor));
    for (float v : img.data)
        if (!std::isfinite(v)) throw std::runtime_error(who + " wrote non-finite values");
    return povrayDownsample(img, factor);
}

ExternalRendererOptions externalRendererOptions(RendererKind kind,
                                                const ExternalRendererOptions& given) {
    if (kind == RendererKind::Builtin)
        throw std::invalid_argument("externalRendererOptions: the built-in tracer is not external");
    ExternalRendererOptions o = given;
    if (kind == RendererKind::Command && o.command.empty())
        throw inputError(option("renderer") + " command", "needs a command template",
                         "give " + option("renderer-cmd"));
    if (kind == RendererKind::Povray) o.command.clear();
    return o;
}

BasisTransportResult precomputeBasisToFile(const std::filesystem::path& sceneFile,
                                           const std::vector<std::string>& overrides,
                                           RendererKind kind,
                                           const ExternalRendererOptions& renderer,
                                           const BasisTransportOptions& options,
                                           const std::filesystem::path& out) {
    if (kind == RendererKind::Builtin)
        throw std::invalid_argument("precomputeBasisToFile: the built-in tracer traces T itself");
    const ExternalRendererOptions ro = externalRendererOptions(kind, renderer);
    const std::unique_ptr<Scene> scene = loadScene(sceneFile, overrides);
    const ExternalRenderer r(*scene, ro);
    BasisTransportResult res = basisTransport(*scene, r, options);
    writeTransportFile(out, res.file.matrix, res.file.provenance, /*result=*/true);
    return res;
}

std::pair<EnvMap, EnvMap> linearityPair(int width, int height, uint64_t seed) {
    Pcg32 rng(mix64(seed + 17), 0x11ea7ULL);
    std::pair<EnvMap, EnvMap> p{EnvMap::constant(width, height, 0.0f),
                                EnvMap::constant(width, height, 0.0f)};
    for (EnvMap* e : {&p.first, &p.second})
        for (float& t : e->texels)
            if (rng.nextFloat() < 0.5f) t = rng.nextFloat();
    return p;
}

BasisTransportResult basisTransport(const Scene& scene, const ExternalRenderer& renderer,
                                    const BasisTransportOptions& o) {
    const Stopwatch clock;
    BasisTransportResult res;
    RenderOptions ro = renderOptionsFor(scene);
    ro.seed = o.seed;
    ro.threads = o.threads;
    TransportProvenance prov = transportProvenance(scene, ro, 1);
    {
        nlohmann::json in = nlohmann::json::parse(prov.inputs);
        in["renderer"] = renderer.key();
        prov.inputs = in.dump();
        const std::string text = prov.fingerprint + "|" + renderer.key();
        prov.fingerprint = hexKey128(text);
    }
    const int ew = scene.basis.width(), eh = scene.basis.height();
    const size_t cols = static_cast<size_t>(ew) * eh;
    const size_t rows = static_cast<size_t>(renderer.width()) * renderer.height();

    {
        ProgressTask task(o.label + ": linearity check", 3);
        const auto [e1, e2] = linearityPair(ew, eh, o.seed);
        res.linearityError = linearityError(renderer, e1, e2, o.seed, o.threads);
        if (!(res.linearityError <= o.linearityTolerance))
            throw inputError("renderer '" + renderer.name() + "'",
                             "is not linear in the light: render(E1 + E2) differs from "
                             "render(E1) + render(E2) by " +
                                 formatNumber(100 * res.linearityError, 3) + " % (tolerance " +
                                 formatNumber(100 * o.linearityTolerance, 3) + " %)",
                             "turn off adaptive antialiasing and radiosity, tone mapping, gamma "
                             "and clamping; T from basis renders needs a linear renderer");
    }

    std::filesystem::path colDir;
    if (!o.cacheDir.empty()) {
        colDir = o.cacheDir / ("basis-" + prov.fingerprint);
        std::filesystem::create_directories(colDir);
    }
    auto colFile = [&](size_t t) { return colDir / ("column-" + std::to_string(t) + ".f32"); };
    std::vector<std::vector<float>> columns(cols);
    std::vector<size_t> todo;
    for (size_t t = 0; t < cols; ++t) {
        if (!colDir.empty() && std::filesystem::exists(colFile(t)) &&
            std::filesystem::file_size(colFile(t)) == rows * sizeof(float)) {
            columns[t].resize(rows);
            std::ifstream is(colFile(t), std::ios::binary);
            is.read(reinterpret_cast<char*>(columns[t].data()),
                    static_cast<std::streamsize>(rows * sizeof(float)));
            if (is) {
                ++res.reused;
                continue;
            }
        }
        todo.push_back(t);
    }
    ProgressTask task(o.label + " (" + std::to_string(renderer.width()) + "x" +
                          std::to_string(renderer.height()) + " px, " + renderer.name() + ")",
                      static_cast<double>(cols));
    task.set(static_cast<double>(res.reused));
    std::atomic<long> done{res.reused};
    std::atomic<size_t> next{0};
    std::exception_ptr error;
    std::mutex errorMutex;
    auto work = [&] {
        for (size_t k; (k = next++) < todo.size();) {
            try {
                throwIfInterrupted();  // the finished columns stay in the cache: a rerun resumes
                const size_t t = todo[k];
                EnvMap e = EnvMap::constant(ew, eh, 0.0f);
                e.texels[t] = 1.0f;
                const Image img = renderer.render(e, o.seed, 1);
                std::vector<float> y(rows);
                for (size_t p = 0; p < rows; ++p) {
                    const float* c = img.data.data() + p * img.channels;
                    y[p] = static_cast<float>(luminance<double>(c[0], c[1], c[2]));
                }
                if (!colDir.empty())
                    writeBytesAtomically(colFile(t), y.data(), y.size() * sizeof(float));
                columns[t] = std::move(y);
                task.set(static_cast<double>(++done));
            } catch (...) {
                std::lock_guard lock(errorMutex);
                if (!error) error = std::current_exception();
                next = todo.size();
            }
        }
    };
    const size_t workers = std::min(
        todo.size(),
        static_cast<size_t>(o.threads > 0 ? o.threads : concurrentRenders(renderer.options())));
    std::vector<std::thread> pool;
    for (size_t k = 1; k < workers; ++k) pool.emplace_back(work);
    work();
    for (std::thread& t : pool) t.join();
    if (error) std::rethrow_exception(error);
    res.rendered = static_cast<int>(todo.size());

    TransportMatrix& T = res.file.matrix;
    T.width = renderer.width();
    T.height = renderer.height();
    T.envWidth = ew;
    T.envHeight = eh;
    T.channels = 1;
    T.planes = 1;
    T.storage = TransportStorage::Dense;
    T.values.assign(rows * cols, 0.0f);
    for (size_t t = 0; t < cols; ++t)
        for (size_t p = 0; p < rows; ++p) T.values[p * cols + t] = columns[t][p];
    T.objectMask = objectMaskFor(scene, ro);
    chooseStorage(T);
    {
        const EnvMap e = linearityPair(ew, eh, o.seed + 1).first;
        const Image img = renderer.render(e, o.seed, 0);
        const std::vector<double> E(e.texels.begin(), e.texels.end());
        std::vector<double> Y(rows);
        T.applyLuminance(E, Y);
        double num = 0, den = 0;
        for (size_t p = 0; p < rows; ++p) {
            const float* c = img.data.data() + p * img.channels;
            const double y = luminance<double>(c[0], c[1], c[2]);
            num += (Y[p] - y) * (Y[p] - y);
            den += y * y;
        }
        res.directError = den > 0 ? std::sqrt(num / den) : 0.0;
    }
    res.file.provenance = prov;
    res.seconds = clock.seconds();
    return res;
}

}  // namespace sl
