// Writes the seed corpora of the fuzz targets into DIR/<target>/ (`scripts/fuzz --make-corpus`
// runs it on tests/fuzz/corpus/): tiny valid files, written by the repository's own writers
// where it has one (EXR, PNG, env maps, .tm) and by OpenImageIO for the formats it only reads
// (TIFF, HDR, half-float EXR). The heightmap and envmap targets read one selector byte first
// (see fuzz_heightmap.cpp, fuzz_envmap.cpp); it is prepended here.
#include <OpenImageIO/imageio.h>
#include <zip.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "core/Image.h"
#include "io/EnvMapIO.h"
#include "io/ImageIO.h"
#include "io/TransportFile.h"
#include "io/X3p.h"
#include "scene/EnvMap.h"
#include "transport/TransportMatrix.h"

namespace fs = std::filesystem;

namespace {

fs::path gRoot;

std::string slurp(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), {}};
}

void put(const std::string& target, const std::string& name, const std::string& bytes) {
    fs::create_directories(gRoot / target);
    std::ofstream os(gRoot / target / name, std::ios::binary | std::ios::trunc);
    os << bytes;
    if (!os) {
        std::fprintf(stderr, "make_corpus: cannot write %s\n", (gRoot / target / name).c_str());
        std::exit(1);
    }
}

/// Writes a file with `write(path)` into a scratch directory and stores selector + its bytes.
template <typename F>
void putFile(const std::string& target, const std::string& name, int selector, F write) {
    const fs::path tmp = gRoot / ".scratch" / name;
    fs::create_directories(tmp.parent_path());
    write(tmp);
    std::string bytes = slurp(tmp);
    fs::remove(tmp);
    if (selector >= 0) bytes.insert(bytes.begin(), static_cast<char>(selector));
    put(target, name, bytes);
}

template <typename T>
void writeOiio(const fs::path& p, int w, int h, int c, OIIO::TypeDesc type,
               const std::vector<T>& px, const char* compression = nullptr, int tile = 0) {
    auto out = OIIO::ImageOutput::create(p.string());
    OIIO::ImageSpec spec(w, h, c, type);
    if (compression) spec.attribute("compression", compression);
    spec.attribute("DateTime", "2000:01:01 00:00:00");  // OpenImageIO would stamp the time
    if (tile) {
        spec.tile_width = tile;
        spec.tile_height = tile;
    }
    if (!out || !out->open(p.string(), spec) ||
        !out->write_image(OIIO::BaseTypeFromC<T>::value, px.data()) || !out->close()) {
        std::fprintf(stderr, "make_corpus: cannot write %s\n", p.c_str());
        std::exit(1);
    }
}

std::string npy(const std::string& descr, int major, const std::string& shape,
                const std::string& data) {
    std::string header =
        "{'descr': '" + descr + "', 'fortran_order': False, 'shape': " + shape + ", }";
    const size_t prefix = major == 1 ? 10 : 12;
    header += std::string((64 - (prefix + header.size() + 1) % 64) % 64, ' ') + "\n";
    std::string s = "\x93NUMPY";
    s += static_cast<char>(major);
    s += '\0';
    const size_t len = header.size();
    for (size_t i = 0; i < prefix - 8; ++i) s += static_cast<char>((len >> (8 * i)) & 0xff);
    return s + header + data;
}

template <typename T>
std::string bytesOf(const std::vector<T>& v) {
    return {reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T)};
}

std::vector<float> ramp(size_t n, float scale) {
    std::vector<float> v(n);
    for (size_t i = 0; i < n; ++i) v[i] = scale * static_cast<float>((i * 7) % 11);
    return v;
}

sl::TransportMatrix smallMatrix(bool dense, int channels, int planes) {
    sl::TransportMatrix t;
    t.width = 3;
    t.height = 2;
    t.envWidth = 4;
    t.envHeight = 3;
    t.channels = channels;
    t.planes = planes;
    t.objectMask = {1, 1, 0, 1, 1, 1};
    const size_t stride = static_cast<size_t>(t.stride());
    if (dense) {
        t.storage = sl::TransportStorage::Dense;
        t.values = ramp(t.rows() * t.cols() * stride, 0.01f);
    } else {
        t.storage = sl::TransportStorage::Sparse;
        t.rowPtr = {0, 2, 3, 3, 5, 6, 8};
        t.colIdx = {0, 5, 11, 2, 3, 7, 1, 10};
        t.values = ramp(t.colIdx.size() * stride, 0.02f);
    }
    return t;
}

