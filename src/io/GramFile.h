// Gram files (.gram): T's Gram matrices (transport/TransportGram.h) kept beside T in the cache
// (app/pipeline/Cache.h), so a run on a cached T does not build them again. One binary file,
// little-endian:
//
//   "SLGRAM01" (8 bytes) | key (32 hex digits) | u64 cols | u64 seen | u64 has Q
//   | seen texels (u16 each) | P (f64, seen² row-major) | Q (f64, seen², when has Q)
//   | u64 hash of every byte before it (core/Hash.h)
//
// The key is the caller's (T's fingerprint and every other input of the matrices: the pair
// mask, whether Q is built, the build's revision); a file is read only under its own key, and
// its values are the built matrices bit for bit. Written atomically (io/AtomicFile.h).
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "transport/TransportGram.h"

namespace sl {

/// Writes `gram` under `key` (32 hex digits) to `file`, atomically. Throws InputError naming
/// the file when the write fails.
void writeGramFile(const std::filesystem::path& file, const std::string& key,
                   const TransportGram& gram);

/// The matrices of `file` when it is a whole, undamaged Gram file holding `key` (and `cols`
/// texels); nullopt otherwise (missing, cut short, damaged, another key). Never throws.
std::optional<TransportGram> readGramFile(const std::filesystem::path& file, const std::string& key,
                                          size_t cols);

/// The key a Gram file holds, read from its first bytes without the matrices (empty when it is
/// not one). Never throws.
std::string peekGramFile(const std::filesystem::path& file);

}  // namespace sl
