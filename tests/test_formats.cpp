// Tests for the surface-metrology height-map readers (io/X3p.h, io/Sdf.h through
// io/HeightmapIO.h loadHeightmap) and the scene's use of a file's own pixel pitch; `info` and
// `bench load`, which report on them. The files are
// written here: X3P with libzip, SDF by hand (ASCII and binary).
#include <gtest/gtest.h>
#include <zip.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "TestUtil.h"
#include "app/bench/LoadBench.h"
#include "app/bench/ReadBench.h"
#include "app/jobs/InfoJob.h"
#include "core/Error.h"
#include "core/Md5.h"
#include "io/HeightmapIO.h"
#include "io/NanoFocusNms.h"
#include "io/SceneFile.h"
#include "io/TrueMap.h"
#include "io/X3p.h"
#include "scene/Heightfield.h"
#include "scene/Scene.h"

namespace fs = std::filesystem;
using namespace sl;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

template <typename T>
void putLE(std::string& out, T v) {
    using U = std::conditional_t<
        sizeof(T) == 1, uint8_t,
        std::conditional_t<sizeof(T) == 2, uint16_t,
                           std::conditional_t<sizeof(T) == 4, uint32_t, uint64_t>>>;
    U u = std::bit_cast<U>(v);
    for (size_t b = 0; b < sizeof(T); ++b) out.push_back(static_cast<char>((u >> (8 * b)) & 0xff));
}

/// Writes a zip with the given members (name -> bytes).
void writeZip(const fs::path& p, const std::map<std::string, std::string>& members) {
    int err = 0;
    zip_t* z = zip_open(p.c_str(), ZIP_CREATE | ZIP_TRUNCATE, &err);
    ASSERT_NE(z, nullptr);
    for (const auto& [name, bytes] : members) {
        zip_source_t* s = zip_source_buffer(z, bytes.data(), bytes.size(), 0);
        ASSERT_NE(s, nullptr);
        ASSERT_GE(zip_file_add(z, name.c_str(), s, ZIP_FL_OVERWRITE), 0);
    }
    ASSERT_EQ(zip_close(z), 0);
}

/// What an X3P test file says; the defaults are a valid 4x3 float64 surface, 5 µm pitch.
struct X3pSpec {
    std::string feature = "SUR";
    std::string cxType = "I", cyType = "I";
    std::string zType = "D";
    double incX = 5e-6, incY = 5e-6;
    std::string zIncrement, zOffset;  // empty: element left out
    int sizeX = 4, sizeY = 3, sizeZ = 1;
    std::vector<double> values;  // sizeX*sizeY, X fastest
    std::vector<bool> valid;     // empty: no valid.bin
    bool withMainXml = true, withData = true;
    std::string dataMd5;    // MD5ChecksumPointData ("auto": the data's)
    long truncateData = 0;  // bytes cut from data.bin
};

std::string x3pXml(const X3pSpec& s) {
    auto num = [](double v) {
        char b[64];
        std::snprintf(b, sizeof b, "%.17g", v);
        return std::string(b);
    };
    std::string cz = "<CZ><AxisType>A</AxisType><DataType>" + s.zType + "</DataType>";
    if (!s.zIncrement.empty()) cz += "<Increment>" + s.zIncrement + "</Increment>";
    if (!s.zOffset.empty()) cz += "<Offset>" + s.zOffset + "</Offset>";
    cz += "</CZ>";
    std::string xml = R"(<?xml version="1.0" encoding="UTF-8"?>
<p:ISO5436_2 xmlns:p="http://www.opengps.eu/2008/ISO5436_2">
 <Record1><Revision>ISO5436 - 2000</Revision><FeatureType>)" +
                      s.feature + R"(</FeatureType>
  <Axes>
   <CX><AxisType>)" + s.cxType +
                      "</AxisType><DataType>D</DataType><Increment>" + num(s.incX) +
                      "</Increment><Offset>0</Offset></CX>\n   <CY><AxisType>" + s.cyType +
                      "</AxisType><DataType>D</DataType><Increment>" + num(s.incY) +
                      "</Increment><Offset>0</Offset></CY>\n   " + cz + R"(
  </Axes></Record1>
 <Record2><Date>2024-01-01T00:00:00+00:00</Date></Record2>
 <Record3><MatrixDimension><SizeX>)" +
                      std::to_string(s.sizeX) + "</SizeX><SizeY>" + std::to_string(s.sizeY) +
                      "</SizeY><SizeZ>" + std::to_string(s.sizeZ) +
                      "</SizeZ></MatrixDimension>\n  <DataLink><PointDataLink>bindata/data.bin"
                      "</PointDataLink>";
    if (!s.dataMd5.empty()) xml += "<MD5ChecksumPointData>" + s.dataMd5 + "</MD5ChecksumPointData>";
    if (!s.valid.empty()) xml += "<ValidPointsLink>bindata/valid.bin</ValidPointsLink>";
    xml +=
        "</DataLink></Record3>\n <Record4><ChecksumFile>md5checksum.hex</ChecksumFile>"
        "</Record4>\n</p:ISO5436_2>\n";
    return xml;
}

void writeX3p(const fs::path& p, const X3pSpec& s) {
    std::string data;
    for (double v : s.values) {
        if (s.zType == "I")
            putLE(data, static_cast<int16_t>(v));
        else if (s.zType == "L")
            putLE(data, static_cast<int32_t>(v));
        else if (s.zType == "F")
            putLE(data, static_cast<float>(v));
        else
            putLE(data, v);
    }
    data.resize(data.size() - static_cast<size_t>(s.truncateData));
    std::map<std::string, std::string> members;
    X3pSpec spec = s;
    if (spec.dataMd5 == "auto") spec.dataMd5 = md5Hex(data.data(), data.size());
    if (s.withMainXml) members["main.xml"] = x3pXml(spec);
    if (s.withData) members["bindata/data.bin"] = data;
    if (!s.valid.empty()) {
        std::string bits((s.valid.size() + 7) / 8, '\0');
        for (size_t k = 0; k < s.valid.size(); ++k)
            if (s.valid[k]) bits[k / 8] = static_cast<char>(bits[k / 8] | (1 << (k % 8)));
        members["bindata/valid.bin"] = bits;
    }
    writeZip(p, members);
}

/// An asymmetric 4x3 map: value = 10·row + column (+ base).
std::vector<double> ramp(int w, int h, double base = 0.0) {
    std::vector<double> v;
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i) v.push_back(base + 10.0 * j + i);
    return v;
}

using test::expectRefused;

/// SDF header fields.
struct SdfSpec {
    std::string version = "BCR-1.0";
    int points = 4, profiles = 3;
    double xs = 5e-6, ys = 5e-6, zs = 1e-6;
    int compression = 0, dataType = 5;
    std::vector<double> values;
    long truncate = 0;
    bool trailer = true;
};

