// Tests for src/io: .npy reader, height maps, image files, atomic writes and env maps.
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "TestUtil.h"
#include "core/Color.h"
#include "core/Error.h"
#include "io/AtomicFile.h"
#include "io/EnvMapIO.h"
#include "io/ExrReader.h"
#include "io/HeightmapIO.h"
#include "io/ImageIO.h"
#include "io/Npy.h"
#include "io/SceneFile.h"

namespace fs = std::filesystem;
using namespace sl;

namespace {

/// A fresh directory per test, removed afterwards.
class TempDir {
  public:
    TempDir() {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        static int counter = 0;
        path_ = fs::temp_directory_path() /
                ("sl_test_io_" + std::string(info->test_suite_name()) + "_" + info->name() + "_" +
                 std::to_string(::getpid()) + "_" + std::to_string(counter++));
        fs::remove_all(path_);
        fs::create_directories(path_);
    }
    ~TempDir() {
        std::error_code ec;
        fs::remove_all(path_, ec);
    }
    fs::path operator/(const std::string& name) const { return path_ / name; }
    const fs::path& path() const { return path_; }
    std::vector<std::string> entries() const {
        std::vector<std::string> out;
        for (const auto& e : fs::directory_iterator(path_)) out.push_back(e.path().filename());
        std::sort(out.begin(), out.end());
        return out;
    }

