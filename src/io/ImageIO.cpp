#include "io/ImageIO.h"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfIO.h>
#include <OpenEXR/ImfOutputFile.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstring>
#include <limits>
#include <new>
#include <string>
#include <system_error>

#include "core/Color.h"
#include "core/Error.h"
#include "core/Text.h"
#include "io/AtomicFile.h"
#include "io/ImageFile.h"
#include "io/PngBuffer.h"

namespace sl {

namespace fs = std::filesystem;

namespace {

const char* const kImageFix =
    "Check that the file is a complete image in a format OpenImageIO reads (EXR, PNG, JPEG, "
    "TIFF, HDR, ...)";

enum class Transfer { Linear, Srgb, Gamma };

struct Encoding {
    Transfer transfer = Transfer::Linear;
    float gamma = 1.0f;
};

Encoding encodingOf(const detail::ImageHeader& spec, const std::string& formatName,
                    const std::string& where) {
    const std::string csName = spec.colorSpace;
    const std::string cs = lower(csName);
    Encoding e;
    if (cs.empty()) {
        const bool srgbFormat = formatName == "png" || formatName == "jpeg";
        e.transfer = (srgbFormat || spec.format == detail::PixelType::UInt8) ? Transfer::Srgb
                                                                             : Transfer::Linear;
        return e;
    }
    if (cs == "srgb" || cs == "srgb_texture" || cs == "srgb_rec709_scene") {
        e.transfer = Transfer::Srgb;
    } else if (cs == "linear" || cs == "scene_linear" || cs == "lin_srgb" || cs == "lin_rec709" ||
               cs == "lin_rec709_scene" || cs == "raw") {
        e.transfer = Transfer::Linear;
    } else if (cs.rfind("gamma", 0) == 0) {
        float g = spec.gamma;
        if (!(g > 0.0f)) {
            try {
                g = std::stof(cs.substr(5));
            } catch (...) {
                g = 0.0f;
            }
        }
        if (!(g > 0.0f) || !std::isfinite(g))
            throw inputError(where, "colour space '" + cs + "' without a usable gamma value",
                             "Save the image as linear EXR or as sRGB PNG");
        e.transfer = g == 1.0f ? Transfer::Linear : Transfer::Gamma;
        e.gamma = g;
    } else {
        throw inputError(
            where, "unsupported colour space '" + csName + "' (supported: linear, sRGB, gamma)",
            "Convert the image to linear Rec.709 EXR (or an sRGB PNG)");
    }
    return e;
}

float decode(const Encoding& e, float v) {
    switch (e.transfer) {
        case Transfer::Linear:
            return v;
        case Transfer::Srgb:
            return srgbDecode(v);
        case Transfer::Gamma:
            return v <= 0.0f ? v : std::pow(v, e.gamma);
    }
    return v;
}

// Normalisation v / max is written as float(v) / float(max) everywhere (so 128 in an 8-bit
// file reads as exactly srgbDecode(128.0f / 255.0f)).
template <typename T>
float normalized(T v) {
    return static_cast<float>(v) / static_cast<float>(std::numeric_limits<T>::max());
}

template <typename T>
std::vector<float> decodeTable(const Encoding& e) {
    constexpr size_t n = size_t(std::numeric_limits<T>::max()) + 1;
    std::vector<float> lut(n);
    for (size_t v = 0; v < n; ++v) lut[v] = decode(e, normalized(static_cast<T>(v)));
    return lut;
}

template <typename T>
void widenDecoded(Image& img, const Encoding& e, int alpha) {
    const int c = img.channels;
    if (e.transfer == Transfer::Linear) {
        detail::widenInPlace<T>(img.data.data(), img.data.size(),
                                [](T v, size_t) { return normalized(v); });
        return;
    }
    const std::vector<float> lut = decodeTable<T>(e);
    detail::widenInPlace<T>(img.data.data(), img.data.size(), [&](T v, size_t k) {
        return alpha >= 0 && static_cast<int>(k % c) == alpha ? normalized(v) : lut[v];
    });
}

// --- writing ---------------------------------------------------------------------------------

void requireExtension(const fs::path& file, const char* ext, const char* what) {
    if (lower(file.extension().string()) != ext)
        throw inputError(file.string(), std::string("a ") + what + " file name must end in " + ext,
                         std::string("Name the output file *") + ext);
}

void validateImage(const fs::path& file, const Image& img, std::initializer_list<int> channels) {
    const std::string where = file.string();
    if (img.width <= 0 || img.height <= 0)
        throw inputError(where, "cannot write an empty image (" + std::to_string(img.width) + "x" +
                                    std::to_string(img.height) + ")");
    if (std::find(channels.begin(), channels.end(), img.channels) == channels.end()) {
        std::string list;
        for (int c : channels) list += (list.empty() ? "" : ", ") + std::to_string(c);
        throw inputError(where, "cannot write an image with " + std::to_string(img.channels) +
                                    " channels (supported: " + list + ")");
    }
    const size_t expected = img.pixelCount() * static_cast<size_t>(img.channels);
    if (img.data.size() != expected)
        throw inputError(
            where, "internal error: image data holds " + std::to_string(img.data.size()) +
                       " values, " + std::to_string(img.width) + "x" + std::to_string(img.height) +
                       "x" + std::to_string(img.channels) + " needs " + std::to_string(expected));
}

[[noreturn]] void throwBadValue(const fs::path& file, const Image& img, size_t k, float v) {
    const size_t c = static_cast<size_t>(img.channels);
    const size_t px = k / c;
    throw inputError(file.string(),
                     std::string("image value is ") + (std::isnan(v) ? "NaN" : "infinite") +
                         " at row " + std::to_string(px / static_cast<size_t>(img.width)) +
                         ", column " + std::to_string(px % static_cast<size_t>(img.width)) +
                         ", channel " + std::to_string(k % c) + "; not written",
                     "Fix the computation that produced it");
}

std::vector<std::string> channelNames(int channels) {
    switch (channels) {
        case 1:
            return {"Y"};
        case 2:
            return {"Y", "A"};
        case 3:
            return {"R", "G", "B"};
        default:
            return {"R", "G", "B", "A"};
    }
}

/// An OpenEXR output stream into memory.
class MemoryStream : public Imf::OStream {
  public:
    explicit MemoryStream(const std::string& name) : Imf::OStream(name.c_str()) {}
    void write(const char c[], int n) override {
        const size_t count = static_cast<size_t>(n);
        if (pos_ + count > bytes.size()) bytes.resize(pos_ + count);
        std::memcpy(bytes.data() + pos_, c, count);
        pos_ += count;
    }
    uint64_t tellp() override { return pos_; }
    void seekp(uint64_t pos) override {
        pos_ = static_cast<size_t>(pos);
        if (pos_ > bytes.size()) bytes.resize(pos_);
    }
    std::vector<char> bytes;

