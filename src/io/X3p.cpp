#include "io/X3p.h"

#include <zip.h>

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <limits>
#include <memory>
#include <mutex>
#include <new>
#include <pugixml.hpp>
#include <sstream>
#include <string>
#include <system_error>
#include <thread>
#include <utility>
#include <vector>

#include "core/Error.h"
#include "core/Md5.h"
#include "core/Text.h"
#include "io/AtomicFile.h"
#include "io/ByteOrder.h"

namespace sl {

namespace fs = std::filesystem;

namespace {

const char* const kFixSave =
    "Save the measurement again as an X3P surface (FeatureType SUR, incremental X and Y axes, "
    "binary data), or export it as SDF, EXR or .npy";
const char* const kFixDamaged = "The X3P file is damaged; export it again";

/// Uncompressed bytes per compressed byte above which a zip member's declared size is not
/// believed (deflate packs at most 1032; stored members have ratio 1).
constexpr uint64_t kMaxInflateRatio = 1100;
constexpr uint64_t kMaxXmlBytes = uint64_t(64) << 20;

// Float heights (F, D) and CZ/Increment. ISO 5436-2 scales integer codes by the increment; for
// float data the readers disagree: Gwyddion applies it, x3ptools (which writes most float X3P
// files: the CSAFE bullet-land and logo samples) reads the floats as metres and ignores it, and
// its older writer left Increment 1e-06 beside heights already in metres. When the increment
// would shrink a relief that is plausible in metres (kMinRawReliefM..kMaxRawReliefM) below any
// instrument's vertical resolution (kMinReliefM), the floats are read as stored, with a warning.
constexpr double kMinReliefM = 1e-10;    // 0.1 nm peak to valley: below it, no measured part
constexpr double kMinRawReliefM = 1e-9;  // 1 nm
constexpr double kMaxRawReliefM = 1e-2;  // 10 mm

/// Bytes inflated per read of a member: the piece the MD5 thread can take while the next is
/// inflated.
constexpr size_t kReadPieceBytes = size_t(4) << 20;

/// The MD5 of a buffer computed on a second thread while the buffer is being filled, so that
/// verifying a member's checksum costs no time beyond inflating it (MD5 runs at ~0.7 GB/s,
/// inflate at a similar rate: one after the other they took twice as long). filled(n) says the
/// first n bytes are final; hex(n) waits for the digest of the first n.
class Md5WhileFilling {
  public:
    explicit Md5WhileFilling(const unsigned char* data) : data_(data), worker_([this] { run(); }) {}
    Md5WhileFilling(const Md5WhileFilling&) = delete;
    Md5WhileFilling& operator=(const Md5WhileFilling&) = delete;
    ~Md5WhileFilling() {
        stop();  // a member that failed to read: the thread ends without a digest
    }

    void filled(size_t bytes) {
        {
            const std::lock_guard<std::mutex> lock(mutex_);
            filled_ = bytes;
        }
        wake_.notify_one();
    }

    std::string hex(size_t bytes) {
        filled(bytes);
        stop();
        return md5_.hex();
    }

  private:
    void stop() {
        {
            const std::lock_guard<std::mutex> lock(mutex_);
            last_ = true;
        }
        wake_.notify_one();
        if (worker_.joinable()) worker_.join();
    }

    void run() {
        size_t hashed = 0;
        for (;;) {
            size_t upTo = 0;
            bool last = false;
            {
                std::unique_lock<std::mutex> lock(mutex_);
                wake_.wait(lock, [&] { return filled_ > hashed || last_; });
                upTo = filled_;
                last = last_;
            }
            if (upTo > hashed) {
                md5_.update(data_ + hashed, upTo - hashed);
                hashed = upTo;
            } else if (last) {
                return;
            }
        }
    }

    const unsigned char* data_;
    Md5 md5_;
    std::mutex mutex_;
    std::condition_variable wake_;
    size_t filled_ = 0;
    bool last_ = false;
    std::thread worker_;  // last: started once the members above exist
};

struct ZipCloser {
    void operator()(zip_t* z) const { zip_discard(z); }
};
struct ZipFileCloser {
    void operator()(zip_file_t* f) const { zip_fclose(f); }
};

std::string trim(const char* s) {
    std::string t = s ? s : "";
    const auto b = t.find_first_not_of(" \t\r\n");
    if (b == std::string::npos) return {};
    const auto e = t.find_last_not_of(" \t\r\n");
    return t.substr(b, e - b + 1);
}

class X3pReader {
  public:
    explicit X3pReader(const fs::path& file) : file_(file), where_(file.string()) {}