  private:
    fs::path path_;
};

void writeBytes(const fs::path& p, const std::string& bytes) {
    std::ofstream f(p, std::ios::binary);
    f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

std::string readBytes(const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

/// A .npy file written byte by byte, as numpy.save does (header padded to a multiple of 64).
std::string npyBytes(const std::string& descr, const std::string& shape, const void* data,
                     size_t dataBytes, int major = 1, bool fortran = false) {
    std::string dict = "{'descr': '" + descr +
                       "', 'fortran_order': " + (fortran ? "True" : "False") +
                       ", 'shape': " + shape + ", }";
    const size_t prefix = major == 1 ? 10 : 12;
    size_t total = prefix + dict.size() + 1;
    const size_t padded = (total + 63) / 64 * 64;
    dict += std::string(padded - total, ' ') + "\n";
    std::string out = "\x93NUMPY";
    out += static_cast<char>(major);
    out += static_cast<char>(0);
    const size_t len = dict.size();
    out += static_cast<char>(len & 0xff);
    out += static_cast<char>((len >> 8) & 0xff);
    if (major != 1) {
        out += static_cast<char>((len >> 16) & 0xff);
        out += static_cast<char>((len >> 24) & 0xff);
    }
    out += dict;
    out.append(static_cast<const char*>(data), dataBytes);
    return out;
}

template <typename T>
void writeNpy(const fs::path& p, const std::string& descr, int rows, int cols,
              const std::vector<T>& v, int major = 1, bool fortran = false) {
    writeBytes(
        p,
        npyBytes(descr, std::string("(") + std::to_string(rows) + ", " + std::to_string(cols) + ")",
                 v.data(), v.size() * sizeof(T), major, fortran));
}

/// Writes pixels with OpenImageIO directly (the format comes from the extension).
void writeOiio(const fs::path& p, int w, int h, int nch, OIIO::TypeDesc fileType,
               OIIO::TypeDesc dataType, const void* data, const char* colorSpace = nullptr) {
    auto out = OIIO::ImageOutput::create(p.string());
    ASSERT_TRUE(out) << OIIO::geterror();
    OIIO::ImageSpec spec(w, h, nch, fileType);
    if (colorSpace) spec.attribute("oiio:ColorSpace", colorSpace);
    ASSERT_TRUE(out->open(p.string(), spec)) << out->geterror();
    ASSERT_TRUE(out->write_image(dataType, data)) << out->geterror();
    ASSERT_TRUE(out->close());
}

/// Runs f, expects InputError whose message contains every string in `parts`.
template <typename F>
void expectInputError(F&& f, std::initializer_list<std::string> parts) {
    try {
        f();
        ADD_FAILURE() << "expected sl::InputError";
    } catch (const InputError& e) {
        const std::string msg = e.what();
        for (const auto& part : parts)
            EXPECT_NE(msg.find(part), std::string::npos)
                << "message lacks \"" << part << "\": " << msg;
    } catch (const std::exception& e) {
        ADD_FAILURE() << "expected sl::InputError, got: " << e.what();
    }
}

// 7 columns x 5 rows, values k/256 − 1: exact in half, float and double.
constexpr int kW = 7, kH = 5;
std::vector<float> halfExactHeights() {
    std::vector<float> v(kW * kH);
    for (int r = 0; r < kH; ++r)
        for (int c = 0; c < kW; ++c)
            v[r * kW + c] = static_cast<float>(r * 37 + c * 5) / 256.0f - 1.0f;
    return v;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Npy

TEST(Npy, ReadsFloat32RowMajor) {
    TempDir dir;
    std::vector<float> v(3 * 7);
    for (size_t k = 0; k < v.size(); ++k) v[k] = 0.5f * static_cast<float>(k) - 3.0f;
    writeNpy(dir / "a.npy", "<f4", 3, 7, v);
    NpyMatrix m = readNpy2D(dir / "a.npy");
    EXPECT_EQ(m.rows, 3);
    EXPECT_EQ(m.cols, 7);
    EXPECT_EQ(m.typeName(), "float32");
    EXPECT_EQ(m.data, v);
}

TEST(Npy, ReadsFloat64InFormatVersions2And3) {
    TempDir dir;
    std::vector<double> v = {0.25, -1.5, 3.0, 1e-3, 7.0, 8.5};
    for (int major : {1, 2, 3}) {
        const fs::path p = dir / (std::string("v") + std::to_string(major) + ".npy");
        writeNpy(p, "<f8", 2, 3, v, major);
        NpyHeader h = readNpyHeader(p);
        EXPECT_EQ(h.versionMajor, major);
        EXPECT_EQ(h.dataOffset % 64, 0u);
        NpyMatrix m = readNpy2D(p);
        ASSERT_EQ(m.data.size(), v.size());
        for (size_t k = 0; k < v.size(); ++k) EXPECT_EQ(m.data[k], static_cast<float>(v[k]));
        EXPECT_EQ(m.typeName(), "float64");
    }
}

TEST(Npy, AcceptsTrailingUnitDimensionAndUInt16) {
    TempDir dir;
    std::vector<uint16_t> v = {0, 1, 2, 65535, 40000, 7};
    writeBytes(dir / "u.npy", npyBytes("<u2", "(3, 2, 1)", v.data(), v.size() * 2));
    NpyMatrix m = readNpy2D(dir / "u.npy");
    EXPECT_EQ(m.rows, 3);
    EXPECT_EQ(m.cols, 2);
    EXPECT_EQ(m.type, NpyType::UInt16);
    for (size_t k = 0; k < v.size(); ++k) EXPECT_EQ(m.data[k], static_cast<float>(v[k]));
}

TEST(Npy, RejectsFortranOrder) {
    TempDir dir;
    std::vector<float> v(6, 1.0f);
    writeNpy(dir / "f.npy", "<f4", 2, 3, v, 1, /*fortran=*/true);
    expectInputError([&] { readNpy2D(dir / "f.npy"); }, {"f.npy", "ascontiguousarray"});
}

TEST(Npy, RejectsMalformedFiles) {
    TempDir dir;
    std::vector<float> v(6, 1.0f);
    // not npy at all
    writeBytes(dir / "garbage.npy", "hello world, definitely not numpy");
    expectInputError([&] { readNpy2D(dir / "garbage.npy"); }, {"garbage.npy", "magic"});
    // truncated data
    std::string b = npyBytes("<f4", "(2, 3)", v.data(), v.size() * 4);
    writeBytes(dir / "trunc.npy", b.substr(0, b.size() - 5));
    expectInputError([&] { readNpy2D(dir / "trunc.npy"); }, {"trunc.npy", "truncated"});
    // trailing bytes
    writeBytes(dir / "extra.npy", b + "xx");
    expectInputError([&] { readNpy2D(dir / "extra.npy"); }, {"extra.npy", "after the array"});
    // truncated header
    writeBytes(dir / "head.npy", b.substr(0, 20));
    expectInputError([&] { readNpy2D(dir / "head.npy"); }, {"head.npy"});
    // 1-D and 3-D shapes
    writeBytes(dir / "oned.npy", npyBytes("<f4", "(6,)", v.data(), 24));
    expectInputError([&] { readNpy2D(dir / "oned.npy"); }, {"oned.npy", "(6,)", "2-D"});
    writeBytes(dir / "threed.npy", npyBytes("<f4", "(1, 2, 3)", v.data(), 24));
    expectInputError([&] { readNpy2D(dir / "threed.npy"); }, {"threed.npy", "not 2-D"});
    // unsupported dtypes
    writeBytes(dir / "int.npy", npyBytes("<i4", "(2, 3)", v.data(), 24));
    expectInputError([&] { readNpy2D(dir / "int.npy"); }, {"int.npy", "<i4"});
    writeBytes(dir / "big.npy", npyBytes(">f4", "(2, 3)", v.data(), 24));
    expectInputError([&] { readNpy2D(dir / "big.npy"); }, {"big.npy", "big-endian"});
    // unsupported version
    std::string v4 = b;
    v4[6] = 4;
    writeBytes(dir / "v4.npy", v4);
    expectInputError([&] { readNpy2D(dir / "v4.npy"); }, {"v4.npy", "version 4.0"});
    // missing file
    expectInputError([&] { readNpy2D(dir / "none.npy"); }, {"none.npy", "not found"});
}

// ---------------------------------------------------------------------------------------------
// HeightmapIO

TEST(HeightmapIO, EveryFloatFormatLoadsIdenticalHeights) {
    TempDir dir;
    const std::vector<float> h = halfExactHeights();
    std::vector<double> h64(h.begin(), h.end());
    using OIIO::TypeDesc;
    writeOiio(dir / "f32.exr", kW, kH, 1, TypeDesc::FLOAT, TypeDesc::FLOAT, h.data());
    writeOiio(dir / "f16.exr", kW, kH, 1, TypeDesc::HALF, TypeDesc::FLOAT, h.data());
    writeOiio(dir / "f32.tif", kW, kH, 1, TypeDesc::FLOAT, TypeDesc::FLOAT, h.data());
    // (OpenImageIO 2.4 writes a HALF TIFF request as float32, so float16 TIFF input cannot be
    // made here; it is read through the same HALF -> float path as half EXR.)
    writeNpy(dir / "f32.npy", "<f4", kH, kW, h);
    writeNpy(dir / "f64.npy", "<f8", kH, kW, h64);
    const std::pair<const char*, const char*> cases[] = {{"f32.exr", "exr float32"},
                                                         {"f16.exr", "exr float16"},
                                                         {"f32.tif", "tiff float32"},
                                                         {"f32.npy", "npy float32"},
                                                         {"f64.npy", "npy float64"}};
    for (const auto& [name, format] : cases) {
        SCOPED_TRACE(name);
        HeightmapData d = loadHeightmap(dir / name, {});
        EXPECT_EQ(d.width, kW);
        EXPECT_EQ(d.height, kH);
        EXPECT_EQ(d.format, format);
        EXPECT_EQ(d.heights, h);  // exact, and row 0 / column 0 where they were written
    }
}

TEST(HeightmapIO, EveryIntegerFormatLoadsIdenticalHeights) {
    TempDir dir;
    std::vector<uint16_t> q(kW * kH);
    for (size_t k = 0; k < q.size(); ++k) q[k] = static_cast<uint16_t>((k * 2003) % 65536);
    q[0] = 0;
    q[1] = 65535;
    const double lo = -0.25, hi = 0.75;
    std::vector<float> expected(q.size());
    for (size_t k = 0; k < q.size(); ++k)
        expected[k] = static_cast<float>(lo + (hi - lo) * (q[k] / 65535.0));
    EXPECT_EQ(expected[0], -0.25f);
    EXPECT_EQ(expected[1], 0.75f);

    using OIIO::TypeDesc;
    writeOiio(dir / "q.png", kW, kH, 1, TypeDesc::UINT16, TypeDesc::UINT16, q.data());
    writeOiio(dir / "q.tif", kW, kH, 1, TypeDesc::UINT16, TypeDesc::UINT16, q.data());
    writeNpy(dir / "q.npy", "<u2", kH, kW, q);
    // The same heights stored as floats in scene units.
    writeOiio(dir / "h.exr", kW, kH, 1, TypeDesc::FLOAT, TypeDesc::FLOAT, expected.data());
    writeNpy(dir / "h.npy", "<f4", kH, kW, expected);

    HeightmapOptions intOpt;
    intOpt.heightRange = std::array<double, 2>{lo, hi};
    for (const auto& [name, format] : std::vector<std::pair<std::string, std::string>>{
             {"q.png", "png uint16"}, {"q.tif", "tiff uint16"}, {"q.npy", "npy uint16"}}) {
        SCOPED_TRACE(name);
        HeightmapData d = loadHeightmap(dir / name, intOpt);
        EXPECT_EQ(d.format, format);
        EXPECT_EQ(d.width, kW);
        EXPECT_EQ(d.height, kH);
        EXPECT_EQ(d.heights, expected);
    }
    EXPECT_EQ(loadHeightmap(dir / "h.exr", {}).heights, expected);
    EXPECT_EQ(loadHeightmap(dir / "h.npy", {}).heights, expected);
}

TEST(HeightmapIO, EightBitPngIsDataNotSrgb) {
    TempDir dir;
    std::vector<uint8_t> v = {0, 1, 128, 254, 255, 77};
    writeOiio(dir / "b.png", 3, 2, 1, OIIO::TypeDesc::UINT8, OIIO::TypeDesc::UINT8, v.data());
    HeightmapOptions opt;
    opt.heightRange = std::array<double, 2>{1.0, 3.0};
    HeightmapData d = loadHeightmap(dir / "b.png", opt);
    EXPECT_EQ(d.format, "png uint8");
    for (size_t k = 0; k < v.size(); ++k)
        EXPECT_EQ(d.heights[k], static_cast<float>(1.0 + 2.0 * (v[k] / 255.0)));
}

TEST(HeightSource, BareMapOrSceneFile) {
    TempDir dir;
    std::vector<uint8_t> v = {0, 51, 255, 102, 204, 153};
    writeOiio(dir / "b.png", 3, 2, 1, OIIO::TypeDesc::UINT8, OIIO::TypeDesc::UINT8, v.data());
    // a bare integer map without a range is read as [0, 1]
    const HeightSource bare = loadHeightSource(dir / "b.png");
    EXPECT_EQ(bare.scene, nullptr);
    EXPECT_EQ(bare.width(), 3);
    EXPECT_EQ(bare.height(), 2);
    for (size_t k = 0; k < v.size(); ++k) EXPECT_EQ(bare.heights()[k], v[k] / 255.0f);
    // overrides on a bare map make it the default scene around it, as render reads one: a
    // scene's rules then hold (an integer map needs its range, named with the map) ...
    try {
        (void)loadHeightSource(dir / "b.png", {"material.alpha=0.1"});
        ADD_FAILURE() << "an integer map without a range was read as a scene";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("b.png"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("height_range"), std::string::npos) << e.what();
    }
    // ... and the overrides apply
    const HeightSource over = loadHeightSource(
        dir / "b.png", {"heightmap.height_range=[2, 4]", "heightmap.pixel_pitch=0.01"});
    ASSERT_NE(over.scene, nullptr);
    EXPECT_EQ(over.heights()[2], 4.0f);
    EXPECT_EQ(over.heights()[0], 2.0f);
    // a scene file gives the whole scene (its range, its camera); overrides apply to it
    std::ofstream(dir / "s.json")
        << (R"({"heightmap": {"path": "b.png", "height_range": [2, 4], "pixel_pitch": 0.01}, "camera": {"width": 8,
                  "height": 6}})");
    const HeightSource sc = loadHeightSource(dir / "s.json", {"camera.width=10"});
    ASSERT_NE(sc.scene, nullptr);
    EXPECT_EQ(sc.width(), 3);
    EXPECT_EQ(sc.height(), 2);
    EXPECT_EQ(sc.heights()[2], 4.0f);
    EXPECT_EQ(sc.scene->camera.width(), 10);
}

TEST(HeightmapIO, NonSquareMapKeepsOrientation) {
    TempDir dir;
    const int w = 7, h = 3;  // 7 columns, 3 rows
    std::vector<float> v(w * h);
    std::vector<uint16_t> q(w * h);
    for (int r = 0; r < h; ++r)
        for (int c = 0; c < w; ++c) {
            v[r * w + c] = static_cast<float>(100 * r + c);
            q[r * w + c] = static_cast<uint16_t>(100 * r + c);
        }
    writeOiio(dir / "o.exr", w, h, 1, OIIO::TypeDesc::FLOAT, OIIO::TypeDesc::FLOAT, v.data());
    writeOiio(dir / "o.png", w, h, 1, OIIO::TypeDesc::UINT16, OIIO::TypeDesc::UINT16, q.data());
    writeNpy(dir / "o.npy", "<f4", h, w, v);
    HeightmapOptions intOpt;
    intOpt.heightRange = std::array<double, 2>{0.0, 65535.0};  // code == height
    for (const char* name : {"o.exr", "o.png", "o.npy"}) {
        SCOPED_TRACE(name);
        HeightmapData d =
            loadHeightmap(dir / name, std::string(name) == "o.png" ? intOpt : HeightmapOptions{});
        ASSERT_EQ(d.width, w);
        ASSERT_EQ(d.height, h);
        EXPECT_EQ(d.heights[0], 0.0f);            // row 0, column 0
        EXPECT_EQ(d.heights[6], 6.0f);            // row 0, last column
        EXPECT_EQ(d.heights[2 * w + 0], 200.0f);  // last row, column 0
        EXPECT_EQ(d.heights[2 * w + 6], 206.0f);  // last row, last column
        EXPECT_EQ(d.heights[1 * w + 3], 103.0f);
    }
}

TEST(HeightmapIO, HeightScaleMultipliesFloatHeights) {
    TempDir dir;
    const std::vector<float> h = halfExactHeights();
    writeNpy(dir / "h.npy", "<f4", kH, kW, h);
    HeightmapOptions opt;
    opt.heightScale = 0.001;  // e.g. a map in micrometres, scene in millimetres
    HeightmapData d = loadHeightmap(dir / "h.npy", opt);
    for (size_t k = 0; k < h.size(); ++k) EXPECT_EQ(d.heights[k], static_cast<float>(0.001 * h[k]));
}

TEST(HeightmapIO, GrayStoredAsRgbIsAcceptedOtherwiseRejected) {
    TempDir dir;
    const int w = 4, h = 3;
    std::vector<float> rgb(w * h * 3);
    std::vector<uint16_t> rgba(w * h * 4);
    for (int p = 0; p < w * h; ++p) {
        for (int c = 0; c < 3; ++c) rgb[p * 3 + c] = 0.125f * static_cast<float>(p);
        for (int c = 0; c < 3; ++c) rgba[p * 4 + c] = static_cast<uint16_t>(1000 * p);
        rgba[p * 4 + 3] = 65535;
    }
    using OIIO::TypeDesc;
    writeOiio(dir / "gray.exr", w, h, 3, TypeDesc::FLOAT, TypeDesc::FLOAT, rgb.data());
    writeOiio(dir / "gray.png", w, h, 4, TypeDesc::UINT16, TypeDesc::UINT16, rgba.data());
    HeightmapData d = loadHeightmap(dir / "gray.exr", {});
    for (int p = 0; p < w * h; ++p) EXPECT_EQ(d.heights[p], 0.125f * static_cast<float>(p));
    HeightmapOptions opt;
    opt.heightRange = std::array<double, 2>{0.0, 65535.0};
    d = loadHeightmap(dir / "gray.png", opt);
    for (int p = 0; p < w * h; ++p) EXPECT_EQ(d.heights[p], static_cast<float>(1000 * p));

    // Tiled, with a data window not at the origin (read by bands of tiles).
    {
        auto out = OIIO::ImageOutput::create((dir / "tiled.exr").string());
        OIIO::ImageSpec spec(w, h, 3, TypeDesc::FLOAT);
        spec.tile_width = spec.tile_height = 16;
        spec.x = 5;
        spec.y = -3;
        ASSERT_TRUE(out->open((dir / "tiled.exr").string(), spec));
        ASSERT_TRUE(out->write_image(TypeDesc::FLOAT, rgb.data()));
        ASSERT_TRUE(out->close());
    }
    d = loadHeightmap(dir / "tiled.exr", {});
    ASSERT_EQ(d.width, w);
    ASSERT_EQ(d.height, h);
    for (int p = 0; p < w * h; ++p) EXPECT_EQ(d.heights[p], 0.125f * static_cast<float>(p));

    rgb[(2 * w + 1) * 3 + 1] += 1.0f;  // row 2, column 1, G differs
    writeOiio(dir / "colour.exr", w, h, 3, TypeDesc::FLOAT, TypeDesc::FLOAT, rgb.data());
    expectInputError([&] { loadHeightmap(dir / "colour.exr", {}); },
                     {"colour.exr", "row 2, column 1", "single-channel"});
    rgba[(1 * w + 2) * 4 + 3] = 0;  // row 1, column 2 transparent
    writeOiio(dir / "alpha.png", w, h, 4, TypeDesc::UINT16, TypeDesc::UINT16, rgba.data());
    expectInputError([&] { loadHeightmap(dir / "alpha.png", opt); },
                     {"alpha.png", "transparent", "row 1, column 2"});
}

TEST(HeightmapIO, ErrorsNameTheFile) {
    TempDir dir;
    using OIIO::TypeDesc;
    expectInputError([&] { loadHeightmap(dir / "missing.exr", {}); }, {"missing.exr", "not found"});
    writeBytes(dir / "corrupt.exr", "these are not the bytes of an OpenEXR file at all");
    expectInputError([&] { loadHeightmap(dir / "corrupt.exr", {}); }, {"corrupt.exr"});
    writeBytes(dir / "corrupt.png", std::string("\x89PNG\r\n\x1a\n", 8) + "broken");
    expectInputError([&] { loadHeightmap(dir / "corrupt.png", {}); }, {"corrupt.png"});

    std::vector<float> h = halfExactHeights();
    h[2 * kW + 3] = std::numeric_limits<float>::quiet_NaN();
    h[3 * kW + 1] = std::numeric_limits<float>::quiet_NaN();
    writeOiio(dir / "nan.exr", kW, kH, 1, TypeDesc::FLOAT, TypeDesc::FLOAT, h.data());
    expectInputError([&] { loadHeightmap(dir / "nan.exr", {}); },
                     {"nan.exr", "NaN", "row 2, column 3"});
    h = halfExactHeights();
    h[1 * kW + 6] = -std::numeric_limits<float>::infinity();
    writeNpy(dir / "inf.npy", "<f4", kH, kW, h);
    expectInputError([&] { loadHeightmap(dir / "inf.npy", {}); },
                     {"inf.npy", "infinite", "row 1, column 6"});
    std::vector<double> big(4, 1.0);
    big[3] = 1e300;  // finite in float64, infinite in float32
    writeNpy(dir / "big.npy", "<f8", 2, 2, big);
    expectInputError([&] { loadHeightmap(dir / "big.npy", {}); }, {"big.npy", "row 1, column 1"});

    std::vector<uint16_t> q(kW * kH, 1000);
    writeOiio(dir / "int.png", kW, kH, 1, TypeDesc::UINT16, TypeDesc::UINT16, q.data());
    expectInputError([&] { loadHeightmap(dir / "int.png", {}); },
                     {"int.png",
                      "integer height map needs heightmap.height_range: [min, max] "
                      "in scene units"});
    writeNpy(dir / "int.npy", "<u2", kH, kW, q);
    expectInputError([&] { loadHeightmap(dir / "int.npy", {}); }, {"int.npy", "height_range"});
    HeightmapOptions scaled;
    scaled.heightRange = std::array<double, 2>{0.0, 1.0};
    scaled.heightScale = 2.0;
    expectInputError([&] { loadHeightmap(dir / "int.png", scaled); }, {"int.png", "height_scale"});
    HeightmapOptions bad;
    bad.heightRange = std::array<double, 2>{1.0, 1.0};
    expectInputError([&] { loadHeightmap(dir / "int.png", bad); }, {"int.png", "min < max"});

    writeNpy(dir / "float.npy", "<f4", kH, kW, halfExactHeights());
    HeightmapOptions ranged;
    ranged.heightRange = std::array<double, 2>{0.0, 1.0};
    expectInputError([&] { loadHeightmap(dir / "float.npy", ranged); },
                     {"float.npy", "height_range applies to integer"});

    writeNpy(dir / "fortran.npy", "<f4", kH, kW, halfExactHeights(), 1, true);
    expectInputError([&] { loadHeightmap(dir / "fortran.npy", {}); },
                     {"fortran.npy", "ascontiguousarray"});

    std::vector<float> one = {1.0f};
    writeOiio(dir / "one.exr", 1, 1, 1, TypeDesc::FLOAT, TypeDesc::FLOAT, one.data());
    expectInputError([&] { loadHeightmap(dir / "one.exr", {}); },
                     {"one.exr", "height map must be at least 2x2"});
    std::vector<float> row(5, 1.0f);
    writeOiio(dir / "row.tif", 5, 1, 1, TypeDesc::FLOAT, TypeDesc::FLOAT, row.data());
    expectInputError([&] { loadHeightmap(dir / "row.tif", {}); }, {"row.tif", "at least 2x2"});
    writeNpy(dir / "empty.npy", "<f4", 0, 5, std::vector<float>{});
    expectInputError([&] { loadHeightmap(dir / "empty.npy", {}); },
                     {"empty.npy", "0 rows and 5 columns", "at least 2x2"});
    writeNpy(dir / "onebyone.npy", "<f8", 1, 1, std::vector<double>{2.0});
    expectInputError([&] { loadHeightmap(dir / "onebyone.npy", {}); },
                     {"onebyone.npy", "at least 2x2"});
    fs::create_directory(dir / "adir.exr");
    expectInputError([&] { loadHeightmap(dir / "adir.exr", {}); }, {"adir.exr"});
}

// ---------------------------------------------------------------------------------------------
// ImageIO

TEST(ImageIO, EightBitPngIsSrgbDecoded) {
    TempDir dir;
    std::vector<uint8_t> v(4 * 2, 128);
    v[1] = 0;
    v[2] = 255;
    writeOiio(dir / "p.png", 4, 2, 1, OIIO::TypeDesc::UINT8, OIIO::TypeDesc::UINT8, v.data());
    Image img = readImage(dir / "p.png");
    ASSERT_EQ(img.width, 4);
    ASSERT_EQ(img.height, 2);
    ASSERT_EQ(img.channels, 1);
    EXPECT_EQ(img.data[0], srgbDecode(128.0f / 255.0f));
    EXPECT_NEAR(img.data[0], 0.2158605f, 1e-6f);
    EXPECT_EQ(img.data[1], 0.0f);
    EXPECT_EQ(img.data[2], 1.0f);
    // 16-bit PNG without a colour tag is sRGB too (Mitsuba 3 treats every PNG so).
    std::vector<uint16_t> w(8, 32768);
    writeOiio(dir / "p16.png", 4, 2, 1, OIIO::TypeDesc::UINT16, OIIO::TypeDesc::UINT16, w.data());
    EXPECT_EQ(readImage(dir / "p16.png").data[0], srgbDecode(32768.0f / 65535.0f));
}

TEST(ImageIO, GammaTaggedPngIsDecodedWithItsGamma) {
    TempDir dir;
    std::vector<uint8_t> v(4, 128);
    {
        auto out = OIIO::ImageOutput::create((dir / "g.png").string());
        OIIO::ImageSpec spec(2, 2, 1, OIIO::TypeDesc::UINT8);
        spec.attribute("oiio:ColorSpace", "Gamma2.2");
        spec.attribute("oiio:Gamma", 2.2f);
        ASSERT_TRUE(out->open((dir / "g.png").string(), spec));
        ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, v.data()));
        ASSERT_TRUE(out->close());
    }
    EXPECT_NEAR(readImage(dir / "g.png").data[0], std::pow(128.0 / 255.0, 2.2), 1e-5);
    // 16-bit TIFF without a colour tag is linear.
    std::vector<uint16_t> w(4, 32768);
    writeOiio(dir / "l.tif", 2, 2, 1, OIIO::TypeDesc::UINT16, OIIO::TypeDesc::UINT16, w.data());
    EXPECT_EQ(readImage(dir / "l.tif").data[0], 32768.0f / 65535.0f);
}

