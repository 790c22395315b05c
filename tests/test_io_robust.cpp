// Readers that refuse bad data and writers that never leave a bad file (issue 14, "Hard cases
// and bad input"): truncated TIFF height maps, negative or non-finite env maps, an env-map grid
// larger than a transport matrix holds, image writes into a full file system, and EXR files
// without a timestamp (equal images, equal bytes). Issue 35: JSON nested 70 000 deep (scene
// files, .tm headers, lamps.json, legends), FIFOs and devices as inputs, binary shard lists.
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "TestUtil.h"
#include "core/Error.h"
#include "core/Hash.h"
#include "core/Image.h"
#include "io/EnvMapIO.h"
#include "io/HeightmapIO.h"
#include "io/ImageIO.h"
#include "io/InputFile.h"
#include "io/LampsFile.h"
#include "io/MaskIO.h"
#include "io/SceneFile.h"
#include "io/TransportFile.h"
#include "io/X3p.h"
#include "optimize/LampFit.h"
#include "render/PathTracer.h"
#include "scene/Scene.h"
#include "transport/TransportSink.h"

namespace fs = std::filesystem;
using namespace sl;

namespace {

/// Runs f and expects an InputError whose message holds every one of `parts`.
void expectRefused(const std::function<void()>& f, const std::vector<std::string>& parts) {
    try {
        f();
        ADD_FAILURE() << "accepted";
    } catch (const InputError& e) {
        const std::string msg = e.what();
        for (const std::string& p : parts)
            EXPECT_NE(msg.find(p), std::string::npos) << "'" << p << "' not in: " << msg;
    }
}

std::vector<std::string> entries(const fs::path& dir) {
    std::vector<std::string> out;
    for (const auto& e : fs::directory_iterator(dir)) out.push_back(e.path().filename());
    std::sort(out.begin(), out.end());
    return out;
}

std::string bytesOf(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), {}};
}

/// Writes pixels of C type T with OpenImageIO (formats our writers do not write).
template <typename T>
void writeOiio(const fs::path& p, int w, int h, int c, OIIO::TypeDesc type,
               const std::vector<T>& px, const std::string& compression, int tile = 0) {
    auto out = OIIO::ImageOutput::create(p.string());
    ASSERT_TRUE(out);
    OIIO::ImageSpec spec(w, h, c, type);
    spec.attribute("compression", compression);
    spec.attribute("tiff:RowsPerStrip", 8);
    if (tile) spec.tile_width = spec.tile_height = tile;
    ASSERT_TRUE(out->open(p.string(), spec));
    ASSERT_TRUE(out->write_image(OIIO::BaseTypeFromC<T>::value, px.data()));
    ASSERT_TRUE(out->close());
}

void truncateTo(const fs::path& p, double fraction) {
    fs::resize_file(p, static_cast<uintmax_t>(static_cast<double>(fs::file_size(p)) * fraction));
}

}  // namespace

// OpenImageIO's read_image() of a strip TIFF that ends early returns true with the missing rows
// left at 0 (only has_error() tells); such a map loaded as a part with a cliff at height 0.
TEST(RobustIO, TruncatedTiffHeightMapIsRefused) {
    test::TempDir dir("robust");
    const int w = 64, h = 64;
    std::vector<uint16_t> codes(w * h);
    std::vector<float> heights(w * h);
    for (int i = 0; i < w * h; ++i) {
        codes[i] = static_cast<uint16_t>(1000 + (i * 37) % 50000);
        heights[i] = 0.001f * static_cast<float>(i % 17);
    }
    HeightmapOptions ranged;
    ranged.heightRange = std::array<double, 2>{0.0, 0.05};
    for (const std::string comp : {"none", "lzw", "zip", "packbits"})
        for (int tile : {0, 16}) {
            SCOPED_TRACE(comp + (tile ? " tiled" : " strips"));
            const fs::path u16 = dir / ("u16-" + comp + std::to_string(tile) + ".tif");
            writeOiio(u16, w, h, 1, OIIO::TypeDesc::UINT16, codes, comp, tile);
            EXPECT_EQ(loadHeightmap(u16, ranged).heights.size(), size_t(w * h));  // whole: fine
            truncateTo(u16, 0.6);
            expectRefused([&] { loadHeightmap(u16, ranged); },
                          {u16.filename().string(), "damaged or truncated"});
            expectRefused([&] { readImage(u16); }, {u16.filename().string(), "truncated"});

            const fs::path f32 = dir / ("f32-" + comp + std::to_string(tile) + ".tif");
            writeOiio(f32, w, h, 1, OIIO::TypeDesc::FLOAT, heights, comp, tile);
            truncateTo(f32, 0.6);
            expectRefused([&] { loadHeightmap(f32, {}); },
                          {f32.filename().string(), "damaged or truncated"});
        }
    // A gray map stored as RGB is read band by band: truncated, refused as well.
    std::vector<uint16_t> rgb(w * h * 3);
    for (int i = 0; i < w * h; ++i) rgb[3 * i] = rgb[3 * i + 1] = rgb[3 * i + 2] = codes[i];
    const fs::path grayRgb = dir / "gray-rgb.tif";
    writeOiio(grayRgb, w, h, 3, OIIO::TypeDesc::UINT16, rgb, "lzw");
    truncateTo(grayRgb, 0.5);
    expectRefused([&] { loadHeightmap(grayRgb, ranged); }, {"gray-rgb.tif", "truncated"});
}

