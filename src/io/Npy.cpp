#include "io/Npy.h"

#include <algorithm>
#include <bit>
#include <climits>
#include <cstring>
#include <fstream>
#include <limits>
#include <system_error>

#include "core/Error.h"

namespace sl {

namespace fs = std::filesystem;

static_assert(std::endian::native == std::endian::little,
              "Npy.cpp reads little-endian data straight into memory");

const char* npyTypeName(NpyType t) {
    switch (t) {
        case NpyType::Float32:
            return "float32";
        case NpyType::Float64:
            return "float64";
        case NpyType::UInt16:
            return "uint16";
    }
    return "?";
}

std::string NpyMatrix::typeName() const {
    return npyTypeName(type);
}

namespace {

constexpr char kMagic[] = "\x93NUMPY";
constexpr size_t kMagicLen = 6;
constexpr size_t kMaxHeaderLen = 1u << 20;  // numpy itself refuses > 10000 by default
const char* const kContiguousFix =
    "Save a C-ordered float array: np.save(path, np.ascontiguousarray(a, dtype=np.float32))";

/// Minimal parser for the Python dict literal in a .npy header.
class DictParser {
  public:
    DictParser(std::string_view text, const std::string& where) : s_(text), where_(where) {}

    struct Value {
        enum Kind { String, Bool, Tuple } kind = String;
        std::string str;
        bool b = false;
        std::vector<size_t> tuple;
    };

    void parse(std::string& descr, bool& fortran, std::vector<size_t>& shape) {
        bool haveDescr = false, haveFortran = false, haveShape = false;
        skipSpace();
        expect('{');
        for (;;) {
            skipSpace();
            if (peek() == '}') {
                ++pos_;
                break;
            }
            std::string key = parseString();
            skipSpace();
            expect(':');
            skipSpace();
            if (key == "descr") {
                if (peek() != '\'' && peek() != '"')
                    fail("the dtype is a structured or nested type (descr is not a string)",
                         kContiguousFix);
                descr = parseString();
                haveDescr = true;
            } else if (key == "fortran_order") {
                fortran = parseBool();
                haveFortran = true;
            } else if (key == "shape") {
                shape = parseTuple();
                haveShape = true;
            } else {
                fail("unexpected header key '" + key + "'", "Write the file with numpy.save");
            }
            skipSpace();
            if (peek() == ',') {
                ++pos_;
                continue;
            }
            skipSpace();
            expect('}');
            break;
        }
        skipSpace();
        if (pos_ != s_.size()) fail("unexpected text after the header dict");
        if (!haveDescr || !haveFortran || !haveShape)
            fail("header lacks one of 'descr', 'fortran_order', 'shape'",
                 "Write the file with numpy.save");
    }

  private:
    [[noreturn]] void fail(const std::string& problem, const std::string& fix =
                                                           "The file is not a valid .npy file; "
                                                           "write it with numpy.save") const {
        throw inputError(where_, "bad .npy header: " + problem, fix);
    }
    char peek() const { return pos_ < s_.size() ? s_[pos_] : '\0'; }
    void skipSpace() {
        while (pos_ < s_.size() &&
               (s_[pos_] == ' ' || s_[pos_] == '\t' || s_[pos_] == '\n' || s_[pos_] == '\r'))
            ++pos_;
    }
    void expect(char c) {
        if (peek() != c)
            fail(std::string("expected '") + c + "' at offset " + std::to_string(pos_));
        ++pos_;
    }
    std::string parseString() {
        char q = peek();
        if (q != '\'' && q != '"')
            fail("expected a quoted string at offset " + std::to_string(pos_));
        ++pos_;
        size_t end = s_.find(q, pos_);
        if (end == std::string_view::npos) fail("unterminated string");
        std::string out(s_.substr(pos_, end - pos_));
        pos_ = end + 1;
        return out;
    }
    bool parseBool() {
        if (s_.substr(pos_, 4) == "True") {
            pos_ += 4;
            return true;
        }
        if (s_.substr(pos_, 5) == "False") {
            pos_ += 5;
            return false;
        }
        fail("fortran_order is neither True nor False");
    }
    std::vector<size_t> parseTuple() {
        std::vector<size_t> out;
        expect('(');
        for (;;) {
            skipSpace();
            if (peek() == ')') {
                ++pos_;
                return out;
            }
            if (peek() < '0' || peek() > '9') fail("shape holds something other than integers");
            size_t v = 0;
            while (peek() >= '0' && peek() <= '9') {
                size_t d = static_cast<size_t>(peek() - '0');
                if (v > (std::numeric_limits<size_t>::max() - d) / 10) fail("shape is too large");
                v = v * 10 + d;
                ++pos_;
            }
            if (peek() == 'L') ++pos_;  // Python 2 long suffix
            out.push_back(v);
            skipSpace();
            if (peek() == ',') {
                ++pos_;
                continue;
            }
            skipSpace();
            expect(')');
            return out;
        }
    }

