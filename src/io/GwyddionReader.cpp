#include "io/GwyddionReader.h"

#include <algorithm>
#include <mutex>
#include <string>

#include "core/Error.h"
#include "io/AtomicFile.h"
#if SL_HAVE_GWYDDION
#include "io/GwyddionModule.h"
#include "io/SharedModule.h"
#endif

namespace sl {

namespace fs = std::filesystem;

#if SL_HAVE_GWYDDION

namespace {

/// The Gwyddion module (io/GwyddionModule.h), loaded on the first call (thread-safe); throws
/// InputError naming `what` when it cannot be.
const detail::GwyddionModule& gwyddion(const std::string& what) {
    static std::once_flag once;
    static const detail::GwyddionModule* module = nullptr;
    static std::string problem;
    std::call_once(once, [] {
        // global: Gwyddion's file modules, which it opens itself, use its libraries' symbols
        // without linking them.
        module = detail::openModule<detail::GwyddionModule>(
            "libscratchlight-gwyddion.so", "sl_gwyddion_module_v1", /*global=*/true,
            detail::kGwyddionModuleVersion, "Gwyddion", &problem);
    });
    if (!module)
        throw inputError(what, "needs Gwyddion to be read, and " + problem,
                         "Install scratchlight with its lib/scratchlight folder, or export the "
                         "measurement as X3P, SDF or EXR");
    return *module;
}

[[noreturn]] void fail(const std::string& where, const detail::GwyddionProblem& p) {
    throw inputError(p.where.empty() ? where : p.where, p.problem, p.fix);
}

}  // namespace

bool gwyddionBuilt() {
    return true;
}

std::string gwyddionDetect(const fs::path& file) {
    std::string module;
    detail::GwyddionProblem problem;
    if (!gwyddion(file.string()).detect(file.string(), &module, &problem))
        fail(file.string(), problem);
    return module;
}

HeightmapData readGwyddion(const fs::path& file, const std::string& channel) {
    HeightmapData d;
    detail::GwyddionProblem problem;
    if (!gwyddion(file.string()).read(file.string(), channel, &d, &problem))
        fail(file.string(), problem);
    return d;
}

void writeGwy(const fs::path& file, int width, int height, const std::vector<float>& heightsMm,
              double pitchMm) {
    writeGwy(file, width, height, std::vector<GwyChannel>{{"", "m", heightsMm}}, pitchMm);
}

void writeGwy(const fs::path& file, int width, int height, const std::vector<GwyChannel>& channels,
              double pitchMm) {
    const std::string where = file.string();
    const size_t n =
        static_cast<size_t>(std::max(width, 0)) * static_cast<size_t>(std::max(height, 0));
    const bool sized = std::all_of(channels.begin(), channels.end(),
                                   [&](const GwyChannel& c) { return c.values.size() == n; });
    if (width < 1 || height < 1 || channels.empty() || !sized || !(pitchMm > 0))
        throw inputError(where, "cannot write a .gwy file of " + std::to_string(channels.size()) +
                                    " channel(s) as " + std::to_string(width) + "x" +
                                    std::to_string(height) + " at pitch " +
                                    std::to_string(pitchMm));
    const detail::GwyddionModule& m = gwyddion(where);
    writeAtomically(file, [&](const fs::path& temp) {
        detail::GwyddionProblem problem;
        if (!m.writeGwy(temp.string(), width, height, channels, pitchMm, &problem))
            fail(where, problem);
    });
}

#else  // !SL_HAVE_GWYDDION

namespace {
[[noreturn]] void notBuilt(const fs::path& file) {
    throw inputError(file.string(),
                     "is not a height map this build reads (EXR, TIFF, PNG, .npy, X3P, SDF); "
                     "instrument formats need Gwyddion's file modules, and this binary was built "
                     "without them",
                     "Export the measurement as X3P, SDF or EXR, or build scratchlight with "
                     "-DSCRATCHLIGHT_GWYDDION=ON (scripts/install-deps installs Gwyddion)");
}
}  // namespace

bool gwyddionBuilt() {
    return false;
}
std::string gwyddionDetect(const fs::path&) {
    return "";
}
HeightmapData readGwyddion(const fs::path& file, const std::string&) {
    notBuilt(file);
}
void writeGwy(const fs::path& file, int, int, const std::vector<float>&, double) {
    notBuilt(file);
}
void writeGwy(const fs::path& file, int, int, const std::vector<GwyChannel>&, double) {
    notBuilt(file);
}

#endif

}  // namespace sl
