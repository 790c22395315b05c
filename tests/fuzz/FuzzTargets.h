// The fuzz targets of tests/fuzz/ (README "Fuzzing and sanitizers"), one function per target:
// each feeds one input to one reader of io/ and checks what the reader accepted. A reader's
// documented refusal, sl::InputError, propagates to the caller: the libFuzzer entry points
// (fuzz_<target>.cpp) catch it, and tests/test_fuzz_regressions.cpp expects it for every input
// that once crashed a target (tests/fuzz/regressions/<target>/) and expects no refusal for the
// seeds (tests/fuzz/corpus/<target>/). Anything else is a finding: a crash, a sanitizer report,
// a leak, a hang, another exception type escaping, or a failed check (fail(), which aborts).
#pragma once

#include <OpenImageIO/imageio.h>
#include <unistd.h>
#include <zip.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "core/Error.h"
#include "core/Hash.h"
#include "core/Md5.h"
#include "io/EnvMapIO.h"
#include "io/HeightmapIO.h"
#include "io/Npy.h"
#include "io/SceneFile.h"
#include "io/TransportFile.h"
#include "scene/Camera.h"
#include "scene/Conductor.h"
#include "scene/EnvMapBasis.h"
#include "scene/Heightfield.h"
#include "scene/Scene.h"

namespace sl::fuzz {

enum class Target { Scene, Npy, Heightmap, Transport, Envmap, Metrology };
inline constexpr const char* kTargetNames[] = {"scene",     "npy",    "heightmap",
                                               "transport", "envmap", "metrology"};

/// A property of an accepted input does not hold: report it as a crash.
[[noreturn]] inline void fail(const char* what) {
    std::fprintf(stderr, "fuzz: accepted input violates: %s\n", what);
    std::abort();
}

/// A scratch file for readers that take a path: one per process and name, in /dev/shm when it
/// exists (no disk writes), removed at exit.
class ScratchFile {
  public:
    explicit ScratchFile(const std::string& name) {
        const std::filesystem::path dir = std::filesystem::is_directory("/dev/shm")
                                              ? std::filesystem::path("/dev/shm")
                                              : std::filesystem::temp_directory_path();
        path_ = dir / ("sl-fuzz-" + std::to_string(::getpid()) + "-" + name);
    }
    ~ScratchFile() {
        std::error_code ec;
        std::filesystem::remove(path_, ec);
    }
    ScratchFile(const ScratchFile&) = delete;
    ScratchFile& operator=(const ScratchFile&) = delete;
    const std::filesystem::path& write(const uint8_t* data, size_t size) {
        std::ofstream os(path_, std::ios::binary | std::ios::trunc);
        os.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
        os.close();
        if (!os) {
            std::fprintf(stderr, "fuzz: cannot write %s\n", path_.c_str());
            std::abort();
        }
        return path_;
    }

  private:
    std::filesystem::path path_;

