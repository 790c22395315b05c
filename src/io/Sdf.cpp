#include "io/Sdf.h"

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <new>
#include <string>
#include <system_error>
#include <vector>

#include "core/Error.h"
#include "core/Text.h"
#include "io/ByteOrder.h"

namespace sl {

namespace fs = std::filesystem;

namespace {

const char* const kFixDamaged = "The SDF file is damaged or truncated; export it again";
const char* const kFixSave =
    "Export the measurement as an uncompressed SDF (or X3P, EXR, .npy) and try again";

constexpr size_t kBinaryHeader = 8 + 10 + 12 + 12 + 2 + 2 + 4 * 8 + 3;  // 81 bytes

/// One SDF data type (Gwyddion's codes, io/HeightmapIO.h).
struct SdfType {
    const char* name;
    size_t bytes;
    bool isFloat, isSigned;
    bool hasSentinel;
    double sentinel;  // the value that marks an invalid point (integer types)
};

const SdfType kTypes[] = {
    {"uint8", 1, false, false, false, 0.0},
    {"uint16", 2, false, false, true, 65535.0},
    {"uint32", 4, false, false, true, 4294967295.0},
    {"float32", 4, true, true, false, 0.0},
    {"int8", 1, false, true, false, 0.0},
    {"int16", 2, false, true, true, -32768.0},
    {"int32", 4, false, true, true, -2147483648.0},
    {"float64", 8, true, true, false, 0.0},
};

std::string trim(std::string_view s) {
    const auto b = s.find_first_not_of(" \t\r\n");
    if (b == std::string_view::npos) return {};
    const auto e = s.find_last_not_of(" \t\r\n");
    return std::string(s.substr(b, e - b + 1));
}

bool parseDouble(std::string_view t, double& v) {
    const char* b = t.data();
    const char* e = t.data() + t.size();
    if (b != e && *b == '+') ++b;
    const auto r = std::from_chars(b, e, v);
    return r.ec == std::errc() && r.ptr == e;
}

/// Little-endian value of type `t` at `p`, as double.
double decode(const SdfType& t, const unsigned char* p) {
    const uint64_t u = loadLittleEndian(p, static_cast<int>(t.bytes));
    if (t.isFloat)
        return t.bytes == 4 ? static_cast<double>(std::bit_cast<float>(static_cast<uint32_t>(u)))
                            : std::bit_cast<double>(u);
    if (!t.isSigned) return static_cast<double>(u);
    switch (t.bytes) {
        case 1:
            return std::bit_cast<int8_t>(static_cast<uint8_t>(u));
        case 2:
            return std::bit_cast<int16_t>(static_cast<uint16_t>(u));
        default:
            return std::bit_cast<int32_t>(static_cast<uint32_t>(u));
    }
}

class SdfReader {
  public:
    explicit SdfReader(const fs::path& file) : file_(file), where_(file.string()) {}

    HeightmapData read() {
        load();
        if (bytes_.size() < 8) fail("the file is too short for an SDF header", kFixDamaged);
        const std::string version(bytes_.begin(), bytes_.begin() + 8);
        const std::string rest = version.substr(1);
        if ((version[0] != 'a' && version[0] != 'b') ||
            (rest != "BCR-1.0" && rest != "BCR-0.0" && rest != "ISO-1.0"))
            fail(
                "does not start with an SDF version (aBCR-1.0, bBCR-1.0, aISO-1.0 or bISO-1.0); "
                "it starts with '" +
                    printable(version) + "'",
                "Check that the file is an SDF surface data file");
        binary_ = version[0] == 'b';
        return binary_ ? readBinary(version) : readAscii(version);
    }

  private:
    [[noreturn]] void fail(const std::string& problem, const std::string& fix = kFixSave) const {
        throw inputError(where_, problem, fix);
    }
    static std::string printable(const std::string& s) {
        std::string o;
        for (char c : s) o += (c >= 32 && c < 127) ? c : '?';
        return o;
    }

    void load() {
        std::error_code ec;
        const auto size = fs::file_size(file_, ec);
        if (ec) fail("cannot read the file: " + ec.message(), kFixDamaged);
        std::ifstream in(file_, std::ios::binary);
        if (!in) fail("cannot open the file", "Check the file's permissions");
        try {
            bytes_.resize(static_cast<size_t>(size));
        } catch (const std::bad_alloc&) {
            fail("not enough memory to read the file (" + std::to_string(size) + " bytes)");
        }
        in.read(reinterpret_cast<char*>(bytes_.data()), static_cast<std::streamsize>(size));
        if (static_cast<uintmax_t>(in.gcount()) != size)
            fail("cannot read the file (it changed while reading?)", kFixDamaged);
    }