void writeSdfBinary(const fs::path& p, const SdfSpec& s) {
    std::string out = "b" + s.version;
    out += std::string("TestMaker ", 10);
    out += std::string("010120241200", 12);
    out += std::string("010120241200", 12);
    putLE(out, static_cast<uint16_t>(s.points));
    putLE(out, static_cast<uint16_t>(s.profiles));
    putLE(out, s.xs);
    putLE(out, s.ys);
    putLE(out, s.zs);
    putLE(out, 1e-9);
    out.push_back(static_cast<char>(s.compression));
    out.push_back(static_cast<char>(s.dataType));
    out.push_back(0);
    EXPECT_EQ(out.size(), 81u);
    for (double v : s.values) {
        switch (s.dataType) {
            case 1:
                putLE(out, static_cast<uint16_t>(v));
                break;
            case 3:
                putLE(out, static_cast<float>(v));
                break;
            case 5:
                putLE(out, static_cast<int16_t>(v));
                break;
            case 6:
                putLE(out, static_cast<int32_t>(v));
                break;
            case 7:
                putLE(out, v);
                break;
            default:
                FAIL() << "type " << s.dataType;
        }
    }
    out.resize(out.size() - static_cast<size_t>(s.truncate));
    if (s.trailer) out += "*\nOperator = test\n";
    test::writeText(p, out);
}

void writeSdfAscii(const fs::path& p, const SdfSpec& s, const std::string& dataText = {}) {
    std::string out = "a" + s.version + "\r\nManufacID   = TestMaker\r\n" +
                      "CreateDate  = 010120241200\r\nModDate     = 010120241200\r\n" +
                      "NumPoints   = " + std::to_string(s.points) + "\r\n" +
                      "NumProfiles = " + std::to_string(s.profiles) + "\r\n";
    char b[200];
    std::snprintf(b, sizeof b,
                  "Xscale      = %.17g\r\nYscale      = %.17g\r\nZscale      = %.17g\r\n", s.xs,
                  s.ys, s.zs);
    out += b;
    out += "Zresolution = -1\r\nCompression = " + std::to_string(s.compression) +
           "\r\nDataType    = " + std::to_string(s.dataType) + "\r\nCheckType   = 0\r\n*\r\n";
    if (!dataText.empty()) {
        out += dataText;
    } else {
        for (int j = 0; j < s.profiles; ++j) {
            for (int i = 0; i < s.points; ++i) {
                const double v = s.values[static_cast<size_t>(j * s.points + i)];
                if (std::isnan(v))
                    out += "NaN ";
                else {
                    std::snprintf(b, sizeof b, "%.17g ", v);
                    out += b;
                }
            }
            out += "\r\n";
        }
        out += "*\r\nOperator = test\r\n";
    }
    test::writeText(p, out);
}

/// Expects d to hold expected[k]·scale (mm), row 0 first.
void expectHeights(const HeightmapData& d, int w, int h, const std::vector<double>& mm,
                   double tol = 1e-7) {
    ASSERT_EQ(d.width, w);
    ASSERT_EQ(d.height, h);
    ASSERT_EQ(d.heights.size(), mm.size());
    for (size_t k = 0; k < mm.size(); ++k)
        EXPECT_NEAR(d.heights[k], mm[k], tol * std::max(1.0, std::abs(mm[k]))) << "sample " << k;
}

}  // namespace

// --- X3P ----------------------------------------------------------------------------------------

TEST(FormatsX3p, Int16WithIncrementAndOffsetPitchAndOrientation) {
    test::TempDir dir("x3p");
    X3pSpec s;
    s.zType = "I";
    s.zIncrement = "1e-6";  // 1 µm per code
    s.zOffset = "2e-6";
    s.values = ramp(4, 3, -5.0);
    writeX3p(dir / "a.x3p", s);
    const HeightmapData d = loadHeightmap(dir / "a.x3p", {});
    std::vector<double> mm;
    for (double v : s.values) mm.push_back((v * 1e-6 + 2e-6) * 1000.0);
    expectHeights(d, 4, 3, mm);
    // row 0 is the first profile (Y index 0), column 0 the first X: value 10·row + column - 5
    EXPECT_NEAR(d.heights[0], (-5 + 2) * 1e-3, 1e-9);
    EXPECT_NEAR(d.heights[1], (-4 + 2) * 1e-3, 1e-9);
    EXPECT_NEAR(d.heights[4], (5 + 2) * 1e-3, 1e-9);
    ASSERT_TRUE(d.pitch.has_value());
    EXPECT_NEAR(*d.pitch, 0.005, 1e-15);
    EXPECT_EQ(d.invalidFilled, 0u);
    EXPECT_EQ(d.format, "x3p int16");
}

TEST(FormatsX3p, Float32Float64Int32Values) {
    test::TempDir dir("x3p");
    for (const char* type : {"F", "D", "L"}) {
        X3pSpec s;
        s.zType = type;
        s.sizeX = 3;
        s.sizeY = 2;
        if (std::string(type) == "L") {
            s.values = {-100000, 0, 7, 100000, 42, -1};
            s.zIncrement = "1e-9";  // nm codes
        } else {
            s.values = {1.5e-6, -2.25e-6, 0.0, 3e-5, 1e-7, -4e-6};  // metres
        }
        const fs::path f = dir / (std::string("v") + type + ".x3p");
        writeX3p(f, s);
        const HeightmapData d = loadHeightmap(f, {});
        std::vector<double> mm;
        for (double v : s.values) mm.push_back(v * (std::string(type) == "L" ? 1e-9 : 1.0) * 1e3);
        SCOPED_TRACE(type);
        expectHeights(d, 3, 2, mm, 1e-6);
    }
}

// Float heights with CZ/Increment ≠ 1: applied when the result is a plausible relief (as
// Gwyddion does); read as stored, in metres, with a warning, when applying it would leave a
// relief below any instrument's resolution (x3ptools' older writer: metres beside 1e-06).
TEST(FormatsX3p, AFloatIncrementThatWouldEraseTheReliefIsIgnoredWithAWarning) {
    test::TempDir dir("x3p");
    X3pSpec s;
    s.zType = "D";
    s.sizeX = 3;
    s.sizeY = 2;
    s.values = {2.1e-7, 8.3e-7, 5e-7, 3e-7, 6e-7, 4e-7};  // metres, 0.62 µm peak to valley
    s.zIncrement = "1e-06";
    writeX3p(dir / "m.x3p", s);
    const HeightmapData d = loadHeightmap(dir / "m.x3p", {});
    std::vector<double> mm;
    for (double v : s.values) mm.push_back(v * 1e3);
    expectHeights(d, 3, 2, mm, 1e-9);
    ASSERT_EQ(d.warnings.size(), 1u);
    EXPECT_NE(d.warnings[0].find("Record1/Axes/CZ/Increment is 1e-06"), std::string::npos)
        << d.warnings[0];
    EXPECT_NE(d.warnings[0].find("height_scale"), std::string::npos) << d.warnings[0];

    // A point the valid-points mask drops holds an instrument's marker (1e3): the relief is the
    // valid points', so the file is read as stored all the same.
    X3pSpec masked = s;
    masked.values[4] = 1e3;
    masked.valid = {true, true, true, true, false, true};
    writeX3p(dir / "v.x3p", masked);
    const HeightmapData dv = loadHeightmap(dir / "v.x3p", {});
    ASSERT_EQ(dv.heights.size(), 6u);
    EXPECT_NEAR(dv.heights[1], s.values[1] * 1e3, 1e-9);
    ASSERT_FALSE(dv.warnings.empty());
    EXPECT_NE(dv.warnings[0].find("Record1/Axes/CZ/Increment is 1e-06"), std::string::npos)
        << dv.warnings[0];

    // The same increment on floats in micrometres gives a plausible relief: applied, silently.
    X3pSpec u = s;
    for (double& v : u.values) v *= 1e6;  // 0.21 .. 0.83 (µm)
    writeX3p(dir / "u.x3p", u);
    const HeightmapData du = loadHeightmap(dir / "u.x3p", {});
    expectHeights(du, 3, 2, mm, 1e-9);
    EXPECT_TRUE(du.warnings.empty());

    // A float map whose relief is below a nanometre as stored is not second-guessed.
    X3pSpec f = s;
    for (double& v : f.values) v *= 1e-3;
    writeX3p(dir / "f.x3p", f);
    const HeightmapData df = loadHeightmap(dir / "f.x3p", {});
    for (size_t k = 0; k < df.heights.size(); ++k)
        EXPECT_NEAR(df.heights[k], f.values[k] * 1e-6 * 1e3, 1e-15);
    EXPECT_TRUE(df.warnings.empty());
}

