#include "core/Md5.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <utility>

namespace sl {

namespace {

constexpr std::array<uint32_t, 64> kShift = {
    7,  12, 17, 22, 7,  12, 17, 22, 7,  12, 17, 22, 7,  12, 17, 22, 5,  9,  14, 20, 5,  9,
    14, 20, 5,  9,  14, 20, 5,  9,  14, 20, 4,  11, 16, 23, 4,  11, 16, 23, 4,  11, 16, 23,
    4,  11, 16, 23, 6,  10, 15, 21, 6,  10, 15, 21, 6,  10, 15, 21, 6,  10, 15, 21};

/// K[i] = floor(|sin(i + 1)| · 2^32) (RFC 1321 §3.4).
constexpr std::array<uint32_t, 64> kK = {
    0xd76aa478, 0xe8c7b756, 0x242070db, 0xc1bdceee, 0xf57c0faf, 0x4787c62a, 0xa8304613, 0xfd469501,
    0x698098d8, 0x8b44f7af, 0xffff5bb1, 0x895cd7be, 0x6b901122, 0xfd987193, 0xa679438e, 0x49b40821,
    0xf61e2562, 0xc040b340, 0x265e5a51, 0xe9b6c7aa, 0xd62f105d, 0x02441453, 0xd8a1e681, 0xe7d3fbc8,
    0x21e1cde6, 0xc33707d6, 0xf4d50d87, 0x455a14ed, 0xa9e3e905, 0xfcefa3f8, 0x676f02d9, 0x8d2a4c8a,
    0xfffa3942, 0x8771f681, 0x6d9d6122, 0xfde5380c, 0xa4beea44, 0x4bdecfa9, 0xf6bb4b60, 0xbebfbc70,
    0x289b7ec6, 0xeaa127fa, 0xd4ef3085, 0x04881d05, 0xd9d4d039, 0xe6db99e5, 0x1fa27cf8, 0xc4ac5665,
    0xf4292244, 0x432aff97, 0xab9423a7, 0xfc93a039, 0x655b59c3, 0x8f0ccc92, 0xffeff47d, 0x85845dd1,
    0x6fa87e4f, 0xfe2ce6e0, 0xa3014314, 0x4e0811a1, 0xf7537e82, 0xbd3af235, 0x2ad7d2bb, 0xeb86d391};

constexpr uint32_t rotl(uint32_t x, uint32_t c) {
    return (x << c) | (x >> (32 - c));
}

/// One MD5 step of round R (0..3) at index I; the round's function, message word and shift are
/// compile-time constants, so the compiler unrolls the 64 steps.
template <int R, int I>
inline void step(uint32_t& a, uint32_t& b, uint32_t& c, uint32_t& d, const uint32_t* m) {
    uint32_t f;
    int g;
    if constexpr (R == 0) {
        f = (b & c) | (~b & d);
        g = I;
    } else if constexpr (R == 1) {
        f = (d & b) | (~d & c);
        g = (5 * I + 1) % 16;
    } else if constexpr (R == 2) {
        f = b ^ c ^ d;
        g = (3 * I + 5) % 16;
    } else {
        f = c ^ (b | ~d);
        g = (7 * I) % 16;
    }
    f += a + kK[I] + m[g];
    a = d;
    d = c;
    c = b;
    b += rotl(f, kShift[I]);
}

template <int R, int... I>
inline void round(uint32_t& a, uint32_t& b, uint32_t& c, uint32_t& d, const uint32_t* m,
                  std::integer_sequence<int, I...>) {
    (step<R, 16 * R + I>(a, b, c, d, m), ...);
}

void block(std::array<uint32_t, 4>& s, const unsigned char* p) {
    uint32_t m[16];
    for (size_t i = 0; i < 16; ++i)
        m[i] = uint32_t(p[4 * i]) | uint32_t(p[4 * i + 1]) << 8 | uint32_t(p[4 * i + 2]) << 16 |
               uint32_t(p[4 * i + 3]) << 24;
    uint32_t a = s[0], b = s[1], c = s[2], d = s[3];
    const auto idx = std::make_integer_sequence<int, 16>();
    round<0>(a, b, c, d, m, idx);
    round<1>(a, b, c, d, m, idx);
    round<2>(a, b, c, d, m, idx);
    round<3>(a, b, c, d, m, idx);
    s[0] += a;
    s[1] += b;
    s[2] += c;
    s[3] += d;
}

}  // namespace

void Md5::update(const void* data, size_t bytes) {
    const auto* p = static_cast<const unsigned char*>(data);
    total_ += bytes;
    if (pendingBytes_ > 0) {
        const size_t take = std::min(bytes, 64 - pendingBytes_);
        std::memcpy(pending_ + pendingBytes_, p, take);
        pendingBytes_ += take, p += take, bytes -= take;
        if (pendingBytes_ < 64) return;
        block(state_, pending_);
        pendingBytes_ = 0;
    }
    for (; bytes >= 64; p += 64, bytes -= 64) block(state_, p);
    std::memcpy(pending_, p, bytes);
    pendingBytes_ = bytes;
}

std::string Md5::hex() {
    // The tail, 0x80, zeros, and the length in bits (little-endian): one or two blocks.
    unsigned char tail[128] = {};
    const size_t rest = pendingBytes_;
    std::memcpy(tail, pending_, rest);
    tail[rest] = 0x80;
    const size_t len = rest < 56 ? 64 : 128;
    const uint64_t bits = total_ * 8;
    for (size_t b = 0; b < 8; ++b) tail[len - 8 + b] = static_cast<unsigned char>(bits >> (8 * b));
    block(state_, tail);
    if (len == 128) block(state_, tail + 64);
    static const char* const hexDigits = "0123456789abcdef";
    std::string out;
    for (uint32_t w : state_)
        for (int b = 0; b < 4; ++b) {
            const auto byte = static_cast<unsigned>((w >> (8 * b)) & 0xff);
            out += hexDigits[byte >> 4];
            out += hexDigits[byte & 15];
        }
    return out;
}

std::string md5Hex(const void* data, size_t bytes) {
    Md5 m;
    m.update(data, bytes);
    return m.hex();
}

}  // namespace sl
