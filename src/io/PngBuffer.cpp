#include "io/PngBuffer.h"

#include <zlib.h>

#include <algorithm>
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
    if (level < 0 || level > 9) throw std::invalid_argument("encodePng8: zlib level 0..9");
    // Filter type 0 (none) on every row.
    std::vector<uint8_t> raw((stride + 1) * height);
    for (int y = 0; y < height; ++y) {
        uint8_t* row = raw.data() + static_cast<size_t>(y) * (stride + 1);
        row[0] = 0;
        std::copy_n(pixels.data() + static_cast<size_t>(y) * stride, stride, row + 1);
    }
    uLongf size = compressBound(static_cast<uLong>(raw.size()));
    std::string idat(size, '\0');
    if (compress2(reinterpret_cast<Bytef*>(idat.data()), &size, raw.data(),
                  static_cast<uLong>(raw.size()), level) != Z_OK)
        throw std::runtime_error("encodePng8: zlib failed");
    idat.resize(size);

    std::string out = "\x89PNG\r\n\x1a\n";
    std::string ihdr;
    put32(ihdr, static_cast<uint32_t>(width));
    put32(ihdr, static_cast<uint32_t>(height));
    static const char colourType[] = {0, 0, 4, 2, 6};
    ihdr.push_back(8);  // bit depth
    ihdr.push_back(colourType[channels]);
    ihdr.push_back(0);  // deflate
    ihdr.push_back(0);  // adaptive filtering (type 0 per row)
    ihdr.push_back(0);  // no interlace
    chunk(out, "IHDR", ihdr);
    chunk(out, "IDAT", idat);
    chunk(out, "IEND", {});
    return out;
}

}  // namespace sl