TEST(FormatsX3p, HeightScaleMultipliesAndUpperCaseExtensionLoads) {
    test::TempDir dir("x3p");
    X3pSpec s;
    s.values = ramp(4, 3, 1.0);
    for (double& v : s.values) v *= 1e-6;
    writeX3p(dir / "A.X3P", s);
    HeightmapOptions opt;
    opt.heightScale = 2.0;
    const HeightmapData d = loadHeightmap(dir / "A.X3P", opt);
    EXPECT_NEAR(d.heights[5], 2.0 * s.values[5] * 1e3, 1e-9);
    HeightmapOptions range;
    range.heightRange = std::array<double, 2>{0.0, 1.0};
    expectRefused(dir / "A.X3P", {"height_range"}, range);
}

TEST(FormatsX3p, NanAndValidMaskPointsAreFilledAndCounted) {
    test::TempDir dir("x3p");
    X3pSpec s;
    s.values = ramp(4, 3);
    for (double& v : s.values) v *= 1e-6;
    s.values[5] = kNaN;  // row 1, column 1: neighbours 1, 10, 12, 21 (µm)
    s.valid.assign(12, true);
    s.valid[11] = false;  // row 2, column 3: neighbours 7 and 22 (µm)
    writeX3p(dir / "n.x3p", s);
    const HeightmapData d = loadHeightmap(dir / "n.x3p", {});
    EXPECT_EQ(d.invalidFilled, 2u);
    EXPECT_NE(d.format.find("2 invalid points filled"), std::string::npos) << d.format;
    EXPECT_NEAR(d.heights[5], (1 + 10 + 12 + 21) / 4.0 * 1e-3, 1e-9);
    EXPECT_NEAR(d.heights[11], (13 + 22) / 2.0 * 1e-3, 1e-9);
    for (float v : d.heights) EXPECT_TRUE(std::isfinite(v));

    // int16 with a mask: masked codes are ignored whatever they hold.
    X3pSpec m;
    m.zType = "I";
    m.zIncrement = "1e-6";
    m.values = {0, 30000, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20};
    m.valid.assign(12, true);
    m.valid[1] = false;  // row 0, column 1: neighbours 0, 2, 8 -> 10/3 µm
    writeX3p(dir / "m.x3p", m);
    const HeightmapData dm = loadHeightmap(dir / "m.x3p", {});
    EXPECT_EQ(dm.invalidFilled, 1u);
    EXPECT_NEAR(dm.heights[1], (0 + 2 + 8) / 3.0 * 1e-3, 1e-8);

    // A hole two layers deep is filled from its rim inwards.
    X3pSpec h;
    h.sizeX = 5;
    h.sizeY = 5;
    h.values.assign(25, 1e-6);
    for (int j = 1; j <= 3; ++j)
        for (int i = 1; i <= 3; ++i) h.values[static_cast<size_t>(j * 5 + i)] = kNaN;
    writeX3p(dir / "h.x3p", h);
    const HeightmapData dh = loadHeightmap(dir / "h.x3p", {});
    EXPECT_EQ(dh.invalidFilled, 9u);
    for (float v : dh.heights) EXPECT_NEAR(v, 1e-3, 1e-9);
}

TEST(FormatsX3p, MostlyOrAllInvalidIsRefused) {
    test::TempDir dir("x3p");
    X3pSpec s;
    s.values = ramp(4, 3);
    // valid at two far corners only: the rectangle of the valid points is the whole map
    for (size_t k = 1; k < 11; ++k) s.values[k] = kNaN;
    writeX3p(dir / "half.x3p", s);
    expectRefused(dir / "half.x3p", {"10 of 12 points are invalid"});
    s.values.assign(12, kNaN);
    writeX3p(dir / "none.x3p", s);
    expectRefused(dir / "none.x3p", {"every point"});
}

TEST(FormatsX3p, UnsupportedVariantsAreRefusedNamingFileAndField) {
    test::TempDir dir("x3p");
    const auto refuse = [&](const std::string& name, X3pSpec s,
                            const std::vector<std::string>& parts) {
        if (s.values.empty()) s.values = ramp(s.sizeX, s.sizeY);
        writeX3p(dir / name, s);
        SCOPED_TRACE(name);
        expectRefused(dir / name, parts);
    };
    X3pSpec absX;
    absX.cxType = "A";
    refuse("absx.x3p", absX, {"Record1/Axes/CX/AxisType", "incremental"});
    X3pSpec absY;
    absY.cyType = "A";
    refuse("absy.x3p", absY, {"Record1/Axes/CY/AxisType"});
    X3pSpec layers;
    layers.sizeZ = 2;
    refuse("layers.x3p", layers, {"SizeZ", "2"});
    X3pSpec prf;
    prf.feature = "PRF";
    refuse("prf.x3p", prf, {"Record1/FeatureType", "PRF"});
    X3pSpec fcm;
    fcm.feature = "FCM";
    refuse("fcm.x3p", fcm, {"Record1/FeatureType", "FCM"});
    X3pSpec type;
    type.zType = "Q";
    refuse("type.x3p", type, {"Record1/Axes/CZ/DataType", "'Q'"});
    X3pSpec truncated;
    truncated.truncateData = 3;
    refuse("trunc.x3p", truncated, {"bindata/data.bin", "93 bytes", "96"});
    X3pSpec noXml;
    noXml.withMainXml = false;
    refuse("noxml.x3p", noXml, {"main.xml"});
    X3pSpec noData;
    noData.withData = false;
    refuse("nodata.x3p", noData, {"bindata/data.bin", "PointDataLink"});
    X3pSpec rect;  // non-square pixels are resampled (io/HeightmapIO.h), not refused
    rect.incY = 6e-6;
    rect.values = ramp(4, 3);
    writeX3p(dir / "rect.x3p", rect);
    const HeightmapData r = loadHeightmap(dir / "rect.x3p", {});
    EXPECT_EQ(r.height, 3);  // ⌊2·6/5⌋ + 1 rows at 5 µm
    EXPECT_NE(r.resampling.find("onto the finer pitch"), std::string::npos) << r.resampling;
    X3pSpec huge;
    huge.sizeX = 2000000;
    huge.values = ramp(4, 3);
    refuse("huge.x3p", huge, {"MatrixDimension"});

    test::writeText(dir / "text.x3p", "this is not a zip file at all\n");
    expectRefused(dir / "text.x3p", {"zip"});
    writeZip(dir / "badxml.x3p", {{"main.xml", "<ISO5436_2><Record1>"}});
    expectRefused(dir / "badxml.x3p", {"main.xml", "XML"});
}