TEST(ImageIO, ExrRoundTripIsExactWithNamedChannels) {
    TempDir dir;
    for (int nch : {1, 3}) {
        Image img(5, 3, nch);
        for (size_t k = 0; k < img.data.size(); ++k)
            img.data[k] = std::ldexp(static_cast<float>(k) + 0.1f, static_cast<int>(k % 9) - 4);
        const fs::path p = dir / ("rt" + std::to_string(nch) + ".exr");
        writeExr(p, img);
        Image back = readImage(p);
        EXPECT_EQ(back.width, 5);
        EXPECT_EQ(back.height, 3);
        EXPECT_EQ(back.channels, nch);
        EXPECT_EQ(back.data, img.data);
        auto in = OIIO::ImageInput::open(p.string());
        ASSERT_TRUE(in);
        EXPECT_EQ(in->spec().format, OIIO::TypeDesc::FLOAT);
        if (nch == 1) {
            EXPECT_EQ(in->spec().channelnames, std::vector<std::string>({"Y"}));
        } else {
            EXPECT_EQ(in->spec().channelnames, std::vector<std::string>({"R", "G", "B"}));
        }
    }
}

/// Every pixel of `p` as OpenImageIO reads it (read_image as float).
std::vector<float> oiioPixels(const fs::path& p, int& nch) {
    auto in = OIIO::ImageInput::open(p.string());
    if (!in) return {};
    const OIIO::ImageSpec& spec = in->spec();
    nch = spec.nchannels;
    std::vector<float> v(static_cast<size_t>(spec.width) * spec.height * spec.nchannels);
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, v.data())) return {};
    return v;
}

