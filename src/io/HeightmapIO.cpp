#include "io/HeightmapIO.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <new>
#include <system_error>

#include "core/Error.h"
#include "core/Text.h"
#include "io/GwyddionReader.h"
#include "io/ImageFile.h"
#include "io/ImageIO.h"
#include "io/NanoFocusNms.h"
#include "io/Npy.h"
#include "io/Sdf.h"
#include "io/TrueMap.h"
#include "io/X3p.h"

namespace sl {

namespace fs = std::filesystem;

namespace {

const char* const kFixFloat =
    "Save heights as float32 (EXR, TIFF or .npy) or uint16 (PNG, TIFF) and try again";
const char* const kFixDamaged =
    "Check that the file is a complete EXR, TIFF, PNG or .npy file (the format its name "
    "says); save it again";

std::string typeName(const detail::ImageHeader& h) {
    using detail::PixelType;
    if (h.format == PixelType::Half) return "float16";
    if (h.format == PixelType::Float) return "float32";
    if (h.format == PixelType::Double) return "float64";
    if (h.format == PixelType::UInt8) return "uint8";
    if (h.format == PixelType::UInt16) return "uint16";
    return h.formatText;
}

std::string formatShortName(const std::string& oiioName) {
    if (oiioName == "openexr") return "exr";
    return oiioName;
}

/// How raw values (float heights, or integer codes 0..65535) become heights.
struct Mapping {
    bool integer = false;
    double lo = 0.0, hi = 1.0;  // integer maps
    double scale = 1.0;         // float maps
};

void checkOptions(const std::string& where, const HeightmapOptions& opt) {
    if (!std::isfinite(opt.heightScale) || opt.heightScale == 0.0)
        throw inputError(
            where, "heightmap.height_scale = " + std::to_string(opt.heightScale) + " is invalid",
            "Use a finite, non-zero height_scale (1 keeps the file's values)");
    if (opt.heightRange) {
        const auto& r = *opt.heightRange;
        if (!std::isfinite(r[0]) || !std::isfinite(r[1]) || !(r[0] < r[1]))
            throw inputError(where,
                             "heightmap.height_range [" + std::to_string(r[0]) + ", " +
                                 std::to_string(r[1]) + "] is invalid",
                             "Give [min, max] in scene units with min < max");
    }
}

Mapping mappingFor(const std::string& where, const HeightmapOptions& opt, bool integer,
                   const std::string& format) {
    Mapping m;
    m.integer = integer;
    if (integer) {
        const auto range = opt.heightRange ? opt.heightRange : opt.defaultIntegerRange;
        if (!range)
            throw inputError(where,
                             "integer height map needs heightmap.height_range: [min, max] in "
                             "scene units (this map is " +
                                 format + ")",
                             "Add \"height_range\": [min, max] to the scene's heightmap "
                             "section (the file's 0 maps to min, its largest code to max), or "
                             "save float heights");
        if (opt.heightScale != 1.0)
            throw inputError(where,
                             "heightmap.height_scale applies to float height maps only; this "
                             "map is " +
                                 format,
                             "Remove height_scale and put the scale into height_range");
        m.lo = (*range)[0];
        m.hi = (*range)[1];
    } else {
        if (opt.heightRange)
            throw inputError(where,
                             "heightmap.height_range applies to integer (8/16-bit) height maps "
                             "only; this map is " +
                                 format + " and stores heights in scene units",
                             "Remove height_range (use height_scale to scale float heights)");
        m.scale = opt.heightScale;
    }
    return m;
}

void checkSize(const std::string& where, long long w, long long h) {
    if (w < 2 || h < 2)
        throw inputError(where,
                         "height map has " + std::to_string(h) + " rows and " + std::to_string(w) +
                             " columns; a height map must be at least 2x2",
                         "Use a map with at least 2 rows and 2 columns");
}

/// Integer code (0..65535, stored as the value of type T) -> height.
template <typename T>
float integerHeight(const Mapping& m, T code) {
    const double t = static_cast<double>(code) / 65535.0;
    return static_cast<float>(m.lo + (m.hi - m.lo) * t);
}

/// Scales float heights (in double, rounded once) and checks every one is finite; names the
/// first bad sample.
void finishFloat(const std::string& where, HeightmapData& d, double scale) {
    const size_t w = static_cast<size_t>(d.width);
    const bool doScale = scale != 1.0;
    bool bad = false;
    for (float& v : d.heights) {
        if (doScale) v = static_cast<float>(static_cast<double>(v) * scale);
        bad |= !std::isfinite(v);
    }
    if (!bad) return;
    for (size_t k = 0; k < d.heights.size(); ++k) {
        if (std::isfinite(d.heights[k])) continue;
        const std::string what = std::isnan(d.heights[k]) ? "NaN"
                                 : doScale                ? "infinite (height_scale applied)"
                                                          : "infinite";
        throw inputError(where,
                         "height is " + what + " at row " + std::to_string(k / w) + ", column " +
                             std::to_string(k % w) + " (the first such sample)",
                         "Replace NaN/Inf samples (e.g. numpy.nan_to_num) and save the map again");
    }
}

/// Fills the invalid (NaN) points of `d` layer by layer from the valid region: each pass gives
/// every invalid point with a valid 4-neighbour the mean of those neighbours (computed for the
/// whole layer before any of it counts as valid), so the result does not depend on the order
/// of the points. Needs at least one valid point. Returns how many points were filled.
size_t fillInvalid(HeightmapData& d) {
    const size_t w = static_cast<size_t>(d.width), h = static_cast<size_t>(d.height);
    std::vector<float>& z = d.heights;
    // 0 valid, 1 invalid, 2 invalid and in the next layer
    std::vector<uint8_t> state(z.size(), 0);
    size_t invalid = 0;
    for (size_t k = 0; k < z.size(); ++k)
        if (std::isnan(z[k])) {
            state[k] = 1;
            ++invalid;
        }
    if (invalid == 0) return 0;
    d.invalid.assign(z.size(), 0);
    for (size_t k = 0; k < z.size(); ++k) d.invalid[k] = state[k];
    const auto neighbours = [&](size_t k, auto&& f) {
        const size_t i = k % w, j = k / w;
        if (i > 0) f(k - 1);
        if (i + 1 < w) f(k + 1);
        if (j > 0) f(k - w);
        if (j + 1 < h) f(k + w);
    };
    std::vector<size_t> layer, next;
    for (size_t k = 0; k < z.size(); ++k) {
        if (state[k] != 1) continue;
        bool touches = false;
        neighbours(k, [&](size_t n) { touches |= state[n] == 0; });
        if (touches) {
            state[k] = 2;
            layer.push_back(k);
        }
    }
    std::vector<float> values;
    while (!layer.empty()) {
        values.assign(layer.size(), 0.0f);
        for (size_t m = 0; m < layer.size(); ++m) {
            double sum = 0.0;
            int count = 0;
            neighbours(layer[m], [&](size_t n) {
                if (state[n] == 0) {
                    sum += z[n];
                    ++count;
                }
            });
            values[m] = static_cast<float>(sum / count);
        }
        next.clear();
        for (size_t m = 0; m < layer.size(); ++m) {
            z[layer[m]] = values[m];
            state[layer[m]] = 0;
        }
        for (size_t k : layer)
            neighbours(k, [&](size_t n) {
                if (state[n] == 1) {
                    state[n] = 2;
                    next.push_back(n);
                }
            });
        layer.swap(next);
    }
    return invalid;
}

std::string micrometres(double mm) {
    char b[32];
    std::snprintf(b, sizeof b, "%.4g", mm * 1000.0);
    return b;
}

/// Non-square pixels -> the finer pitch, by linear interpolation along the coarser axis
/// (io/HeightmapIO.h); the invalid mask follows (a sample is invented when a source sample
/// with non-zero weight was).
void resampleSquare(const std::string& where, HeightmapData& d) {
    if (!d.pitchY) return;
    const double px = *d.pitch, py = *d.pitchY;
    d.pitchY.reset();
    if (std::abs(px - py) <= 1e-6 * std::max(px, py)) return;
    const double p = std::min(px, py);
    const bool alongY = py > px;  // rows are farther apart than columns: interpolate rows
    const size_t w = static_cast<size_t>(d.width), h = static_cast<size_t>(d.height);
    const size_t n = alongY ? h : w;  // samples along the interpolated axis
    if (n < 2) {  // one row (column): nothing to interpolate, the other axis' pitch holds
        d.pitch = alongY ? px : py;
        return;
    }
    const double ratio = (alongY ? py : px) / p;
    if (ratio - 1.0 <= detail::kSquarePitchTolerance) {
        // Pitches a hair apart (an instrument's calibration, e.g. 19.57 x 19.58 nm): within
        // what a calibration knows, so interpolating would only blur the map; its samples are
        // kept and called square at the finer pitch.
        d.resampling = std::to_string(w) + "x" + std::to_string(h) + " samples of " +
                       micrometres(px) + " x " + micrometres(py) + " um read as square at " +
                       micrometres(p) + " um (the pitches differ by " +
                       formatNumber(100.0 * (ratio - 1.0), 2) + " %, within the " +
                       formatNumber(100.0 * detail::kSquarePitchTolerance) +
                       " % read as square: no interpolation)";
        d.pitch = p;
        return;
    }
    // Real instruments differ by a few times at most (a line scanner's profiles perhaps 100);
    // a 124-byte file with a 1e7 ratio made 1.6 GB of interpolated points (scripts/fuzz).
    if (!(ratio <= 1000))
        throw inputError(where,
                         "its x and y pitches (" + micrometres(px) + " and " + micrometres(py) +
                             " um) differ more than 1000-fold: square pixels would stretch it " +
                             formatNumber(ratio) + " times",
                         "Check the file's pitches (a damaged header?)");
    // Counted in double first: a pitch ratio of 1e70 (a damaged file) must be refused, not
    // converted to size_t (undefined; found by scripts/fuzz).
    const double along = std::floor(static_cast<double>(n - 1) * ratio + 1e-9) + 1;
    const double points = along * static_cast<double>(alongY ? w : h);
    if (!(points <= static_cast<double>(detail::kMaxMetrologySamples)))
        throw inputError(where,
                         "resampled to square pixels the map would have " + formatNumber(points) +
                             " points, more than the " +
                             std::to_string(detail::kMaxMetrologySamples) + " accepted",
                         "Crop the measurement");
    const auto m = static_cast<size_t>(along);
    const size_t nw = alongY ? w : m, nh = alongY ? m : h;
    std::vector<float> out(nw * nh);
    std::vector<uint8_t> bad(d.invalid.empty() ? 0 : nw * nh);
    for (size_t k = 0; k < m; ++k) {
        const double pos = static_cast<double>(k) / ratio;
        size_t k0 = static_cast<size_t>(std::floor(pos));
        if (k0 > n - 2) k0 = n - 2;
        const double t = std::clamp(pos - static_cast<double>(k0), 0.0, 1.0);
        const size_t others = alongY ? w : h;
        for (size_t o = 0; o < others; ++o) {
            const size_t a = alongY ? k0 * w + o : o * w + k0;
            const size_t b = alongY ? a + w : a + 1;
            const size_t to = alongY ? k * nw + o : o * nw + k;
            out[to] = static_cast<float>((1.0 - t) * d.heights[a] + t * d.heights[b]);
            if (!bad.empty())
                bad[to] =
                    static_cast<uint8_t>((t < 1.0 && d.invalid[a]) || (t > 0.0 && d.invalid[b]));
        }
    }
    d.resampling = std::to_string(w) + "x" + std::to_string(h) + " samples of " + micrometres(px) +
                   " x " + micrometres(py) + " um resampled to " + std::to_string(nw) + "x" +
                   std::to_string(nh) + " of " + micrometres(p) +
                   " um (linear interpolation along " + (alongY ? "y" : "x") +
                   " onto the finer pitch)";
    d.width = static_cast<int>(nw);
    d.height = static_cast<int>(nh);
    d.heights = std::move(out);
    d.invalid = std::move(bad);
    d.pitch = p;
}

/// Crops `d` (NaN for invalid points) to the bounding box of its valid points: the border rows
/// and columns that hold none (a part smaller than the instrument's field, a round field on a
/// rectangular sensor) are not the part, and filling them would invent it. Says so among the
/// warnings (the map's grid is no longer the file's). Needs at least one valid point.
void cropToValid(HeightmapData& d) {
    const int w = d.width, h = d.height;
    int x0 = w, x1 = -1, y0 = h, y1 = -1;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            if (!std::isnan(d.heights[static_cast<size_t>(y) * w + x])) {
                x0 = std::min(x0, x), x1 = std::max(x1, x);
                y0 = std::min(y0, y), y1 = std::max(y1, y);
            }
    if (x1 < 0 || (x0 == 0 && y0 == 0 && x1 == w - 1 && y1 == h - 1)) return;
    const int cw = x1 - x0 + 1, ch = y1 - y0 + 1;
    std::vector<float> z(static_cast<size_t>(cw) * static_cast<size_t>(ch));
    for (int y = 0; y < ch; ++y)
        std::copy_n(d.heights.begin() + (static_cast<ptrdiff_t>(y0 + y) * w + x0), cw,
                    z.begin() + static_cast<ptrdiff_t>(y) * cw);
    d.warnings.push_back("more than half of its " + std::to_string(w) + "x" + std::to_string(h) +
                         " points are invalid: read as the columns " + std::to_string(x0) + ".." +
                         std::to_string(x1) + " and rows " + std::to_string(y0) + ".." +
                         std::to_string(y1) +
                         " that hold every valid point (a mask or labels drawn on the file's "
                         "grid no longer line up)");
    d.heights = std::move(z);
    d.width = cw;
    d.height = ch;
}

/// Measured maps (X3P, SDF, Gwyddion): heights in mm with NaN for invalid points -> checked,
/// (cropped to their valid points when more than half are invalid,) filled, square, scaled
/// heights.
HeightmapData finishMetrology(const std::string& where, HeightmapData d,
                              const HeightmapOptions& opt) {
    checkSize(where, d.width, d.height);
    const Mapping m = mappingFor(where, opt, false, d.format);
    // NaN, and +-Inf as some instruments mark an unmeasured point (Alicona's X3P export):
    // both are invalid points, filled below.
    size_t invalid = 0;
    for (float& v : d.heights)
        if (!std::isfinite(v)) {
            v = std::numeric_limits<float>::quiet_NaN();
            ++invalid;
        }
    const size_t n = d.heights.size();
    if (invalid == n)
        throw inputError(where, "every point of the height map is invalid (" + d.format + ")",
                         "Export a measurement that has valid points");
    if (invalid > n / 2) {
        cropToValid(d);
        checkSize(where, d.width, d.height);
        // the crop drops only invalid points: the invalid ones left follow from the sizes
        const size_t kept = d.heights.size();
        const size_t stillInvalid = invalid - (n - kept);
        if (stillInvalid > kept / 2)
            throw inputError(
                where,
                std::to_string(invalid) + " of " + std::to_string(n) +
                    " points are invalid (NaN, infinite or masked), more than half" +
                    (kept < n ? ", also within the " + std::to_string(d.width) + "x" +
                                    std::to_string(d.height) + " box that holds the valid ones"
                              : std::string()) +
                    "; the height map would be mostly invented",
                "Crop the measurement to its valid region and export it again");
    }
    d.invalidFilled = fillInvalid(d);
    if (d.invalidFilled > 0)
        d.format += ", " + std::to_string(d.invalidFilled) + " invalid points filled";
    resampleSquare(where, d);
    finishFloat(where, d, m.scale);
    return d;
}

HeightmapData loadNpy(const fs::path& file, const HeightmapOptions& opt) {
    const std::string where = file.string();
    const NpyHeader h = readNpyHeader(file);
    const bool integer = h.type == NpyType::UInt16;
    const std::string format = std::string("npy ") + npyTypeName(h.type);
    checkSize(where, static_cast<long long>(h.shape[1]), static_cast<long long>(h.shape[0]));
    const Mapping m = mappingFor(where, opt, integer, format);

    NpyMatrix mat = readNpy2D(file);
    HeightmapData d;
    d.width = mat.cols;
    d.height = mat.rows;
    d.format = format;
    d.heights = std::move(mat.data);
    if (integer) {
        for (float& v : d.heights) v = integerHeight(m, v);
    } else {
        finishFloat(where, d, m.scale);
    }
    return d;
}

/// Copies channel 0 of a strip of interleaved pixels into `out` (packed T values, written with
/// memcpy because `out` may be the float buffer's storage), after checking that the other
/// colour channels equal channel 0 and that alpha (if any) is opaque.
template <typename T>
void takeGrayChannel(const std::string& where, const T* strip, size_t pixels, int nch, int alpha,
                     T opaque, int firstRow, int width, unsigned char* out) {
    for (size_t p = 0; p < pixels; ++p) {
        const T* px = strip + p * static_cast<size_t>(nch);
        for (int c = 1; c < nch; ++c) {
            const bool ok = c == alpha ? px[c] == opaque
                                       : (px[c] == px[0] || (px[c] != px[c] && px[0] != px[0]));
            if (!ok) {
                const size_t row = static_cast<size_t>(firstRow) + p / static_cast<size_t>(width);
                const size_t col = p % static_cast<size_t>(width);
                if (c == alpha)
                    throw inputError(where,
                                     "height map has transparent pixels (first at row " +
                                         std::to_string(row) + ", column " + std::to_string(col) +
                                         ")",
                                     "Save the heights as one opaque gray channel");
                throw inputError(where,
                                 "height map has " + std::to_string(nch) +
                                     " channels that differ (first at row " + std::to_string(row) +
                                     ", column " + std::to_string(col) + ", channel " +
                                     std::to_string(c) + "); a height map has one channel",
                                 "Save the heights as a single-channel (gray) image");
            }
        }
        std::memcpy(out + p * sizeof(T), px, sizeof(T));
    }
}

HeightmapData loadWithOiio(const fs::path& file, const HeightmapOptions& opt) {
    const std::string where = file.string();
    auto in = detail::openImageFile(file, kFixDamaged);
    const detail::ImageHeader& spec = in->header();
    const std::string fmtName = formatShortName(in->formatName());
    if (spec.deep || spec.depth > 1)
        throw inputError(where, "deep or volume images cannot be height maps", kFixFloat);
    checkSize(where, spec.width, spec.height);
    detail::checkImageSize(file, spec);

    using detail::PixelType;
    const PixelType native = spec.format;
    const bool isFloat =
        native == PixelType::Half || native == PixelType::Float || native == PixelType::Double;
    const bool isInt = native == PixelType::UInt8 || native == PixelType::UInt16;
    const std::string format = fmtName + " " + typeName(spec);
    if (!isFloat && !isInt)
        throw inputError(where, "unsupported pixel type " + typeName(spec) + " (" + format + ")",
                         kFixFloat);
    const Mapping m = mappingFor(where, opt, isInt, format);

    HeightmapData d;
    d.width = spec.width;
    d.height = spec.height;
    d.format = format;
    const size_t n = static_cast<size_t>(spec.width) * static_cast<size_t>(spec.height);
    try {
        d.heights.resize(n);
    } catch (const std::bad_alloc&) {
        throw inputError(where, "not enough memory for a " + std::to_string(spec.width) + "x" +
                                    std::to_string(spec.height) + " height map");
    }
    // Integers are read as UINT16 (OIIO scales uint8 by 257, exactly: v/255 == 257v/65535) and
    // mapped by us in double; OIIO's own uint16 -> float conversion is not correctly rounded.
    const PixelType readAs = isInt ? PixelType::UInt16 : PixelType::Float;
    const size_t readSize = detail::pixelTypeSize(readAs);
    const int nch = spec.nchannels;

    // Bands of rows (io/ImageFile.h readBands), channel 0 into the heights; uint16 codes are
    // stored packed at the front of the float buffer and widened below.
    unsigned char* bytes = reinterpret_cast<unsigned char*>(d.heights.data());
    const size_t w = static_cast<size_t>(spec.width);
    detail::readBands(*in, file, readAs, kFixDamaged, [&](int y0, int y1, const void* values) {
        const size_t px = static_cast<size_t>(y1 - y0) * w, off = static_cast<size_t>(y0) * w;
        if (nch == 1)
            std::memcpy(bytes + off * readSize, values, px * readSize);
        else if (isInt)
            takeGrayChannel<uint16_t>(where, static_cast<const uint16_t*>(values), px, nch,
                                      spec.alphaChannel, uint16_t(65535), y0, spec.width,
                                      bytes + off * sizeof(uint16_t));
        else
            takeGrayChannel<float>(where, static_cast<const float*>(values), px, nch,
                                   spec.alphaChannel, 1.0f, y0, spec.width,
                                   bytes + off * sizeof(float));
    });
    in->close();

    if (isInt) {
        detail::widenInPlace<uint16_t>(d.heights.data(), n,
                                       [&m](uint16_t v, size_t) { return integerHeight(m, v); });
    } else {
        finishFloat(where, d, m.scale);
    }
    return d;
}

/// What a file's first bytes say it is.
enum class Content { Npy, Zip, Sdf, TrueMap, Nms, Image, Unknown };

Content sniff(const fs::path& file) {
    unsigned char b[kNmsNameOffset + kNmsNameLength] = {};
    size_t got = 0;
    if (FILE* f = std::fopen(file.c_str(), "rb")) {
        got = std::fread(b, 1, sizeof b, f);
        std::fclose(f);
    }
    const auto starts = [&](const char* magic, size_t len, size_t at = 0) {
        return got >= at + len && std::memcmp(b + at, magic, len) == 0;
    };
    if (starts("\x93NUMPY", 6)) return Content::Npy;
    if (starts("PK\x03\x04", 4)) return Content::Zip;
    if (starts("aBCR-", 5) || starts("bBCR-", 5) || starts("aISO-", 5) || starts("bISO-", 5))
        return Content::Sdf;
    if (starts(kTrueMapMagic, kTrueMapMagicLength)) return Content::TrueMap;
    if (starts(kNmsName, kNmsNameLength, kNmsNameOffset)) return Content::Nms;
    if (starts("\x76\x2f\x31\x01", 4) || starts("\x89PNG", 4) || starts("II*\0", 4) ||
        starts("MM\0*", 4) || starts("\xff\xd8\xff", 3))
        return Content::Image;
    return Content::Unknown;
}

}  // namespace

namespace {

HeightmapData loadAnyHeightmap(const fs::path& file, const HeightmapOptions& opt,
                               HeightmapReader reader) {
    const std::string where = file.string();
    checkOptions(where, opt);
    std::error_code ec;
    if (!fs::exists(file, ec))
        throw inputError(where, "height map file not found",
                         "Check heightmap.path (relative paths are resolved against the scene "
                         "file's directory)");
    if (!fs::is_regular_file(file, ec))
        throw inputError(where, "the height map path is not a regular file",
                         "Point heightmap.path at an EXR, TIFF, PNG, .npy, X3P or SDF file");
    if (reader == HeightmapReader::Gwyddion)
        return finishMetrology(where, readGwyddion(file, opt.channel), opt);
    const std::string ext = lower(file.extension().string());
    switch (sniff(file)) {
        case Content::Npy:
            return loadNpy(file, opt);
        case Content::Sdf:
            return finishMetrology(where, readSdf(file), opt);
        case Content::TrueMap:
            return finishMetrology(where, readTrueMap(file), opt);
        case Content::Nms:
            return finishMetrology(where, readNanoFocusNms(file), opt);
        case Content::Image:
            return loadWithOiio(file, opt);
        case Content::Zip:
            if (ext == ".x3p" || !gwyddionBuilt())
                return finishMetrology(where, readX3p(file), opt);
            // A zip named otherwise: an X3P, else one of the zip-based instrument formats.
            try {
                return finishMetrology(where, readX3p(file), opt);
            } catch (const InputError&) {
                if (gwyddionDetect(file).empty()) throw;
            }
            return finishMetrology(where, readGwyddion(file, opt.channel), opt);
        case Content::Unknown:
            break;
    }
    // The content says nothing we know: a damaged file of the format its name says keeps that
    // format's error; anything else is Gwyddion's if one of its file modules claims it.
    if (ext == ".npy") return loadNpy(file, opt);
    if (ext == ".x3p") return finishMetrology(where, readX3p(file), opt);
    if (ext == ".sdf") return finishMetrology(where, readSdf(file), opt);
    if (ext == ".tmd") return finishMetrology(where, readTrueMap(file), opt);
    if (ext == ".nms") return finishMetrology(where, readNanoFocusNms(file), opt);
    const bool image = ext == ".exr" || ext == ".tif" || ext == ".tiff" || ext == ".png" ||
                       ext == ".jpg" || ext == ".jpeg" || ext == ".hdr";
    if (image) return loadWithOiio(file, opt);
    if (!gwyddionDetect(file).empty())
        return finishMetrology(where, readGwyddion(file, opt.channel), opt);
    try {
        return loadWithOiio(file, opt);  // an image format named otherwise
    } catch (const InputError&) {
        // No reader claims it: say which readers there are, and whether Gwyddion's are among them.
        if (gwyddionBuilt())
            throw inputError(where,
                             "no reader claims this file: it is not an image (EXR, TIFF, PNG), "
                             ".npy, X3P, SDF, TrueMap .tmd or NanoFocus .nms, and none of "
                             "Gwyddion's file modules reads it",
                             "Check that the file is whole, or export it from the instrument's "
                             "software as X3P or SDF");
        throw inputError(where,
                         "no reader claims this file: it is not an image (EXR, TIFF, PNG), .npy, "
                         "X3P, SDF, TrueMap .tmd or NanoFocus .nms, and this scratchlight was "
                         "built without Gwyddion "
                         "(SCRATCHLIGHT_GWYDDION=OFF), whose file modules read instrument "
                         "formats (.opd, .plu, .sur, .dat, ...)",
                         "Build scratchlight with -DSCRATCHLIGHT_GWYDDION=ON, or export the file "
                         "from the instrument's software as X3P or SDF");
    }
}

}  // namespace

HeightmapData loadHeightmap(const fs::path& file, const HeightmapOptions& opt,
                            HeightmapReader reader) {
    HeightmapData d = loadAnyHeightmap(file, opt, reader);
    // Our own readers' files hold one height channel: a channel asked of one is a mistake.
    // (Gwyddion says which channel it read whenever one is asked for: HeightmapData::channel.)
    if (!opt.channel.empty() && d.channel.empty())
        throw inputError("heightmap.channel",
                         "\"" + opt.channel + "\" asks for a channel of " + file.string() + " (" +
                             d.format + "), which holds one height map",
                         "Remove heightmap.channel; it chooses among an instrument file's "
                         "channels read through Gwyddion");
    return d;
}

}  // namespace sl