TEST(FormatsX3p, Md5ChecksumsAreVerified) {
    EXPECT_EQ(md5Hex("", 0), "d41d8cd98f00b204e9800998ecf8427e");
    EXPECT_EQ(md5Hex("abc", 3), "900150983cd24fb0d6963f7d28e17f72");
    const std::string a56(56, 'a');  // the length field spills into a second padding block
    EXPECT_EQ(md5Hex(a56.data(), a56.size()), "3b0c8ac703f828b04c6c197006d17218");

    test::TempDir dir("x3p");
    X3pSpec s;
    s.values = ramp(4, 3);
    s.dataMd5 = "auto";
    writeX3p(dir / "ok.x3p", s);
    EXPECT_EQ(loadHeightmap(dir / "ok.x3p", {}).width, 4);
    s.dataMd5 = "0123456789abcdef0123456789abcdef";
    writeX3p(dir / "bad.x3p", s);
    expectRefused(dir / "bad.x3p", {"bindata/data.bin", "MD5", "MD5ChecksumPointData"});
}

TEST(FormatsX3p, Md5InPiecesIsTheMd5OfTheWhole) {
    // The digest must not depend on how the bytes arrive: split points inside and across
    // 64-byte blocks, empty pieces, and a message whose padding spills into a second block.
    std::mt19937 rng(7);
    for (size_t n : {size_t(0), size_t(1), size_t(55), size_t(56), size_t(63), size_t(64),
                     size_t(65), size_t(127), size_t(128), size_t(1000), size_t(100003)}) {
        std::string bytes(n, '\0');
        for (char& b : bytes) b = static_cast<char>(rng() & 0xff);
        const std::string whole = md5Hex(bytes.data(), bytes.size());
        for (int trial = 0; trial < 20; ++trial) {
            Md5 m;
            size_t at = 0;
            while (at < n) {
                const size_t piece = std::min<size_t>(n - at, rng() % 150);
                m.update(bytes.data() + at, piece);
                at += piece;
            }
            EXPECT_EQ(m.hex(), whole) << n << " bytes, trial " << trial;
        }
    }
}

TEST(FormatsX3p, AMemberOfManyReadPiecesIsVerifiedAsAWhole) {
    // 1100 x 1100 float64 = 9.7 MB: the member is inflated in several pieces while a second
    // thread hashes them; the heights, the digest and a wrong digest's refusal are as for one.
    test::TempDir dir("x3p");
    X3pSpec s;
    s.sizeX = s.sizeY = 1100;
    s.values.resize(size_t(1100) * 1100);
    std::mt19937 rng(11);
    std::normal_distribution<double> g(0.0, 1e-6);
    for (double& v : s.values) v = g(rng);
    s.dataMd5 = "auto";
    writeX3p(dir / "big.x3p", s);
    const HeightmapData d = loadHeightmap(dir / "big.x3p", {});
    ASSERT_EQ(d.width, 1100);
    for (size_t k : {size_t(0), size_t(4u << 17), s.values.size() - 1})
        EXPECT_EQ(d.heights[k], static_cast<float>(s.values[k] * 1000.0)) << k;
    s.dataMd5 = "0123456789abcdef0123456789abcdef";
    writeX3p(dir / "bad.x3p", s);
    expectRefused(dir / "bad.x3p", {"bindata/data.bin", "MD5", "MD5ChecksumPointData"});
}

TEST(FormatsX3p, WriterRoundTripsHeightsAndPitch) {
    test::TempDir dir("x3p");
    const int w = 7, h = 5;
    std::vector<float> mm(static_cast<size_t>(w * h));
    for (size_t k = 0; k < mm.size(); ++k) mm[k] = 0.001f * static_cast<float>(k) - 0.0123f;
    sl::writeX3p(dir / "w.x3p", w, h, mm, 0.0025);
    const HeightmapData d = loadHeightmap(dir / "w.x3p", {});
    EXPECT_EQ(d.width, w);
    EXPECT_EQ(d.height, h);
    EXPECT_EQ(d.format, "x3p float64");
    ASSERT_TRUE(d.pitch.has_value());
    EXPECT_NEAR(*d.pitch, 0.0025, 1e-15);
    for (size_t k = 0; k < mm.size(); ++k) EXPECT_FLOAT_EQ(d.heights[k], mm[k]) << k;
    // main.xml's checksum file is verified too: the writer's passes (above), a wrong one fails.
    int err = 0;
    zip_t* z = zip_open((dir / "w.x3p").c_str(), 0, &err);
    ASSERT_NE(z, nullptr);
    const std::string wrong = "00000000000000000000000000000000 *main.xml\n";
    zip_source_t* src = zip_source_buffer(z, wrong.data(), wrong.size(), 0);
    ASSERT_GE(zip_file_add(z, "md5checksum.hex", src, ZIP_FL_OVERWRITE), 0);
    ASSERT_EQ(zip_close(z), 0);
    // main.xml edited after its checksum (as x3ptools does): the data's own MD5 still holds, so
    // it is read with a warning.
    const HeightmapData edited = loadHeightmap(dir / "w.x3p", {});
    ASSERT_EQ(edited.warnings.size(), 1u);
    EXPECT_NE(edited.warnings[0].find("md5checksum.hex"), std::string::npos) << edited.warnings[0];
    EXPECT_THROW(sl::writeX3p(dir / "x.x3p", 3, 3, mm, 0.01), InputError);
}

