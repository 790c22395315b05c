// The OpenImageIO module (io/ImageCodec.h): the only file that includes OpenImageIO's headers
// apart from app/host/Version.cpp's version string. Built as libscratchlight-oiio.so (CMakeLists.txt),
// loaded by imageCodec() when a file needs it; nothing else of this program is linked into it.
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <memory>
#include <string>
#include <utility>

#include "io/ImageCodec.h"

namespace sl::detail {

namespace {

PixelType fromTypeDesc(OIIO::TypeDesc t) {
    if (t == OIIO::TypeDesc::UNKNOWN) return PixelType::Unknown;
    if (t == OIIO::TypeDesc::UINT8) return PixelType::UInt8;
    if (t == OIIO::TypeDesc::UINT16) return PixelType::UInt16;
    if (t == OIIO::TypeDesc::HALF) return PixelType::Half;
    if (t == OIIO::TypeDesc::FLOAT) return PixelType::Float;
    if (t == OIIO::TypeDesc::DOUBLE) return PixelType::Double;
    return PixelType::Other;
}

OIIO::TypeDesc toTypeDesc(PixelType t) {
    switch (t) {
        case PixelType::UInt8:
            return OIIO::TypeDesc::UINT8;
        case PixelType::UInt16:
            return OIIO::TypeDesc::UINT16;
        case PixelType::Half:
            return OIIO::TypeDesc::HALF;
        case PixelType::Float:
            return OIIO::TypeDesc::FLOAT;
        case PixelType::Double:
            return OIIO::TypeDesc::DOUBLE;
        default:
            return OIIO::TypeDesc::UNKNOWN;
    }
}

class OiioReader final : public ImageReader {
  public:
    explicit OiioReader(std::unique_ptr<OIIO::ImageInput> in) : in_(std::move(in)) {}
    std::string formatName() const override { return in_->format_name(); }

    bool open(const std::string& path) override {
        OIIO::ImageSpec spec;
        if (!in_->open(path, spec)) {
            error_ = in_->geterror();
            if (error_.empty()) error_ = OIIO::geterror();
            return false;
        }
        const OIIO::ImageSpec& s = in_->spec();
        header_.x = s.x;
        header_.y = s.y;
        header_.z = s.z;
        header_.width = s.width;
        header_.height = s.height;
        header_.depth = s.depth;
        header_.nchannels = s.nchannels;
        header_.alphaChannel = s.alpha_channel;
        header_.deep = s.deep;
        header_.format = fromTypeDesc(s.format);
        header_.formatText = s.format.c_str();
        header_.perChannelFormats = !s.channelformats.empty();
        header_.tileWidth = s.tile_width;
        header_.tileHeight = s.tile_height;
        header_.tileDepth = s.tile_depth;
        header_.rowsPerStrip = s.get_int_attribute("tiff:RowsPerStrip", 0);
        header_.colorSpace = s.get_string_attribute("oiio:ColorSpace");
        header_.gamma = s.get_float_attribute("oiio:Gamma", 0.0f);
        header_.nativePixelBytes = s.pixel_bytes(/*native=*/true);
        return true;
    }

    const ImageHeader& header() const override { return header_; }

    bool readNative(int y0, int y1, void* native) override {
        const OIIO::ImageSpec& s = in_->spec();
        const int nch = s.nchannels;
        const bool ok = s.tile_width > 0
                            ? in_->read_tiles(0, 0, s.x, s.x + s.width, s.y + y0, s.y + y1, s.z,
                                              s.z + 1, 0, nch, OIIO::TypeDesc::UNKNOWN, native)
                            : in_->read_scanlines(0, 0, s.y + y0, s.y + y1, s.z, 0, nch,
                                                  OIIO::TypeDesc::UNKNOWN, native);
        // Its read_image() of a truncated strip TIFF returns true with rows left at 0; only
        // has_error() says that rows are missing (io/ImageFile.h).
        if (ok && !in_->has_error()) return true;
        error_ = in_->geterror();
        if (error_.empty()) error_ = "no reason given";
        return false;
    }

    bool convert(const void* native, size_t pixels, PixelType type, void* out) const override {
        const OIIO::ImageSpec& s = in_->spec();
        const OIIO::TypeDesc to = toTypeDesc(type);
        const int nch = s.nchannels;
        if (s.channelformats.empty())
            return OIIO::convert_pixel_values(s.format, native, to, out,
                                              static_cast<int>(pixels * size_t(nch)));
        // Per-channel formats (OpenEXR): one channel at a time.
        const size_t nativePixel = s.pixel_bytes(true), outPixel = to.size() * size_t(nch);
        const int rows = static_cast<int>(pixels / static_cast<size_t>(std::max(s.width, 1)));
        size_t offset = 0;
        for (int c = 0; c < nch; ++c) {
            const OIIO::TypeDesc cf = s.channelformats[static_cast<size_t>(c)];
            if (!OIIO::convert_image(
                    1, s.width, rows, 1, static_cast<const unsigned char*>(native) + offset, cf,
                    static_cast<OIIO::stride_t>(nativePixel), OIIO::AutoStride, OIIO::AutoStride,
                    static_cast<unsigned char*>(out) + size_t(c) * to.size(), to,
                    static_cast<OIIO::stride_t>(outPixel), OIIO::AutoStride, OIIO::AutoStride))
                return false;
            offset += cf.size();
        }
        return true;
    }

    std::string error() override { return std::exchange(error_, std::string()); }
    void close() override { in_->close(); }

  private:
    std::unique_ptr<OIIO::ImageInput> in_;
    ImageHeader header_;
    std::string error_;
};

std::unique_ptr<ImageReader> createReader(const std::string& extension, std::string* error) {
    // create() with a bare extension makes that format's reader without touching the file.
    auto in = OIIO::ImageInput::create(extension);
    if (!in) {
        const std::string e = OIIO::geterror();  // OIIO keeps the message otherwise
        if (error) *error = e;
        return nullptr;
    }
    return std::make_unique<OiioReader>(std::move(in));
}

const ImageCodec kCodec{kImageCodecVersion, &createReader};

}  // namespace

}  // namespace sl::detail

extern "C" __attribute__((visibility("default"))) const sl::detail::ImageCodec*
sl_image_codec_v1() {
    return &sl::detail::kCodec;
}
