#include "io/ImageFile.h"

#include <algorithm>
#include <array>
#include <cstring>
#include <fstream>
#include <system_error>
#include <vector>

#include "core/Error.h"
#include "core/Text.h"
#include "io/ByteOrder.h"
#include "io/ExrReader.h"

namespace sl::detail {

namespace fs = std::filesystem;

namespace {

const char* const kExrFix = "The file is not a complete OpenEXR file; write it again";

/// Scanlines per chunk of each OpenEXR compression (NO, RLE, ZIPS, ZIP, PIZ, PXR24, B44, B44A,
/// DWAA, DWAB).
constexpr std::array<int, 10> kExrLinesPerChunk = {1, 1, 1, 16, 32, 16, 32, 32, 32, 256};

class ExrHeaderWalker {
  public:
    ExrHeaderWalker(const fs::path& file) : where_(file.string()), in_(file, std::ios::binary) {
        std::error_code ec;
        size_ = fs::file_size(file, ec);
        if (!in_ || ec) throw inputError(where_, "cannot open the file", "Check permissions");
        maxSamples_ = std::max(kMinDecodedLimit, size_ * kMaxDecodedPerFileByte) / sizeof(float);
    }

    void walk() {
        unsigned char head[8];
        read(head, 8, "the magic number and version");
        if (loadU32(head) != 20000630u)
            throw inputError(where_, "not an OpenEXR file (no OpenEXR magic number)", kExrFix);
        const uint32_t flags = loadU32(head + 4);
        if ((flags & 0xff) != 2)
            throw inputError(where_,
                             "OpenEXR format version " + std::to_string(flags & 0xff) +
                                 " is not supported (only 2 exists)",
                             kExrFix);
        const bool tiled = flags & 0x200, longNames = flags & 0x400, multipart = flags & 0x1000;
        maxName_ = longNames ? 255 : 31;
        uint64_t chunks = 0;
        for (int part = 0;; ++part) {
            Part p;
            if (!readHeader(p)) {
                if (part == 0) fail("the header has no attributes");
                break;  // the empty header that ends a multi-part file's list
            }
            if (!p.haveDataWindow) fail("the header lacks its dataWindow");
            const int64_t w = int64_t(p.box[2]) - p.box[0] + 1,
                          h = int64_t(p.box[3]) - p.box[1] + 1;
            if (w < 1 || h < 1)
                fail("the dataWindow [" + std::to_string(p.box[0]) + ", " +
                     std::to_string(p.box[1]) + "] - [" + std::to_string(p.box[2]) + ", " +
                     std::to_string(p.box[3]) + "] is empty");
            // What OpenEXR allocates when it opens the part: buffers for a whole chunk (a tile,
            // or up to 256 scanlines whatever the image's height), held to the same limit as
            // the image's pixels (checkImageSize, which runs only after the open).
            if (p.compression >= kExrLinesPerChunk.size())
                fail("unknown compression " + std::to_string(p.compression));
            const bool tiledPart = tiled || p.haveTiles;
            const uint64_t chunkW = static_cast<uint64_t>(tiledPart ? std::max(w, p.tileX) : w),
                           chunkH = static_cast<uint64_t>(
                               tiledPart ? std::max(h, p.tileY)
                                         : std::max<int64_t>(h, kExrLinesPerChunk[p.compression]));
            const uint64_t channels = std::max<uint64_t>(p.channels, 1);
            if (chunkW > maxSamples_ || chunkH > maxSamples_ ||
                chunkW * chunkH > maxSamples_ / channels)
                fail("the image (" + std::to_string(w) + "x" + std::to_string(h) + ", " +
                     std::to_string(channels) + " channels) is more than a " +
                     std::to_string(size_) + "-byte file can hold");
            if (p.chunkCount >= 0) {
                chunks += static_cast<uint64_t>(p.chunkCount);
            } else if (tiled || p.haveTiles) {
                if (p.tileX < 1 || p.tileY < 1) fail("the tile size is 0");
                chunks += static_cast<uint64_t>((w + p.tileX - 1) / p.tileX) *
                          static_cast<uint64_t>((h + p.tileY - 1) / p.tileY);
            } else {
                const int64_t lines = kExrLinesPerChunk[p.compression];
                chunks += static_cast<uint64_t>((h + lines - 1) / lines);
            }
            if (!multipart) break;
        }
        // Each chunk has an 8-byte entry in the offset table that follows the headers.
        const uint64_t rest = size_ - pos_;
        if (chunks > rest / 8)
            fail("the header promises " + std::to_string(chunks) +
                 " chunks of pixels; the file has room for the offsets of " +
                 std::to_string(rest / 8));
    }