    HeightmapData read() {
        open();
        parseXml();
        return readData();
    }

  private:
    [[noreturn]] void fail(const std::string& problem, const std::string& fix = kFixSave) const {
        throw inputError(where_, problem, fix);
    }
    /// main.xml's element at `path` (below the root), or nullptr.
    pugi::xml_node node(const char* path) const { return root_.first_element_by_path(path); }
    std::string text(const char* path, bool required = true) const {
        const pugi::xml_node n = node(path);
        if (!n) {
            if (required) fail(std::string("main.xml has no ") + path);
            return {};
        }
        return trim(n.child_value());
    }
    double number(const char* path, double def, bool required = false) const {
        const std::string t = text(path, required);
        if (t.empty()) {
            if (required) fail(std::string("main.xml: ") + path + " is empty");
            return def;
        }
        const char* b = t.data();
        if (*b == '+') ++b;
        double v = 0.0;
        const auto r = std::from_chars(b, t.data() + t.size(), v);
        if (r.ec != std::errc() || r.ptr != t.data() + t.size() || !std::isfinite(v))
            fail(std::string("main.xml: ") + path + " = '" + t + "' is not a finite number",
                 kFixDamaged);
        return v;
    }
    long long count(const char* path) const {
        const std::string t = text(path);
        long long v = 0;
        const auto r = std::from_chars(t.data(), t.data() + t.size(), v);
        if (r.ec != std::errc() || r.ptr != t.data() + t.size() || v < 1)
            fail(std::string("main.xml: ") + path + " = '" + t + "' is not a positive integer",
                 kFixDamaged);
        return v;
    }

    void open() {
        int err = 0;
        zip_t* z = zip_open(file_.c_str(), ZIP_RDONLY, &err);
        if (!z) {
            zip_error_t ze;
            zip_error_init_with_code(&ze, err);
            const std::string msg = zip_error_strerror(&ze);
            zip_error_fini(&ze);
            fail("not a readable X3P file (an X3P file is a zip archive): " + msg,
                 "Check that the file is a complete .x3p file; export it again");
        }
        zip_.reset(z);
    }

    /// Where main.xml is: the archive's root, or one folder that holds it (x3ptools' and Mac
    /// zips: `sample-land/main.xml`, beside `__MACOSX/` entries, which are ignored). Sets the
    /// prefix every member name of main.xml is relative to.
    void findRoot() {
        if (zip_name_locate(zip_.get(), "main.xml", 0) >= 0) return;
        const zip_int64_t n = zip_get_num_entries(zip_.get(), 0);
        std::vector<std::string> found;
        for (zip_int64_t i = 0; i < n; ++i) {
            const char* c = zip_get_name(zip_.get(), static_cast<zip_uint64_t>(i), 0);
            if (!c) continue;
            const std::string name = c;
            if (name.rfind("__MACOSX/", 0) == 0) continue;
            const size_t slash = name.find('/');
            if (slash == std::string::npos || slash == 0) continue;
            if (name.compare(slash, std::string::npos, "/main.xml") == 0)
                found.push_back(name.substr(0, slash + 1));
        }
        if (found.size() > 1)
            fail("the archive holds " + std::to_string(found.size()) +
                     " measurements (main.xml in '" + found[0] + "' and '" + found[1] + "')",
                 "Put one measurement in each .x3p file");
        if (found.size() == 1) prefix_ = found[0];
    }