    /// Checks the header's values (shared by both variants); sets type_, w_, h_, pitchMm_.
    void checkHeader(long long points, long long profiles, double xs, double ys, double zs,
                     long long compression, long long dataType) {
        if (compression != 0)
            fail("Compression = " + std::to_string(compression) +
                 " is unsupported (only uncompressed SDF, Compression = 0, is read)");
        if (dataType < 0 || dataType > 7)
            fail("DataType = " + std::to_string(dataType) +
                 " is unknown (0 uint8, 1 uint16, 2 uint32, 3 float32, 4 int8, 5 int16, 6 "
                 "int32, 7 float64)");
        type_ = &kTypes[dataType];
        if (points < 1 || profiles < 1)
            fail("NumPoints = " + std::to_string(points) +
                     ", NumProfiles = " + std::to_string(profiles) + ": both must be at least 1",
                 kFixDamaged);
        if (points > detail::kMaxMetrologySide || profiles > detail::kMaxMetrologySide ||
            points * profiles > detail::kMaxMetrologySamples)
            fail("NumPoints x NumProfiles = " + std::to_string(points) + " x " +
                     std::to_string(profiles) + " is larger than the " +
                     std::to_string(detail::kMaxMetrologySamples) + " points accepted",
                 "Crop or resample the measurement");
        w_ = points;
        h_ = profiles;
        if (!(std::isfinite(xs) && xs > 0) || !(std::isfinite(ys) && ys > 0))
            fail("Xscale and Yscale (the sample spacing in m) must be > 0; they are " +
                     std::to_string(xs) + " and " + std::to_string(ys),
                 kFixDamaged);
        if (!std::isfinite(zs) || zs == 0.0)
            fail("Zscale = " + std::to_string(zs) + " must be finite and non-zero", kFixDamaged);
        pitchMm_ = xs * 1000.0;
        pitchYMm_ = ys * 1000.0;  // loadHeightmap resamples non-square pixels
        zScaleMm_ = zs * 1000.0;
    }

    HeightmapData start(const std::string& variant) {
        HeightmapData d;
        d.width = static_cast<int>(w_);
        d.height = static_cast<int>(h_);
        d.pitch = pitchMm_;
        if (pitchYMm_ != pitchMm_) d.pitchY = pitchYMm_;
        d.format = "sdf " + variant + " " + type_->name;
        try {
            d.heights.resize(static_cast<size_t>(w_ * h_));
        } catch (const std::bad_alloc&) {
            fail("not enough memory for a " + std::to_string(w_) + "x" + std::to_string(h_) +
                 " height map");
        }
        return d;
    }

    float height(double v) const {
        if (std::isnan(v) || (type_->hasSentinel && v == type_->sentinel))
            return std::numeric_limits<float>::quiet_NaN();
        return static_cast<float>(v * zScaleMm_);
    }

    HeightmapData readBinary(const std::string& version) {
        if (bytes_.size() < kBinaryHeader)
            fail("the file is " + std::to_string(bytes_.size()) +
                     " bytes, shorter than the 81-byte binary SDF header",
                 kFixDamaged);
        const unsigned char* p = bytes_.data() + 8 + 10 + 12 + 12;
        const auto u16 = [&]() {
            const uint16_t v = loadU16(p);
            p += 2;
            return v;
        };
        const auto f64 = [&]() {
            const double v = loadF64(p);
            p += 8;
            return v;
        };
        const long long points = u16(), profiles = u16();
        const double xs = f64(), ys = f64(), zs = f64();
        f64();  // Zresolution: informative
        const long long compression = p[0], dataType = p[1];
        checkHeader(points, profiles, xs, ys, zs, compression, dataType);
        const uint64_t need = static_cast<uint64_t>(w_ * h_) * type_->bytes;
        if (bytes_.size() - kBinaryHeader < need)
            fail("the data is truncated: NumPoints x NumProfiles = " + std::to_string(w_) + " x " +
                     std::to_string(h_) + " " + type_->name + " values need " +
                     std::to_string(need) + " bytes after the header, the file has " +
                     std::to_string(bytes_.size() - kBinaryHeader),
                 kFixDamaged);
        HeightmapData d = start(std::string("binary (") + version + ")");
        const unsigned char* data = bytes_.data() + kBinaryHeader;
        for (size_t k = 0; k < d.heights.size(); ++k)
            d.heights[k] = height(decode(*type_, data + k * type_->bytes));
        return d;
    }

