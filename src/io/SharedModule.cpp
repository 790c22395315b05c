#include "io/SharedModule.h"

#include <dlfcn.h>

#include <filesystem>
#include <system_error>
#include <vector>

namespace sl::detail {

namespace fs = std::filesystem;

namespace {

std::vector<fs::path> moduleCandidates(const std::string& fileName) {
    std::vector<fs::path> out;
    std::error_code ec;
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    if (!ec && exe.has_parent_path()) {
        out.push_back(exe.parent_path() / fileName);
        out.push_back(exe.parent_path().parent_path() / "lib" / "scratchlight" / fileName);
    }
#ifdef SL_MODULE_BUILD_DIR
    out.push_back(fs::path(SL_MODULE_BUILD_DIR) / fileName);
#endif
    return out;
}

}  // namespace

void* openModuleEntry(const std::string& fileName, const char* entry, bool global,
                      std::string* problem) {
    std::string tried;
    for (const fs::path& p : moduleCandidates(fileName)) {
        std::error_code ec;
        if (!fs::is_regular_file(p, ec)) {
            tried += (tried.empty() ? "" : ", ") + p.string();
            continue;
        }
        void* h = dlopen(p.c_str(), RTLD_NOW | (global ? RTLD_GLOBAL : RTLD_LOCAL));
        if (!h) {
            const char* e = dlerror();
            *problem = p.string() + " could not be loaded (" + (e ? e : "no reason given") + ")";
            return nullptr;
        }
        void* f = dlsym(h, entry);
        if (!f) *problem = p.string() + " is not scratchlight's module " + fileName;
        return f;
    }
    *problem = fileName + " was not found (looked for " + tried + ")";
    return nullptr;
}

}  // namespace sl::detail