    /// The member `name` (`why` says where it is named; relative to the folder main.xml is
    /// in), which must hold `expected` bytes (0: any size up to `limit`). When main.xml's
    /// `md5Field` gives a digest, the member is checked against it (hashed while it inflates).
    std::vector<unsigned char> member(const std::string& relName, const std::string& why,
                                      uint64_t expected, uint64_t limit = 0,
                                      const char* md5Field = nullptr) {
        const std::string name = prefix_ + relName;
        zip_stat_t st;
        zip_stat_init(&st);
        if (zip_stat(zip_.get(), name.c_str(), 0, &st) != 0)
            fail("the archive has no member '" + name + "' (" + why + ")", kFixDamaged);
        if (!(st.valid & ZIP_STAT_SIZE) || !(st.valid & ZIP_STAT_COMP_SIZE))
            fail("the size of member '" + name + "' is unknown", kFixDamaged);
        if (expected != 0 && st.size != expected)
            fail("member '" + name + "' holds " + std::to_string(st.size) +
                     " bytes; Record3/MatrixDimension and the data type say " +
                     std::to_string(expected),
                 kFixDamaged);
        if (limit != 0 && st.size > limit)
            fail("member '" + name + "' is " + std::to_string(st.size) + " bytes, more than the " +
                     std::to_string(limit) + " accepted",
                 kFixDamaged);
        if (st.size / kMaxInflateRatio > st.comp_size + 1024)
            fail("member '" + name + "' claims " + std::to_string(st.size) + " bytes from " +
                     std::to_string(st.comp_size) + " compressed bytes",
                 kFixDamaged);
        std::vector<unsigned char> buf;
        try {
            buf.resize(static_cast<size_t>(st.size));
        } catch (const std::bad_alloc&) {
            fail("not enough memory for member '" + name + "' (" + std::to_string(st.size) +
                 " bytes)");
        }
        std::unique_ptr<zip_file_t, ZipFileCloser> f(zip_fopen(zip_.get(), name.c_str(), 0));
        if (!f) fail("cannot open member '" + name + "': " + zip_strerror(zip_.get()), kFixDamaged);
        const std::string wantMd5 = md5Field ? lower(text(md5Field, false)) : std::string();
        std::unique_ptr<Md5WhileFilling> md5;
        if (!wantMd5.empty()) md5 = std::make_unique<Md5WhileFilling>(buf.data());
        size_t got = 0;
        while (got < buf.size()) {
            const zip_int64_t n =
                zip_fread(f.get(), buf.data() + got, std::min(buf.size() - got, kReadPieceBytes));
            if (n < 0)
                fail("cannot read member '" + name + "': " + zip_file_strerror(f.get()),
                     kFixDamaged);
            if (n == 0) break;
            got += static_cast<size_t>(n);
            if (md5) md5->filled(got);
        }
        if (got != buf.size())
            fail("member '" + name + "' ends after " + std::to_string(got) + " of " +
                     std::to_string(buf.size()) + " bytes",
                 kFixDamaged);
        if (md5) {
            const std::string gotMd5 = md5->hex(got);
            if (gotMd5 != wantMd5)
                fail("member '" + name + "' does not match its MD5 checksum (" + md5Field + " is " +
                         wantMd5 + ", the member's is " + gotMd5 + ")",
                     kFixDamaged);
        }
        return buf;
    }

    /// main.xml against the checksum file Record4/ChecksumFile names ("<hex> *main.xml"), when
    /// that member exists.
    void checkXmlMd5() {
        const std::string name = text("Record4/ChecksumFile", false);
        if (name.empty() || zip_name_locate(zip_.get(), (prefix_ + name).c_str(), 0) < 0) return;
        const std::vector<unsigned char> sum =
            member(name, "named by Record4/ChecksumFile", 0, 4096);
        const std::string want =
            lower(trim(std::string(sum.begin(), sum.end()).substr(0, 32).c_str()));
        const std::string got = md5Hex(xml_.data(), xml_.size());
        if (want == got) return;
        const std::string problem = "main.xml does not match its MD5 checksum in '" + name + "' (" +
                                    want + "; main.xml's is " + got + ")";
        // main.xml edited after its checksum was written (x3ptools does): the heights are still
        // verified by their own MD5, so read them with a warning; without one, refuse.
        if (text("Record3/DataLink/MD5ChecksumPointData", false).empty())
            fail(problem, kFixDamaged);
        xmlChecksumWarning_ =
            problem + "; read anyway: the point data's own MD5 checksum is verified";
    }