TEST(ImageIO, ExrsReadWithOpenExrAreOpenImageIOsPixelsToTheBit) {
    // io/ExrReader.h reads the EXRs it can without OpenImageIO; each must give what OpenImageIO
    // gives, and the others must still be read (by OpenImageIO's module).
    TempDir dir;
    struct Case {
        const char* name;
        int nch;
        OIIO::TypeDesc type;
        bool direct;  // read by OpenEXR itself
        std::vector<std::string> channels;
        int tile = 0, x = 0, y = 0;
    };
    const std::vector<Case> cases = {
        {"y-float", 1, OIIO::TypeDesc::FLOAT, true, {"Y"}},
        {"z-half", 1, OIIO::TypeDesc::HALF, true, {"Z"}},
        {"rgb-float", 3, OIIO::TypeDesc::FLOAT, true, {"R", "G", "B"}},
        {"rgba-half", 4, OIIO::TypeDesc::HALF, true, {"R", "G", "B", "A"}},
        {"rgb-tiled", 3, OIIO::TypeDesc::FLOAT, true, {"R", "G", "B"}, 4},
        {"y-window", 1, OIIO::TypeDesc::FLOAT, true, {"Y"}, 0, 3, -2},
        {"two-named", 2, OIIO::TypeDesc::FLOAT, false, {"height", "quality"}},
        {"alpha-only", 1, OIIO::TypeDesc::FLOAT, false, {"A"}},
        {"y-uint", 1, OIIO::TypeDesc::UINT, false, {"Y"}},
    };
    const int w = 7, h = 5;
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        std::vector<float> v(static_cast<size_t>(w) * h * c.nch);
        for (size_t k = 0; k < v.size(); ++k)
            v[k] = std::ldexp(static_cast<float>(k % 13) + 0.37f, static_cast<int>(k % 7) - 3);
        const fs::path p = dir / (std::string(c.name) + ".exr");
        {
            auto out = OIIO::ImageOutput::create(p.string());
            ASSERT_TRUE(out);
            OIIO::ImageSpec spec(w, h, c.nch, c.type);
            spec.channelnames = c.channels;
            spec.alpha_channel = c.nch == 4 ? 3 : -1;
            spec.x = c.x;
            spec.y = c.y;
            if (c.tile) spec.tile_width = spec.tile_height = c.tile;
            ASSERT_TRUE(out->open(p.string(), spec)) << out->geterror();
            ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, v.data())) << out->geterror();
            ASSERT_TRUE(out->close());
        }
        EXPECT_EQ(detail::openExrDirect(p.string()) != nullptr, c.direct);
        int nch = 0;
        const std::vector<float> want = oiioPixels(p, nch);
        ASSERT_FALSE(want.empty());
        const Image got = readImage(p);
        EXPECT_EQ(got.width, w);
        EXPECT_EQ(got.height, h);
        EXPECT_EQ(got.channels, nch);
        ASSERT_EQ(got.data.size(), want.size());
        EXPECT_EQ(std::memcmp(got.data.data(), want.data(), want.size() * sizeof(float)), 0);
    }
}

