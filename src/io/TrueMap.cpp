#include "io/TrueMap.h"

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>

#include "core/Error.h"
#include "core/Text.h"
#include "io/AtomicFile.h"
#include "io/ByteOrder.h"
#include "io/InputFile.h"

namespace sl {

namespace {

// The header (io/HeightmapIO.h): 32 bytes of name ("Binary TrueMap Data File v2.0\r\n\0"), 24
// of comment, uint32 width and height, float32 length X and Y and offset X and Y (mm).
constexpr size_t kNameBytes = 32, kCommentBytes = 24;
constexpr size_t kHeaderBytes = kNameBytes + kCommentBytes + 2 * 4 + 4 * 4;  // 80

}  // namespace

HeightmapData readTrueMap(const std::filesystem::path& file) {
    const std::string where = file.string();
    const uint64_t maxBytes = kHeaderBytes + 4ull * detail::kMaxMetrologySamples;
    const std::string bytes = readInputFile(file, "the height map", maxBytes);
    const auto fail = [&](const std::string& problem, const std::string& fix) {
        throw inputError(where, problem, fix);
    };
    const char* const kFixDamaged = "The TMD file is damaged or truncated; export it again";
    if (bytes.size() < kHeaderBytes || bytes.compare(0, kTrueMapMagicLength, kTrueMapMagic) != 0)
        fail("not a TrueMap v2.0 file (it does not start with '" + std::string(kTrueMapMagic) +
                 "' and an 80-byte header)",
             kFixDamaged);
    const char* h = bytes.data() + kNameBytes + kCommentBytes;
    const uint32_t w = loadU32(h), ht = loadU32(h + 4);
    const double lx = loadF32(h + 8), ly = loadF32(h + 12);
    if (w < 2 || ht < 2 || w > detail::kMaxMetrologySide || ht > detail::kMaxMetrologySide ||
        static_cast<long long>(w) * ht > detail::kMaxMetrologySamples)
        fail("its header's size is " + std::to_string(w) + " x " + std::to_string(ht) +
                 " samples, outside 2 .. " + std::to_string(detail::kMaxMetrologySide) +
                 " a side and " + std::to_string(detail::kMaxMetrologySamples) + " in all",
             kFixDamaged);
    if (!(std::isfinite(lx) && lx > 0 && std::isfinite(ly) && ly > 0))
        fail("its header's lengths X and Y (" + formatNumber(lx) + ", " + formatNumber(ly) +
                 " mm) are not both positive",
             kFixDamaged);
    const size_t n = static_cast<size_t>(w) * ht;
    if (bytes.size() != kHeaderBytes + 4 * n)
        fail("holds " + std::to_string(bytes.size()) + " bytes; its header (" + std::to_string(w) +
                 " x " + std::to_string(ht) + " float32 samples) says " +
                 std::to_string(kHeaderBytes + 4 * n),
             kFixDamaged);

    HeightmapData d;
    d.width = static_cast<int>(w);
    d.height = static_cast<int>(ht);
    d.format = "truemap v2.0 float32";
    // A length is the whole side, so the spacing is length / samples (as TrueMap writes it).
    d.pitch = lx / w;
    if (ly / ht != *d.pitch) d.pitchY = ly / ht;
    d.heights.resize(n);
    const char* p = bytes.data() + kHeaderBytes;
    for (size_t k = 0; k < n; ++k, p += 4) d.heights[k] = loadF32(p);  // mm; NaN is invalid
    return d;
}

void writeTrueMap(const std::filesystem::path& file, int width, int height,
                  const std::vector<float>& heightsMm, double pitchMm) {
    std::string out(kHeaderBytes, '\0');
    std::memcpy(out.data(), kTrueMapMagic, kTrueMapMagicLength);
    std::memcpy(out.data() + kTrueMapMagicLength, "\r\n", 2);
    const char comment[] = "scratchlight";
    std::memcpy(out.data() + kNameBytes, comment, sizeof comment - 1);
    const auto put = [&](size_t at, auto v) {
        storeLittleEndian(out.data() + at, std::bit_cast<uint32_t>(v), 4);
    };
    const size_t h = kNameBytes + kCommentBytes;
    put(h, static_cast<uint32_t>(width));
    put(h + 4, static_cast<uint32_t>(height));
    put(h + 8, static_cast<float>(width * pitchMm));
    put(h + 12, static_cast<float>(height * pitchMm));
    out.resize(kHeaderBytes + 4 * heightsMm.size());
    for (size_t k = 0; k < heightsMm.size(); ++k) put(kHeaderBytes + 4 * k, heightsMm[k]);
    writeBytesAtomically(file, out.data(), out.size());
}

}  // namespace sl