    void parseXml() {
        findRoot();
        xml_ = member("main.xml", "every X3P file has one", 0, kMaxXmlBytes);
        const pugi::xml_parse_result r = doc_.load_buffer(xml_.data(), xml_.size());
        if (!r)
            fail(std::string("main.xml is not valid XML: ") + r.description() + " at byte " +
                     std::to_string(r.offset),
                 kFixDamaged);
        root_ = doc_.document_element();
        const std::string rootName = root_.name();
        const auto endsWith = [&](const std::string& suffix) {
            return rootName.size() >= suffix.size() &&
                   rootName.compare(rootName.size() - suffix.size(), suffix.size(), suffix) == 0;
        };
        const std::string local =
            rootName.substr(rootName.find(':') == std::string::npos ? 0 : rootName.find(':') + 1);
        if (!endsWith("ISO5436_2") && local != "ISO5436")  // x3ptools writes <ISO5436>
            fail("main.xml's root element is <" + rootName + ">, not <ISO5436_2>", kFixDamaged);

        const std::string feature = text("Record1/FeatureType");
        if (feature != "SUR")
            fail("Record1/FeatureType is '" + feature +
                 "'; only SUR (an areal surface) is a height map (PRF profiles and FCM "
                 "feature containers are not supported)");
        for (const char* axis : {"Record1/Axes/CX/AxisType", "Record1/Axes/CY/AxisType"}) {
            const std::string t = text(axis);
            if (t != "I")
                fail(std::string(axis) + " is '" + t +
                     "'; only incremental X and Y axes (I, a regular grid) are supported, not "
                     "absolute coordinates (A)");
        }
        const std::string zAxis = text("Record1/Axes/CZ/AxisType");
        if (zAxis != "A")
            fail("Record1/Axes/CZ/AxisType is '" + zAxis + "'; the Z axis must be absolute (A)");
        const double ix = number("Record1/Axes/CX/Increment", 0.0, true);
        const double iy = number("Record1/Axes/CY/Increment", 0.0, true);
        if (!(ix > 0) || !(iy > 0))
            fail("Record1/Axes/CX/Increment and CY/Increment must be > 0 (they are " +
                 std::to_string(ix) + " and " + std::to_string(iy) + " m)");
        pitchMm_ = ix * 1000.0;
        pitchYMm_ = iy * 1000.0;  // loadHeightmap resamples non-square pixels

        type_ = text("Record1/Axes/CZ/DataType");
        code_ = type_.size() == 1 ? type_[0] : '?';
        if (type_ == "I")
            bytes_ = 2;
        else if (type_ == "L" || type_ == "F")
            bytes_ = 4;
        else if (type_ == "D")
            bytes_ = 8;
        else
            fail("Record1/Axes/CZ/DataType is '" + type_ +
                 "'; supported are I (int16), L (int32), F (float32) and D (float64)");
        zInc_ = number("Record1/Axes/CZ/Increment", 1.0);
        zOff_ = number("Record1/Axes/CZ/Offset", 0.0);
        if (zInc_ == 0.0) fail("Record1/Axes/CZ/Increment is 0", kFixDamaged);

        w_ = count("Record3/MatrixDimension/SizeX");
        h_ = count("Record3/MatrixDimension/SizeY");
        const long long sz = count("Record3/MatrixDimension/SizeZ");
        if (sz != 1)
            fail("Record3/MatrixDimension/SizeZ is " + std::to_string(sz) +
                 "; only one layer (SizeZ 1) is a height map");
        if (w_ > detail::kMaxMetrologySide || h_ > detail::kMaxMetrologySide ||
            w_ * h_ > detail::kMaxMetrologySamples)
            fail("Record3/MatrixDimension " + std::to_string(w_) + " x " + std::to_string(h_) +
                     " is larger than the " + std::to_string(detail::kMaxMetrologySamples) +
                     " points accepted",
                 "Crop or resample the measurement");
        if (!node("Record3/DataLink/PointDataLink"))
            fail(
                "main.xml has no Record3/DataLink/PointDataLink (points listed in the XML are "
                "not supported)");
        dataName_ = text("Record3/DataLink/PointDataLink");
        validName_ = text("Record3/DataLink/ValidPointsLink", false);
        checkXmlMd5();
    }