// The readers refuse a header that claims more pixels than its file can hold (io/ImageFile.h);
// constant images, which compress best, still load.
TEST(RobustIO, HighlyCompressedImagesStillLoad) {
    test::TempDir dir("robust");
    const int n = 2048;
    writeMaskPng(dir / "flat.png", std::vector<uint8_t>(size_t(n) * n, 200), n, n);
    writeExr(dir / "flat.exr", Image(n, n, 3, 0.25f));
    for (const char* name : {"flat.png", "flat.exr"}) {
        SCOPED_TRACE(name);
        const Image img = readImage(dir / name);
        EXPECT_LT(fs::file_size(dir / name) * 500, img.data.size() * sizeof(float));  // > 500:1
        EXPECT_EQ(img.width, n);
        EXPECT_EQ(img.height, n);
    }
    HeightmapOptions ranged;
    ranged.heightRange = std::array<double, 2>{0.0, 1.0};
    EXPECT_EQ(loadHeightmap(dir / "flat.png", ranged).heights.size(), size_t(n) * n);
}

TEST(RobustIO, EnvMapWithNegativeOrNonFinitePixelsIsRefused) {
    test::TempDir dir("robust");
    for (auto [w, h] : {std::pair{8, 4}, std::pair{16, 8}}) {  // on the grid; resampled
        SCOPED_TRACE(std::to_string(w) + "x" + std::to_string(h));
        std::vector<float> px(static_cast<size_t>(w * h * 3), 0.5f);
        px[(1 * w + 2) * 3 + 1] = -0.25f;  // row 1, column 2, green
        writeOiio(dir / "neg.exr", w, h, 3, OIIO::TypeDesc::FLOAT, px, "zip");
        for (int channels : {0, 1, 3})
            expectRefused([&] { loadEnvMap(dir / "neg.exr", 8, 4, channels); },
                          {"neg.exr", "negative (-0.25)", "row 1, column 2, channel 1"});
        px[(1 * w + 2) * 3 + 1] = std::numeric_limits<float>::quiet_NaN();
        writeOiio(dir / "nan.exr", w, h, 3, OIIO::TypeDesc::FLOAT, px, "zip");
        expectRefused([&] { loadEnvMap(dir / "nan.exr", 8, 4, 0); },
                      {"nan.exr", "NaN", "row 1, column 2"});
        px[(1 * w + 2) * 3 + 1] = std::numeric_limits<float>::infinity();
        writeOiio(dir / "inf.exr", w, h, 3, OIIO::TypeDesc::FLOAT, px, "zip");
        expectRefused([&] { loadEnvMap(dir / "inf.exr", 8, 4, 1); },
                      {"inf.exr", "infinite", "row 1, column 2"});
    }
    // A negative alpha is not light: ignored, as the resampler ignores alpha.
    std::vector<float> rgba(8 * 4 * 4, 0.5f);
    rgba[3] = -1.0f;
    writeOiio(dir / "alpha.exr", 8, 4, 4, OIIO::TypeDesc::FLOAT, rgba, "zip");
    EXPECT_EQ(loadEnvMap(dir / "alpha.exr", 8, 4, 3).texels, std::vector<float>(8 * 4 * 3, 0.5f));
}

