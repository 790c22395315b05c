// External renderers behind render/Renderer.h: POV-Ray 3.7 (the scene of io/PovrayExport.h)
// and any command line given as a template, and T from their basis renders.
//
// A RENDER: a fresh temporary directory (under $TMPDIR), the scene's files written into it, the
// program run there (argument vector, no shell; stdout/stderr kept in render.log) with a
// timeout, its output read back through OpenImageIO (io/ImageIO.h), checked (size, finite
// values) and the directory removed. A missing program, a non-zero exit, a timeout, a missing
// or wrong-sized or non-finite output: a clear error naming the program, with the end of its
// log.
//
//   povray    io/PovrayExport.h's scene.pov + heightfield.png + envmap.exr, run as
//             `povray +Iscene.pov +Ooutput.exr ...` (povrayArguments) and box-filtered from
//             supersample × the camera's size.
//   command   a template such as "mitsuba -m scalar_rgb {scene} -o {output}": split into words
//             at white space ('…' and "…" group), each of {scene}, {envmap}, {output} replaced
//             by the path of the Mitsuba 3 export's scene.xml (io/MitsubaExport.h, which also
//             writes heightfield.ply and envmap.exr, the latter {envmap}) and of output.exr. The
//             command must write the camera's width × height into {output} (any format OIIO
//             reads, linear).
//
// T FROM BASIS RENDERS: with E = e_t (texel t = 1, every other 0), our bilinear lookup IS
// texel t's basis function (scene/EnvMapBasis.h), so a renderer linear in the light renders
// column t of T: I = Σ_t E_t·render(e_t). basisTransport renders the 1250 columns in parallel
// (concurrentRenders at once, each with one thread), keeps each finished column in the cache
// folder (basis-<fingerprint>/, so an interrupted run resumes) and assembles a gray T (the
// luminance of each render) with the object mask of our tracer's trace (the same camera). It
// first checks linearity: linearityError(E1, E2) on two random sparse maps, refused with a
// message when above the tolerance (adaptive antialiasing or radiosity, tone mapping, gamma,
// clamping are what break it).
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "io/PovrayExport.h"
#include "io/TransportFile.h"
#include "render/Renderer.h"

namespace sl {

struct Scene;

/// Which renderer a command renders with (`--renderer`; `--renderer-cmd` implies `command`).
enum class RendererKind { Builtin, Povray, Command };
struct RendererKindRow {
    RendererKind value;
    const char* name;
    const char* help;
};
std::span<const RendererKindRow> rendererKindTable();

struct ExternalRendererOptions {
    std::string program = "povray";  // the POV-Ray executable (PATH lookup)
    std::string command;             // a template (see the header comment); empty: POV-Ray
    PovraySettings povray;
    double timeoutSeconds = 600;  // per render
    /// Renders at once in basis renders and black-box gradients (0: 4 × the cores: POV-Ray's
    /// front end idles in 50 ms sleeps, so one 16² render takes 0.66 s of wall time and
    /// little CPU; 16 at once took 0.86 s on 2 cores).
    int concurrentRenders = 0;
};

/// The options of the external renderer `kind` from what was given: POV-Ray ignores a command
/// template; `command` without one is an InputError naming the option. Not for Builtin.
ExternalRendererOptions externalRendererOptions(RendererKind kind,
                                                const ExternalRendererOptions& given);

/// The renders at once `options` asks for (0 resolved).
int concurrentRenders(const ExternalRendererOptions& options);

class ExternalRenderer final : public Renderer {
  public:
    /// Keeps a reference to `scene`. Throws InputError when the program is not found.
    ExternalRenderer(const Scene& scene, ExternalRendererOptions options);
    std::string name() const override { return options_.command.empty() ? "povray" : "command"; }
    Image render(const EnvMap& env, uint64_t seed, int threads) const override;
    bool seeded() const override;
    int width() const override;
    int height() const override;
    /// What determines its renders besides the scene and E (for fingerprints).
    std::string key() const;
    const ExternalRendererOptions& options() const { return options_; }

  private:
    const Scene& scene_;
    ExternalRendererOptions options_;
};

/// The words of a command template with {scene}, {envmap}, {output} replaced.
std::vector<std::string> expandCommand(const std::string& templ, const std::string& scene,
                                       const std::string& envmap, const std::string& output);

struct ProcessResult {
    int exitCode = -1;      // the exit status (-1: killed by a signal or not started)
    bool timedOut = false;  // killed after the timeout
    std::string log;        // the end of its stdout + stderr
};

/// Runs argv in `dir` (stdout and stderr into dir/render.log) and waits at most timeoutSeconds.
/// The program runs in its own process group, and the group is what is signalled: on the
/// timeout (SIGKILL), on an interrupt request (core/Interrupt.h: SIGTERM, SIGKILL after 2 s;
/// then Interrupted is thrown) and when the program ends (SIGKILL to what it left running), so
/// nothing it started outlives the call. Throws InputError when argv[0] cannot be started.
ProcessResult runProcess(const std::vector<std::string>& argv, const std::filesystem::path& dir,
                         double timeoutSeconds);

struct BasisTransportOptions {
    int threads = 0;                   // renders at once (0: all cores)
    std::filesystem::path cacheDir;    // where finished columns are kept (empty: not kept)
    double linearityTolerance = 0.01;  // refuse above this linearityError
    uint64_t seed = 0;                 // the renders' seed
    std::string label = "basis renders";
};

struct BasisTransportResult {
    TransportFile file;
    double linearityError = 0;
    /// ‖T·E − render(E)‖/‖render(E)‖ for a random E (linearityPair's first map), rendered
    /// directly after T is built: the check that T reproduces the renderer.
    double directError = 0;
    int rendered = 0, reused = 0;  // columns rendered now, read from the cache
    double seconds = 0;
};

/// T of `renderer` (gray) from its basis renders (see the header comment).
BasisTransportResult basisTransport(const Scene& scene, const ExternalRenderer& renderer,
                                    const BasisTransportOptions& options);

/// Loads the scene file (with -D overrides), builds T from basis renders with the renderer
/// `kind` (Povray or Command) and writes it to `out` (.tm, atomic).
BasisTransportResult precomputeBasisToFile(const std::filesystem::path& sceneFile,
                                           const std::vector<std::string>& overrides,
                                           RendererKind kind,
                                           const ExternalRendererOptions& renderer,
                                           const BasisTransportOptions& options,
                                           const std::filesystem::path& out);

/// Two random sparse env maps on the scene's grid (for linearity checks): each texel lit with
/// probability 0.5, values in [0, 1), from `seed`.
std::pair<EnvMap, EnvMap> linearityPair(int width, int height, uint64_t seed);

}  // namespace sl
