#include "io/GramFile.h"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <vector>

#include "core/Hash.h"
#include "io/AtomicFile.h"

namespace sl {

namespace {

constexpr char kMagic[8] = {'S', 'L', 'G', 'R', 'A', 'M', '0', '1'};
constexpr size_t kKeyLength = 32;
constexpr size_t kHeaderBytes = sizeof kMagic + kKeyLength + 3 * sizeof(uint64_t);
constexpr uint64_t kHashSeed = 0x5347524d;  // "SGRM"

void put(std::vector<char>& out, const void* data, size_t bytes) {
    const auto* p = static_cast<const char*>(data);
    out.insert(out.end(), p, p + bytes);
}

}  // namespace

void writeGramFile(const std::filesystem::path& file, const std::string& key,
                   const TransportGram& gram) {
    if (key.size() != kKeyLength)
        throw std::invalid_argument("writeGramFile: the key must be 32 hex digits");
    const auto seen = gram.seen();
    const auto p = gram.pairMatrix(), q = gram.productMatrix();
    const uint64_t head[3] = {gram.cols(), seen.size(), gram.hasProducts() ? 1u : 0u};
    std::vector<char> out;
    out.reserve(kHeaderBytes + seen.size_bytes() + p.size_bytes() + q.size_bytes() + 8);
    put(out, kMagic, sizeof kMagic);
    put(out, key.data(), kKeyLength);
    put(out, head, sizeof head);
    put(out, seen.data(), seen.size_bytes());
    put(out, p.data(), p.size_bytes());
    put(out, q.data(), q.size_bytes());
    const uint64_t h = hash64(out.data(), out.size(), kHashSeed);
    put(out, &h, sizeof h);
    writeBytesAtomically(file, out.data(), out.size());
}

std::optional<TransportGram> readGramFile(const std::filesystem::path& file, const std::string& key,
                                          size_t cols) {
    try {
        std::error_code ec;
        if (!std::filesystem::is_regular_file(file, ec)) return std::nullopt;
        const uintmax_t size = std::filesystem::file_size(file, ec);
        if (ec || size < kHeaderBytes + 8) return std::nullopt;
        std::ifstream in(file, std::ios::binary);
        std::vector<char> bytes(static_cast<size_t>(size));
        if (!in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()))) return std::nullopt;
        if (std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0 ||
            std::string(bytes.data() + sizeof kMagic, kKeyLength) != key)
            return std::nullopt;
        uint64_t head[3];
        std::memcpy(head, bytes.data() + sizeof kMagic + kKeyLength, sizeof head);
        const uint64_t m = head[1];
        if (head[0] != cols || m > cols || head[2] > 1) return std::nullopt;
        const size_t matrices = head[2] ? 2 : 1;
        const size_t body = static_cast<size_t>(m) * sizeof(uint16_t) +
                            matrices * static_cast<size_t>(m * m) * sizeof(double);
        if (bytes.size() != kHeaderBytes + body + 8) return std::nullopt;
        uint64_t stored;
        std::memcpy(&stored, bytes.data() + kHeaderBytes + body, sizeof stored);
        if (hash64(bytes.data(), kHeaderBytes + body, kHashSeed) != stored) return std::nullopt;
        const char* at = bytes.data() + kHeaderBytes;
        std::vector<uint16_t> seen(static_cast<size_t>(m));
        std::memcpy(seen.data(), at, seen.size() * sizeof(uint16_t));
        at += seen.size() * sizeof(uint16_t);
        std::vector<double> p(static_cast<size_t>(m * m)), q(head[2] ? p.size() : 0);
        std::memcpy(p.data(), at, p.size() * sizeof(double));
        at += p.size() * sizeof(double);
        if (!q.empty()) std::memcpy(q.data(), at, q.size() * sizeof(double));
        return TransportGram(cols, std::move(seen), std::move(p), std::move(q));
    } catch (const std::exception&) {
        return std::nullopt;
    }
}

std::string peekGramFile(const std::filesystem::path& file) {
    std::ifstream in(file, std::ios::binary);
    char head[sizeof kMagic + kKeyLength];
    if (!in.read(head, sizeof head) || std::memcmp(head, kMagic, sizeof kMagic) != 0) return {};
    std::string key(head + sizeof kMagic, kKeyLength);
    for (char c : key)
        if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'))) return {};
    return key;
}

}  // namespace sl
