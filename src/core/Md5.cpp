#include "core/Md5.h"

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>

namespace sl {

namespace {

constexpr std::array<uint32_t, 64> kShift = {
    7,  12, 17, 22, 7,  12, 17, 22, 7,  12, 17, 22, 7,  12, 17, 22, 5,  9,  14, 20, 5,  9,
    14, 20, 5,  9,  14, 20, 5,  9,  14, 20, 4,  11, 16, 23, 4,  11, 16, 23, 4,  11, 16, 23,
    4,  11, 16, 23, 6,  10, 15, 21, 6,  10, 15, 21, 6,  10, 15, 21, 6,  10, 15, 21};

/// K[i] = floor(|sin(i + 1)| · 2^32) (RFC 1321 §3.4).
const std::array<uint32_t, 64>& constants() {
    static const std::array<uint32_t, 64> k = [] {
        std::array<uint32_t, 64> t{};
        for (size_t i = 0; i < t.size(); ++i)
            t[i] = static_cast<uint32_t>(
                std::floor(std::abs(std::sin(static_cast<double>(i + 1))) * 4294967296.0));
        return t;
    }();
    return k;
}

uint32_t rotl(uint32_t x, uint32_t c) {
    return (x << c) | (x >> (32 - c));
}

void block(std::array<uint32_t, 4>& s, const unsigned char* p) {
    const auto& k = constants();
    uint32_t m[16];
    for (size_t i = 0; i < 16; ++i)
        m[i] = uint32_t(p[4 * i]) | uint32_t(p[4 * i + 1]) << 8 | uint32_t(p[4 * i + 2]) << 16 |
               uint32_t(p[4 * i + 3]) << 24;
    uint32_t a = s[0], b = s[1], c = s[2], d = s[3];
    for (size_t i = 0; i < 64; ++i) {
        uint32_t f = 0;
        size_t g = 0;
        if (i < 16) {
            f = (b & c) | (~b & d);
            g = i;
        } else if (i < 32) {
            f = (d & b) | (~d & c);
            g = (5 * i + 1) % 16;
        } else if (i < 48) {
            f = b ^ c ^ d;
            g = (3 * i + 5) % 16;
        } else {
            f = c ^ (b | ~d);
            g = (7 * i) % 16;
        }
        f += a + k[i] + m[g];
        a = d;
        d = c;
        c = b;
        b += rotl(f, kShift[i]);
    }
    s[0] += a;
    s[1] += b;
    s[2] += c;
    s[3] += d;
}

}  // namespace

std::string md5Hex(const void* data, size_t bytes) {
    std::array<uint32_t, 4> s = {0x67452301u, 0xefcdab89u, 0x98badcfeu, 0x10325476u};
    const auto* p = static_cast<const unsigned char*>(data);
    size_t i = 0;
    for (; i + 64 <= bytes; i += 64) block(s, p + i);
    // The tail, 0x80, zeros, and the length in bits (little-endian): one or two blocks.
    unsigned char tail[128] = {};
    const size_t rest = bytes - i;
    if (rest > 0) std::memcpy(tail, p + i, rest);
    tail[rest] = 0x80;
    const size_t len = rest < 56 ? 64 : 128;
    const uint64_t bits = static_cast<uint64_t>(bytes) * 8;
    for (size_t b = 0; b < 8; ++b) tail[len - 8 + b] = static_cast<unsigned char>(bits >> (8 * b));
    block(s, tail);
    if (len == 128) block(s, tail + 64);
    static const char* const hex = "0123456789abcdef";
    std::string out;
    for (uint32_t w : s)
        for (int b = 0; b < 4; ++b) {
            const auto byte = static_cast<unsigned>((w >> (8 * b)) & 0xff);
            out += hex[byte >> 4];
            out += hex[byte & 15];
        }
    return out;
}

}  // namespace sl