  public:
    const std::filesystem::path& path() const { return path_; }
};

// --- scene ------------------------------------------------------------------------------------

/// The scene file parser (io/SceneFile.h parseScene), then what loadScene does with the parsed
/// values short of reading the height map: the material, env-map grid and camera checks of
/// scene/, on a fixed 4x4 part. An accepted scene must give finite camera rays.
inline void sceneInput(const uint8_t* data, size_t size) {
    static const std::vector<float> heights = {0.0f, 0.01f, 0.0f, 0.02f, 0.01f, 0.0f, 0.03f, 0.0f,
                                               0.0f, 0.01f, 0.0f, 0.02f, 0.01f, 0.0f, 0.0f,  0.0f};
    static const auto part = std::make_unique<Heightfield>(4, 4, 0.01, heights);
    const auto finite = [](const Vec3f& v) {
        return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
    };
    const SceneDesc d = parseScene(std::string(reinterpret_cast<const char*>(data), size),
                                   "/nonexistent", "fuzz.json");
    const ConductorBsdf bsdf(d.material.params);
    const EnvMapBasis basis(d.envmap.width, d.envmap.height);
    const Camera camera(resolveCamera(d.camera, *part));
    const double w = camera.desc().width, h = camera.desc().height;
    for (double y : {0.0, 0.5 * h, h})
        for (double x : {0.0, 0.5 * w, w}) {
            const Ray r = camera.generateRay(x, y);
            if (!finite(r.origin) || !finite(r.direction)) fail("camera rays are finite");
        }
}

// --- npy --------------------------------------------------------------------------------------

/// The .npy reader (io/Npy.h): the header parser on the bytes in memory, then readNpy2D on them
/// as a file. An accepted array must hold rows x cols values; the header's data must fill the
/// file.
inline void npyInput(const uint8_t* data, size_t size) {
    static ScratchFile file("in.npy");
    std::optional<NpyHeader> h;
    try {
        h = parseNpyHeader(data, size, size, "fuzz.npy");
    } catch (const InputError&) {
    }
    if (h && h->dataOffset + h->elementCount * h->itemSize != size)
        fail("the header's data fills the file");
    const NpyMatrix m = readNpy2D(file.write(data, size));
    if (!h) fail("readNpy2D accepts only what parseNpyHeader accepts");
    if (m.rows < 0 || m.cols < 0 ||
        m.data.size() != static_cast<size_t>(m.rows) * static_cast<size_t>(m.cols))
        fail("rows x cols values");
}

// --- heightmap --------------------------------------------------------------------------------

/// The height-map readers (io/HeightmapIO.h loadHeightmap: EXR, TIFF, PNG, .npy). Input: one
/// selector byte, then the file's bytes. The selector picks the file's extension (bits 0-1:
/// .exr, .tif, .png, .npy) and the scene's options (bit 2: height_range [0, 1] for integer
/// maps; bit 3: height_scale 2). An accepted map must be at least 2x2 with width x height finite
/// heights.
inline void heightmapInput(const uint8_t* data, size_t size) {
    static ScratchFile files[4] = {ScratchFile("hm.exr"), ScratchFile("hm.tif"),
                                   ScratchFile("hm.png"), ScratchFile("hm.npy")};
    if (size < 1) return;
    const uint8_t sel = data[0];
    HeightmapOptions opt;
    if (sel & 4) opt.heightRange = std::array<double, 2>{0.0, 1.0};
    if (sel & 8) opt.heightScale = 2.0;
    const HeightmapData d = loadHeightmap(files[sel & 3].write(data + 1, size - 1), opt);
    if (d.width < 2 || d.height < 2 ||
        d.heights.size() != static_cast<size_t>(d.width) * static_cast<size_t>(d.height))
        fail("at least 2x2, width x height heights");
    for (float v : d.heights)
        if (!std::isfinite(v)) fail("heights are finite");
}

// --- transport --------------------------------------------------------------------------------

/// The input with its header hash and section hashes made to match its bytes, when its header
/// is JSON (else nothing).
inline std::optional<std::string> withRepairedChecksums(const std::string& in) {
    using json = nlohmann::json;
    if (in.size() < 16 || std::memcmp(in.data(), "SLTMATRX", 8) != 0) return std::nullopt;
    uint32_t len = 0;
    std::memcpy(&len, in.data() + 12, 4);
    if (16ull + len + 8 > in.size()) return std::nullopt;
    json h = json::parse(in.substr(16, len), nullptr, /*allow_exceptions=*/false);
    if (!h.is_object()) return std::nullopt;
    const std::string payload = in.substr(16 + size_t(len) + 8);
    if (h.contains("sections") && h["sections"].is_array())
        for (json& s : h["sections"]) {
            if (!s.is_object() || !s.contains("offset") || !s.contains("bytes") ||
                !s["offset"].is_number_unsigned() || !s["bytes"].is_number_unsigned())
                continue;
            const auto offset = s["offset"].get<uint64_t>(), bytes = s["bytes"].get<uint64_t>();
            if (offset <= payload.size() && bytes <= payload.size() - offset)
                s["hash"] = toHex(hash64(payload.data() + offset, bytes));
        }
    const std::string header = h.dump();
    const auto newLen = static_cast<uint32_t>(header.size());
    const uint64_t headerHash = hash64(header.data(), header.size());
    std::string out = in.substr(0, 12);
    out.append(reinterpret_cast<const char*>(&newLen), 4);
    out += header;
    out.append(reinterpret_cast<const char*>(&headerHash), 8);
    return out + payload;
}

/// The transport-matrix file reader (io/TransportFile.h readTransport) on the bytes in memory.
/// An accepted matrix must be usable: T·E and Tᵀ·g run on it with finite results for finite E
/// and g.
inline void transportBytes(const std::string& bytes) {
    std::istringstream in(bytes);
    TransportFile f = readTransport(in, bytes.size(), "fuzz.tm");
    TransportMatrix& t = f.matrix;
    t.threads = 1;
    const std::vector<double> E(t.cols(), 0.5), g(t.rows(), 1.0);
    std::vector<double> Y(t.rows()), grad(t.cols());
    t.applyLuminance(E, Y);
    t.applyTransposeLuminance(g, grad);
    for (double v : Y)
        if (!std::isfinite(v)) fail("T·E is finite");
    for (double v : grad)
        if (!std::isfinite(v)) fail("Tᵀ·g is finite");
}

/// Each input is read twice: as it is, and with its checksums repaired (the header's hash and
/// every section's hash recomputed over the mutated bytes), so that mutations reach the
/// header's fields and the matrix structure behind the checksums. Throws the first refusal.
inline void transportInput(const uint8_t* data, size_t size) {
    const std::string bytes(reinterpret_cast<const char*>(data), size);
    std::optional<InputError> refused;
    try {
        transportBytes(bytes);
    } catch (const InputError& e) {
        refused = e;
    }
    if (auto repaired = withRepairedChecksums(bytes)) transportBytes(*repaired);
    if (refused) throw *refused;
}

// --- envmap -----------------------------------------------------------------------------------

/// The env-map loader (io/EnvMapIO.h loadEnvMap: any image readImage reads, resampled onto the
/// texel grid). Input: one selector byte, then the file's bytes. The selector picks the
/// extension (bits 0-1: .exr, .png, .hdr, .tif), the texel grid (bits 2-3: 50x25, 8x4, 4x3,
/// 2x3) and the channels asked for (bits 4-5: 0 = as in the file, 1, 3, 0). An accepted map
/// must have the grid's size and finite, non-negative texels.
inline void envmapInput(const uint8_t* data, size_t size) {
    static ScratchFile files[4] = {ScratchFile("env.exr"), ScratchFile("env.png"),
                                   ScratchFile("env.hdr"), ScratchFile("env.tif")};
    static const int grids[4][2] = {{50, 25}, {8, 4}, {4, 3}, {2, 3}};
    static const int channelChoices[4] = {0, 1, 3, 0};
    if (size < 1) return;
    const uint8_t sel = data[0];
    const int w = grids[(sel >> 2) & 3][0], h = grids[(sel >> 2) & 3][1];
    const int channels = channelChoices[(sel >> 4) & 3];
    const EnvMap env = loadEnvMap(files[sel & 3].write(data + 1, size - 1), w, h, channels);
    if (env.width != w || env.height != h || (channels != 0 && env.channels != channels) ||
        env.texels.size() != env.texelCount() * static_cast<size_t>(env.channels))
        fail("the grid's size and channels");
    for (float v : env.texels)
        if (!std::isfinite(v) || v < 0.0f) fail("texels finite and >= 0");
}

// --- metrology (X3P, SDF) ----------------------------------------------------------------------

/// The bytes of an X3P archive holding main.xml and bindata/data.bin, with the MD5 digest of
/// the point data in main.xml (MD5ChecksumPointData, when present) made to match the data.
inline std::string assembleX3p(std::string xml, const std::string& data,
                               const std::filesystem::path& scratch) {
    const std::string open = "<MD5ChecksumPointData>", close = "</MD5ChecksumPointData>";
    const size_t a = xml.find(open);
    const size_t b = a == std::string::npos ? a : xml.find(close, a + open.size());
    if (b != std::string::npos)
        xml.replace(a + open.size(), b - a - open.size(), md5Hex(data.data(), data.size()));
    int err = 0;
    zip_t* z = zip_open(scratch.c_str(), ZIP_CREATE | ZIP_TRUNCATE, &err);
    if (!z) fail("the harness can create a zip");
    for (const auto& [name, bytes] : {std::pair<const char*, const std::string*>{"main.xml", &xml},
                                      {"bindata/data.bin", &data}}) {
        zip_source_t* src = zip_source_buffer(z, bytes->data(), bytes->size(), 0);
        if (!src || zip_file_add(z, name, src, ZIP_FL_OVERWRITE) < 0) fail("zip_file_add");
    }
    if (zip_close(z) != 0) fail("zip_close");
    std::ifstream in(scratch, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), {}};
}