    HeightmapData readAscii(const std::string& version) {
        const std::string_view text(reinterpret_cast<const char*>(bytes_.data()), bytes_.size());
        size_t pos = text.find('\n');
        if (pos == std::string_view::npos) fail("the header has no end (no '*' line)", kFixDamaged);
        ++pos;
        std::map<std::string, std::string> fields;  // lower-case key -> value
        bool star = false;
        while (pos < text.size()) {
            size_t end = text.find('\n', pos);
            if (end == std::string_view::npos) end = text.size();
            const std::string line = trim(text.substr(pos, end - pos));
            pos = std::min(end + 1, text.size());
            if (line.empty() || line[0] == ';') continue;
            if (line[0] == '*') {
                star = true;
                break;
            }
            size_t sep = line.find('=');
            if (sep == std::string::npos) sep = line.find_first_of(" \t");
            if (sep == std::string::npos) continue;
            fields[lower(trim(std::string_view(line).substr(0, sep)))] =
                trim(std::string_view(line).substr(sep + 1));
        }
        if (!star) fail("the header has no end (no line '*' before the data)", kFixDamaged);
        const auto field = [&](const char* key, bool required, double def) {
            const auto it = fields.find(lower(key));
            if (it == fields.end()) {
                if (required) fail(std::string("the header has no ") + key, kFixDamaged);
                return def;
            }
            double v = 0.0;
            if (!parseDouble(it->second, v) || !std::isfinite(v))
                fail(std::string(key) + " = '" + it->second + "' is not a number", kFixDamaged);
            return v;
        };
        const auto integer = [&](const char* key, bool required, double def) {
            const double v = field(key, required, def);
            if (v != std::floor(v) || std::abs(v) > 1e12)
                fail(std::string(key) + " = " + std::to_string(v) + " is not an integer",
                     kFixDamaged);
            return static_cast<long long>(v);
        };
        const long long points = integer("NumPoints", true, 0);
        const long long profiles = integer("NumProfiles", true, 0);
        const double xs = field("Xscale", true, 0), ys = field("Yscale", true, 0);
        const double zs = field("Zscale", true, 0);
        const long long compression = integer("Compression", false, 0);
        const long long dataType = integer("DataType", true, 0);
        checkHeader(points, profiles, xs, ys, zs, compression, dataType);
        // Every value takes at least two characters (a digit and a separator).
        if (2 * static_cast<uint64_t>(w_ * h_) > text.size() - pos + 1)
            fail("the data is truncated: NumPoints x NumProfiles = " + std::to_string(w_ * h_) +
                     " values cannot fit in the " + std::to_string(text.size() - pos) +
                     " bytes after the header",
                 kFixDamaged);

        HeightmapData d = start(std::string("ascii (") + version + ")");
        const auto isSpace = [](char c) {
            return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == ',';
        };
        for (size_t k = 0; k < d.heights.size(); ++k) {
            while (pos < text.size() && isSpace(text[pos])) ++pos;
            size_t end = pos;
            while (end < text.size() && !isSpace(text[end])) ++end;
            const std::string_view tok = text.substr(pos, end - pos);
            if (tok.empty() || tok[0] == '*')
                fail("the data is truncated: " + std::to_string(k) + " values of NumPoints x " +
                         "NumProfiles = " + std::to_string(w_) + " x " + std::to_string(h_),
                     kFixDamaged);
            double v = 0.0;
            if (!parseDouble(tok, v))
                fail("value " + std::to_string(k) + " (profile " + std::to_string(k / w_) +
                         ", point " + std::to_string(k % w_) + ") '" +
                         printable(std::string(tok.substr(0, 40))) + "' is not a number",
                     kFixDamaged);
            d.heights[k] = height(v);
            pos = end;
        }
        while (pos < text.size() && isSpace(text[pos])) ++pos;
        if (pos < text.size() && text[pos] != '*')
            fail("more values than NumPoints x NumProfiles = " + std::to_string(w_) + " x " +
                     std::to_string(h_) + " before the end marker '*'",
                 kFixDamaged);
        return d;
    }

    fs::path file_;
    std::string where_;
    std::vector<unsigned char> bytes_;
    bool binary_ = false;
    const SdfType* type_ = nullptr;
    long long w_ = 0, h_ = 0;
    double pitchMm_ = 0.0, pitchYMm_ = 0.0, zScaleMm_ = 1000.0;
};

}  // namespace

HeightmapData readSdf(const fs::path& file) {
    return SdfReader(file).read();
}

}  // namespace sl