    HeightmapData readData() {
        const uint64_t n = static_cast<uint64_t>(w_) * static_cast<uint64_t>(h_);
        const std::vector<unsigned char> raw =
            member(dataName_, "named by Record3/DataLink/PointDataLink", n * bytes_, 0,
                   "Record3/DataLink/MD5ChecksumPointData");
        std::vector<unsigned char> valid;
        if (!validName_.empty())
            valid = member(validName_, "named by Record3/DataLink/ValidPointsLink", (n + 7) / 8, 0,
                           "Record3/DataLink/MD5ChecksumValidPoints");

        HeightmapData d;
        d.width = static_cast<int>(w_);
        d.height = static_cast<int>(h_);
        d.pitch = pitchMm_;
        if (pitchYMm_ != pitchMm_) d.pitchY = pitchYMm_;
        if (!xmlChecksumWarning_.empty()) d.warnings.push_back(xmlChecksumWarning_);
        d.format = "x3p " + std::string(type_ == "I"   ? "int16"
                                        : type_ == "L" ? "int32"
                                        : type_ == "F" ? "float32"
                                                       : "float64");
        try {
            d.heights.resize(static_cast<size_t>(n));
        } catch (const std::bad_alloc&) {
            fail("not enough memory for a " + std::to_string(w_) + "x" + std::to_string(h_) +
                 " height map");
        }
        // One loop per data type (the type is not tested per point); little-endian values
        // are assembled from bytes, so the host's byte order does not matter.
        const double mm = 1000.0;
        const float nan = std::numeric_limits<float>::quiet_NaN();
        const auto convert = [&](auto decode) {
            const unsigned char* p = raw.data();
            float* out = d.heights.data();
            const size_t count = d.heights.size();
            double scale = zInc_;
            if ((code_ == 'F' || code_ == 'D') && zInc_ != 1.0) {
                double lo = std::numeric_limits<double>::infinity(), hi = -lo;
                // Over the valid points only: a point the valid-points mask drops may hold
                // any finite value (an instrument's marker), which is not the relief.
                for (size_t k = 0; k < count; ++k) {
                    if (!valid.empty() && !((valid[k / 8] >> (k % 8)) & 1)) continue;
                    const double v = decode(raw.data() + k * bytes_);
                    if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
                }
                const double rawRelief = hi - lo;
                if (rawRelief >= kMinRawReliefM && rawRelief <= kMaxRawReliefM &&
                    rawRelief * std::abs(zInc_) < kMinReliefM) {
                    scale = 1.0;
                    std::ostringstream w;
                    w << "Record1/Axes/CZ/Increment is " << zInc_ << " for " << d.format
                      << " heights: applied, it would make the relief "
                      << rawRelief * std::abs(zInc_)
                      << " m peak to valley, below any instrument's resolution; the heights are "
                         "read as stored, in metres (a relief of "
                      << rawRelief
                      << " m), as x3ptools reads float X3P files. If the file's "
                         "heights are in another unit, scale them with the scene's "
                         "heightmap.height_scale";
                    d.warnings.push_back(w.str());
                }
            }
            for (size_t k = 0; k < count; ++k, p += bytes_) {
                const double v = decode(p);
                out[k] = std::isnan(v) ? nan : static_cast<float>((v * scale + zOff_) * mm);
            }
            if (!valid.empty())
                for (size_t k = 0; k < count; ++k)
                    if (!((valid[k / 8] >> (k % 8)) & 1)) out[k] = nan;
        };
        if (code_ == 'I')
            convert(
                [](const unsigned char* p) { return double(std::bit_cast<int16_t>(loadU16(p))); });
        else if (code_ == 'L')
            convert(
                [](const unsigned char* p) { return double(std::bit_cast<int32_t>(loadU32(p))); });
        else if (code_ == 'F')
            convert([](const unsigned char* p) { return double(loadF32(p)); });
        else
            convert([](const unsigned char* p) { return loadF64(p); });
        return d;
    }

