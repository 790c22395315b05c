// MD5 (RFC 1321), only for the checksums file formats carry (X3P's MD5ChecksumPointData and
// md5checksum.hex); not for anything security-related.
#pragma once

#include <cstddef>
#include <string>

namespace sl {

/// The MD5 digest of `bytes` bytes at `data` as 32 lower-case hex digits.
std::string md5Hex(const void* data, size_t bytes);

}  // namespace sl