  private:
    struct Part {
        bool haveDataWindow = false, haveTiles = false;
        std::array<int32_t, 4> box{};
        size_t compression = 0;
        int64_t tileX = 0, tileY = 0;
        int64_t chunkCount = -1;
        uint64_t channels = 0;
    };

    [[noreturn]] void fail(const std::string& problem) const {
        throw inputError(where_, "damaged OpenEXR header: " + problem, kExrFix);
    }

    void read(void* out, uint64_t n, const std::string& what) {
        if (n > size_ - pos_) fail("the file ends inside " + what);
        in_.read(static_cast<char*>(out), static_cast<std::streamsize>(n));
        if (!in_) fail("cannot read " + what);
        pos_ += n;
    }

    void skip(uint64_t n, const std::string& what) {
        if (n > size_ - pos_) fail("the file ends inside " + what);
        pos_ += n;
        in_.seekg(static_cast<std::streamoff>(pos_));
    }

    std::string readName(const char* what) {
        std::string s;
        for (;;) {
            char c;
            read(&c, 1, what);
            if (c == '\0') return s;
            if (s.size() >= maxName_)
                fail(std::string(what) + " is longer than " + std::to_string(maxName_) +
                     " characters");
            s += c;
        }
    }

    /// Reads one header; false if it is empty (its first byte ends it).
    bool readHeader(Part& p) {
        for (int count = 0;; ++count) {
            const std::string name = readName("an attribute name");
            if (name.empty()) return count > 0;
            const std::string type = readName("an attribute type");
            unsigned char sz[4];
            read(sz, 4, "the size of attribute '" + name + "'");
            const auto size = static_cast<int32_t>(loadU32(sz));
            if (size < 0) fail("attribute '" + name + "' has a negative size");
            const std::string what =
                "attribute '" + name + "' (" + std::to_string(size) + " bytes)";
            if (name == "dataWindow" && type == "box2i" && size == 16) {
                unsigned char b[16];
                read(b, 16, what);
                for (int k = 0; k < 4; ++k) p.box[k] = static_cast<int32_t>(loadU32(b + 4 * k));
                p.haveDataWindow = true;
            } else if (name == "compression" && type == "compression" && size == 1) {
                unsigned char c;
                read(&c, 1, what);
                p.compression = c;
            } else if (name == "tiles" && type == "tiledesc" && size == 9) {
                unsigned char t[9];
                read(t, 9, what);
                p.tileX = loadU32(t);
                p.tileY = loadU32(t + 4);
                p.haveTiles = true;
            } else if (type == "chlist") {
                // Entries: name '\0', pixel type (int), pLinear, 3 reserved, x and y sampling
                // (ints); a '\0' ends the list. Walked whatever the attribute's name: OpenEXR
                // reads every chlist so.
                if (static_cast<uint64_t>(size) > size_ - pos_)
                    fail("the file ends inside " + what);
                std::vector<char> list(static_cast<size_t>(size));
                read(list.data(), list.size(), what);
                size_t k = 0;
                while (k < list.size() && list[k] != '\0') {
                    const size_t end =
                        std::find(list.begin() + static_cast<std::ptrdiff_t>(k), list.end(), '\0') -
                        list.begin();
                    k = end + 1 + 16;
                    if (k > list.size()) fail("the channel list is cut short");
                    if (name == "channels") ++p.channels;
                }
                // OpenEXR reads the entries up to the list's '\0' and goes on from there,
                // whatever the size says: a list whose '\0' is not its last byte makes OpenEXR
                // read the rest as further attributes (a 1.3 KB file with an empty list of 19
                // bytes then asked for 2 GB; found by scripts/fuzz)
                if (k + 1 != list.size())
                    fail("the channel list's end is not its last byte (" + what + ")");
            } else if (name == "chunkCount" && type == "int" && size == 4) {
                unsigned char c[4];
                read(c, 4, what);
                const auto n = static_cast<int32_t>(loadU32(c));
                if (n < 0) fail("chunkCount is negative");
                p.chunkCount = n;
            } else {
                skip(static_cast<uint64_t>(size), what);
            }
        }
    }

