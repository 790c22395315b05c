#include "io/TransportFile.h"

#include <bit>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>

#include "core/Error.h"
#include "core/Hash.h"
#include "io/AtomicFile.h"
#include "scene/Scene.h"

namespace sl {

namespace {

using json = nlohmann::json;
constexpr char kMagic[8] = {'S', 'L', 'T', 'M', 'A', 'T', 'R', 'X'};
constexpr uint32_t kVersion = 1;

static_assert(std::endian::native == std::endian::little, "the .tm format is little-endian");

json vec(const Vec3d& v) {
    return json::array({v.x, v.y, v.z});
}
json rgb(const Rgb& v) {
    return json::array({v.x, v.y, v.z});
}

struct Section {
    std::string name;
    const void* data;
    size_t bytes;
};

std::string damaged(const std::filesystem::path& f, const std::string& what) {
    return f.string() + ": damaged transport-matrix file (" + what +
           "). Delete it and recompute it with `scratchlight precompute`";
}

}  // namespace

TransportProvenance transportProvenance(const Scene& scene, const RenderOptions& opt,
                                        int channels) {
    const CameraDesc& c = scene.camera.desc();
    const ConductorParams& m = scene.bsdf.params();
    json in;
    in["format"] = "scratchlight transport v1";
    in["tracer_revision"] = kTracerRevision;
    in["convention"] = kTransportConvention;
    in["channels"] = channels;
    in["planes"] = opt.sampleSets;  // 2: two independent sample sets, the halves T_a, T_b
    in["camera"] = {
        {"type", c.type == CameraDesc::Type::Perspective ? "perspective" : "orthographic"},
        {"origin", vec(c.origin)},
        {"target", vec(c.target)},
        {"up", vec(c.up)},
        {"fov", c.fovDeg},
        {"width_mm", c.widthMm},
        {"width", c.width},
        {"height", c.height}};
    in["material"] = {{"smooth", m.smooth},
                      {"distribution", m.distribution == Microfacet::GGX ? "ggx" : "beckmann"},
                      {"alpha_u", m.alphaU},
                      {"alpha_v", m.alphaV},
                      {"eta", rgb(m.ior.eta)},
                      {"k", rgb(m.ior.k)},
                      {"specular_reflectance", rgb(m.specularReflectance)},
                      {"name", scene.desc.material.name}};
    in["envmap"] = {{"width", scene.basis.width()}, {"height", scene.basis.height()}};
    in["heightmap"] = {
        {"width", scene.mapWidth},
        {"height", scene.mapHeight},
        {"pixel_pitch", scene.desc.heightmap.pitch},
        {"content_hash", toHex(hash64(scene.heights.data(), scene.heights.size() * sizeof(float)))},
        {"file", scene.desc.heightmap.path.filename().string()}};
    in["render"] = {{"spp", opt.spp}, {"max_depth", opt.maxDepth}, {"seed", opt.seed}};
    if (!scene.desc.file.empty())
        in["scene_file"] = std::filesystem::absolute(scene.desc.file).lexically_normal().string();
    TransportProvenance p;
    p.inputs = in.dump();
    // The file name is informative only: the content hash identifies the height map.
    json keyed = in;
    keyed["heightmap"].erase("file");
    keyed["material"].erase("name");
    keyed.erase("scene_file");
    std::string text = keyed.dump();
    p.fingerprint =
        toHex(hash64(text.data(), text.size(), 1)) + toHex(hash64(text.data(), text.size(), 2));
    p.spp = opt.spp;
    p.maxDepth = opt.maxDepth;
    p.seed = opt.seed;
    return p;
}

void writeTransportFile(const std::filesystem::path& file, const TransportMatrix& t,
                        const TransportProvenance& prov) {
    std::vector<Section> sections = {{"object_mask", t.objectMask.data(), t.objectMask.size()}};
    if (t.storage == TransportStorage::Sparse) {
        sections.push_back({"row_ptr", t.rowPtr.data(), t.rowPtr.size() * sizeof(uint64_t)});
        sections.push_back({"col_idx", t.colIdx.data(), t.colIdx.size() * sizeof(uint16_t)});
    }
    sections.push_back({"values", t.values.data(), t.values.size() * sizeof(float)});

    json h;
    h["width"] = t.width;
    h["height"] = t.height;
    h["env_width"] = t.envWidth;
    h["env_height"] = t.envHeight;
    h["channels"] = t.channels;
    h["planes"] = t.planes;
    h["storage"] = t.storage == TransportStorage::Sparse ? "csr" : "dense";
    h["nnz"] = t.nnz();
    h["convention"] = kTransportConvention;
    h["fingerprint"] = prov.fingerprint;
    h["inputs"] = json::parse(prov.inputs);
    h["spp"] = prov.spp;
    h["max_depth"] = prov.maxDepth;
    h["seed"] = prov.seed;
    uint64_t offset = 0;
    for (const Section& s : sections) {
        h["sections"].push_back({{"name", s.name},
                                 {"offset", offset},
                                 {"bytes", s.bytes},
                                 {"hash", toHex(hash64(s.data, s.bytes))}});
        offset += s.bytes;
    }
    const std::string header = h.dump();
    const uint64_t headerHash = hash64(header.data(), header.size());

    writeAtomically(file, [&](const std::filesystem::path& tmp) {
        std::ofstream os(tmp, std::ios::binary);
        if (!os) throw inputError(file.string(), "cannot write the transport-matrix file");
        const auto len = static_cast<uint32_t>(header.size());
        os.write(kMagic, 8);
        os.write(reinterpret_cast<const char*>(&kVersion), 4);
        os.write(reinterpret_cast<const char*>(&len), 4);
        os.write(header.data(), static_cast<std::streamsize>(header.size()));
        os.write(reinterpret_cast<const char*>(&headerHash), 8);
        for (const Section& s : sections)
            os.write(static_cast<const char*>(s.data), static_cast<std::streamsize>(s.bytes));
        os.flush();
        if (!os) throw inputError(file.string(), "writing failed (disk full?)");
    });
}

TransportFile readTransportFile(const std::filesystem::path& file,
                                const std::string& expectedFingerprint) {
    std::ifstream in(file, std::ios::binary);
    if (!in)
        throw inputError(file.string(), "cannot open the transport-matrix file",
                         "check the path, or create it with `scratchlight precompute`");
    const auto fileSize = std::filesystem::file_size(file);
    char magic[8] = {};
    uint32_t version = 0, len = 0;
    in.read(magic, 8);
    in.read(reinterpret_cast<char*>(&version), 4);
    in.read(reinterpret_cast<char*>(&len), 4);
    if (!in || std::memcmp(magic, kMagic, 8) != 0)
        throw inputError(file.string(), "not a scratchlight transport-matrix file",
                         "give a .tm file written by `scratchlight precompute`");
    if (version != kVersion)
        throw inputError(file.string(),
                         "transport-matrix format version " + std::to_string(version) +
                             " is not supported (this build reads version " +
                             std::to_string(kVersion) + ")",
                         "recompute it with this version's `scratchlight precompute`");
    if (16ull + len + 8 > fileSize) throw InputError(damaged(file, "truncated header"));
    std::string header(len, '\0');
    uint64_t headerHash = 0;
    in.read(header.data(), len);
    in.read(reinterpret_cast<char*>(&headerHash), 8);
    if (!in || hash64(header.data(), header.size()) != headerHash)
        throw InputError(damaged(file, "header checksum mismatch"));

    TransportFile out;
    TransportMatrix& t = out.matrix;
    json h;
    try {
        h = json::parse(header);
        t.width = h.at("width").get<int>();
        t.height = h.at("height").get<int>();
        t.envWidth = h.at("env_width").get<int>();
        t.envHeight = h.at("env_height").get<int>();
        t.channels = h.at("channels").get<int>();
        t.planes = h.value("planes", 1);
        t.storage = h.at("storage").get<std::string>() == "csr" ? TransportStorage::Sparse
                                                                : TransportStorage::Dense;
        out.provenance.fingerprint = h.at("fingerprint").get<std::string>();
        out.provenance.inputs = h.at("inputs").dump();
        out.provenance.spp = h.at("spp").get<int>();
        out.provenance.maxDepth = h.at("max_depth").get<int>();
        out.provenance.seed = h.at("seed").get<uint64_t>();
        if (h.at("convention").get<std::string>() != kTransportConvention)
            throw inputError(file.string(), "made with a different env-map convention",
                             "recompute it with `scratchlight precompute`");
    } catch (const json::exception& e) {
        throw InputError(damaged(file, std::string("bad header: ") + e.what()));
    }
    if (!expectedFingerprint.empty() && expectedFingerprint != out.provenance.fingerprint)
        throw inputError(file.string(),
                         "stale transport matrix: it was made from other inputs (scene, height "
                         "map, spp, seed or max_depth) than the ones given",
                         "recompute it with `scratchlight precompute`");
    if (t.width < 1 || t.height < 1 || t.envWidth < 2 || t.envHeight < 3 ||
        (t.channels != 1 && t.channels != 3) || (t.planes != 1 && t.planes != 2))
        throw InputError(damaged(file, "bad dimensions"));

    const uint64_t payloadStart = 16ull + len + 8;
    size_t expectedEnd = payloadStart;
    for (const json& s : h.at("sections")) {
        const std::string name = s.at("name").get<std::string>();
        const uint64_t offset = s.at("offset").get<uint64_t>(),
                       bytes = s.at("bytes").get<uint64_t>();
        if (payloadStart + offset + bytes > fileSize)
            throw InputError(damaged(file, "truncated section " + name));
        auto readInto = [&](auto& vec) {
            using T = typename std::decay_t<decltype(vec)>::value_type;
            if (bytes % sizeof(T)) throw InputError(damaged(file, "bad size of " + name));
            vec.resize(bytes / sizeof(T));
            in.seekg(static_cast<std::streamoff>(payloadStart + offset));
            in.read(reinterpret_cast<char*>(vec.data()), static_cast<std::streamsize>(bytes));
            if (!in) throw InputError(damaged(file, "cannot read section " + name));
            if (toHex(hash64(vec.data(), bytes)) != s.at("hash").get<std::string>())
                throw InputError(damaged(file, "checksum mismatch in section " + name));
        };
        if (name == "object_mask")
            readInto(t.objectMask);
        else if (name == "row_ptr")
            readInto(t.rowPtr);
        else if (name == "col_idx")
            readInto(t.colIdx);
        else if (name == "values")
            readInto(t.values);
        else
            throw InputError(damaged(file, "unknown section " + name));
        expectedEnd = std::max<size_t>(expectedEnd, payloadStart + offset + bytes);
    }
    if (expectedEnd != fileSize) throw InputError(damaged(file, "unexpected trailing bytes"));

    // Structural consistency.
    const size_t rows = t.rows(), cols = t.cols();
    bool ok = t.objectMask.size() == rows;
    if (t.storage == TransportStorage::Sparse) {
        ok = ok && t.rowPtr.size() == rows + 1 && t.rowPtr.front() == 0 &&
             t.rowPtr.back() == t.colIdx.size() &&
             t.values.size() == t.colIdx.size() * static_cast<size_t>(t.stride());
        for (size_t r = 0; ok && r < rows; ++r) ok = t.rowPtr[r] <= t.rowPtr[r + 1];
        for (size_t k = 0; ok && k < t.colIdx.size(); ++k) ok = t.colIdx[k] < cols;
    } else {
        ok = ok && t.values.size() == rows * cols * static_cast<size_t>(t.stride());
    }
    if (!ok) throw InputError(damaged(file, "inconsistent matrix structure"));
    return out;
}

}  // namespace sl
