// GwyddionModule: the door between io/GwyddionReader.cpp and Gwyddion, opened on first use.
// Gwyddion's libraries pull in GTK 2 and its GL stack (some 40 shared libraries beside the
// program's own), whose loading and relocation at start-up doubled the dynamic loader's work on
// every run (LD_DEBUG=statistics on an empty program linked as the binary was: 74 M cycles with
// them, 37 M without), also the runs that read no instrument file. So the program does not
// link them: io/GwyddionModule.cpp, the only file that includes Gwyddion's headers, is built as
// libscratchlight-gwyddion.so beside the executable (installed in lib/scratchlight) and loaded
// by io/GwyddionReader.cpp (io/SharedModule.h) the first time a file needs Gwyddion.
//
// The interface is C++ (both sides are built together, same compiler and standard library).
// Errors are returned as text, never thrown across the door; GwyddionReader turns them into
// InputErrors.
#pragma once

#include <string>
#include <vector>

#include "io/GwyChannel.h"
#include "io/HeightmapData.h"

namespace sl::detail {

/// What went wrong, as inputError(where, problem, fix) says it (where empty: the file).
struct GwyddionProblem {
    std::string where, problem, fix;
};

inline constexpr int kGwyddionModuleVersion = 3;

/// The module's entry points (kGwyddionModuleVersion: both sides must agree). Each returns
/// false with *problem set when it fails. Gwyddion is initialised on the first call; every
/// call holds the module's one lock (Gwyddion is not thread-safe).
struct GwyddionModule {
    int version = kGwyddionModuleVersion;
    /// The file module that claims `file` by its content and name ("" when none does).
    bool (*detect)(const std::string& file, std::string* module, GwyddionProblem* problem);
    /// The file's height channel, or the one `channel` names (io/GwyddionReader.h readGwyddion).
    bool (*read)(const std::string& file, const std::string& channel, HeightmapData* out,
                 GwyddionProblem* problem);
    /// W×H channels (row 0 first) of square pitch pitchMm as a .gwy file at `path`.
    bool (*writeGwy)(const std::string& path, int width, int height,
                     const std::vector<GwyChannel>& channels, double pitchMm,
                     GwyddionProblem* problem);
};

}  // namespace sl::detail

/// The module's one exported symbol (io/GwyddionModule.cpp).
extern "C" const sl::detail::GwyddionModule* sl_gwyddion_module_v1();