TEST(ImageIO, ARunOnExrInputsWritingExrAndPngNeverLoadsOpenImageIO) {
    // OpenImageIO is a module loaded on first use (io/ImageCodec.h): a render of the bundled
    // part (an EXR height map) to EXR and PNG files must not load it. The dynamic loader lists
    // what it loads (LD_DEBUG=files).
    TempDir dir;
    const std::string scene = std::string(SL_SOURCE_DIR) + "/scenes/default/scene.json";
    const test::RunResult r =
        test::runShell("LD_DEBUG=files " + std::string(SL_CLI_PATH) + " render " + scene +
                       " --size 16 --spp 1 -o " + (dir / "r.exr").string() + " 2>&1");
    ASSERT_EQ(r.exitCode, 0) << r.output.substr(r.output.size() > 4000 ? r.output.size() - 4000
                                                                       : 0);
    EXPECT_NE(r.output.find("libtbb"), std::string::npos);  // LD_DEBUG does list libraries
    EXPECT_EQ(r.output.find("libOpenImageIO"), std::string::npos);
    EXPECT_EQ(r.output.find("libscratchlight-oiio"), std::string::npos);
    EXPECT_TRUE(fs::exists(dir / "r.exr"));
}

TEST(ImageIO, PngPreviewIsSrgbEncodedAndClamped) {
    TempDir dir;
    Image img(4, 1, 3);
    const float vals[4] = {0.0f, 0.2158605f, 0.5f, 7.0f};
    for (int x = 0; x < 4; ++x)
        for (int c = 0; c < 3; ++c) img.at(x, 0, c) = vals[x];
    img.at(0, 0, 2) = -1.0f;  // clamped to 0
    writePng(dir / "prev.png", img);
    auto in = OIIO::ImageInput::open((dir / "prev.png").string());
    ASSERT_TRUE(in);
    std::vector<uint8_t> px(12);
    ASSERT_TRUE(in->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, px.data()));
    EXPECT_EQ(px[0], 0);
    EXPECT_EQ(px[2], 0);
    EXPECT_EQ(px[3], 128);
    EXPECT_EQ(px[6], static_cast<uint8_t>(std::lround(srgbEncode(0.5f) * 255.0f)));
    EXPECT_EQ(px[9], 255);
    // Exposure scales before encoding.
    writePng(dir / "exp.png", img, 2.0f);
    Image back = readImage(dir / "exp.png");
    EXPECT_NEAR(back.at(1, 0, 0), 2.0f * 0.2158605f, 0.01f);
    EXPECT_EQ(back.at(2, 0, 0), 1.0f);
    // Gray.
    Image gray(2, 2, 1, 0.5f);
    writePng(dir / "gray.png", gray);
    EXPECT_NEAR(readImage(dir / "gray.png").data[3], 0.5f, 0.003f);
}