// 4096x2048 passed the scene check and precompute died ("TransportSink: more than 65536
// texels"); now the scene file refuses it, naming the field and the limit.
TEST(RobustIO, OversizeEnvMapGridIsRefusedByTheSceneCheck) {
    const auto scene = [](int w, int h) {
        return R"({"heightmap": {"path": "h.exr"}, "envmap": {"width": )" + std::to_string(w) +
               R"(, "height": )" + std::to_string(h) + "}}";
    };
    expectRefused(
        [&] { parseScene(scene(4096, 2048), "/tmp", "big.json"); },
        {"big.json", "envmap.width/height", "4096x2048", "8388608 texels", "limit of 65536"});
    expectRefused([&] { parseScene(scene(257, 256), "/tmp", "big.json"); },
                  {"envmap.width/height", "65536"});
    EXPECT_EQ(parseScene(scene(256, 256), "/tmp", "ok.json").envmap.width, 256);

    // A scene built in code is refused by the transport sink the same way, as an InputError.
    SceneDesc d;
    d.envmap.width = 300;
    d.envmap.height = 300;
    Scene s(d, 4, 4, test::bumpyHeightMap(4));
    RenderOptions o;
    o.spp = 1;
    expectRefused([&] { precomputeTransport(s, o, 1); },
                  {"envmap.width/height", "300x300", "65536"});
}

namespace {

/// Runs in a death test's child (forked, and re-executed: no thread pool of the parent, such as
/// OpenEXR's, is left waiting in the child): sets the file-size limit to `limitBytes` with
/// SIGXFSZ ignored, so that a write past it fails with EFBIG instead of killing the process (what
/// a full disk does to a writer, without root or a small file system), runs `write` and exits
/// 0 if it threw an InputError holding `expected`, 1 if it returned, 2 if the message differed,
/// 3 for any other exception.
[[noreturn]] void writeUnderFileSizeLimit(rlim_t limitBytes, const std::function<void()>& write,
                                          const std::string& expected) {
    ::signal(SIGXFSZ, SIG_IGN);
    const rlimit lim{limitBytes, limitBytes};
    if (::setrlimit(RLIMIT_FSIZE, &lim) != 0) ::_exit(4);
    int code = 1;
    try {
        write();
    } catch (const InputError& e) {
        code = std::string(e.what()).find(expected) != std::string::npos ? 0 : 2;
        std::fprintf(stderr, "%s\n", e.what());
    } catch (...) {
        code = 3;
    }
    std::fflush(stderr);
    ::_exit(code);
}

/// Noise compresses badly: the files are far larger than the 4 KB limit below.
Image noisyImage(int w, int h, int c) {
    Image img(w, h, c);
    uint32_t x = 12345;
    for (float& v : img.data) {
        x = x * 1664525u + 1013904223u;
        v = static_cast<float>(x >> 8) / static_cast<float>(1u << 24);
    }
    return img;
}

}  // namespace