    std::string_view s_;
    const std::string& where_;
    size_t pos_ = 0;
};

uint32_t readLE(const uint8_t* p, size_t n) {
    uint32_t v = 0;
    for (size_t i = 0; i < n; ++i) v |= static_cast<uint32_t>(p[i]) << (8 * i);
    return v;
}

std::string shapeString(const std::vector<size_t>& shape) {
    std::string s = "(";
    for (size_t i = 0; i < shape.size(); ++i) {
        if (i) s += ", ";
        s += std::to_string(shape[i]);
    }
    if (shape.size() == 1) s += ",";
    return s + ")";
}

}  // namespace

NpyHeader parseNpyHeader(const uint8_t* bytes, size_t available, size_t fileSize,
                         const std::string& where) {
    const std::string notNpy = "Write the file with numpy.save (np.save(path, a))";
    if (available < kMagicLen + 2 || std::memcmp(bytes, kMagic, kMagicLen) != 0)
        throw inputError(where, "not a .npy file (missing the \\x93NUMPY magic)", notNpy);
    NpyHeader h;
    h.versionMajor = bytes[6];
    h.versionMinor = bytes[7];
    size_t lenBytes = 0;
    if (h.versionMajor == 1)
        lenBytes = 2;
    else if (h.versionMajor == 2 || h.versionMajor == 3)
        lenBytes = 4;
    else
        throw inputError(where,
                         "unsupported .npy format version " + std::to_string(h.versionMajor) + "." +
                             std::to_string(h.versionMinor) + " (supported: 1.0, 2.0, 3.0)",
                         "Save with numpy.save from a current numpy");
    if (h.versionMinor != 0)
        throw inputError(where,
                         "unsupported .npy format version " + std::to_string(h.versionMajor) + "." +
                             std::to_string(h.versionMinor),
                         "Save with numpy.save from a current numpy");
    const size_t prefix = kMagicLen + 2 + lenBytes;
    if (available < prefix) throw inputError(where, "file is truncated inside the .npy header");
    const size_t headerLen = readLE(bytes + kMagicLen + 2, lenBytes);
    if (headerLen > kMaxHeaderLen)
        throw inputError(where,
                         "the .npy header claims " + std::to_string(headerLen) +
                             " bytes, more than any numpy writes",
                         notNpy);
    if (available < prefix + headerLen || fileSize < prefix + headerLen)
        throw inputError(where, "file is truncated inside the .npy header", notNpy);
    h.dataOffset = prefix + headerLen;

    std::string_view text(reinterpret_cast<const char*>(bytes + prefix), headerLen);
    DictParser(text, where).parse(h.descr, h.fortranOrder, h.shape);

    // dtype
    const std::string& d = h.descr;
    if (d.size() == 3 && (d[0] == '<' || d[0] == '=' || d[0] == '|')) {
        std::string t = d.substr(1);
        if (t == "f4" && d[0] != '|') {
            h.type = NpyType::Float32;
            h.itemSize = 4;
        } else if (t == "f8" && d[0] != '|') {
            h.type = NpyType::Float64;
            h.itemSize = 8;
        } else if (t == "u2" && d[0] != '|') {
            h.type = NpyType::UInt16;
            h.itemSize = 2;
        } else {
            throw inputError(where,
                             "unsupported dtype '" + d +
                                 "' (supported: float32 '<f4', float64 '<f8', uint16 '<u2')",
                             kContiguousFix);
        }
    } else if (!d.empty() && d[0] == '>') {
        throw inputError(where, "big-endian dtype '" + d + "' is not supported",
                         "Save little-endian data: np.save(path, a.astype('<f4'))");
    } else {
        throw inputError(
            where,
            "unsupported dtype '" + d + "' (supported: float32 '<f4', float64 '<f8', uint16 '<u2')",
            kContiguousFix);
    }

    if (h.fortranOrder)
        throw inputError(where, "the array is stored in Fortran (column-major) order",
                         "Save it in C order: np.save(path, np.ascontiguousarray(a))");

    // shape: (H, W) or (H, W, 1)
    bool ok2d = h.shape.size() == 2 || (h.shape.size() == 3 && h.shape[2] == 1);
    if (!ok2d)
        throw inputError(where,
                         "array shape " + shapeString(h.shape) +
                             " is not 2-D (expected (rows, columns) or (rows, columns, 1))",
                         "Save a 2-D height array, e.g. np.save(path, a.reshape(rows, columns))");
    if (h.shape[0] > static_cast<size_t>(INT_MAX) || h.shape[1] > static_cast<size_t>(INT_MAX))
        throw inputError(where, "array shape " + shapeString(h.shape) + " is too large");
    h.elementCount = h.shape[0] * h.shape[1];
    if (h.shape[1] != 0 && h.elementCount / h.shape[1] != h.shape[0])
        throw inputError(where, "array shape " + shapeString(h.shape) + " is too large");
    if (h.elementCount > (std::numeric_limits<size_t>::max() - h.dataOffset) / h.itemSize)
        throw inputError(where, "array shape " + shapeString(h.shape) + " is too large");

    const size_t expected = h.dataOffset + h.elementCount * h.itemSize;
    if (fileSize < expected)
        throw inputError(where,
                         "file is truncated: the header promises " +
                             std::to_string(expected - h.dataOffset) + " bytes of " +
                             npyTypeName(h.type) + " data for shape " + shapeString(h.shape) +
                             ", the file holds " + std::to_string(fileSize - h.dataOffset),
                         "Save the file again with numpy.save");
    if (fileSize > expected)
        throw inputError(where,
                         "file has " + std::to_string(fileSize - expected) +
                             " bytes after the array data (not a plain .npy file?)",
                         "Save one array with numpy.save (not savez or a concatenation)");
    return h;
}

namespace {

struct OpenedNpy {
    std::ifstream in;
    NpyHeader header;
};

OpenedNpy openNpy(const fs::path& file) {
    const std::string where = file.string();
    std::error_code ec;
    if (!fs::exists(file, ec))
        throw inputError(where, "file not found",
                         "Check the path (relative paths are resolved "
                         "against the scene file's directory)");
    if (!fs::is_regular_file(file, ec)) throw inputError(where, "not a regular file");
    const auto size = fs::file_size(file, ec);
    if (ec) throw inputError(where, "cannot read the file size (" + ec.message() + ")");

    OpenedNpy o;
    o.in.open(file, std::ios::binary);
    if (!o.in) throw inputError(where, "cannot open the file for reading", "Check permissions");

    // Prefix, then the full header.
    std::vector<uint8_t> buf(12, 0);
    o.in.read(reinterpret_cast<char*>(buf.data()), 12);
    size_t got = static_cast<size_t>(o.in.gcount());
    size_t headerLen = 0;
    if (got >= 10 && std::memcmp(buf.data(), kMagic, kMagicLen) == 0) {
        size_t lenBytes = buf[6] == 1 ? 2 : 4;
        if (got >= 8 + lenBytes) headerLen = readLE(buf.data() + 8, lenBytes);
        size_t want = std::min<size_t>(8 + lenBytes + std::min(headerLen, kMaxHeaderLen + 1),
                                       static_cast<size_t>(size));
        if (want > got) {
            buf.resize(want);
            o.in.read(reinterpret_cast<char*>(buf.data() + got),
                      static_cast<std::streamsize>(want - got));
            got += static_cast<size_t>(o.in.gcount());
        }
    }
    o.header = parseNpyHeader(buf.data(), got, static_cast<size_t>(size), where);
    o.in.clear();
    o.in.seekg(static_cast<std::streamoff>(o.header.dataOffset));
    if (!o.in) throw inputError(where, "cannot seek to the array data");
    return o;
}

template <typename T>
void readConverted(std::ifstream& in, float* out, size_t n, const std::string& where) {
    constexpr size_t kChunk = size_t(1) << 16;
    std::vector<T> buf(std::min(n, kChunk));
    for (size_t done = 0; done < n;) {
        size_t k = std::min(kChunk, n - done);
        in.read(reinterpret_cast<char*>(buf.data()), static_cast<std::streamsize>(k * sizeof(T)));
        if (static_cast<size_t>(in.gcount()) != k * sizeof(T))
            throw inputError(where, "read error in the array data (file shrank or I/O error)");
        for (size_t i = 0; i < k; ++i) out[done + i] = static_cast<float>(buf[i]);
        done += k;
    }
}

}  // namespace

NpyHeader readNpyHeader(const fs::path& file) {
    return openNpy(file).header;
}

NpyMatrix readNpy2D(const fs::path& file) {
    const std::string where = file.string();
    OpenedNpy o = openNpy(file);
    const NpyHeader& h = o.header;
    NpyMatrix m;
    m.rows = static_cast<int>(h.shape[0]);
    m.cols = static_cast<int>(h.shape[1]);
    m.type = h.type;
    m.data.resize(h.elementCount);
    if (h.elementCount == 0) return m;
    switch (h.type) {
        case NpyType::Float32: {
            const auto bytes = static_cast<std::streamsize>(h.elementCount * sizeof(float));
            o.in.read(reinterpret_cast<char*>(m.data.data()), bytes);
            if (o.in.gcount() != bytes)
                throw inputError(where, "read error in the array data (file shrank or I/O error)");
            break;
        }
        case NpyType::Float64:
            readConverted<double>(o.in, m.data.data(), h.elementCount, where);
            break;
        case NpyType::UInt16:
            readConverted<uint16_t>(o.in, m.data.data(), h.elementCount, where);
            break;
    }
    return m;
}

}  // namespace sl