  private:
    size_t pos_ = 0;
};

/// 16-bit PNG files (data: height maps): zlib's default level (OpenImageIO's, which wrote them
/// before).
constexpr int kPngFileLevel = 6;
/// 8-bit previews and masks: zlib's fastest level. The same pixels; level 6 spent ~5 % of the CPU
/// of a run on a cached T in deflate (issue 32, sixth pass).
constexpr int kPngPreviewLevel = 1;

void writePngFile(const fs::path& file, const std::string& encoded) {
    writeBytesAtomically(file, encoded.data(), encoded.size());
}

}  // namespace

Image readImage(const fs::path& file) {
    const std::string where = file.string();
    auto in = detail::openImageFile(file, kImageFix);
    const detail::ImageHeader& spec = in->header();
    if (spec.deep) throw inputError(where, "deep images are not supported", "Flatten the image");
    if (spec.depth > 1) throw inputError(where, "volume images are not supported");
    detail::checkImageSize(file, spec);
    const size_t n = static_cast<size_t>(spec.width) * static_cast<size_t>(spec.height) *
                     static_cast<size_t>(spec.nchannels);
    const Encoding enc = encodingOf(spec, in->formatName(), where);

    Image img;
    img.width = spec.width;
    img.height = spec.height;
    img.channels = spec.nchannels;
    try {
        img.data.resize(n);
    } catch (const std::bad_alloc&) {
        throw inputError(where, "not enough memory for a " + std::to_string(spec.width) + "x" +
                                    std::to_string(spec.height) + "x" +
                                    std::to_string(spec.nchannels) + " float image");
    }
    using detail::PixelType;
    const PixelType native = spec.format;
    const bool u8 = native == PixelType::UInt8, u16 = native == PixelType::UInt16;
    const PixelType readAs = u8 ? PixelType::UInt8 : u16 ? PixelType::UInt16 : PixelType::Float;
    // Integer values are stored packed at the front of the float buffer and widened below.
    const size_t rowBytes = static_cast<size_t>(spec.width) * static_cast<size_t>(spec.nchannels) *
                            detail::pixelTypeSize(readAs);
    unsigned char* bytes = reinterpret_cast<unsigned char*>(img.data.data());
    detail::readBands(*in, file, readAs, kImageFix, [&](int y0, int y1, const void* values) {
        std::memcpy(bytes + static_cast<size_t>(y0) * rowBytes, values,
                    static_cast<size_t>(y1 - y0) * rowBytes);
    });
    in->close();

    if (u8) {
        widenDecoded<uint8_t>(img, enc, spec.alphaChannel);
    } else if (u16) {
        widenDecoded<uint16_t>(img, enc, spec.alphaChannel);
    } else if (enc.transfer != Transfer::Linear) {
        const size_t c = static_cast<size_t>(img.channels);
        for (size_t k = 0; k < n; ++k)
            if (static_cast<int>(k % c) != spec.alphaChannel)
                img.data[k] = decode(enc, img.data[k]);
    }
    return img;
}

void writeExr(const fs::path& file, const Image& img) {
    requireExtension(file, ".exr", "OpenEXR");
    validateImage(file, img, {1, 3, 4});
    for (size_t k = 0; k < img.data.size(); ++k)
        if (!std::isfinite(img.data[k])) throwBadValue(file, img, k, img.data[k]);
    // Written with OpenEXR itself: OpenImageIO 2.4 stamps every EXR with the time of writing
    // (capDate), so equal images made different files. The header is OpenImageIO's otherwise:
    // ZIP at level 4, increasing Y, float32 channels.
    std::vector<char> encoded;
    try {
        Imf::Header header(img.width, img.height);
        header.compression() = Imf::ZIP_COMPRESSION;
        header.zipCompressionLevel() = 4;
        const std::vector<std::string> names = channelNames(img.channels);
        Imf::FrameBuffer frame;
        const size_t xStride = sizeof(float) * static_cast<size_t>(img.channels);
        for (size_t c = 0; c < names.size(); ++c) {
            header.channels().insert(names[c], Imf::Channel(Imf::FLOAT));
            // OpenEXR's slices take a writable pointer; it only reads from it here.
            char* base = reinterpret_cast<char*>(const_cast<float*>(img.data.data()) + c);
            frame.insert(names[c], Imf::Slice(Imf::FLOAT, base, xStride,
                                              xStride * static_cast<size_t>(img.width)));
        }
        MemoryStream out(file.string());
        {
            Imf::OutputFile exr(out, header);
            exr.setFrameBuffer(frame);
            exr.writePixels(img.height);
        }  // the destructor writes the chunk offsets
        encoded = std::move(out.bytes);
    } catch (const std::exception& e) {
        throw inputError(file.string(), std::string("cannot encode the image (") + e.what() + ")");
    }
    writeBytesAtomically(file, encoded.data(), encoded.size());
}

void writePng(const fs::path& file, const Image& img, float exposure) {
    requireExtension(file, ".png", "PNG");
    validateImage(file, img, {1, 3, 4});
    if (!std::isfinite(exposure) || exposure < 0.0f)
        throw inputError(file.string(), "exposure " + std::to_string(exposure) + " is invalid",
                         "Use a finite exposure >= 0");
    std::vector<uint8_t> px(img.data.size());
    const size_t c = static_cast<size_t>(img.channels);
    for (size_t k = 0; k < img.data.size(); ++k) {
        const float v = img.data[k];
        if (std::isnan(v)) throwBadValue(file, img, k, v);
        float e;
        if (c == 4 && k % c == 3)
            e = std::clamp(v, 0.0f, 1.0f);  // alpha: linear
        else
            e = srgbEncode(exposure == 0.0f ? 0.0f : v * exposure);  // clamps to [0, 1]
        px[k] = static_cast<uint8_t>(std::lround(e * 255.0f));
    }
    writePngFile(file, encodePng(px.data(), img.width, img.height, img.channels, 8, PngColour::Srgb,
                                 kPngPreviewLevel));
}

void writePng16(const fs::path& file, const Image& img) {
    requireExtension(file, ".png", "PNG");
    validateImage(file, img, {1, 3, 4});
    std::vector<uint16_t> px(img.data.size());
    for (size_t k = 0; k < img.data.size(); ++k) {
        const float v = img.data[k];
        if (std::isnan(v)) throwBadValue(file, img, k, v);
        px[k] = static_cast<uint16_t>(std::lround(std::clamp(v, 0.0f, 1.0f) * 65535.0f));
    }
    // Data, not colour: gAMA 1.0.
    writePngFile(file, encodePng(px.data(), img.width, img.height, img.channels, 16,
                                 PngColour::Linear, kPngFileLevel));
}

void writeMaskPng(const fs::path& file, const std::vector<uint8_t>& mask, int w, int h) {
    requireExtension(file, ".png", "PNG");
    if (w <= 0 || h <= 0)
        throw inputError(file.string(), "cannot write an empty mask (" + std::to_string(w) + "x" +
                                            std::to_string(h) + ")");
    if (mask.size() != static_cast<size_t>(w) * static_cast<size_t>(h))
        throw inputError(file.string(), "internal error: mask holds " +
                                            std::to_string(mask.size()) + " bytes, " +
                                            std::to_string(w) + "x" + std::to_string(h) +
                                            " needs " + std::to_string(static_cast<size_t>(w) * h));
    writePngFile(file, encodePng(mask.data(), w, h, 1, 8, PngColour::Linear, kPngPreviewLevel));
}

}  // namespace sl