void scenes() {
    put("scene", "default.json", slurp(fs::path(SL_SOURCE_DIR) / "scenes/default/scene.json"));
    put("scene", "minimal.json",
        R"({"heightmap": {"path": "part.png", "height_range": [0, 0.05]}})");
    put("scene", "full.json", R"({
  "heightmap": {"path": "h.exr", "pixel_pitch": 0.02, "height_scale": 2},
  "material": {"type": "roughconductor", "distribution": "beckmann", "alpha_u": 0.1,
               "alpha_v": 0.02, "eta": [1.2, 0.9, 0.7], "k": 3.5},
  "camera": {"type": "perspective", "origin": [0, 10, 10], "target": [0, 0, 0],
             "up": [0, 1, 0], "fov": 40, "width": 64, "height": 48},
  "envmap": {"width": 20, "height": 10, "constant": 0.5},
  "render": {"spp": 4, "max_depth": 3, "seed": 7},
  "description": "every section"
})");
    put("scene", "ortho.json", R"({"heightmap": {"path": "h.npy"},
 "material": {"type": "conductor", "material": "none"},
 "camera": {"type": "orthographic", "width_mm": 2.5, "origin": [0, 5, 0], "up": [0, 0, -1]},
 "envmap": {"preset": "studio", "width": 8, "height": 4}})");
}

void npys() {
    put("npy", "f4.npy", npy("<f4", 1, "(3, 4)", bytesOf(ramp(12, 0.5f))));
    put("npy", "f8-v2.npy", npy("<f8", 2, "(2, 2)", bytesOf(std::vector<double>{1, -2, 3.5, 4})));
    put("npy", "u2-v3.npy",
        npy("<u2", 3, "(2, 3, 1)", bytesOf(std::vector<uint16_t>{0, 1, 65535, 300, 2, 9})));
}

void heightmaps() {
    using OIIO::TypeDesc;
    const std::vector<float> h = ramp(16, 0.001f);
    std::vector<uint16_t> q(16);
    for (size_t i = 0; i < q.size(); ++i) q[i] = static_cast<uint16_t>(i * 4000);
    // Selector: bits 0-1 extension (exr, tif, png, npy), bit 2 height_range, bit 3 scale 2.
    putFile("heightmap", "f32.exr", 0, [&](const fs::path& p) {
        sl::Image img(4, 4, 1);
        img.data = h;
        sl::writeExr(p, img);
    });
    putFile("heightmap", "gray-rgb.exr", 8, [&](const fs::path& p) {
        sl::Image img(4, 4, 3);
        for (size_t i = 0; i < 16; ++i)
            img.data[3 * i] = img.data[3 * i + 1] = img.data[3 * i + 2] = h[i];
        sl::writeExr(p, img);
    });
    putFile("heightmap", "half.exr", 0,
            [&](const fs::path& p) { writeOiio(p, 4, 4, 1, TypeDesc::HALF, h); });
    putFile("heightmap", "f32.tif", 1,
            [&](const fs::path& p) { writeOiio(p, 4, 4, 1, TypeDesc::FLOAT, h, "none"); });
    putFile("heightmap", "u16-lzw.tif", 1 | 4,
            [&](const fs::path& p) { writeOiio(p, 4, 4, 1, TypeDesc::UINT16, q, "lzw"); });
    putFile("heightmap", "u8-rgb-tiled.tif", 1 | 4, [&](const fs::path& p) {
        std::vector<uint8_t> rgb(16 * 16 * 3);
        for (size_t i = 0; i < 256; ++i) rgb[3 * i] = rgb[3 * i + 1] = rgb[3 * i + 2] = uint8_t(i);
        writeOiio(p, 16, 16, 3, TypeDesc::UINT8, rgb, "zip", 16);
    });
    putFile("heightmap", "u16.png", 2 | 4, [&](const fs::path& p) {
        sl::Image img(4, 4, 1);
        for (size_t i = 0; i < 16; ++i) img.data[i] = static_cast<float>(i) / 15.0f;
        sl::writePng16(p, img);
    });
    putFile("heightmap", "u8.png", 2 | 4, [&](const fs::path& p) {
        std::vector<uint8_t> m(16);
        for (size_t i = 0; i < m.size(); ++i) m[i] = static_cast<uint8_t>(i * 16);
        sl::writeMaskPng(p, m, 4, 4);
    });
    putFile("heightmap", "u16-rgba.png", 2 | 4, [&](const fs::path& p) {
        std::vector<uint16_t> px(16 * 4, 65535);
        for (size_t i = 0; i < 16; ++i) px[4 * i] = px[4 * i + 1] = px[4 * i + 2] = q[i];
        writeOiio(p, 4, 4, 4, TypeDesc::UINT16, px);
    });
    put("heightmap", "f4.npy", '\x03' + npy("<f4", 1, "(4, 4)", bytesOf(h)));
    put("heightmap", "u2.npy", '\x07' + npy("<u2", 1, "(4, 4)", bytesOf(q)));
}