TEST(FormatsX3p, GenSurfaceWritesAnX3pAndASceneThatUsesItsPitch) {
    test::TempDir dir("x3p");
    const auto r = test::runCli("gen-surface -o " + (dir / "part.x3p").string() +
                                " --width 40 --height 30 --pitch 0.02 --scene " +
                                (dir / "part.json").string() + " --image-size 16");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    std::ifstream in(dir / "part.json");
    const std::string json((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_EQ(json.find("pixel_pitch"), std::string::npos) << json;
    auto scene = loadScene(dir / "part.json");
    EXPECT_EQ(scene->mapWidth, 40);
    EXPECT_EQ(scene->mapHeight, 30);
    EXPECT_NEAR(scene->surface->pitch(), 0.02, 1e-12);
}

// --- SDF ----------------------------------------------------------------------------------------

TEST(FormatsSdf, BinaryTypesValuesPitchAndOrientation) {
    test::TempDir dir("sdf");
    for (int type : {5, 6, 3, 7, 1}) {
        SdfSpec s;
        s.dataType = type;
        s.values = ramp(4, 3, type == 1 ? 0.0 : -5.0);
        if (type == 3 || type == 7)
            for (double& v : s.values) v *= 0.25;  // fractional values for float types
        const fs::path f = dir / (std::to_string(type) + "b.sdf");
        writeSdfBinary(f, s);
        const HeightmapData d = loadHeightmap(f, {});
        SCOPED_TRACE(type);
        std::vector<double> mm;
        for (double v : s.values) mm.push_back(v * 1e-6 * 1e3);
        expectHeights(d, 4, 3, mm, 1e-6);
        ASSERT_TRUE(d.pitch.has_value());
        EXPECT_NEAR(*d.pitch, 0.005, 1e-15);
        EXPECT_EQ(d.format.rfind("sdf binary", 0), 0u) << d.format;
    }
}

TEST(FormatsSdf, AsciiValuesPitchAndOrientation) {
    test::TempDir dir("sdf");
    SdfSpec s;
    s.dataType = 5;
    s.values = ramp(4, 3, -5.0);
    writeSdfAscii(dir / "a.sdf", s);
    const HeightmapData d = loadHeightmap(dir / "a.sdf", {});
    std::vector<double> mm;
    for (double v : s.values) mm.push_back(v * 1e-3);
    expectHeights(d, 4, 3, mm);
    EXPECT_NEAR(*d.pitch, 0.005, 1e-15);
    EXPECT_NEAR(d.heights[1] - d.heights[0], 1e-3, 1e-9);  // along a profile: column
    EXPECT_NEAR(d.heights[4] - d.heights[0], 1e-2, 1e-9);  // next profile: row

    SdfSpec f;
    f.dataType = 7;
    f.zs = 1.0;
    f.values = ramp(4, 3);
    for (double& v : f.values) v *= 1.25e-7;
    writeSdfAscii(dir / "f.sdf", f);
    std::vector<double> fm;
    for (double v : f.values) fm.push_back(v * 1e3);
    expectHeights(loadHeightmap(dir / "f.sdf", {}), 4, 3, fm, 1e-6);
}

TEST(FormatsSdf, InvalidPointsAreFilledAndCounted) {
    test::TempDir dir("sdf");
    SdfSpec s;
    s.dataType = 5;
    s.values = ramp(4, 3);
    s.values[5] = -32768;  // int16 sentinel
    writeSdfBinary(dir / "s.sdf", s);
    const HeightmapData d = loadHeightmap(dir / "s.sdf", {});
    EXPECT_EQ(d.invalidFilled, 1u);
    EXPECT_NEAR(d.heights[5], (1 + 10 + 12 + 21) / 4.0 * 1e-3, 1e-8);

    SdfSpec f;
    f.dataType = 3;
    f.values = ramp(4, 3);
    f.values[0] = kNaN;  // corner: neighbours 1 and 10 (µm)
    writeSdfAscii(dir / "n.sdf", f);
    const HeightmapData dn = loadHeightmap(dir / "n.sdf", {});
    EXPECT_EQ(dn.invalidFilled, 1u);
    EXPECT_NEAR(dn.heights[0], 5.5e-3, 1e-8);
    writeSdfBinary(dir / "nb.sdf", f);
    EXPECT_EQ(loadHeightmap(dir / "nb.sdf", {}).invalidFilled, 1u);
}

TEST(FormatsSdf, UnsupportedAndDamagedFilesAreRefusedNamingFileAndField) {
    test::TempDir dir("sdf");
    SdfSpec c;
    c.compression = 1;
    c.values = ramp(4, 3);
    writeSdfBinary(dir / "c.sdf", c);
    expectRefused(dir / "c.sdf", {"Compression = 1", "unsupported"});
    writeSdfAscii(dir / "ca.sdf", c);
    expectRefused(dir / "ca.sdf", {"Compression = 1", "unsupported"});

    SdfSpec t;
    t.values = ramp(4, 3);
    t.truncate = 5;
    t.trailer = false;  // (a trailer's bytes would pass for data)
    writeSdfBinary(dir / "t.sdf", t);
    expectRefused(dir / "t.sdf", {"truncated", "24 bytes", "has 19"});
    writeSdfAscii(dir / "ta.sdf", t, "1 2 3 4\n5 6 7\n" + std::string(20, ' '));
    expectRefused(dir / "ta.sdf", {"truncated", "7 values"});
    writeSdfAscii(dir / "more.sdf", t, "1 2 3 4 5 6 7 8 9 10 11 12 13\n*\n");
    expectRefused(dir / "more.sdf", {"more values"});
    writeSdfAscii(dir / "word.sdf", t, "1 2 3 x 5 6 7 8 9 10 11 12\n");
    expectRefused(dir / "word.sdf", {"value 3", "'x'"});

    SdfSpec dt;
    dt.dataType = 9;
    dt.values = {};
    writeSdfBinary(dir / "dt.sdf", dt);
    expectRefused(dir / "dt.sdf", {"DataType = 9"});

    SdfSpec rect;
    rect.ys = 1e-5;
    rect.values = ramp(4, 3);
    writeSdfBinary(dir / "rect.sdf", rect);
    const HeightmapData rs = loadHeightmap(dir / "rect.sdf", {});  // resampled, not refused
    EXPECT_EQ(rs.height, 5);  // ⌊2·10/5⌋ + 1 rows at 5 µm
    EXPECT_NEAR(*rs.pitch, 0.005, 1e-12);

    test::writeText(dir / "junk.sdf", "hello world, not an sdf file\n");
    expectRefused(dir / "junk.sdf", {"SDF version"});
    test::writeText(dir / "short.sdf", "bBCR-1.0 too short");
    expectRefused(dir / "short.sdf", {"81-byte"});
    test::writeText(dir / "nostar.sdf", "aBCR-1.0\nNumPoints = 2\n");
    expectRefused(dir / "nostar.sdf", {"'*'"});
    test::writeText(dir / "nokey.sdf", "aBCR-1.0\nNumPoints = 2\nNumProfiles = 2\n*\n1 2 3 4\n");
    expectRefused(dir / "nokey.sdf", {"Xscale"});
}

// --- scenes -------------------------------------------------------------------------------------

TEST(FormatsX3p, InfinitePointsAreInvalidAndPitchesAHairApartAreNotInterpolated) {
    // Alicona's X3P export marks an unmeasured point +Inf and writes pitches that differ in the
    // fifth digit (2.279984 x 2.279795 µm): the points are filled as NaN ones are, and the map
    // keeps its samples (interpolating onto a 0.008 % finer pitch would only blur it).
    test::TempDir dir("x3p");
    X3pSpec s;
    s.zType = "F";
    s.incX = 2.279984e-6;
    s.incY = 2.279795e-6;
    s.values = ramp(4, 3);
    for (double& v : s.values) v *= 1e-6;
    s.values[5] = std::numeric_limits<double>::infinity();   // row 1, column 1
    s.values[6] = -std::numeric_limits<double>::infinity();  // row 1, column 2
    writeX3p(dir / "alicona.x3p", s);
    const HeightmapData d = loadHeightmap(dir / "alicona.x3p", {});
    EXPECT_EQ(d.invalidFilled, 2u);
    EXPECT_EQ(d.width, 4);
    EXPECT_EQ(d.height, 3);
    EXPECT_NEAR(*d.pitch, 2.279795e-3, 1e-12);  // the finer pitch
    EXPECT_NE(d.resampling.find("read as square"), std::string::npos) << d.resampling;
    EXPECT_NE(d.resampling.find("differ by 0.0083 %, within the 0.1 %"), std::string::npos)
        << d.resampling;
    // Every measured sample is the file's, unmoved.
    for (size_t k = 0; k < 12; ++k) {
        if (k == 5 || k == 6) continue;
        EXPECT_FLOAT_EQ(d.heights[k], static_cast<float>(static_cast<float>(s.values[k]) * 1e3));
    }
    // Side by side, each is the mean of its valid neighbours (not of the other).
    EXPECT_NEAR(d.heights[5], (1 + 10 + 21) / 3.0 * 1e-3, 1e-7);
    EXPECT_NEAR(d.heights[6], (2 + 13 + 22) / 3.0 * 1e-3, 1e-7);

    // Pitches further apart than a calibration (0.1 %) are interpolated: 2 % onto 4.9 µm.
    X3pSpec near;
    near.incY = 4.9e-6;  // finer along y: columns are interpolated, rows kept
    near.sizeX = 60;
    near.values = ramp(60, 3);
    writeX3p(dir / "near.x3p", near);
    const HeightmapData dn = loadHeightmap(dir / "near.x3p", {});
    EXPECT_EQ(dn.width, 61);  // ⌊59·5/4.9⌋ + 1
    EXPECT_NE(dn.resampling.find("onto the finer pitch"), std::string::npos) << dn.resampling;
}

/// A TrueMap v2.0 file (io/HeightmapIO.h): `cut` bytes short, or with `extra` bytes after it.
void writeTrueMap(const fs::path& p, uint32_t w, uint32_t h, float lx, float ly,
                  const std::vector<float>& z, size_t cut = 0) {
    std::string out = "Binary TrueMap Data File v2.0\r\n";
    out.push_back('\0');
    out += std::string("Created by a test") + std::string(7, ' ');
    const auto put = [&](auto v) {
        char b[sizeof v];
        std::memcpy(b, &v, sizeof v);  // the tests run on little-endian hosts
        out.append(b, sizeof v);
    };
    put(w);
    put(h);
    for (float v : {lx, ly, 0.0f, 0.0f}) put(v);
    for (float v : z) put(v);
    out.resize(out.size() - cut);
    test::writeText(p, out);
}

TEST(FormatsTrueMap, ValuesPitchInvalidPointsAndDamagedFiles) {
    test::TempDir dir("tmd");
    std::vector<float> z;
    for (double v : ramp(4, 3)) z.push_back(static_cast<float>(v * 1e-3));  // mm
    z[5] = std::numeric_limits<float>::quiet_NaN();  // neighbours 1, 10, 12, 21 (µm)
    writeTrueMap(dir / "a.tmd", 4, 3, 0.02f, 0.015f, z);
    // Read by its content, whatever its name.
    fs::copy_file(dir / "a.tmd", dir / "a.dat");
    for (const char* name : {"a.tmd", "a.dat"}) {
        SCOPED_TRACE(name);
        const HeightmapData d = loadHeightmap(dir / name, {});
        EXPECT_EQ(d.format.rfind("truemap v2.0 float32", 0), 0u) << d.format;
        EXPECT_EQ(d.width, 4);
        EXPECT_EQ(d.height, 3);
        EXPECT_NEAR(*d.pitch, 0.005, 1e-9);  // 0.02 mm over 4 samples; 0.015 over 3
        EXPECT_TRUE(d.resampling.empty()) << d.resampling;
        EXPECT_EQ(d.invalidFilled, 1u);
        EXPECT_FLOAT_EQ(d.heights[11], 0.023f);  // row 2, column 3
        EXPECT_NEAR(d.heights[5], (1 + 10 + 12 + 21) / 4.0 * 1e-3, 1e-7);
    }
    writeTrueMap(dir / "short.tmd", 4, 3, 0.02f, 0.015f, z, 4);
    expectRefused(dir / "short.tmd", {"124 bytes", "4 x 3", "128"});
    writeTrueMap(dir / "flat.tmd", 4, 3, 0.0f, 0.015f, z);
    expectRefused(dir / "flat.tmd", {"lengths X and Y"});
    writeTrueMap(dir / "huge.tmd", 4, 2000000, 0.02f, 0.015f, z);
    expectRefused(dir / "huge.tmd", {"4 x 2000000"});
    test::writeText(dir / "v1.tmd", "Binary TrueMap Data File v1.0 and then some bytes\n");
    expectRefused(dir / "v1.tmd", {"not a TrueMap v2.0 file"});
}

/// A NanoFocus NMS file (io/HeightmapIO.h): codes, z range in µm, spacing in nm.
void writeNms(const fs::path& p, uint32_t nx, uint32_t ny, double zmin, double zmax, double dx,
              double dy, const std::vector<uint16_t>& codes, bool intensities, size_t cut = 0) {
    std::string out(3468, '\0');
    const auto at = [&](size_t o, auto v) { std::memcpy(out.data() + o, &v, sizeof v); };
    std::memcpy(out.data() + 32, "OM_MS_2.0", 9);
    at(16, zmin);
    at(24, zmax);
    at(1368, nx);
    at(1372, ny);
    at(1376, dx);
    at(1384, dy);
    for (uint16_t c : codes) out.append(reinterpret_cast<const char*>(&c), 2);
    if (intensities) out.append(codes.size(), '\x7f');
    out.resize(out.size() - cut);
    test::writeText(p, out);
}

TEST(FormatsNms, CodesSpanTheHeaderRangePitchAndDamagedFiles) {
    test::TempDir dir("nms");
    std::vector<uint16_t> codes(12);
    for (size_t k = 0; k < 12; ++k) codes[k] = static_cast<uint16_t>(k * 5957);
    codes[11] = 65535;
    writeNms(dir / "a.nms", 4, 3, 2.0, 8.0, 312.5, 312.5, codes, true);
    writeNms(dir / "b.bin", 4, 3, 2.0, 8.0, 312.5, 400.0, codes, false);  // no intensities
    const HeightmapData a = loadHeightmap(dir / "a.nms", {});
    EXPECT_EQ(a.format, "nanofocus nms uint16");
    EXPECT_EQ(a.width, 4);
    EXPECT_EQ(a.height, 3);
    EXPECT_NEAR(*a.pitch, 312.5e-6, 1e-15);  // nm -> mm
    for (size_t k = 0; k < 12; ++k)          // code 0 is z min, 65535 z max (µm -> mm)
        EXPECT_NEAR(a.heights[k], (2.0 + 6.0 * codes[k] / 65535.0) * 1e-3, 1e-9) << k;
    EXPECT_NEAR(a.heights[11], 8e-3, 1e-9);
    const HeightmapData b = loadHeightmap(dir / "b.bin", {});  // by content, resampled along y
    EXPECT_EQ(b.width, 4);
    EXPECT_EQ(b.height, 3);  // ⌊2·400/312.5⌋ + 1
    EXPECT_NE(b.resampling.find("onto the finer pitch"), std::string::npos) << b.resampling;

    writeNms(dir / "short.nms", 4, 3, 2.0, 8.0, 312.5, 312.5, codes, true, 1);
    expectRefused(dir / "short.nms", {"3503 bytes", "3492", "3504"});
    writeNms(dir / "range.nms", 4, 3, 8.0, 2.0, 312.5, 312.5, codes, true);
    expectRefused(dir / "range.nms", {"height range", "byte 16"});
    writeNms(dir / "pitch.nms", 4, 3, 2.0, 8.0, 0.0, 312.5, codes, true);
    expectRefused(dir / "pitch.nms", {"spacing", "byte 1376"});
    test::writeText(dir / "other.nms", std::string(40, 'x'));
    expectRefused(dir / "other.nms", {"not a NanoFocus NMS file"});
}

TEST(FormatsTrueMap, WritersRoundTripThroughTheReaders) {
    // TrueMap: float32 heights back bit for bit; NMS: within half a code of the range.
    test::TempDir dir("tmd");
    std::vector<float> h;
    for (double v : ramp(5, 4)) h.push_back(static_cast<float>(0.001 * v - 0.003));
    writeTrueMap(dir / "w.tmd", 5, 4, h, 0.004);
    const HeightmapData t = loadHeightmap(dir / "w.tmd", {});
    EXPECT_EQ(t.width, 5);
    EXPECT_EQ(t.height, 4);
    EXPECT_NEAR(*t.pitch, 0.004, 1e-9);
    EXPECT_EQ(t.heights, h);
    writeNanoFocusNms(dir / "w.nms", 5, 4, h, 0.004);
    const HeightmapData m = loadHeightmap(dir / "w.nms", {});
    EXPECT_EQ(m.format, "nanofocus nms uint16");
    EXPECT_NEAR(*m.pitch, 0.004, 1e-12);
    const double halfCode = 0.5 * 0.034 / 65535.0;  // h spans -0.003 .. 0.031 mm
    for (size_t k = 0; k < h.size(); ++k) EXPECT_NEAR(m.heights[k], h[k], halfCode + 1e-9) << k;
    EXPECT_FLOAT_EQ(m.heights[0], h[0]);  // the ends are codes 0 and 65535 exactly
    EXPECT_FLOAT_EQ(m.heights[19], h[19]);
}

TEST(FormatsScene, PitchComesFromTheFileUnlessTheSceneGivesOne) {
    test::TempDir dir("scene");
    X3pSpec s;
    s.sizeX = 8;
    s.sizeY = 6;
    s.values.assign(48, 0.0);
    for (size_t k = 0; k < s.values.size(); ++k) s.values[k] = 1e-6 * double(k % 5);
    writeX3p(dir / "part.x3p", s);
    const std::string cam = R"("camera": {"width": 16, "height": 12})";

    test::writeText(dir / "file.json", R"({"heightmap": {"path": "part.x3p"}, )" + cam + "}");
    auto scene = loadScene(dir / "file.json");
    EXPECT_NEAR(scene->desc.heightmap.pitch, 0.005, 1e-15);
    EXPECT_NEAR(scene->surface->pitch(), 0.005, 1e-15);
    EXPECT_EQ(scene->mapWidth, 8);
    EXPECT_EQ(scene->mapHeight, 6);

    test::writeText(dir / "same.json",
                    R"({"heightmap": {"path": "part.x3p", "pixel_pitch": 0.005}, )" + cam + "}");
    EXPECT_NEAR(loadScene(dir / "same.json")->surface->pitch(), 0.005, 1e-15);

    test::writeText(dir / "other.json",
                    R"({"heightmap": {"path": "part.x3p", "pixel_pitch": 0.01}, )" + cam + "}");
    try {
        loadScene(dir / "other.json");
        ADD_FAILURE() << "a disagreeing pixel_pitch was accepted";
    } catch (const InputError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find((dir / "other.json").string()), std::string::npos) << msg;
        EXPECT_NE(msg.find("heightmap.pixel_pitch 0.01 disagrees with the file's 0.005 mm"),
                  std::string::npos)
            << msg;
        EXPECT_NE(msg.find("remove pixel_pitch"), std::string::npos) << msg;
    }

    // A map without its own pitch needs the scene's (a silent default was 6x off on a real
    // part): refused, saying how to give it; the override that accepts the default works.
    std::vector<float> flat(48, 0.0f);
    test::writeNpyF32(dir / "part.npy", 6, 8, flat);
    test::writeText(dir / "npy.json", R"({"heightmap": {"path": "part.npy"}, )" + cam + "}");
    try {
        loadScene(dir / "npy.json");
        ADD_FAILURE() << "a map without a pitch was read at the default";
    } catch (const InputError& e) {
        const std::string msg = e.what();
        for (const char* part : {"npy.json", "part.npy", "carries no sample spacing",
                                 "\"pixel_pitch\": MM", "option 'assume-pitch'"})
            EXPECT_NE(msg.find(part), std::string::npos) << part << " not in: " << msg;
    }
    EXPECT_NEAR(loadScene(dir / "npy.json", {"heightmap.pixel_pitch=0.01"})->surface->pitch(), 0.01,
                1e-15);
    test::writeText(dir / "npy2.json",
                    R"({"heightmap": {"path": "part.npy", "pixel_pitch": 0.03}, )" + cam + "}");
    const auto withPitch = loadScene(dir / "npy2.json");
    EXPECT_NEAR(withPitch->surface->pitch(), 0.03, 1e-15);
    EXPECT_EQ(describePart(*withPitch),
              "part part.npy (npy float32): 8 x 6 samples, pitch 0.03 mm, 0.21 x 0.15 mm, heights "
              "0 .. 0 mm, 0 invalid points filled");

    // SDF too.
    SdfSpec sd;
    sd.points = 8;
    sd.profiles = 6;
    sd.xs = sd.ys = 2e-6;
    sd.values.assign(48, 3.0);
    writeSdfBinary(dir / "part.sdf", sd);
    test::writeText(dir / "sdf.json", R"({"heightmap": {"path": "part.sdf"}, )" + cam + "}");
    EXPECT_NEAR(loadScene(dir / "sdf.json")->surface->pitch(), 0.002, 1e-15);
}

TEST(FormatsInfo, InfoSaysWhatTheReadersFound) {
    // `info` (app/jobs/InfoJob.h) says what every command reads: the summary, without the CLI.
    test::TempDir dir("info");
    // A measured X3P: a tilted plane with one invalid point. Its pitch is the file's, the
    // default levelling (auto) removes the plane, so the heights after it are flat: Sq 0.
    X3pSpec s;
    s.sizeX = 8;
    s.sizeY = 6;
    for (int j = 0; j < 6; ++j)
        for (int i = 0; i < 8; ++i) s.values.push_back(1e-6 * (3.0 + 2.0 * i - 1.5 * j));
    s.values[13] = kNaN;
    writeX3p(dir / "plane.x3p", s);
    InfoJobSummary x = runInfoJob({dir / "plane.x3p", {}});
    EXPECT_EQ(x.reader, loadHeightmap(dir / "plane.x3p", {}).format);
    EXPECT_TRUE(x.measured);
    EXPECT_EQ(x.width, 8);
    EXPECT_EQ(x.height, 6);
    ASSERT_TRUE(x.pitch.has_value());
    EXPECT_NEAR(*x.pitch, 0.005, 1e-15);
    EXPECT_EQ(x.pitchFrom, "file");
    EXPECT_EQ(x.resampling, "");
    EXPECT_EQ(x.invalidFilled, 1u);
    EXPECT_EQ(x.levelling.applied.mode, LevellingDesc::Mode::Plane);
    EXPECT_TRUE(x.levelling.automatic);
    EXPECT_GT(x.levelling.rmsBefore, 1e-3);
    EXPECT_LT(x.sq, 1e-9);
    EXPECT_LT(x.maxHeight - x.minHeight, 1e-8);
    EXPECT_TRUE(x.heightsInMm);
    EXPECT_TRUE(x.part.is_null());
    nlohmann::ordered_json j = infoJson(x);
    EXPECT_EQ(j["size_px"], nlohmann::ordered_json({8, 6}));
    EXPECT_NEAR(j["size_mm"][0].get<double>(), 7 * 0.005, 1e-15);
    EXPECT_EQ(j["resampled"], false);
    EXPECT_EQ(j["levelling"]["mode"], "plane");
    EXPECT_TRUE(j["scene"].is_null());

    // Non-square pixels are resampled, and info says so.
    s.incY = 1e-5;
    writeX3p(dir / "rect.x3p", s);
    const InfoJobSummary r = runInfoJob({dir / "rect.x3p", {}});
    EXPECT_NE(r.resampling, "");
    EXPECT_EQ(infoJson(r)["resampled"], true);

    // A bare .npy carries no pitch and is not levelled (auto: heights as designed): its Sq is
    // the RMS of its values about their mean.
    std::vector<float> v(48);
    for (size_t k = 0; k < v.size(); ++k) v[k] = static_cast<float>(k % 5);
    test::writeNpyF32(dir / "part.npy", 6, 8, v);
    const InfoJobSummary n = runInfoJob({dir / "part.npy", {}});
    EXPECT_FALSE(n.pitch.has_value());
    EXPECT_EQ(n.pitchFrom, "none");
    EXPECT_FALSE(n.measured);
    EXPECT_FALSE(n.heightsInMm);
    EXPECT_EQ(n.levelling.applied.mode, LevellingDesc::Mode::None);
    double mean = 0, ss = 0;
    for (float h : v) mean += h / 48.0;
    for (float h : v) ss += (h - mean) * (h - mean);
    EXPECT_NEAR(n.sq, std::sqrt(ss / 48.0), 1e-12);
    EXPECT_EQ(n.minHeight, 0.0);
    EXPECT_EQ(n.maxHeight, 4.0);
    EXPECT_TRUE(infoJson(n)["pixel_pitch_mm"].is_null());

    // Its scene gives the pitch, and the scene's material and camera are reported; an override
    // applies as it does for every command.
    test::writeText(dir / "npy.json",
                    R"({"heightmap": {"path": "part.npy", "pixel_pitch": 0.02},
                        "camera": {"width": 16, "height": 12}})");
    const InfoJobSummary c = runInfoJob({dir / "npy.json", {"material.alpha=0.2"}});
    EXPECT_EQ(c.scene, (dir / "npy.json").string());
    EXPECT_EQ(c.file, (dir / "part.npy").string());
    ASSERT_TRUE(c.pitch.has_value());
    EXPECT_EQ(*c.pitch, 0.02);
    EXPECT_EQ(c.pitchFrom, "scene");
    EXPECT_TRUE(c.heightsInMm);
    j = infoJson(c);
    EXPECT_EQ(j["camera"]["width"], 16);
    EXPECT_NEAR(j["material"]["alpha"][0].get<double>(), 0.2, 1e-6);
    EXPECT_NEAR(j["size_mm"][1].get<double>(), 5 * 0.02, 1e-15);
}