// OpenImageIO's PNG writer ignores failed writes (its close() returns true): a full disk left a
// truncated PNG renamed into place. Every image write is now checked, the temporary removed,
// and an existing file kept.
TEST(RobustIO, ImageWriteIntoAFullFileSystemFailsAndLeavesNothing) {
    GTEST_FLAG_SET(death_test_style, "threadsafe");
    // One directory for the test and its children (each child re-runs the test up to its
    // EXPECT_EXIT): named by the test process, removed by it alone.
    const bool child = !GTEST_FLAG_GET(internal_run_death_test).empty();
    const fs::path path = fs::temp_directory_path() /
                          ("sl-test-fullfs-" + std::to_string(child ? ::getppid() : ::getpid()));
    struct Dir {
        fs::path path_;
        bool owner;
        const fs::path& path() const { return path_; }
        fs::path operator/(const std::string& name) const { return path_ / name; }
        ~Dir() {
            std::error_code ec;
            if (owner) fs::remove_all(path_, ec);
        }
    } dir{path, !child};
    if (!child) fs::remove_all(path);
    fs::create_directories(path);
    const Image img = noisyImage(256, 256, 3);
    const std::string msg = "cannot be written";
    const auto full = [&](const std::function<void()>& write) {
        writeUnderFileSizeLimit(4096, write, msg);
    };
    EXPECT_EXIT(full([&] { writePng(dir / "preview.png", img); }), testing::ExitedWithCode(0),
                "preview.png: cannot be written");
    EXPECT_EXIT(full([&] { writePng16(dir / "data.png", img); }), testing::ExitedWithCode(0),
                "data.png");
    EXPECT_EXIT(full([&] { writeExr(dir / "render.exr", img); }), testing::ExitedWithCode(0),
                "render.exr");
    EXPECT_EXIT(full([&] { writeEnvMap(dir / "env.exr", EnvMap::constant(64, 32, 0.5f, 3)); }),
                testing::ExitedWithCode(1), "");  // 64x32 constant: smaller than the limit
    std::filesystem::remove(dir / "env.exr");
    EXPECT_TRUE(entries(dir.path()).empty()) << entries(dir.path()).front();

    // An existing file is neither replaced nor truncated by the failed write.
    writePng(dir / "keep.png", Image(2, 2, 3, 0.5f));
    const std::string before = bytesOf(dir / "keep.png");
    EXPECT_EXIT(full([&] { writePng(dir / "keep.png", img); }), testing::ExitedWithCode(0),
                "keep.png");
    EXPECT_EQ(bytesOf(dir / "keep.png"), before);
    EXPECT_EQ(entries(dir.path()), std::vector<std::string>{"keep.png"});

    // Below the limit the same write succeeds in the child.
    EXPECT_EXIT(writeUnderFileSizeLimit(
                    1 << 20, [&] { writePng(dir / "small.png", img); }, msg),
                testing::ExitedWithCode(1), "");
    EXPECT_EQ(readImage(dir / "small.png").width, 256);
}

// OpenImageIO stamps every EXR with the time of writing (capDate) unless told otherwise: equal
// results were different files.
TEST(RobustIO, EqualExrOutputsAreByteIdentical) {
    test::TempDir dir("robust");
    const Image img = noisyImage(32, 16, 3);
    writeExr(dir / "a.exr", img);
    EnvMap env = EnvMap::constant(8, 4, 0.25f, 1);
    writeEnvMap(dir / "env-a.exr", env);
    // Into the next second, so that a timestamp would differ.
    const auto now = std::chrono::system_clock::now().time_since_epoch();
    std::this_thread::sleep_for(std::chrono::seconds(1) -
                                (now - std::chrono::floor<std::chrono::seconds>(now)) +
                                std::chrono::milliseconds(20));
    writeExr(dir / "b.exr", img);
    writeEnvMap(dir / "env-b.exr", env);
    EXPECT_EQ(bytesOf(dir / "a.exr"), bytesOf(dir / "b.exr"));
    EXPECT_EQ(bytesOf(dir / "env-a.exr"), bytesOf(dir / "env-b.exr"));
    auto in = OIIO::ImageInput::open((dir / "a.exr").string());
    ASSERT_TRUE(in);
    EXPECT_EQ(in->spec().find_attribute("DateTime"), nullptr);
    EXPECT_EQ(readImage(dir / "a.exr").data, img.data);
}

// ---- Hard inputs, second pass (issue 35): deep JSON, devices and FIFOs as inputs. ----

namespace {

/// `depth` nested arrays: [[[...0...]]].
std::string deepArray(size_t depth) {
    return std::string(depth, '[') + "0" + std::string(depth, ']');
}

/// Runs the CLI under `timeout` (a hang fails the test instead of blocking the suite).
test::RunResult runCliBounded(const std::string& args) {
    return test::runShell("timeout 20 " + std::string(SL_CLI_PATH) + " " + args);
}

}  // namespace

// A JSON value nested ~70 000 deep: the error message quoted it with the JSON library's
// recursive dump(), which overflowed the stack (SIGSEGV). Now the depth is refused before parsing
// and a quoted value is a bounded prefix.
TEST(RobustIO, DeeplyNestedJsonSceneIsRefusedNotACrash) {
    test::TempDir dir("deep");
    const fs::path scene = dir / "deep.json";
    test::writeText(scene, R"({"heightmap": {"path": )" + deepArray(70000) + "}}");
    expectRefused([&] { readSceneFile(scene); }, {"deep.json", "nested deeper than 64"});
    expectRefused([&] { parseScene(R"({"camera": {"fov": )" + deepArray(70000) + "}}", "."); },
                  {"nested deeper than 64"});
    // Through the command line too: exit 1 and the message, no signal.
    const auto r = runCliBounded("render " + scene.string() + " -o " + (dir / "o.exr").string());
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("nested deeper than 64"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir / "o.exr"));
    // A shallow but wrong value is quoted as a bounded prefix.
    std::string wide = "[";
    for (int k = 0; k < 30000; ++k) wide += "1, ";
    wide += "1]";
    try {
        parseScene(R"({"heightmap": {"path": "x.exr"}, "description": )" + wide + "}", ".");
        ADD_FAILURE() << "accepted";
    } catch (const InputError& e) {
        EXPECT_LT(std::string(e.what()).size(), 400u) << e.what();
        EXPECT_NE(std::string(e.what()).find("must be a string, got [1, 1, 1"), std::string::npos)
            << e.what();
    }
}