void envmaps() {
    using OIIO::TypeDesc;
    // Selector: bits 0-1 extension (exr, png, hdr, tif), bits 2-3 grid (50x25, 8x4, 4x3, 2x3),
    // bits 4-5 channels (0, 1, 3).
    putFile("envmap", "grid-8x4.exr", 0 | (1 << 2), [&](const fs::path& p) {
        sl::EnvMap e = sl::EnvMap::constant(8, 4, 0.0f, 1);
        e.texels = ramp(32, 0.1f);
        sl::writeEnvMap(p, e);
    });
    putFile("envmap", "rgb-16x8.exr", 0 | (1 << 2) | (1 << 4), [&](const fs::path& p) {
        sl::Image img(16, 8, 3);
        img.data = ramp(16 * 8 * 3, 0.25f);
        sl::writeExr(p, img);
    });
    putFile("envmap", "srgb-8x4.png", 1 | (1 << 2) | (2 << 4), [&](const fs::path& p) {
        sl::Image img(8, 4, 3);
        img.data = ramp(8 * 4 * 3, 0.1f);
        sl::writePng(p, img);
    });
    putFile("envmap", "rgb-16x8.hdr", 2, [&](const fs::path& p) {
        writeOiio(p, 16, 8, 3, TypeDesc::FLOAT, ramp(16 * 8 * 3, 0.3f));
    });
    putFile("envmap", "rgb-4x3.tif", 3 | (2 << 2), [&](const fs::path& p) {
        writeOiio(p, 4, 3, 3, TypeDesc::FLOAT, ramp(4 * 3 * 3, 0.2f), "none");
    });
}

void transports() {
    sl::TransportProvenance prov;
    prov.fingerprint = "0123456789abcdef0123456789abcdef";
    prov.inputs = R"({"format":"scratchlight transport v1","note":"fuzz seed"})";
    prov.spp = 4;
    prov.maxDepth = 3;
    prov.seed = 1;
    const struct {
        const char* name;
        bool dense;
        int channels, planes;
    } kinds[] = {{"csr-gray.tm", false, 1, 1},
                 {"csr-rgb-halves.tm", false, 3, 2},
                 {"dense-gray.tm", true, 1, 1},
                 {"dense-rgb.tm", true, 3, 1}};
    for (const auto& k : kinds)
        putFile("transport", k.name, -1, [&](const fs::path& p) {
            sl::writeTransportFile(p, smallMatrix(k.dense, k.channels, k.planes), prov);
        });
}

/// One member of a zip archive, whole.
std::string zipMember(const fs::path& archive, const char* name) {
    int err = 0;
    zip_t* z = zip_open(archive.c_str(), ZIP_RDONLY, &err);
    zip_stat_t st;
    zip_file_t* f = z && zip_stat(z, name, 0, &st) == 0 ? zip_fopen(z, name, 0) : nullptr;
    if (!f) {
        std::fprintf(stderr, "make_corpus: cannot read %s from %s\n", name, archive.c_str());
        std::exit(1);
    }
    std::string bytes(st.size, '\0');
    const zip_int64_t got = zip_fread(f, bytes.data(), st.size);
    zip_fclose(f);
    zip_close(z);
    if (got != static_cast<zip_int64_t>(st.size)) std::exit(1);
    return bytes;
}

