#include "io/PngBuffer.h"

#include <zlib.h>

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <vector>

namespace sl {

namespace {

void put32(std::string& out, uint32_t v) {
    out.push_back(static_cast<char>((v >> 24) & 0xFF));
    out.push_back(static_cast<char>((v >> 16) & 0xFF));
    out.push_back(static_cast<char>((v >> 8) & 0xFF));
    out.push_back(static_cast<char>(v & 0xFF));
}

void chunk(std::string& out, const char* type, const std::string& data) {
    put32(out, static_cast<uint32_t>(data.size()));
    const size_t start = out.size();
    out.append(type, 4);
    out += data;
    const auto* p = reinterpret_cast<const Bytef*>(out.data() + start);
    const uLong crc = crc32(0L, p, static_cast<uInt>(out.size() - start));
    put32(out, static_cast<uint32_t>(crc));
}

}  // namespace

std::string encodePng8(std::span<const uint8_t> pixels, int width, int height, int channels,
                       int level) {
    if (width <= 0 || height <= 0 || channels < 1 || channels > 4)
        throw std::invalid_argument("encodePng8: bad image size or channel count");
    const size_t stride = static_cast<size_t>(width) * channels;
    if (pixels.size() != stride * height)
        throw std::invalid_argument("encodePng8: pixel count does not match the size");
    return encodePng(pixels.data(), width, height, channels, 8, PngColour::None, level);
}

std::string encodePng(const void* pixels, int width, int height, int channels, int bitDepth,
                      PngColour colour, int level) {
    if (width <= 0 || height <= 0 || channels < 1 || channels > 4)
        throw std::invalid_argument("encodePng: bad image size or channel count");
    if (bitDepth != 8 && bitDepth != 16) throw std::invalid_argument("encodePng: depth 8 or 16");
    if (level < 0 || level > 9) throw std::invalid_argument("encodePng: zlib level 0..9");
    const size_t bytes = static_cast<size_t>(bitDepth / 8);
    const size_t stride = static_cast<size_t>(width) * static_cast<size_t>(channels) * bytes;
    // Filter type 0 (none) on every row; 16-bit samples big-endian.
    std::vector<uint8_t> raw((stride + 1) * static_cast<size_t>(height));
    const auto* src = static_cast<const uint8_t*>(pixels);
    for (size_t y = 0; y < static_cast<size_t>(height); ++y) {
        uint8_t* row = raw.data() + y * (stride + 1);
        row[0] = 0;
        const uint8_t* in = src + y * stride;
        if (bytes == 1) {
            std::copy_n(in, stride, row + 1);
        } else {
            for (size_t i = 0; i < stride; i += 2) {
                uint16_t v;
                std::memcpy(&v, in + i, 2);
                row[1 + i] = static_cast<uint8_t>(v >> 8);
                row[2 + i] = static_cast<uint8_t>(v & 0xFF);
            }
        }
    }
    uLongf size = compressBound(static_cast<uLong>(raw.size()));
    std::string idat(size, '\0');
    if (compress2(reinterpret_cast<Bytef*>(idat.data()), &size, raw.data(),
                  static_cast<uLong>(raw.size()), level) != Z_OK)
        throw std::runtime_error("encodePng: zlib failed");
    idat.resize(size);

    std::string out = "\x89PNG\r\n\x1a\n";
    std::string ihdr;
    put32(ihdr, static_cast<uint32_t>(width));
    put32(ihdr, static_cast<uint32_t>(height));
    static const char colourType[] = {0, 0, 4, 2, 6};
    ihdr.push_back(static_cast<char>(bitDepth));
    ihdr.push_back(colourType[channels]);
    ihdr.push_back(0);  // deflate
    ihdr.push_back(0);  // adaptive filtering (type 0 per row)
    ihdr.push_back(0);  // no interlace
    chunk(out, "IHDR", ihdr);
    if (colour == PngColour::Srgb) {
        // sRGB with the gAMA and cHRM chunks the PNG specification asks beside it, as
        // OpenImageIO wrote them (absolute colorimetric intent, gamma 1/2.2, Rec. 709).
        std::string g;
        put32(g, 45455);
        chunk(out, "gAMA", g);
        chunk(out, "sRGB", std::string(1, '\3'));
        std::string c;
        for (uint32_t v : {31270u, 32900u, 64000u, 33000u, 30000u, 60000u, 15000u, 6000u})
            put32(c, v);
        chunk(out, "cHRM", c);
    }
    if (colour == PngColour::Linear) {
        std::string g;
        put32(g, 100000);  // gamma 1.0 (the chunk holds 100000 / gamma)
        chunk(out, "gAMA", g);
    }
    chunk(out, "IDAT", idat);
    chunk(out, "IEND", {});
    return out;
}

}  // namespace sl
