// Little-endian fields of binary files, read and written byte by byte so that the host's byte
// order does not matter (the OpenEXR header walker, the X3P, SDF, TrueMap and NanoFocus NMS
// readers, and the TrueMap and NMS writers).
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>

namespace sl {

/// The `bytes`-byte (1..8) little-endian unsigned integer at p.
inline uint64_t loadLittleEndian(const unsigned char* p, int bytes) {
    uint64_t v = 0;
    for (int b = bytes - 1; b >= 0; --b) v = (v << 8) | p[b];
    return v;
}
inline uint64_t loadLittleEndian(const char* p, int bytes) {
    return loadLittleEndian(reinterpret_cast<const unsigned char*>(p), bytes);
}

/// Writes the low `bytes` bytes of u at p, least significant first.
inline void storeLittleEndian(char* p, uint64_t u, int bytes) {
    for (int b = 0; b < bytes; ++b) p[b] = static_cast<char>((u >> (8 * b)) & 0xff);
}

template <class Byte>
inline uint16_t loadU16(const Byte* p) {
    return static_cast<uint16_t>(loadLittleEndian(p, 2));
}
template <class Byte>
inline uint32_t loadU32(const Byte* p) {
    return static_cast<uint32_t>(loadLittleEndian(p, 4));
}
template <class Byte>
inline float loadF32(const Byte* p) {
    return std::bit_cast<float>(loadU32(p));
}
template <class Byte>
inline double loadF64(const Byte* p) {
    return std::bit_cast<double>(loadLittleEndian(p, 8));
}

}  // namespace sl