    fs::path file_;
    std::string where_;
    std::unique_ptr<zip_t, ZipCloser> zip_;
    std::vector<unsigned char> xml_;
    pugi::xml_document doc_;
    pugi::xml_node root_;
    double pitchMm_ = 0.0, pitchYMm_ = 0.0, zInc_ = 1.0, zOff_ = 0.0;
    std::string type_, dataName_, validName_;
    std::string prefix_;              // the folder main.xml is in ("" at the root)
    std::string xmlChecksumWarning_;  // main.xml's checksum did not match (see checkXmlMd5)
    char code_ = '?';
    uint64_t bytes_ = 0;
    long long w_ = 0, h_ = 0;
};

std::string xmlNumber(double v) {
    char b[40];
    std::snprintf(b, sizeof b, "%.15g", v);
    return b;
}

}  // namespace

HeightmapData readX3p(const fs::path& file) {
    return X3pReader(file).read();
}

void writeX3p(const fs::path& file, int width, int height, const std::vector<float>& heightsMm,
              double pitchMm) {
    const std::string where = file.string();
    if (width < 1 || height < 1 ||
        heightsMm.size() != static_cast<size_t>(width) * static_cast<size_t>(height))
        throw inputError(where, "cannot write an X3P file of " + std::to_string(heightsMm.size()) +
                                    " heights as " + std::to_string(width) + "x" +
                                    std::to_string(height));
    if (!(std::isfinite(pitchMm) && pitchMm > 0))
        throw inputError(where, "cannot write an X3P file with pitch " + std::to_string(pitchMm));
    std::string data;
    data.reserve(heightsMm.size() * 8);
    for (float h : heightsMm) {
        const uint64_t u = std::bit_cast<uint64_t>(static_cast<double>(h) / 1000.0);
        for (int b = 0; b < 8; ++b) data.push_back(static_cast<char>((u >> (8 * b)) & 0xff));
    }
    const std::string inc = xmlNumber(pitchMm / 1000.0);
    const std::string xml =
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
        "<p:ISO5436_2 xmlns:p=\"http://www.opengps.eu/2008/ISO5436_2\" "
        "xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\">\n"
        " <Record1>\n  <Revision>ISO5436 - 2000</Revision>\n  <FeatureType>SUR</FeatureType>\n"
        "  <Axes>\n"
        "   <CX><AxisType>I</AxisType><DataType>D</DataType><Increment>" +
        inc +
        "</Increment><Offset>0</Offset></CX>\n"
        "   <CY><AxisType>I</AxisType><DataType>D</DataType><Increment>" +
        inc +
        "</Increment><Offset>0</Offset></CY>\n"
        "   <CZ><AxisType>A</AxisType><DataType>D</DataType><Increment>1</Increment>"
        "<Offset>0</Offset></CZ>\n"
        "  </Axes>\n </Record1>\n"
        " <Record3>\n  <MatrixDimension><SizeX>" +
        std::to_string(width) + "</SizeX><SizeY>" + std::to_string(height) +
        "</SizeY><SizeZ>1</SizeZ></MatrixDimension>\n"
        "  <DataLink><PointDataLink>bindata/data.bin</PointDataLink><MD5ChecksumPointData>" +
        md5Hex(data.data(), data.size()) +
        "</MD5ChecksumPointData></DataLink>\n </Record3>\n"
        " <Record4><ChecksumFile>md5checksum.hex</ChecksumFile></Record4>\n"
        "</p:ISO5436_2>\n";
    const std::string sum = md5Hex(xml.data(), xml.size()) + " *main.xml\n";

    constexpr time_t kFixedZipTime = 315619200;  // 1980-01-02 00:00 UTC: >= 1980 in any zone
    writeAtomically(file, [&](const fs::path& temp) {
        int err = 0;
        zip_t* z = zip_open(temp.c_str(), ZIP_CREATE | ZIP_TRUNCATE, &err);
        if (!z) throw inputError(where, "cannot create the X3P archive");
        std::unique_ptr<zip_t, ZipCloser> guard(z);
        for (const auto& [name, bytes] :
             {std::pair<const char*, const std::string*>{"main.xml", &xml},
              {"bindata/data.bin", &data},
              {"md5checksum.hex", &sum}}) {
            zip_source_t* src = zip_source_buffer(z, bytes->data(), bytes->size(), 0);
            const zip_int64_t index = src ? zip_file_add(z, name, src, ZIP_FL_OVERWRITE) : -1;
            if (index < 0) {
                if (src) zip_source_free(src);
                throw inputError(where, std::string("cannot add ") + name +
                                            " to the X3P archive: " + zip_strerror(z));
            }
            // A fixed member time (early 1980, where zip time begins), not the clock: the
            // same map gives the same bytes, as our EXR files do.
            if (zip_file_set_mtime(z, static_cast<zip_uint64_t>(index), kFixedZipTime, 0) != 0)
                throw inputError(where, std::string("cannot set the time of ") + name +
                                            " in the X3P archive: " + zip_strerror(z));
        }
        if (zip_close(z) != 0)
            throw inputError(where,
                             std::string("cannot write the X3P archive: ") + zip_strerror(z));
        guard.release();  // zip_close freed it
    });
}

}  // namespace sl
