#include "io/ImageCodec.h"

#include <atomic>
#include <mutex>
#include <string>

#include "core/Error.h"
#include "io/SharedModule.h"

namespace sl::detail {

namespace {

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
    s.codec =
        openModule<ImageCodec>("libscratchlight-oiio.so", "sl_image_codec_v1",
                               /*global=*/false, kImageCodecVersion, "OpenImageIO", &s.problem);
#endif
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