    std::string where_;
    std::ifstream in_;
    uint64_t size_ = 0, pos_ = 0, maxSamples_ = 0;
    size_t maxName_ = 31;
};

}  // namespace

void checkExrHeader(const fs::path& file) {
    ExrHeaderWalker(file).walk();
}

void checkPngChunks(const fs::path& file) {
    const std::string where = file.string();
    const char* const fix = "The file is not a complete PNG file; write it again";
    std::error_code ec;
    const uint64_t size = fs::file_size(file, ec);
    std::ifstream in(file, std::ios::binary);
    if (!in || ec) throw inputError(where, "cannot open the file", "Check permissions");
    unsigned char sig[8];
    if (!in.read(reinterpret_cast<char*>(sig), 8) || std::memcmp(sig, "\x89PNG\r\n\x1a\n", 8) != 0)
        throw inputError(where, "not a PNG file (no PNG signature)", fix);
    for (uint64_t pos = 8;;) {
        unsigned char head[8];
        if (size - pos < 12 || !in.read(reinterpret_cast<char*>(head), 8))
            throw inputError(where, "damaged PNG: the file ends before its IEND chunk", fix);
        const uint64_t length = uint64_t(head[0]) << 24 | uint64_t(head[1]) << 16 |
                                uint64_t(head[2]) << 8 | uint64_t(head[3]);
        const std::string type(reinterpret_cast<const char*>(head + 4), 4);
        if (length > size - pos - 12)
            throw inputError(where,
                             "damaged PNG: chunk '" + type + "' claims " + std::to_string(length) +
                                 " bytes, the file has " + std::to_string(size - pos - 12) +
                                 " left",
                             fix);
        if (type == "IEND") return;
        pos += 12 + length;
        in.seekg(static_cast<std::streamoff>(pos));
    }
}

std::unique_ptr<ImageReader> openImageFile(const fs::path& file, const std::string& fix,
                                           bool exrDirect) {
    const std::string where = file.string();
    std::error_code ec;
    if (!fs::exists(file, ec))
        throw inputError(where, "file not found",
                         "Check the path (looked for " + fs::absolute(file, ec).string() +
                             "; a path in a scene file is relative to the scene file's folder, "
                             "one on the command line to the working directory)");
    if (fs::is_directory(file, ec)) throw inputError(where, "is a directory, not an image file");
    if (!fs::is_regular_file(file, ec))
        throw inputError(where, "not a regular file", "Give the path of an image file");
    const std::string ext = lower(file.extension().string());
    if (ext.size() < 2)
        throw inputError(where, "the file name has no extension to tell its image format",
                         "Name the file by its format (.exr, .png, .tif, ...)");
    if (ext == ".exr") {
        checkExrHeader(file);
        if (exrDirect)
            if (auto direct = openExrDirect(where)) return direct;
    }
    std::string err;
    auto in = imageCodec(where).createReader(ext.substr(1), &err);
    if (!in)
        throw inputError(where, "no image reader for files named *" + ext,
                         "Save the image as EXR, PNG or TIFF");
    const std::string format = in->formatName();
    if (format == "openexr" && ext != ".exr") checkExrHeader(file);
    if (format == "png") checkPngChunks(file);
    if (!in->open(where)) {
        err = in->error();
        throw inputError(where, "cannot read the file as " + format + " (" + err + ")", fix);
    }
    return in;
}

void checkImageSize(const fs::path& file, const ImageHeader& spec) {
    const std::string where = file.string();
    if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0 || spec.depth < 1)
        throw inputError(where, "the image is empty (" + std::to_string(spec.width) + "x" +
                                    std::to_string(spec.height) + ", " +
                                    std::to_string(spec.nchannels) + " channels)");
    std::error_code ec;
    const uint64_t fileBytes = fs::file_size(file, ec);
    const uint64_t limit =
        std::max(kMinDecodedLimit, (ec ? 0 : fileBytes) * kMaxDecodedPerFileByte);
    const uint64_t ch = uint64_t(spec.nchannels), maxSamples = limit / sizeof(float);
    const auto tooLarge = [&](const std::string& what) {
        throw inputError(where,
                         "the header claims " + what + ", more than a " +
                             std::to_string(fileBytes) + "-byte file can hold",
                         "The file is damaged or truncated; write it again");
    };
    if (uint64_t(spec.width) * uint64_t(spec.height) * uint64_t(spec.depth) * ch > maxSamples)
        tooLarge(std::to_string(spec.width) + "x" + std::to_string(spec.height) + " pixels of " +
                 std::to_string(spec.nchannels) + " channels");
    if (spec.tileWidth > 0 && uint64_t(spec.tileWidth) * uint64_t(std::max(spec.tileHeight, 1)) *
                                      uint64_t(std::max(spec.tileDepth, 1)) * ch >
                                  maxSamples)
        tooLarge("tiles of " + std::to_string(spec.tileWidth) + "x" +
                 std::to_string(spec.tileHeight) + " pixels");
    const int rowsPerStrip = spec.rowsPerStrip;
    if (spec.tileWidth <= 0 && rowsPerStrip > spec.height &&
        uint64_t(spec.width) * uint64_t(rowsPerStrip) * ch > maxSamples)
        tooLarge("strips of " + std::to_string(rowsPerStrip) + " rows of " +
                 std::to_string(spec.width) + " pixels");
}