/// The surface-metrology readers (io/X3p.h, io/Sdf.h, io/TrueMap.h, io/NanoFocusNms.h through
/// io/HeightmapIO.h loadHeightmap). Input: one selector byte, then the payload. Bits 0-1: 0 = the
/// payload is a file named .sdf (ASCII or binary SDF, or a TrueMap or NMS file, which the content
/// picks); 1 = the payload is an .x3p file (a zip: most mutations stop at its CRCs);
/// 2, 3 = the payload is a little-endian uint16 n, n bytes of main.xml and the point data, put
/// into an X3P archive by assembleX3p, so that mutations reach the XML's fields and the data's
/// checks behind the zip's CRCs and the MD5 digest. Bit 2: height_scale 2. An accepted map must
/// be at least 2x2 with width x height finite heights (invalid points filled) and, when the file
/// gives one, a finite positive pitch.
inline void metrologyInput(const uint8_t* data, size_t size) {
    static ScratchFile sdf("m.sdf"), x3p("m.x3p"), scratch("m-assembled.x3p");
    if (size < 1) return;
    const uint8_t sel = data[0];
    HeightmapOptions opt;
    if (sel & 4) opt.heightScale = 2.0;
    const uint8_t* payload = data + 1;
    const size_t n = size - 1;
    std::filesystem::path file;
    switch (sel & 3) {
        case 0:
            file = sdf.write(payload, n);
            break;
        case 1:
            file = x3p.write(payload, n);
            break;
        default: {
            if (n < 2) return;
            const size_t xmlBytes = std::min<size_t>(payload[0] | (payload[1] << 8), n - 2);
            const std::string xml(reinterpret_cast<const char*>(payload + 2), xmlBytes);
            const std::string bin(reinterpret_cast<const char*>(payload + 2 + xmlBytes),
                                  n - 2 - xmlBytes);
            const std::string zipBytes = assembleX3p(xml, bin, scratch.path());
            file = x3p.write(reinterpret_cast<const uint8_t*>(zipBytes.data()), zipBytes.size());
        }
    }
    const HeightmapData d = loadHeightmap(file, opt);
    if (d.width < 2 || d.height < 2 ||
        d.heights.size() != static_cast<size_t>(d.width) * static_cast<size_t>(d.height))
        fail("at least 2x2, width x height heights");
    for (float v : d.heights)
        if (!std::isfinite(v)) fail("heights are finite");
    if (d.pitch && !(std::isfinite(*d.pitch) && *d.pitch > 0)) fail("the pitch is finite, > 0");
}

/// Once per fuzzing process: OpenImageIO without worker threads (one core per fuzzer, and
/// reports that do not depend on thread timing).
inline void initialize() {
    OIIO::attribute("threads", 1);
    OIIO::attribute("exr_threads", 0);
}

/// The function of a target.
inline void feed(Target t, const uint8_t* data, size_t size) {
    switch (t) {
        case Target::Scene:
            return sceneInput(data, size);
        case Target::Npy:
            return npyInput(data, size);
        case Target::Heightmap:
            return heightmapInput(data, size);
        case Target::Transport:
            return transportInput(data, size);
        case Target::Envmap:
            return envmapInput(data, size);
        case Target::Metrology:
            return metrologyInput(data, size);
    }
}

}  // namespace sl::fuzz
