// SharedModule: how this program opens one of its own modules, the shared objects built beside
// the executable that hold what only some files need (io/ImageCodec.h: OpenImageIO;
// io/GwyddionModule.h: Gwyddion's file modules). A library linked at start is loaded and
// relocated on every run, needed or not; a module costs nothing until a file asks for it.
#pragma once

#include <string>

namespace sl::detail {

/// Loads the module `fileName` (e.g. "libscratchlight-oiio.so") from beside the executable (the
/// build tree), the installed <prefix>/lib/scratchlight, then the build tree this was compiled
/// in, and returns its entry point `entry`; null with *problem saying why (not found: the places
/// looked in; not loadable: dlerror's reason; no entry: not ours). `global`: its symbols and its
/// libraries' are made available to what is loaded after it (RTLD_GLOBAL: Gwyddion's file
/// modules, opened by Gwyddion itself, name its libraries' symbols without linking them).
void* openModuleEntry(const std::string& fileName, const char* entry, bool global,
                      std::string* problem);

/// The module `fileName` whose entry `entry` returns its table `const M*` (a struct with an
/// `int version`): openModuleEntry, then the table, which must be of `version` (both sides are
/// built together); null with *problem saying why ("its module could not be opened: …", or "the
/// <what> module is of another version of scratchlight").
template <typename M>
const M* openModule(const std::string& fileName, const char* entry, bool global, int version,
                    const std::string& what, std::string* problem) {
    using Entry = const M* (*)();
    const auto open = reinterpret_cast<Entry>(openModuleEntry(fileName, entry, global, problem));
    if (!open) {
        *problem = "its module could not be opened: " + *problem;
        return nullptr;
    }
    const M* module = open();
    if (module && module->version == version) return module;
    *problem = "the " + what + " module is of another version of scratchlight";
    return nullptr;
}

}  // namespace sl::detail
