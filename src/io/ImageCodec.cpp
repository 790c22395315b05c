#include "io/ImageCodec.h"

#include <dlfcn.h>

#include <atomic>
#include <filesystem>
#include <mutex>
#include <string>
#include <system_error>
#include <vector>

#include "core/Error.h"

namespace sl::detail {

namespace fs = std::filesystem;

namespace {

#ifndef SL_IMAGE_CODEC_LINKED
constexpr const char* kModuleName = "libscratchlight-oiio.so";

/// Where the module may be: beside the executable (the build tree), the installed
/// <prefix>/lib/scratchlight, then the build tree this was compiled in.
std::vector<fs::path> moduleCandidates() {
    std::vector<fs::path> out;
    std::error_code ec;
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    if (!ec && exe.has_parent_path()) {
        out.push_back(exe.parent_path() / kModuleName);
        out.push_back(exe.parent_path().parent_path() / "lib" / "scratchlight" / kModuleName);
    }
#ifdef SL_IMAGE_CODEC_BUILD_DIR
    out.push_back(fs::path(SL_IMAGE_CODEC_BUILD_DIR) / kModuleName);
#endif
    return out;
}
#endif

struct Loaded {
    std::once_flag once;
    const ImageCodec* codec = nullptr;
    std::string problem;  // why it could not be loaded
    std::atomic<bool> loaded{false};
};

Loaded& state() {
    static Loaded s;
    return s;
}

void load(Loaded& s) {
#ifdef SL_IMAGE_CODEC_LINKED  // linked into this program (the fuzz targets)
    s.codec = sl_image_codec_v1();
#else
    std::string tried;
    for (const fs::path& p : moduleCandidates()) {
        std::error_code ec;
        if (!fs::is_regular_file(p, ec)) {
            tried += (tried.empty() ? "" : ", ") + p.string();
            continue;
        }
        void* h = dlopen(p.c_str(), RTLD_NOW | RTLD_LOCAL);
        if (!h) {
            const char* e = dlerror();
            s.problem = "cannot load " + p.string() + " (" + (e ? e : "no reason given") + ")";
            return;
        }
        using Entry = const ImageCodec* (*)();
        auto entry = reinterpret_cast<Entry>(dlsym(h, "sl_image_codec_v1"));
        if (!entry) {
            s.problem = p.string() + " is not scratchlight's OpenImageIO module";
            return;
        }
        s.codec = entry();
        break;
    }
    if (!s.codec && s.problem.empty())
        s.problem = std::string("the OpenImageIO module ") + kModuleName +
                    " was not found (looked for " + tried + ")";
#endif
    if (s.codec && s.codec->version != kImageCodecVersion) {
        s.problem = "the OpenImageIO module is of another version of scratchlight";
        s.codec = nullptr;
    }
    s.loaded = s.codec != nullptr;
}

}  // namespace

size_t pixelTypeSize(PixelType t) {
    switch (t) {
        case PixelType::UInt8:
            return 1;
        case PixelType::UInt16:
        case PixelType::Half:
            return 2;
        case PixelType::Float:
            return 4;
        case PixelType::Double:
            return 8;
        default:
            return 0;
    }
}

const ImageCodec& imageCodec(const std::string& what) {
    Loaded& s = state();
    std::call_once(s.once, [&] { load(s); });
    if (!s.codec)
        throw inputError(what, "needs OpenImageIO to be read, and " + s.problem,
                         "Install scratchlight with its lib/scratchlight folder, or convert the "
                         "file to an EXR of float channels");
    return *s.codec;
}

bool imageCodecLoaded() {
    return state().loaded;
}

}  // namespace sl::detail
