// Fast non-cryptographic 64-bit hashing for fingerprints and file checksums (detects damage and
// staleness, not tampering). Words of 8 bytes are mixed with the SplitMix64 finaliser.
#pragma once

#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>

#include "core/Rng.h"

namespace sl {

class Hasher {
  public:
    explicit Hasher(uint64_t seed = 0) : h_(mix64(seed ^ 0x243f6a8885a308d3ULL)) {}

    Hasher& add(const void* data, size_t bytes) {
        const auto* p = static_cast<const unsigned char*>(data);
        size_t i = 0;
        for (; i + 8 <= bytes; i += 8) {
            uint64_t w;
            std::memcpy(&w, p + i, 8);
            h_ = mix64(h_ ^ w) + 0x9e3779b97f4a7c15ULL;
        }
        uint64_t tail = 0;
        // memcpy needs valid pointers even for 0 bytes (an empty vector's data() may be null).
        if (bytes > i) std::memcpy(&tail, p + i, bytes - i);
        h_ = mix64(h_ ^ tail ^ (static_cast<uint64_t>(bytes) << 56));
        length_ += bytes;
        return *this;
    }
    Hasher& add(std::string_view s) { return add(s.data(), s.size()); }
    uint64_t digest() const { return mix64(h_ ^ length_); }

  private:
    uint64_t h_;
    uint64_t length_ = 0;
};

inline uint64_t hash64(const void* data, size_t bytes, uint64_t seed = 0) {
    return Hasher(seed).add(data, bytes).digest();
}

inline std::string toHex(uint64_t v) {
    static const char* digits = "0123456789abcdef";
    std::string s(16, '0');
    for (int i = 15; i >= 0; --i, v >>= 4) s[static_cast<size_t>(i)] = digits[v & 15];
    return s;
}

/// A 128-bit key of `text` as 32 hex digits (two 64-bit hashes, seeds 1 and 2): the names of
/// the cache's files (transport fingerprints, lights, Grams, parts' records) and of renders.
inline std::string hexKey128(std::string_view text) {
    return toHex(hash64(text.data(), text.size(), 1)) + toHex(hash64(text.data(), text.size(), 2));
}

}  // namespace sl
