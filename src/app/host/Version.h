// What build of scratchlight this is, and of the libraries it was built with: `scratchlight
// --version` prints it and every summary.json records it.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace sl {

struct VersionInfo {
    std::string version;  // the project's VERSION (CMakeLists.txt)
    std::string commit;   // git describe --always --dirty of the source tree at build time
    std::string embree, openimageio, openexr, nlopt, ceres, eigen, tbb;  // "major.minor.patch"
};

const VersionInfo& versionInfo();

/// "scratchlight 0.1.0 (commit …)" and one line per library.
std::string versionText();

/// {"version", "commit", "command", "date"}: what every summary records of the run that wrote
/// it. `commandLine` is how the run was asked for (recorded, never parsed); the date is UTC, ISO
/// 8601, to the second.
nlohmann::json runProvenance(const std::string& commandLine);

}  // namespace sl