TEST(RobustIO, JsonExcerptIsBoundedForAnyValue) {
    // Built by the iterative parser, then quoted: no recursion per level, at most 80 characters.
    const nlohmann::json deep = nlohmann::json::parse(deepArray(70000));
    const std::string q = jsonExcerpt(deep);
    EXPECT_EQ(q, std::string(80, '[') + "...");
    EXPECT_EQ(jsonExcerpt(nlohmann::json{{"a", 1}}), R"({"a": 1})");
    EXPECT_EQ(jsonExcerpt(std::string(1000, 'x'), 10), "\"xxxxxxxxx...");
    EXPECT_EQ(jsonNestingDepth(R"({"a": "[[[[", "b": [[1]]})"), 3);
    EXPECT_EQ(textExcerpt(std::string("a\x01\xff", 3)), "a\\x01\\xff");
}

// The same value inside a .tm header's "inputs": the header is refused as damaged.
TEST(RobustIO, DeeplyNestedTransportHeaderIsRefusedNotACrash) {
    test::TempDir dir("deeptm");
    const TransportMatrix t = test::tinyTransportMatrix();
    TransportProvenance prov;
    prov.fingerprint = std::string(32, '0');
    prov.inputs = R"({"pad": "PADPAD"})";
    const fs::path file = dir / "deep.tm";
    writeTransportFile(file, t, prov);
    ASSERT_NO_THROW(readTransportFile(file));
    // Splice 70 000 levels into the header in place of "PADPAD"; fix its length and checksum.
    std::string bytes = bytesOf(file);
    uint32_t len = 0;
    std::memcpy(&len, bytes.data() + 12, 4);
    std::string header = bytes.substr(16, len);
    const size_t at = header.find("\"PADPAD\"");
    ASSERT_NE(at, std::string::npos);
    header.replace(at, 8, deepArray(70000));
    const uint64_t hash = hash64(header.data(), header.size());
    const auto newLen = static_cast<uint32_t>(header.size());
    std::string out = bytes.substr(0, 12);
    out.append(reinterpret_cast<const char*>(&newLen), 4);
    out += header;
    out.append(reinterpret_cast<const char*>(&hash), 8);
    out += bytes.substr(16 + len + 8);
    test::writeText(file, out);
    expectRefused([&] { readTransportFile(file); }, {"deep.tm", "damaged", "deeper than 64"});
}

TEST(RobustIO, DeeplyNestedLampsAndLegendFilesAreRefused) {
    test::TempDir dir("deeplamps");
    test::writeText(dir / "lamps.json",
                    R"({"distance_mm": 500, "lamps": )" + deepArray(70000) + "}");
    expectRefused([&] { readLampsFile(dir / "lamps.json"); },
                  {"lamps.json", "nested deeper than 64"});
    const std::vector<uint8_t> mask(16, 255);
    writeMaskPng(dir / "t-truth.png", mask, 4, 4);
    test::writeText(dir / "t-truth.json", R"({"labels": )" + deepArray(70000) + "}");
    expectRefused([&] { readLabelMask(dir / "t-truth.png", 4, 4); },
                  {"t-truth.json", "nested deeper than 64"});
    // A directory where a legend belongs: a clear message, not a raw stream error.
    writeMaskPng(dir / "d-truth.png", mask, 4, 4);
    fs::create_directories(dir / "d-truth.json");
    expectRefused([&] { readLabelMask(dir / "d-truth.png", 4, 4); },
                  {"d-truth.json", "is a directory"});
}

// `render /dev/zero` read without bound (2.4 GB in 5 s); a FIFO as the scene file blocked the
// open forever. Every input path is checked to be a regular file first.
TEST(RobustIO, DevicesAndFifosAreRefusedNotRead) {
    test::TempDir dir("fifo");
    const fs::path fifo = dir / "scene.json";
    ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
    expectRefused([&] { readSceneFile(fifo); }, {"scene.json", "not a regular file"});
    expectRefused([&] { readSceneFile("/dev/zero"); }, {"/dev/zero", "not a regular file"});
    expectRefused([&] { readTransportFile(fifo); }, {"not a regular file"});
    expectRefused([&] { readLampsFile(fifo); }, {"not a regular file"});
    writeMaskPng(dir / "f-truth.png", std::vector<uint8_t>(16, 255), 4, 4);
    ASSERT_EQ(mkfifo((dir / "f-truth.json").c_str(), 0600), 0);
    expectRefused([&] { readLabelMask(dir / "f-truth.png", 4, 4); }, {"not a regular file"});
    const fs::path list = dir / "T.shards";
    ASSERT_EQ(mkfifo(list.c_str(), 0600), 0);
    expectRefused([&] { readTransportFile(list); }, {"T.shards", "not a regular file"});
    const auto t0 = std::chrono::steady_clock::now();
    for (const std::string& in : {fifo.string(), std::string("/dev/zero")}) {
        const auto r = runCliBounded("render " + in + " -o " + (dir / "o.exr").string());
        EXPECT_EQ(r.exitCode, 1) << r.output;
        EXPECT_NE(r.output.find("not a regular file"), std::string::npos) << r.output;
    }
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 10);
    // A plausible size: a scene file of more than 16 MiB is refused before it is read.
    const fs::path big = dir / "big.json";
    { std::ofstream(big) << "{}"; }
    fs::resize_file(big, (16u << 20) + 1);
    expectRefused([&] { readSceneFile(big); }, {"big.json", "at most 16 MiB"});
}

// A binary file given as a shard list printed its bytes as a "file name".
TEST(RobustIO, BinaryShardListIsNamedNotPrinted) {
    test::TempDir dir("binshards");
    std::string junk = "\x93NUMPY\x01\x00";
    for (int i = 0; i < 300; ++i) junk += static_cast<char>(i * 37);
    test::writeText(dir / "T.shards", junk);
    try {
        readTransportFile(dir / "T.shards");
        ADD_FAILURE() << "accepted";
    } catch (const InputError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("line 1"), std::string::npos) << msg;
        EXPECT_NE(msg.find("binary"), std::string::npos) << msg;
        EXPECT_LT(msg.size(), 400u) << msg;
    }
}

// ---- Issue 35, item 5: what the files and options admit. ----

// lamps.json bar widths of -5 or 500 degrees and ring bands past the zenith were read.
TEST(RobustIO, LampsFileRefusesWhatNoLampIs) {
    test::TempDir dir("lampsrange");
    const fs::path file = dir / "lamps.json";
    auto lamps = [&](const std::string& lamp) {
        test::writeText(file, R"({"distance_mm": 500, "lamps": [)" + lamp + "]}");
    };
    const std::string bar =
        R"({"kind": "bar", "radiance": 1, "azimuth_deg": 10, "elevation_deg": 40,
            "angular_length_deg": 30, "roll_deg": 0, "angular_width_deg": )";
    lamps(bar + "10}");
    EXPECT_EQ(readLampsFile(file).lamps.size(), 1u);
    for (const std::string w : {"-5", "500", "0"}) {
        lamps(bar + w + "}");
        expectRefused([&] { readLampsFile(file); }, {"lamps[0] angular_width_deg", "is " + w});
    }
    const std::string ring =
        R"({"kind": "ring", "radiance": 1, "elevation_deg": 60, "elevation_band_deg": )";
    lamps(ring + "[40, 80]}");
    EXPECT_EQ(readLampsFile(file).lamps.size(), 1u);
    for (const std::string band : {"[80, 120]", "[-100, 10]", "[50, 40]"}) {
        lamps(ring + band + "}");
        expectRefused([&] { readLampsFile(file); }, {"elevation_band_deg", "[-90, 90]"});
    }
    lamps(ring + R"(["a", 3]})");
    expectRefused([&] { readLampsFile(file); }, {"elevation_band_deg", "not [lo, hi]"});
    lamps(R"({"kind": "disk", "radiance": 1, "azimuth_deg": 0, "elevation_deg": 40,
              "angular_radius_deg": 0})");
    expectRefused([&] { readLampsFile(file); }, {"angular_radius_deg", "(0, 90]"});
    // A radiance of 1e39 (inf as a float) was read; the bound is a constant light's (const:V).
    const std::string disk =
        R"({"kind": "disk", "azimuth_deg": 0, "elevation_deg": 40, "angular_radius_deg": 5, )";
    lamps(disk + R"("radiance": 1e6})");
    EXPECT_EQ(readLampsFile(file).lamps.size(), 1u);
    for (const std::string r : {"1e39", "1000001", "-1"}) {
        lamps(disk + R"("radiance": )" + r + "}");
        expectRefused([&] { readLampsFile(file); }, {"lamps[0] radiance", "[0, 1e+06]"});
    }
}