TEST(FormatsBench, ReadBenchReadsTheSameHeightsFromEveryFormat) {
    ReadBenchOptions o;
    o.size = 40;  // 1600 samples: the NaN every 9973rd is the first only
    o.repeats = 1;
    const ReadBenchResult r = runReadBench(o);
    ASSERT_GE(r.rows.size(), 4u);
    EXPECT_EQ(r.rows.front().format, "exr float32");
    std::map<std::string, const ReadBenchRow*> by;
    for (const ReadBenchRow& row : r.rows) {
        EXPECT_EQ(row.width, 40) << row.format;
        EXPECT_EQ(row.height, 40) << row.format;
        EXPECT_GT(row.ratioToExr, 0.0) << row.format;
        by[row.reader] = &row;
    }
    ASSERT_TRUE(by.count("ours (io/TrueMap.cpp)") && by.count("ours (io/NanoFocusNms.cpp)"));
    // the float formats carry the instrument's invalid point; NMS has no code for one
    EXPECT_EQ(by["ours (io/X3p.cpp)"]->invalidFilled, 1u);
    EXPECT_EQ(by["ours (io/TrueMap.cpp)"]->invalidFilled, 1u);
    EXPECT_EQ(by["ours (io/NanoFocusNms.cpp)"]->invalidFilled, 0u);
    EXPECT_NE(r.csv().find("tmd float32,ours (io/TrueMap.cpp),40,40,"), std::string::npos);
}

