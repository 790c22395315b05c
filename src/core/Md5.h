// MD5 (RFC 1321), only for the checksums file formats carry (X3P's MD5ChecksumPointData and
// md5checksum.hex); not for anything security-related.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

namespace sl {

/// MD5 over bytes that arrive in pieces: update() any number of times, then hex(). The digest
/// is that of the pieces joined, whatever their sizes.
class Md5 {
  public:
    void update(const void* data, size_t bytes);
    /// The digest of everything given so far as 32 lower-case hex digits (ends the message:
    /// call it once).
    std::string hex();

  private:
    std::array<uint32_t, 4> state_ = {0x67452301u, 0xefcdab89u, 0x98badcfeu, 0x10325476u};
    unsigned char pending_[64] = {};  // the bytes of an unfinished block
    size_t pendingBytes_ = 0;
    uint64_t total_ = 0;
};

/// The MD5 digest of `bytes` bytes at `data` as 32 lower-case hex digits.
std::string md5Hex(const void* data, size_t bytes);

}  // namespace sl