// --forbid-azimuth 0:360 forbade nothing (lamps still placed at 0 degrees).
TEST(RobustIO, ForbiddenAzimuthRangesAreChecked) {
    constexpr double kDeg = 3.14159265358979323846 / 180;
    LampFitOptions o;
    o.forbiddenAzimuth = {{150 * kDeg, 210 * kDeg}, {350 * kDeg, 10 * kDeg}};
    EXPECT_NO_THROW(checkLampFitOptions(o));
    o.forbiddenAzimuth = {{0, 360 * kDeg}};
    expectRefused([&] { checkLampFitOptions(o); },
                  {"option 'forbid-azimuth' 0:360", "forbids every azimuth"});
    o.forbiddenAzimuth = {{-180 * kDeg, 180 * kDeg}};
    expectRefused([&] { checkLampFitOptions(o); }, {"forbids every azimuth"});
    o.forbiddenAzimuth = {{30 * kDeg, 30 * kDeg}};
    expectRefused([&] { checkLampFitOptions(o); }, {"is empty"});
    o.forbiddenAzimuth = {{0, 1e9}};
    expectRefused([&] { checkLampFitOptions(o); }, {"[-360, 360]"});
}

// Roughness 1.5 or 1e30 was read (1e30 as a float is inf); const:1e39 rendered in full, then the
// EXR writer blamed out.exr.
TEST(RobustIO, RoughnessAndConstantLightRangesAreChecked) {
    const std::string hm = R"({"heightmap": {"path": "x.exr"}, "material": )";
    EXPECT_NO_THROW(parseScene(hm + R"({"alpha": 1}})", "."));
    for (const std::string bad :
         {R"({"alpha": 1.5})", R"({"alpha": 1e30})", R"({"alpha": 0.1, "alpha_v": 2})"})
        expectRefused([&] { parseScene(hm + bad + "}", "."); },
                      {"material.alpha", "must be in (0, 1]"});
    expectRefused([&] { lightFromSpec("const:1e39", 50, 25, 1, "--envmap"); },
                  {"const:1e39", "more than 1e+06"});
    EXPECT_NO_THROW(lightFromSpec("const:2", 50, 25, 1, "--envmap"));
}

// `gen-surface -o A.x3p` twice gave different bytes: the zip members carried the clock's time.
TEST(RobustIO, X3pMembersCarryAFixedTime) {
    test::TempDir dir("x3ptime");
    const std::vector<float> h(6 * 5, 0.25f);
    writeX3p(dir / "a.x3p", 6, 5, h, 0.01);
    const std::string bytes = bytesOf(dir / "a.x3p");
    // Every local file header (PK\3\4): DOS date at +12, year - 1980 in its top 7 bits.
    int members = 0;
    for (size_t at = 0; (at = bytes.find("PK\x03\x04", at)) != std::string::npos; at += 4) {
        ASSERT_LE(at + 14, bytes.size());
        const auto date = static_cast<uint16_t>(static_cast<uint8_t>(bytes[at + 12]) |
                                                static_cast<uint8_t>(bytes[at + 13]) << 8);
        EXPECT_EQ(date >> 9, 0) << "member " << members << " is not dated 1980";
        ++members;
    }
    EXPECT_EQ(members, 3);
    writeX3p(dir / "b.x3p", 6, 5, h, 0.01);
    EXPECT_EQ(bytesOf(dir / "b.x3p"), bytes);
}