void readBands(ImageReader& in, const fs::path& file, PixelType type, const std::string& fix,
               const std::function<void(int y0, int y1, const void* values)>& sink) {
    const ImageHeader& spec = in.header();
    const int nch = spec.nchannels;
    const size_t nativePixel = spec.nativePixelBytes;
    const size_t outPixel = pixelTypeSize(type) * static_cast<size_t>(nch);
    const size_t rowNative = nativePixel * static_cast<size_t>(spec.width);
    const size_t rowOut = outPixel * static_cast<size_t>(spec.width);
    // About 4 MB of native pixels per band; tiled files: whole rows of tiles.
    int rows = static_cast<int>(std::clamp<size_t>(
        (size_t(4) << 20) / std::max<size_t>(rowNative, 1), 1, static_cast<size_t>(spec.height)));
    const bool tiled = spec.tileWidth > 0;
    if (tiled) rows = (rows + spec.tileHeight - 1) / spec.tileHeight * spec.tileHeight;
    std::vector<unsigned char> native(static_cast<size_t>(rows) * rowNative);
    std::vector<unsigned char> out(static_cast<size_t>(rows) * rowOut);
    for (int y0 = 0; y0 < spec.height; y0 += rows) {
        const int y1 = std::min(spec.height, y0 + rows);
        if (!in.readNative(y0, y1, native.data())) {
            std::string err = in.error();
            if (err.empty()) err = "no reason given";
            throw inputError(
                file.string(),
                "cannot read the pixels: the file is damaged or truncated (" + err + ")", fix);
        }
        const size_t pixels = static_cast<size_t>(y1 - y0) * static_cast<size_t>(spec.width);
        if (!in.convert(native.data(), pixels, type, out.data()))
            throw inputError(file.string(),
                             "cannot convert its pixels (" + spec.formatText + ") to numbers", fix);
        sink(y0, y1, out.data());
    }
}

}  // namespace sl::detail
