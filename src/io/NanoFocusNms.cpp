#include "io/NanoFocusNms.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "core/Error.h"
#include "core/Text.h"
#include "io/AtomicFile.h"
#include "io/ByteOrder.h"
#include "io/InputFile.h"

namespace sl {

namespace {

// The fields read (io/HeightmapIO.h), at their byte offsets: float64 z min and max (µm) at 16,
// uint32 points X and Y at 1368, float64 spacing X and Y (nm) at 1376; the uint16 height image
// at 3468, then (optionally) a uint8 intensity image of as many points.
constexpr size_t kZRange = 16, kPoints = 1368, kSpacing = 1376, kData = 3468;

}  // namespace

HeightmapData readNanoFocusNms(const std::filesystem::path& file) {
    const std::string where = file.string();
    const uint64_t maxBytes = kData + 3ull * detail::kMaxMetrologySamples;
    const std::string bytes = readInputFile(file, "the height map", maxBytes);
    const auto fail = [&](const std::string& problem, const std::string& fix) {
        throw inputError(where, problem, fix);
    };
    const char* const kFixDamaged =
        "The NMS file is damaged or truncated; export it again (as X3P or SDF from the "
        "instrument's software)";
    if (bytes.size() < kData ||
        bytes.compare(kNmsNameOffset, kNmsNameLength, std::string(kNmsName)) != 0)
        fail("not a NanoFocus NMS file (no '" + std::string(kNmsName) + "' at byte " +
                 std::to_string(kNmsNameOffset) + " of a " + std::to_string(kData) +
                 "-byte header)",
             kFixDamaged);
    const char* b = bytes.data();
    const double zmin = loadF64(b + kZRange), zmax = loadF64(b + kZRange + 8);
    const auto nx = loadU32(b + kPoints);
    const auto ny = loadU32(b + kPoints + 4);
    const double dx = loadF64(b + kSpacing), dy = loadF64(b + kSpacing + 8);
    if (nx < 2 || ny < 2 || nx > detail::kMaxMetrologySide || ny > detail::kMaxMetrologySide ||
        static_cast<long long>(nx) * ny > detail::kMaxMetrologySamples)
        fail("its header's size (byte " + std::to_string(kPoints) + ") is " + std::to_string(nx) +
                 " x " + std::to_string(ny) + " points, outside 2 .. " +
                 std::to_string(detail::kMaxMetrologySide) + " a side",
             kFixDamaged);
    if (!(std::isfinite(dx) && dx > 0 && std::isfinite(dy) && dy > 0))
        fail("its header's spacing (byte " + std::to_string(kSpacing) + ": " + formatNumber(dx) +
                 " x " + formatNumber(dy) + " nm) is not positive",
             kFixDamaged);
    if (!(std::isfinite(zmin) && std::isfinite(zmax) && zmax >= zmin))
        fail("its header's height range (byte " + std::to_string(kZRange) + ": " +
                 formatNumber(zmin) + " .. " + formatNumber(zmax) + " um) is not a range",
             kFixDamaged);
    const size_t n = static_cast<size_t>(nx) * ny;
    if (bytes.size() != kData + 2 * n && bytes.size() != kData + 3 * n)
        fail("holds " + std::to_string(bytes.size()) + " bytes; its header (" + std::to_string(nx) +
                 " x " + std::to_string(ny) + " points) says " + std::to_string(kData + 2 * n) +
                 " (heights) or " + std::to_string(kData + 3 * n) + " (heights and intensities)",
             kFixDamaged);

    HeightmapData d;
    d.width = static_cast<int>(nx);
    d.height = static_cast<int>(ny);
    d.format = "nanofocus nms uint16";
    d.pitch = dx * 1e-6;  // nm -> mm
    if (dy != dx) d.pitchY = dy * 1e-6;
    d.heights.resize(n);
    // Codes 0 .. 65535 span [z min, z max] in µm; no code is known to mark an invalid point.
    const double step = (zmax - zmin) / 65535.0 * 1e-3;  // mm per code
    const char* p = b + kData;
    for (size_t k = 0; k < n; ++k, p += 2)
        d.heights[k] =
            static_cast<float>(zmin * 1e-3 + step * static_cast<double>(loadLittleEndian(p, 2)));
    return d;
}

void writeNanoFocusNms(const std::filesystem::path& file, int width, int height,
                       const std::vector<float>& heightsMm, double pitchMm) {
    const size_t n = heightsMm.size();
    std::string out(kData + 3 * n, '\0');
    const auto put = [&](size_t at, uint64_t u, int bytes) {
        storeLittleEndian(out.data() + at, u, bytes);
    };
    std::memcpy(out.data() + kNmsNameOffset, "OM_MS_2.0", 9);
    const auto [lo, hi] = std::minmax_element(heightsMm.begin(), heightsMm.end());
    const double zmin = n ? *lo * 1e3 : 0.0, zmax = n ? *hi * 1e3 : 0.0;  // µm
    put(kZRange, std::bit_cast<uint64_t>(zmin), 8);
    put(kZRange + 8, std::bit_cast<uint64_t>(zmax), 8);
    put(kPoints, static_cast<uint32_t>(width), 4);
    put(kPoints + 4, static_cast<uint32_t>(height), 4);
    put(kSpacing, std::bit_cast<uint64_t>(pitchMm * 1e6), 8);  // nm
    put(kSpacing + 8, std::bit_cast<uint64_t>(pitchMm * 1e6), 8);
    const double codes = zmax > zmin ? 65535.0 / (zmax - zmin) : 0.0;
    for (size_t k = 0; k < n; ++k) {
        const double c = std::round((heightsMm[k] * 1e3 - zmin) * codes);
        put(kData + 2 * k, static_cast<uint64_t>(std::clamp(c, 0.0, 65535.0)), 2);
    }
    std::fill(out.begin() + static_cast<std::ptrdiff_t>(kData + 2 * n), out.end(), '\x80');
    writeBytesAtomically(file, out.data(), out.size());
}

}  // namespace sl