TEST(FormatsBench, LoadBenchTimesEachFileAsTheCommandsLoadIt) {
    // `bench load` (app/bench/LoadBench.h), run tiny without the CLI: a row per file in their
    // order, each file read and levelled as every command reads a bare height map
    // (loadHeightSource); no timing asserted, only what the rows say and how they are formed.
    test::TempDir dir("load-bench");
    X3pSpec s;  // measured, non-square pixels, one invalid point, a tilt for the plane to remove
    s.sizeX = 8;
    s.sizeY = 6;
    s.incY = 1e-5;
    for (int j = 0; j < 6; ++j)
        for (int i = 0; i < 8; ++i) s.values.push_back(1e-6 * (3.0 + 2.0 * i - 1.5 * j + (i % 3)));
    s.values[13] = kNaN;
    writeX3p(dir / "tilt, rect.x3p", s);
    SdfSpec b;
    b.values = ramp(4, 3);
    writeSdfBinary(dir / "b.sdf", b);
    std::vector<float> v(48);
    for (size_t k = 0; k < v.size(); ++k) v[k] = static_cast<float>(k % 7);
    test::writeNpyF32(dir / "part.npy", 6, 8, v);

    LoadBenchOptions o;
    o.files = {dir / "tilt, rect.x3p", dir / "b.sdf", dir / "part.npy"};
    o.repeats = 2;
    const LoadBenchResult r = runLoadBench(o);
    ASSERT_EQ(r.rows.size(), 3u);
    for (size_t i = 0; i < 3; ++i) {
        const LoadBenchRow& row = r.rows[i];
        SCOPED_TRACE(row.file.string());
        EXPECT_EQ(row.file, o.files[i]);
        const HeightSource src = loadHeightSource(row.file);
        EXPECT_EQ(row.reader, src.map.format);
        EXPECT_EQ(row.width, src.width());
        EXPECT_EQ(row.height, src.height());
        EXPECT_EQ(row.invalidFilled, src.map.invalidFilled);
        EXPECT_EQ(row.resampling, src.map.resampling);
        EXPECT_EQ(row.bytes, fs::file_size(row.file));
        // the levelling the commands apply, to the bit
        EXPECT_EQ(row.levelling.applied.mode, src.load.levelling.applied.mode);
        EXPECT_EQ(row.levelling.automatic, src.load.levelling.automatic);
        EXPECT_EQ(row.levelling.rmsAfter, src.load.levelling.rmsAfter);
        EXPECT_EQ(row.levelling.coefficients, src.load.levelling.coefficients);
        for (double t : {row.firstSeconds, row.rawSeconds, row.readSeconds, row.readCpuSeconds,
                         row.levelSeconds})
            EXPECT_TRUE(std::isfinite(t) && t >= 0.0) << t;
        EXPECT_EQ(row.readRatio(), row.readSeconds / row.rawSeconds);
        EXPECT_EQ(row.readMBps(), static_cast<double>(row.bytes) / 1e6 / row.readSeconds);
    }
    EXPECT_NE(r.rows[0].resampling, "");
    EXPECT_EQ(r.rows[0].invalidFilled, 1u);
    EXPECT_EQ(r.rows[0].levelling.applied.mode, LevellingDesc::Mode::Plane);
    EXPECT_EQ(r.rows[2].levelling.applied.mode, LevellingDesc::Mode::None);
    // CSV: a header and a line per file; a path and a reader holding commas stay one field
    const std::string csv = r.csv();
    std::istringstream lines(csv);
    std::vector<std::string> l;
    for (std::string line; std::getline(lines, line);) l.push_back(line);
    ASSERT_EQ(l.size(), 4u) << csv;
    EXPECT_EQ(l[0].rfind("file,reader,bytes,", 0), 0u) << l[0];
    EXPECT_EQ(l[1].rfind("\"" + o.files[0].string() + "\",\"" + r.rows[0].reader + "\",", 0), 0u)
        << l[1];

    // Bad input is named: no file, no repeat, a file no reader reads.
    EXPECT_THROW(runLoadBench({}), InputError);
    LoadBenchOptions zero = o;
    zero.repeats = 0;
    EXPECT_THROW(runLoadBench(zero), InputError);
    test::writeText(dir / "notes.txt", "not a height map");
    LoadBenchOptions bad;
    bad.files = {dir / "notes.txt"};
    try {
        runLoadBench(bad);
        ADD_FAILURE() << "notes.txt was read";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("notes.txt"), std::string::npos) << e.what();
    }
}
