#include "io/ExrReader.h"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfPartType.h>
#include <OpenEXR/ImfTileDescription.h>

#include <array>
#include <cstring>
#include <exception>
#include <string>
#include <utility>
#include <vector>

namespace sl::detail {

namespace {

class ExrReader final : public ImageReader {
  public:
    std::string formatName() const override { return "openexr"; }

    bool open(const std::string& path) override {
        try {
            file_ = std::make_unique<Imf::InputFile>(path.c_str());
            const Imf::Header& h = file_->header();
            if (h.hasType() && h.type() != Imf::SCANLINEIMAGE && h.type() != Imf::TILEDIMAGE)
                return false;  // deep
            if (h.find("oiio:ColorSpace") != h.end() || h.find("oiio:Gamma") != h.end())
                return false;
            std::vector<std::string> names;
            Imf::PixelType type = Imf::NUM_PIXELTYPES;
            for (auto c = h.channels().begin(); c != h.channels().end(); ++c) {
                if (c.channel().xSampling != 1 || c.channel().ySampling != 1) return false;
                if (c.channel().type != Imf::HALF && c.channel().type != Imf::FLOAT) return false;
                if (type != Imf::NUM_PIXELTYPES && c.channel().type != type) return false;
                type = c.channel().type;
                names.emplace_back(c.name());
            }
            // OpenEXR lists channels alphabetically; OpenImageIO puts R, G, B, A first.
            if (names.size() == 1) {
                const std::string& n = names[0];
                if (n == "A" || n == "a" || n == "alpha" || n == "Alpha") return false;
                channels_ = names;
            } else if (names == std::vector<std::string>{"B", "G", "R"}) {
                channels_ = {"R", "G", "B"};
            } else if (names == std::vector<std::string>{"A", "B", "G", "R"}) {
                channels_ = {"R", "G", "B", "A"};
                header_.alphaChannel = 3;
            } else {
                return false;
            }
            const Imath::Box2i dw = h.dataWindow();
            window_ = dw;
            header_.x = dw.min.x;
            header_.y = dw.min.y;
            header_.width = dw.max.x - dw.min.x + 1;
            header_.height = dw.max.y - dw.min.y + 1;
            header_.nchannels = static_cast<int>(channels_.size());
            header_.format = type == Imf::HALF ? PixelType::Half : PixelType::Float;
            header_.formatText = type == Imf::HALF ? "half" : "float";
            if (h.hasTileDescription()) {
                header_.tileWidth = static_cast<int>(h.tileDescription().xSize);
                header_.tileHeight = static_cast<int>(h.tileDescription().ySize);
                header_.tileDepth = 1;
            }
            header_.nativePixelBytes = sizeof(float) * channels_.size();
            return header_.width > 0 && header_.height > 0;
        } catch (const std::exception&) {
            return false;  // OpenImageIO then reads it, or says why not
        }
    }

    const ImageHeader& header() const override { return header_; }

    bool readNative(int y0, int y1, void* native) override {
        try {
            const size_t xs = header_.nativePixelBytes;
            const size_t ys = xs * static_cast<size_t>(header_.width);
            Imath::Box2i band = window_;
            band.min.y = window_.min.y + y0;
            band.max.y = window_.min.y + y1 - 1;
            Imf::FrameBuffer fb;
            for (size_t c = 0; c < channels_.size(); ++c)
                fb.insert(channels_[c],
                          Imf::Slice::Make(Imf::FLOAT,
                                           static_cast<unsigned char*>(native) + c * sizeof(float),
                                           band, xs, ys));
            file_->setFrameBuffer(fb);
            file_->readPixels(band.min.y, band.max.y);
            return true;
        } catch (const std::exception& e) {
            error_ = e.what();
            return false;
        }
    }

    bool convert(const void* native, size_t pixels, PixelType type, void* out) const override {
        if (type != PixelType::Float) return false;
        std::memcpy(out, native, pixels * header_.nativePixelBytes);
        return true;
    }

    std::string error() override { return std::exchange(error_, std::string()); }
    void close() override { file_.reset(); }

  private:
    std::unique_ptr<Imf::InputFile> file_;
    std::vector<std::string> channels_;
    Imath::Box2i window_;
    ImageHeader header_;
    std::string error_;
};

}  // namespace

std::unique_ptr<ImageReader> openExrDirect(const std::string& path) {
    auto r = std::make_unique<ExrReader>();
    if (!r->open(path)) return nullptr;
    return r;
}

}  // namespace sl::detail