template <typename T>
void putLE(std::string& out, T v) {
    out.append(reinterpret_cast<const char*>(&v), sizeof v);
}

void metrology() {
    // Selector: bits 0-1 .sdf, .x3p, or (2, 3) main.xml + point data assembled into an .x3p by
    // the target; bit 2 height_scale 2.
    const std::vector<float> h = ramp(12, 0.001f);
    putFile("metrology", "f64.x3p", 1, [&](const fs::path& p) { sl::writeX3p(p, 4, 3, h, 0.01); });
    {
        const fs::path tmp = gRoot / ".scratch" / "parts.x3p";
        fs::create_directories(tmp.parent_path());
        sl::writeX3p(tmp, 4, 3, h, 0.01);
        const std::string xml = zipMember(tmp, "main.xml"),
                          data = zipMember(tmp, "bindata/data.bin");
        std::string in(1, '\x02');
        putLE(in, static_cast<uint16_t>(xml.size()));
        put("metrology", "assembled.x3p.bin", in + xml + data);
        in[0] = '\x06';
        put("metrology", "assembled-scale2.x3p.bin", in + xml + data);
    }
    put("metrology", "ascii.sdf",
        std::string("\x00", 1) +
            "aBCR-1.0\r\nManufacID   = fuzz\r\nCreateDate  = 010120241200\r\n"
            "ModDate     = 010120241200\r\nNumPoints   = 3\r\nNumProfiles = 2\r\n"
            "Xscale      = 5e-06\r\nYscale      = 5e-06\r\nZscale      = 1e-06\r\n"
            "Zresolution = -1\r\nCompression = 0\r\nDataType    = 5\r\nCheckType   = 0\r\n*\r\n"
            "1 2 3\r\n4 5 -6\r\n*\r\nOperator = fuzz\r\n");
    std::string b = "\x04";  // height_scale 2
    b += "bBCR-1.0";
    b += std::string("fuzz      ", 10) + "010120241200" + "010120241200";
    putLE(b, uint16_t{3});
    putLE(b, uint16_t{2});
    for (double v : {5e-6, 5e-6, 1e-6, 1e-9}) putLE(b, v);
    b += std::string("\x00\x03\x00", 3);  // no compression, float32, no check
    for (float v : {1.0f, 2.0f, 3.0f, 4.0f, 5.5f, -6.0f}) putLE(b, v);
    put("metrology", "binary-f32.sdf", b + "*\nOperator = fuzz\n");
    // TrueMap and NanoFocus NMS, recognised by their content under the .sdf name (selector 0).
    std::string t(1, '\x00');
    t += std::string("Binary TrueMap Data File v2.0\r\n\0", 32) +
         std::string("fuzz                 \r\n\0", 24);
    putLE(t, uint32_t{3});
    putLE(t, uint32_t{2});
    for (float v : {0.015f, 0.01f, 0.0f, 0.0f}) putLE(t, v);
    for (float v : {0.001f, 0.002f, 0.003f, 0.004f, 0.0055f, -0.006f}) putLE(t, v);
    put("metrology", "truemap.tmd.bin", t);
    std::string m(1 + 3468, '\x00');
    const auto at = [&](size_t o, auto v) { std::memcpy(m.data() + 1 + o, &v, sizeof v); };
    std::memcpy(m.data() + 1 + 32, "OM_MS_2.0", 9);
    at(16, 2.0);
    at(24, 8.0);
    at(1368, uint32_t{3});
    at(1372, uint32_t{2});
    at(1376, 312.5);
    at(1384, 312.5);
    for (int v : {0, 100, 2000, 30000, 65000, 65535}) putLE(m, static_cast<uint16_t>(v));
    m += std::string(6, '\x7f');
    put("metrology", "nanofocus.nms.bin", m);
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: %s DIR   (writes DIR/<target>/...)\n", argv[0]);
        return 2;
    }
    gRoot = argv[1];
    scenes();
    npys();
    heightmaps();
    envmaps();
    transports();
    metrology();
    fs::remove_all(gRoot / ".scratch");
    return 0;
}
