// Little-endian fields of binary files, read and written byte by byte so that the host's byte
// order does not matter (the TrueMap and NanoFocus NMS readers and writers).
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>

namespace sl {

/// The `bytes`-byte (1..8) little-endian unsigned integer at p.
inline uint64_t loadLittleEndian(const char* p, int bytes) {
    uint64_t v = 0;
    for (int b = bytes - 1; b >= 0; --b) v = (v << 8) | static_cast<unsigned char>(p[b]);
    return v;
}

/// Writes the low `bytes` bytes of u at p, least significant first.
inline void storeLittleEndian(char* p, uint64_t u, int bytes) {
    for (int b = 0; b < bytes; ++b) p[b] = static_cast<char>((u >> (8 * b)) & 0xff);
}

inline uint32_t loadU32(const char* p) {
    return static_cast<uint32_t>(loadLittleEndian(p, 4));
}
inline float loadF32(const char* p) {
    return std::bit_cast<float>(loadU32(p));
}
inline double loadF64(const char* p) {
    return std::bit_cast<double>(loadLittleEndian(p, 8));
}

}  // namespace sl