TEST(ImageIO, Png16IsLinearData) {
    TempDir dir;
    Image img(3, 2, 1);
    img.data = {0.0f, 1.0f, 0.5f, 0.25f, 2.0f, -1.0f};
    writePng16(dir / "d.png", img);
    Image back = readImage(dir / "d.png");  // tagged linear: no sRGB decode
    const float expect[6] = {0.0f, 1.0f, 32768.0f / 65535.0f, 16384.0f / 65535.0f, 1.0f, 0.0f};
    for (int k = 0; k < 6; ++k) EXPECT_EQ(back.data[k], expect[k]);
    HeightmapOptions opt;
    opt.heightRange = std::array<double, 2>{0.0, 65535.0};
    HeightmapData d = loadHeightmap(dir / "d.png", opt);
    EXPECT_EQ(d.heights[2], 32768.0f);
    EXPECT_EQ(d.heights[3], 16384.0f);
}

TEST(ImageIO, MaskPngRoundTrip) {
    TempDir dir;
    std::vector<uint8_t> mask = {0, 255, 255, 0, 128, 1};
    writeMaskPng(dir / "m.png", mask, 3, 2);
    auto in = OIIO::ImageInput::open((dir / "m.png").string());
    ASSERT_TRUE(in);
    EXPECT_EQ(in->spec().nchannels, 1);
    std::vector<uint8_t> back(6);
    ASSERT_TRUE(in->read_image(0, 0, 0, 1, OIIO::TypeDesc::UINT8, back.data()));
    EXPECT_EQ(back, mask);
    EXPECT_EQ(readImage(dir / "m.png").data[4], 128.0f / 255.0f);  // linear tag honoured
    expectInputError([&] { writeMaskPng(dir / "bad.png", mask, 4, 2); }, {"bad.png"});
}

TEST(ImageIO, ReadErrorsNameTheFile) {
    TempDir dir;
    expectInputError([&] { readImage(dir / "nope.png"); }, {"nope.png", "not found"});
    writeBytes(dir / "junk.exr", "junk junk junk junk junk");
    expectInputError([&] { readImage(dir / "junk.exr"); }, {"junk.exr"});
}

TEST(ImageIO, WritersRejectBadInputWithoutLeavingFiles) {
    TempDir dir;
    Image img(2, 2, 3, 0.5f);
    expectInputError([&] { writeExr(dir / "x.png", img); }, {"x.png", ".exr"});
    expectInputError([&] { writePng(dir / "x.exr", img); }, {"x.exr", ".png"});
    img.at(1, 1, 2) = std::numeric_limits<float>::quiet_NaN();
    expectInputError([&] { writeExr(dir / "nan.exr", img); },
                     {"nan.exr", "NaN", "row 1, column 1"});
    expectInputError([&] { writePng(dir / "nan.png", img); }, {"nan.png", "NaN"});
    expectInputError([&] { writePng16(dir / "nan16.png", img); }, {"nan16.png", "NaN"});
    Image two(2, 2, 2);
    expectInputError([&] { writeExr(dir / "two.exr", two); }, {"two.exr", "2 channels"});
    EXPECT_TRUE(dir.entries().empty());
}

// ---------------------------------------------------------------------------------------------
// Atomic writes (ImageIO)

TEST(ImageIO, FailedWriteLeavesNoFileAndNoTemp) {
    TempDir dir;
    Image bad(4, 4, 3);
    bad.data.resize(10);  // size mismatch
    expectInputError([&] { writeExr(dir / "out.exr", bad); }, {"out.exr"});
    expectInputError([&] { writePng(dir / "out.png", bad); }, {"out.png"});
    EXPECT_TRUE(dir.entries().empty());

    // Unwritable location: the parent "directory" is a regular file.
    writeBytes(dir / "blocker", "x");
    Image good(2, 2, 1, 0.25f);
    expectInputError([&] { writeExr(dir / "blocker" / "sub" / "out.exr", good); }, {"out.exr"});
    EXPECT_EQ(dir.entries(), std::vector<std::string>({"blocker"}));
}

TEST(ImageIO, ExistingFileIsNotClobberedByAFailedWrite) {
    TempDir dir;
    writeBytes(dir / "keep.exr", "precious");
    Image bad(4, 4, 1);
    bad.data.clear();
    expectInputError([&] { writeExr(dir / "keep.exr", bad); }, {"keep.exr"});
    EXPECT_EQ(readBytes(dir / "keep.exr"), "precious");
    // A write that fails after the temporary exists (abandoned AtomicOutput).
    {
        AtomicOutput out(dir / "keep.exr");
        writeBytes(out.tempPath(), "half-written");
        EXPECT_TRUE(fs::exists(out.tempPath()));
    }
    EXPECT_EQ(readBytes(dir / "keep.exr"), "precious");
    EXPECT_EQ(dir.entries(), std::vector<std::string>({"keep.exr"}));
    // A successful write replaces it.
    writeExr(dir / "keep.exr", Image(2, 2, 1, 0.5f));
    EXPECT_EQ(readImage(dir / "keep.exr").data, std::vector<float>(4, 0.5f));
    EXPECT_EQ(dir.entries(), std::vector<std::string>({"keep.exr"}));
}

TEST(ImageIO, AtomicOutputTempNameAndDirectories) {
    TempDir dir;
    {
        AtomicOutput out(dir / "a" / "b" / "render.exr");
        EXPECT_EQ(out.tempPath().parent_path(), dir / "a" / "b");
        EXPECT_EQ(out.tempPath().extension(), ".exr");
        EXPECT_EQ(out.tempPath().filename().string().rfind(".render.tmp-", 0), 0u);
        EXPECT_TRUE(fs::is_directory(dir / "a" / "b"));
        // no commit: the directories it created are removed again
    }
    EXPECT_TRUE(dir.entries().empty());
    {
        AtomicOutput out(dir / "a" / "b" / "render.exr");
        expectInputError([&] { out.commit(); }, {"render.exr", "no file"});
    }
    EXPECT_TRUE(dir.entries().empty());
    writeExr(dir / "c" / "d" / "img.exr", Image(2, 2, 1, 1.0f));
    EXPECT_TRUE(fs::is_regular_file(dir / "c" / "d" / "img.exr"));
    std::vector<std::string> inside;
    for (const auto& e : fs::directory_iterator(dir / "c" / "d"))
        inside.push_back(e.path().filename());
    EXPECT_EQ(inside, std::vector<std::string>({"img.exr"}));
    fs::create_directory(dir / "isdir.exr");
    expectInputError([&] { writeExr(dir / "isdir.exr", Image(2, 2, 1)); },
                     {"isdir.exr", "directory"});
}

// ---------------------------------------------------------------------------------------------
// EnvMapIO

namespace {

/// ∫ input over the sphere with the pixel-area convention, in double.
std::vector<double> inputIntegral(const Image& src, int outChannels) {
    std::vector<double> sum(outChannels, 0.0);
    const double pi = std::numbers::pi;
    for (int y = 0; y < src.height; ++y) {
        const double sa = 2.0 * pi / src.width *
                          (std::cos(y * pi / src.height) - std::cos((y + 1) * pi / src.height));
        for (int x = 0; x < src.width; ++x) {
            if (outChannels == 1 && src.channels >= 3)
                sum[0] += sa * luminance<double>(src.at(x, y, 0), src.at(x, y, 1), src.at(x, y, 2));
            else
                for (int c = 0; c < outChannels; ++c)
                    sum[c] += sa * src.at(x, y, src.channels == 1 ? 0 : c);
        }
    }
    return sum;
}

std::vector<double> outputIntegral(const EnvMap& env) {
    const std::vector<double> sa = envCellSolidAngles(env.width, env.height);
    std::vector<double> sum(env.channels, 0.0);
    for (size_t t = 0; t < env.texelCount(); ++t)
        for (int c = 0; c < env.channels; ++c) sum[c] += sa[t] * env.texels[t * env.channels + c];
    return sum;
}

Image randomImage(int w, int h, int c, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 4.0f);
    Image img(w, h, c);
    for (float& v : img.data) v = u(rng);
    return img;
}

}  // namespace

