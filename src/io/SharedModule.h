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

}  // namespace sl::detail
