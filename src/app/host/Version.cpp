#include "app/host/Version.h"

#include <OpenEXR/OpenEXRConfig.h>
#include <OpenImageIO/oiioversion.h>
#include <ceres/version.h>
#include <embree3/rtcore_config.h>
#include <nlopt.h>
#include <oneapi/tbb/version.h>

#include <Eigen/Core>
#include <ctime>

#include "Commit.inc"  // SL_COMMIT, written by scripts/commit.cmake
#include "app/host/Mpi.h"

namespace sl {

const VersionInfo& versionInfo() {
    static const VersionInfo v = [] {
        VersionInfo i;
        i.version = SL_VERSION;
        i.commit = SL_COMMIT;
        i.embree = RTC_VERSION_STRING;
        i.openimageio = OIIO_VERSION_STRING;
        i.openexr = OPENEXR_VERSION_STRING;
        int major = 0, minor = 0, bugfix = 0;
        nlopt_version(&major, &minor, &bugfix);
        i.nlopt =
            std::to_string(major) + "." + std::to_string(minor) + "." + std::to_string(bugfix);
        i.ceres = CERES_VERSION_STRING;
        i.eigen = std::to_string(EIGEN_WORLD_VERSION) + "." + std::to_string(EIGEN_MAJOR_VERSION) +
                  "." + std::to_string(EIGEN_MINOR_VERSION);
        i.tbb = std::to_string(TBB_VERSION_MAJOR) + "." + std::to_string(TBB_VERSION_MINOR);
        return i;
    }();
    return v;
}

std::string versionText() {
    const VersionInfo& v = versionInfo();
    std::string t = "scratchlight ";
    t += v.version;
    t += " (commit ";
    t += v.commit;
    t += ")\n";
    const std::pair<const char*, const std::string*> libs[] = {
        {"Embree", &v.embree},   {"OpenImageIO", &v.openimageio},
        {"OpenEXR", &v.openexr}, {"NLopt", &v.nlopt},
        {"Ceres", &v.ceres},     {"Eigen", &v.eigen},
        {"oneTBB", &v.tbb}};
    for (const auto& [name, ver] : libs) {
        t += "  ";
        t += name;
        t += " ";
        t += *ver;
        t += "\n";
    }
    // MPI is optional (app/host/Mpi.h): optimize over MPI ranks.
    t += "  MPI ";
    t += mpiBuilt() ? mpiLibraryVersion() : std::string("not built (optimize runs as one process)");
    t += "\n";
    t.pop_back();  // the caller ends the line
    return t;
}

nlohmann::json runProvenance(const std::string& commandLine) {
    const VersionInfo& v = versionInfo();
    const std::time_t now = std::time(nullptr);
    std::tm utc{};
    gmtime_r(&now, &utc);
    char date[32];
    std::strftime(date, sizeof date, "%Y-%m-%dT%H:%M:%SZ", &utc);
    return {{"version", v.version}, {"commit", v.commit}, {"command", commandLine}, {"date", date}};
}

}  // namespace sl