TEST(EnvMapIO, CellSolidAnglesSumToFourPi) {
    for (auto [w, h] :
         std::vector<std::pair<int, int>>{{50, 25}, {1, 2}, {7, 2}, {13, 9}, {200, 101}}) {
        const std::vector<double> sa = envCellSolidAngles(w, h);
        ASSERT_EQ(sa.size(), static_cast<size_t>(w * h));
        double s = 0.0;
        for (double a : sa) {
            EXPECT_GT(a, 0.0);
            s += a;
        }
        EXPECT_NEAR(s, 4.0 * std::numbers::pi, 1e-12) << w << "x" << h;
    }
    // Pole rows are half-height cells: area 2π(1 − cos(π/(2(H−1))))/W each.
    const std::vector<double> sa = envCellSolidAngles(50, 25);
    EXPECT_NEAR(sa[0], 2.0 * std::numbers::pi / 50 * (1.0 - std::cos(std::numbers::pi / 48)),
                1e-15);
    EXPECT_DOUBLE_EQ(sa[0], sa[24 * 50 + 7]);
}

TEST(EnvMapIO, ConstantInputGivesConstantOutput) {
    Image rgb(64, 32, 3);
    for (int p = 0; p < 64 * 32; ++p) {
        rgb.data[p * 3 + 0] = 0.2f;
        rgb.data[p * 3 + 1] = 0.5f;
        rgb.data[p * 3 + 2] = 0.9f;
    }
    EnvMap e3 = resampleEquirect(rgb, 50, 25, 3);
    EXPECT_EQ(e3.width, 50);
    EXPECT_EQ(e3.height, 25);
    EXPECT_EQ(e3.channels, 3);
    for (size_t t = 0; t < e3.texelCount(); ++t) {
        EXPECT_NEAR(e3.texels[t * 3 + 0], 0.2f, 1e-6f);
        EXPECT_NEAR(e3.texels[t * 3 + 1], 0.5f, 1e-6f);
        EXPECT_NEAR(e3.texels[t * 3 + 2], 0.9f, 1e-6f);
    }
    EnvMap e1 = resampleEquirect(rgb, 50, 25, 1);
    const float y = 0.2126f * 0.2f + 0.7152f * 0.5f + 0.0722f * 0.9f;
    for (float v : e1.texels) EXPECT_NEAR(v, y, 1e-6f);
    // Gray input to RGB output repeats the value.
    EnvMap g = resampleEquirect(Image(10, 7, 1, 0.3f), 4, 3, 3);
    for (float v : g.texels) EXPECT_NEAR(v, 0.3f, 1e-6f);
}

TEST(EnvMapIO, ResamplingPreservesTheSphereIntegral) {
    const Image src = randomImage(97, 41, 3, 7);
    for (auto [w, h] :
         std::vector<std::pair<int, int>>{{50, 25}, {8, 3}, {1, 2}, {300, 150}, {97, 41}}) {
        for (int c : {1, 3}) {
            SCOPED_TRACE(std::to_string(w) + "x" + std::to_string(h) + "x" + std::to_string(c));
            EnvMap e = resampleEquirect(src, w, h, c);
            const auto in = inputIntegral(src, c), out = outputIntegral(e);
            for (int k = 0; k < c; ++k) EXPECT_NEAR(out[k] / in[k], 1.0, 1e-6);
        }
    }
}

TEST(EnvMapIO, BrightPixelLandsInTheTexelWhoseCellContainsIt) {
    // 400x200 input onto 50x25: each output column spans 8 input columns; output rows' cells
    // are (j±½)·π/24, input rows y·π/200. Pixel (x=83, y=60): u ∈ [0.2075, 0.21] → column 10
    // (cell [0.2, 0.22]); θ ∈ [0.3π, 0.305π] → row 7 (cell [6.5, 7.5]·π/24 = [0.2708π, 0.3125π]).
    const int W = 50, H = 25;
    Image src(400, 200, 1, 0.0f);
    src.at(83, 60) = 5.0f;
    EnvMap e = resampleEquirect(src, W, H, 1);
    const std::vector<double> sa = envCellSolidAngles(W, H);
    const double pi = std::numbers::pi;
    const double pixelSa = 2.0 * pi / 400 * (std::cos(60 * pi / 200) - std::cos(61 * pi / 200));
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            const float v = e.texels[j * W + i];
            if (j == 7 && i == 10)
                EXPECT_NEAR(v * sa[j * W + i], 5.0 * pixelSa, 1e-9);
            else
                EXPECT_EQ(v, 0.0f) << "row " << j << " column " << i;
        }
    // A pixel touching the north pole lands in row 0.
    Image pole(400, 200, 1, 0.0f);
    pole.at(399, 0) = 1.0f;
    EnvMap p = resampleEquirect(pole, W, H, 1);
    EXPECT_GT(p.texels[0 * W + 49], 0.0f);
    for (int t = 0; t < W * H; ++t)
        if (t != 49) {
            EXPECT_EQ(p.texels[t], 0.0f);
        }
}

TEST(EnvMapIO, OrientationAndColumnCells) {
    // Top half bright: rows above the equator are 1, below 0, the equator row (its cell
    // straddles θ = π/2 symmetrically) exactly ½. Row 0 is +Y.
    Image src(40, 20, 1, 0.0f);
    for (int y = 0; y < 10; ++y)
        for (int x = 0; x < 40; ++x) src.at(x, y) = 1.0f;
    EnvMap e = resampleEquirect(src, 8, 5, 1);
    for (int i = 0; i < 8; ++i) {
        EXPECT_NEAR(e.texels[0 * 8 + i], 1.0f, 1e-6f);
        EXPECT_NEAR(e.texels[1 * 8 + i], 1.0f, 1e-6f);
        EXPECT_NEAR(e.texels[2 * 8 + i], 0.5f, 1e-6f);
        EXPECT_NEAR(e.texels[3 * 8 + i], 0.0f, 1e-6f);
        EXPECT_NEAR(e.texels[4 * 8 + i], 0.0f, 1e-6f);
    }
    // Column cells are u ∈ [i/W, (i+1)/W] (texel centre (i+½)/W): with 2 input columns per
    // texel, texel i is the mean of input columns 2i and 2i+1.
    Image cols(100, 10, 1);
    for (int y = 0; y < 10; ++y)
        for (int x = 0; x < 100; ++x) cols.at(x, y) = static_cast<float>(x);
    EnvMap c = resampleEquirect(cols, 50, 6, 1);
    for (int j = 0; j < 6; ++j)
        for (int i = 0; i < 50; ++i) EXPECT_NEAR(c.texels[j * 50 + i], 2.0 * i + 0.5, 1e-4);
}

TEST(EnvMapIO, WriteAndLoadRoundTrip) {
    TempDir dir;
    EnvMap e = EnvMap::constant(50, 25, 0.0f, 1);
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (float& v : e.texels) v = u(rng);
    writeEnvMap(dir / "env.exr", e);
    // Same size: taken as texels, unchanged.
    EnvMap back = loadEnvMap(dir / "env.exr", 50, 25, 1);
    EXPECT_EQ(back.texels, e.texels);
    EnvMap rgb = loadEnvMap(dir / "env.exr", 50, 25, 3);
    for (size_t t = 0; t < e.texelCount(); ++t) EXPECT_EQ(rgb.texels[t * 3 + 1], e.texels[t]);
    // Other size: resampled, integral preserved.
    EnvMap small = loadEnvMap(dir / "env.exr", 10, 5, 1);
    EXPECT_EQ(small.width, 10);
    EXPECT_EQ(small.height, 5);
    EXPECT_NEAR(outputIntegral(small)[0] / inputIntegral(e.toImage(), 1)[0], 1.0, 1e-6);
    // An 8-bit PNG env map is sRGB-decoded.
    std::vector<uint8_t> px(16 * 8 * 3, 128);
    writeOiio(dir / "env.png", 16, 8, 3, OIIO::TypeDesc::UINT8, OIIO::TypeDesc::UINT8, px.data());
    EnvMap fromPng = loadEnvMap(dir / "env.png", 6, 4, 3);
    for (float v : fromPng.texels) EXPECT_NEAR(v, srgbDecode(128.0f / 255.0f), 1e-6f);
}

TEST(EnvMapIO, PreviewIsNearestNeighbour) {
    EnvMap e = EnvMap::constant(3, 2, 0.0f, 3);
    for (size_t k = 0; k < e.texels.size(); ++k) e.texels[k] = static_cast<float>(k);
    Image img = envMapPreview(e, 4);
    EXPECT_EQ(img.width, 12);
    EXPECT_EQ(img.height, 8);
    EXPECT_EQ(img.channels, 3);
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 12; ++x)
            for (int c = 0; c < 3; ++c)
                EXPECT_EQ(img.at(x, y, c), e.texels[((y / 4) * 3 + x / 4) * 3 + c]);
    TempDir dir;
    writePng(dir / "prev.png", img);
    EXPECT_TRUE(fs::is_regular_file(dir / "prev.png"));
}

TEST(EnvMapIO, RejectsBadArguments) {
    Image src(8, 4, 3, 1.0f);
    expectInputError([&] { resampleEquirect(src, 8, 4, 2); }, {"channels"});
    expectInputError([&] { resampleEquirect(src, 8, 1, 1); }, {"height >= 2"});
    expectInputError([&] { resampleEquirect(src, 0, 4, 1); }, {"width >= 1"});
    src.at(3, 2, 1) = std::numeric_limits<float>::infinity();
    expectInputError([&] { resampleEquirect(src, 8, 4, 1, "sky.exr"); },
                     {"sky.exr", "infinite", "row 2, column 3"});
    TempDir dir;
    expectInputError([&] { loadEnvMap(dir / "nosky.hdr", 50, 25, 1); }, {"nosky.hdr", "not found"});
    expectInputError([&] { envMapPreview(EnvMap::constant(2, 2, 0.0f), 0); }, {"scale"});
}

namespace {

/// The spdlog lines `body` logs (the default logger swapped for a stream while it runs).
template <class Body>
std::string loggedBy(Body body) {
    std::ostringstream out;
    auto previous = spdlog::default_logger();
    auto logger = std::make_shared<spdlog::logger>(
        "capture", std::make_shared<spdlog::sinks::ostream_sink_mt>(out));
    logger->set_pattern("%l: %v");
    spdlog::set_default_logger(logger);
    try {
        body();
    } catch (...) {
        spdlog::set_default_logger(previous);
        throw;
    }
    spdlog::set_default_logger(previous);
    return out.str();
}

}  // namespace

// Real HDR photos (Blender's HDRIs) carry resampling ringing: a few texels at −3e-6 against a
// maximum of 55 are clamped with one warning line; −0.5 is real negative energy and refused.
TEST(EnvMapIO, TinyNegativeTexelsAreClampedWithOneWarningLargeOnesRefused) {
    TempDir dir;
    Image img(64, 32, 3, 1.0f);
    img.at(10, 5, 0) = 55.0f;  // the sun
    img.at(3, 20, 1) = -3e-6f;
    img.at(40, 30, 2) = -2e-6f;
    img.at(41, 30, 0) = -1e-6f;
    writeExr(dir / "ringing.exr", img);
    for (auto [w, h, ch] : {std::tuple{64, 32, 3}, std::tuple{50, 25, 1}, std::tuple{50, 25, 0}}) {
        EnvMap env;
        const std::string log = loggedBy([&] { env = loadEnvMap(dir / "ringing.exr", w, h, ch); });
        EXPECT_EQ(std::count(log.begin(), log.end(), '\n'), 1) << log;
        for (const char* part : {"warning", "ringing.exr", "3 pixels", "-3e-06", "row 20, column 3",
                                 "maximum 55", "clamped to 0"})
            EXPECT_NE(log.find(part), std::string::npos) << part << " not in: " << log;
        EXPECT_GE(*std::min_element(env.texels.begin(), env.texels.end()), 0.0f);
    }
    // On the grid the clamped pixels are exactly 0, the others untouched.
    const EnvMap onGrid = loadEnvMap(dir / "ringing.exr", 64, 32, 3);
    EXPECT_EQ(onGrid.texels[(20 * 64 + 3) * 3 + 1], 0.0f);
    EXPECT_EQ(onGrid.texels[(5 * 64 + 10) * 3 + 0], 55.0f);
    // The same path serves every light spec (render, optimize --compare/--init, judge, view).
    EXPECT_NE(loggedBy([&] {
                  lightFromSpec((dir / "ringing.exr").string(), 50, 25, 1, "compare");
              }).find("clamped"),
              std::string::npos);

    img.at(3, 20, 1) = -0.5f;
    writeExr(dir / "negative.exr", img);
    try {
        loadEnvMap(dir / "negative.exr", 50, 25, 1);
        ADD_FAILURE() << "-0.5 against 55 was accepted";
    } catch (const InputError& e) {
        const std::string m = e.what();
        for (const char* part : {"negative.exr", "negative (-0.5)", "row 20, column 3, channel 1",
                                 "3 negative values", "maximum of 55", "Clamp"})
            EXPECT_NE(m.find(part), std::string::npos) << part << " not in: " << m;
    }
    // No positive value at all: nothing to measure the ringing against.
    writeExr(dir / "dark.exr", Image(8, 4, 1, -1e-9f));
    EXPECT_THROW(loadEnvMap(dir / "dark.exr", 8, 4, 1), InputError);
}

// A bare height map (defectmap, scratchmap) says what was read, as a scene's part does.
TEST(HeightSource, ABareMapSaysWhatWasRead) {
    TempDir dir;
    Image img(4, 3, 1, 0.0f);
    img.at(1, 1, 0) = 0.25f;
    writeExr(dir / "bare.exr", img);
    const std::string log = loggedBy([&] { loadHeightSource(dir / "bare.exr"); });
    EXPECT_NE(log.find("info: part bare.exr (exr float32): 4 x 3 samples, no pitch (a bare "
                       "height map), heights 0 .. 0.25, 0 invalid points filled"),
              std::string::npos)
        << log;
}
