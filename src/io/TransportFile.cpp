#include "io/TransportFile.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/Error.h"
#include "core/Hash.h"
#include "core/Interrupt.h"
#include "core/Registry.h"
#include "io/AtomicFile.h"
#include "io/InputFile.h"
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

std::string damaged(const std::string& where, const std::string& what) {
    return where + ": damaged transport-matrix file (" + what +
           "). Delete it and recompute it with `scratchlight precompute`";
}

}  // namespace

namespace {

/// The fingerprint of a provenance's inputs: everything but what names files.
std::string fingerprintOf(const json& in) {
    // The file name is informative only: the content hash identifies the height map.
    json keyed = in;
    if (keyed.contains("heightmap")) keyed["heightmap"].erase("file");
    if (keyed.contains("material")) keyed["material"].erase("name");
    keyed.erase("scene_file");
    keyed.erase("scene_overrides");
    const std::string text = keyed.dump();
    return hexKey128(text);
}

}  // namespace

json transportSceneInputs(const Scene& scene) {
    const CameraDesc& c = scene.camera.desc();
    const ConductorParams& m = scene.bsdf.params();
    json in;
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
    if (!scene.desc.file.empty())
        in["scene_file"] = std::filesystem::absolute(scene.desc.file).lexically_normal().string();
    // The fields they change are recorded above; these let sceneOfTransport load the same scene.
    if (!scene.desc.overrides.empty()) in["scene_overrides"] = scene.desc.overrides;
    return in;
}

json sceneInputsOfTransport(const TransportProvenance& provenance) {
    json in = json::parse(provenance.inputs);
    // What transportProvenance adds to the scene's share (the trace's options).
    for (const char* key : {"format", "tracer_revision", "convention", "channels", "planes",
                            "render", "rows", "pixels"})
        in.erase(key);
    return in;
}

CameraDesc cameraOfTransport(const TransportProvenance& provenance) {
    const json c = json::parse(provenance.inputs).at("camera");
    auto v = [](const json& a) {
        return Vec3d{a.at(0).get<double>(), a.at(1).get<double>(), a.at(2).get<double>()};
    };
    CameraDesc d;
    d.type = c.at("type").get<std::string>() == "perspective" ? CameraDesc::Type::Perspective
                                                              : CameraDesc::Type::Orthographic;
    d.origin = v(c.at("origin"));
    d.target = v(c.at("target"));
    d.up = v(c.at("up"));
    d.fovDeg = c.at("fov").get<double>();
    d.widthMm = c.at("width_mm").get<double>();
    d.width = c.at("width").get<int>();
    d.height = c.at("height").get<int>();
    return d;
}

TransportProvenance transportProvenance(const Scene& scene, const RenderOptions& opt,
                                        int channels) {
    return transportProvenance(transportSceneInputs(scene), opt, channels);
}

TransportProvenance transportProvenance(const json& sceneInputs, const RenderOptions& opt,
                                        int channels) {
    json in = sceneInputs;
    in["format"] = "scratchlight transport v1";
    in["tracer_revision"] = kTracerRevision;
    in["convention"] = kTransportConvention;
    in["channels"] = channels;
    in["planes"] = opt.sampleSets;  // 2: two independent sample sets, the halves T_a, T_b
    in["render"] = {{"spp", opt.spp},
                    {"max_depth", opt.maxDepth},
                    {"seed", opt.seed},
                    {"sampling", registryRow(samplingTable(), opt.sampling).name}};
    if (!opt.guide.empty())
        in["render"]["guide_hash"] =
            toHex(hash64(opt.guide.data(), opt.guide.size() * sizeof(float)));
    if (!opt.sppScale.empty()) {  // per-pixel sample multipliers (absent: spp everywhere)
        std::vector<uint8_t> f(opt.sppScale.size());
        std::transform(opt.sppScale.begin(), opt.sppScale.end(), f.begin(),
                       [](uint8_t v) { return std::max<uint8_t>(v, 1); });
        in["render"]["spp_scale"] = {
            {"max", *std::max_element(f.begin(), f.end())},
            {"scaled_pixels", std::count_if(f.begin(), f.end(), [](uint8_t v) { return v > 1; })},
            {"hash", toHex(hash64(f.data(), f.size()))}};
    }
    if (opt.rowBegin != 0 || opt.rowEnd != 0)  // a shard (absent for the whole image)
        in["rows"] = {opt.rowBegin, opt.rowEnd > 0
                                        ? opt.rowEnd
                                        : sceneInputs.at("camera").at("height").get<int>()};
    if (!opt.pixels.empty()) {  // only some pixels traced (a region; absent for all)
        std::vector<uint8_t> flags(opt.pixels.size());  // 0/1 whatever non-zero value is set
        std::transform(opt.pixels.begin(), opt.pixels.end(), flags.begin(),
                       [](uint8_t f) { return f != 0 ? 1 : 0; });
        const auto traced = static_cast<size_t>(std::count(flags.begin(), flags.end(), 1));
        in["pixels"] = {{"traced", traced}, {"hash", toHex(hash64(flags.data(), flags.size()))}};
    }
    TransportProvenance p;
    p.inputs = in.dump();
    p.fingerprint = fingerprintOf(in);
    p.spp = opt.spp;
    p.maxDepth = opt.maxDepth;
    p.seed = opt.seed;
    return p;
}

void writeTransportFile(const std::filesystem::path& file, const TransportMatrix& t,
                        const TransportProvenance& prov, bool result) {
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

    AtomicOutput out(file);
    {
        const std::filesystem::path& tmp = out.tempPath();
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
        os.close();  // flushes; a failed flush or close sets failbit
        if (!os) throw inputError(file.string(), "writing failed (disk full?)");
    }
    if (result) enterCommit();  // Ctrl-C while writing: the temporary goes, nothing appears
    out.commit();
}

TransportFile mergeTransportShards(std::vector<TransportFile> shards, const std::string& where,
                                   const std::vector<std::string>& names) {
    auto shardName = [&](size_t k) {
        return k < names.size() ? where + ": " + names[k]
                                : where + " shard " + std::to_string(k + 1);
    };
    if (shards.empty())
        throw inputError(where, "lists no shard",
                         "list the .tm files of `precompute " + option("rows") + "`");
    ShardOf common;  // the inputs and fingerprint every shard's inputs but its rows must have
    std::vector<std::array<int, 2>> ranges;
    for (size_t k = 0; k < shards.size(); ++k) {
        const std::string name = shardName(k);
        const ShardOf in = shardOf(shards[k], name);
        ranges.push_back({in.rowBegin, in.rowEnd});
        if (k == 0) {
            common = in;
        } else if (in.fingerprint != common.fingerprint) {
            throw inputError(name,
                             "was traced with other inputs than the first shard (scene, camera, "
                             "material, spp, seed or max_depth)",
                             "trace every shard with the same scene and options");
        }
    }
    TransportMatrix& first = shards.front().matrix;
    const size_t rows = first.rows();
    for (size_t k = 0; k < shards.size(); ++k) {
        const TransportMatrix& t = shards[k].matrix;
        if (!sameShape(t, first))
            throw inputError(shardName(k), "has other dimensions than the first shard",
                             "trace every shard alike");
    }
    const std::vector<int> owner = shardRowOwners(ranges, first.height, where, names);
    for (TransportFile& f : shards)
        if (f.matrix.storage == TransportStorage::Dense) f.matrix.toSparse();
    TransportMatrix m = emptySparseOfShape(first);
    const size_t st = static_cast<size_t>(m.stride()), W = static_cast<size_t>(m.width);
    for (size_t r = 0; r < rows; ++r) {
        const TransportMatrix& t = shards[static_cast<size_t>(owner[r / W])].matrix;
        const uint64_t b = t.rowPtr[r], e = t.rowPtr[r + 1];
        m.colIdx.insert(m.colIdx.end(), t.colIdx.begin() + static_cast<std::ptrdiff_t>(b),
                        t.colIdx.begin() + static_cast<std::ptrdiff_t>(e));
        m.values.insert(m.values.end(), t.values.begin() + static_cast<std::ptrdiff_t>(b * st),
                        t.values.begin() + static_cast<std::ptrdiff_t>(e * st));
        m.rowPtr[r + 1] = m.colIdx.size();
        m.objectMask[r] = t.objectMask[r];
    }
    chooseStorage(m);
    TransportFile out;
    out.matrix = std::move(m);
    out.provenance = shards.front().provenance;
    out.provenance.inputs = common.inputs;
    out.provenance.fingerprint = common.fingerprint;
    return out;
}

std::vector<int> shardRowOwners(const std::vector<std::array<int, 2>>& ranges, int height,
                                const std::string& where, const std::vector<std::string>& names) {
    std::vector<int> owner(static_cast<size_t>(std::max(height, 0)), -1);
    for (size_t k = 0; k < ranges.size(); ++k) {
        for (int y = ranges[k][0]; y < ranges[k][1]; ++y) {
            if (y < 0 || y >= height)
                throw inputError(k < names.size() ? where + ": " + names[k]
                                                  : where + " shard " + std::to_string(k + 1),
                                 "has rows outside the image", "trace it again");
            const int had = owner[static_cast<size_t>(y)];
            if (had >= 0) {
                std::string what = "row " + std::to_string(y) + " is in two shards";
                if (k < names.size())
                    what += " (" + names[static_cast<size_t>(had)] + " and " + names[k] + ")";
                throw inputError(where, what, "give each row range once");
            }
            owner[static_cast<size_t>(y)] = static_cast<int>(k);
        }
    }
    for (int y = 0; y < height; ++y)
        if (owner[static_cast<size_t>(y)] < 0)
            throw inputError(where, "no shard has image row " + std::to_string(y),
                             "trace the missing rows with `precompute " + option("rows") + " A:B`");
    return owner;
}

ShardOf shardOf(const TransportFile& shard, const std::string& name) {
    json in = json::parse(shard.provenance.inputs);
    if (!in.contains("rows"))
        throw inputError(name, "is a whole transport matrix, not a shard",
                         "list only the files of `precompute " + option("rows") + " A:B`");
    ShardOf s;
    s.rowBegin = in["rows"][0].get<int>();
    s.rowEnd = in["rows"][1].get<int>();
    in.erase("rows");
    s.inputs = in.dump();
    s.fingerprint = fingerprintOf(in);
    return s;
}

std::vector<std::filesystem::path> shardListFiles(const std::filesystem::path& list) {
    std::istringstream in(readInputFile(list, "a shard list", 1ull << 20,
                                        "check the path (a text file with one .tm file per line)"));
    std::vector<std::filesystem::path> files;
    std::string line;
    for (int number = 1; std::getline(in, line); ++number) {
        for (const char c : line)
            if ((static_cast<unsigned char>(c) < 0x20 && c != '\t' && c != '\r') || c == 0x7f)
                throw inputError(list.string() + ": line " + std::to_string(number),
                                 "is not a file name (\"" + textExcerpt(line, 40) +
                                     "\": control bytes; is this a binary file?)",
                                 "a shard list is a text file with one .tm file per line");
        const size_t a = line.find_first_not_of(" \t\r");
        if (a == std::string::npos || line[a] == '#') continue;
        const size_t b = line.find_last_not_of(" \t\r");
        std::filesystem::path p = line.substr(a, b - a + 1);
        if (p.is_relative()) p = list.parent_path() / p;
        if (p.extension() == ".shards")
            throw inputError(list.string(), "lists another shard list, " + p.string(),
                             "list the shards' .tm files themselves");
        files.push_back(p);
    }
    return files;
}

namespace {

TransportFile readShardList(const std::filesystem::path& list,
                            const std::string& expectedFingerprint) {
    std::vector<TransportFile> shards;
    std::vector<std::string> names;
    for (const std::filesystem::path& p : shardListFiles(list)) {
        shards.push_back(readTransportFile(p));
        names.push_back(p.string());
    }
    TransportFile merged = mergeTransportShards(std::move(shards), list.string(), names);
    if (!expectedFingerprint.empty() && merged.provenance.fingerprint != expectedFingerprint)
        throw inputError(list.string(), "its shards were traced from other inputs",
                         "trace the shards again from this scene");
    return merged;
}

}  // namespace

int peekTransportFile(const std::filesystem::path& file, std::string* fingerprint) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(file, ec)) return 0;
    std::ifstream in(file, std::ios::binary);
    char magic[8] = {};
    uint32_t version = 0, len = 0;
    in.read(magic, 8);
    if (!in || std::memcmp(magic, kMagic, 8) != 0) return 0;
    in.read(reinterpret_cast<char*>(&version), 4);
    in.read(reinterpret_cast<char*>(&len), 4);
    if (!in || version != kVersion || len > (1u << 24)) return 1;
    std::string header(len, '\0');
    uint64_t headerHash = 0;
    in.read(header.data(), len);
    in.read(reinterpret_cast<char*>(&headerHash), 8);
    if (!in || hash64(header.data(), header.size()) != headerHash ||
        jsonNestingDepth(header) > kMaxJsonDepth)
        return 1;
    try {
        const json h = json::parse(header);
        if (fingerprint) *fingerprint = h.at("fingerprint").get<std::string>();
    } catch (const json::exception&) {
        return 1;
    }
    return 2;
}

TransportFile readTransportFile(const std::filesystem::path& file,
                                const std::string& expectedFingerprint) {
    if (file.extension() == ".shards") return readShardList(file, expectedFingerprint);
    checkInputFile(file, "a transport-matrix file", UINT64_MAX,
                   "check the path, or create it with `scratchlight precompute`");
    std::ifstream in(file, std::ios::binary);
    std::error_code ec;
    const auto fileSize = std::filesystem::file_size(file, ec);
    if (!in || ec)
        throw inputError(file.string(), "cannot open the transport-matrix file",
                         "check the path, or create it with `scratchlight precompute`");
    return readTransport(in, fileSize, file.string(), expectedFingerprint);
}

TransportFile readTransport(std::istream& in, uint64_t fileSize, const std::string& where,
                            const std::string& expectedFingerprint) {
    const std::streamoff base = in.tellg() < 0 ? 0 : static_cast<std::streamoff>(in.tellg());
    char magic[8] = {};
    uint32_t version = 0, len = 0;
    in.read(magic, 8);
    in.read(reinterpret_cast<char*>(&version), 4);
    in.read(reinterpret_cast<char*>(&len), 4);
    if (!in || fileSize < 16 || std::memcmp(magic, kMagic, 8) != 0)
        throw inputError(where, "not a scratchlight transport-matrix file",
                         "give a .tm file written by `scratchlight precompute`");
    if (version != kVersion)
        throw inputError(where,
                         "transport-matrix format version " + std::to_string(version) +
                             " is not supported (this build reads version " +
                             std::to_string(kVersion) + ")",
                         "recompute it with this version's `scratchlight precompute`");
    if (16ull + len + 8 > fileSize) throw InputError(damaged(where, "truncated header"));
    std::string header(len, '\0');
    uint64_t headerHash = 0;
    in.read(header.data(), len);
    in.read(reinterpret_cast<char*>(&headerHash), 8);
    if (!in || hash64(header.data(), header.size()) != headerHash)
        throw InputError(damaged(where, "header checksum mismatch"));

    // The header, every field checked for presence, type and range before it is used.
    TransportFile out;
    TransportMatrix& t = out.matrix;
    const uint64_t payloadStart = 16ull + len + 8, payloadBytes = fileSize - payloadStart;
    struct SectionRef {
        std::string name, hash;
        uint64_t offset = 0, bytes = 0;
    };
    std::vector<SectionRef> sections;
    uint64_t nnz = 0;
    try {
        if (jsonNestingDepth(header) > kMaxJsonDepth)
            throw InputError(damaged(where, "the header nests deeper than " +
                                                std::to_string(kMaxJsonDepth) + " levels"));
        const json h = json::parse(header);
        if (!h.is_object()) throw InputError(damaged(where, "the header is not a JSON object"));
        auto integer = [&](const json& obj, const char* key, int64_t lo, int64_t hi) {
            const json& v = obj.at(key);
            if (!v.is_number_integer() ||
                (v.is_number_unsigned() && v.get<uint64_t>() > uint64_t(hi)) ||
                v.get<int64_t>() < lo || v.get<int64_t>() > hi)
                throw InputError(
                    damaged(where, "header field '" + std::string(key) + "' is " + jsonExcerpt(v) +
                                       ", expected a whole number in [" + std::to_string(lo) +
                                       ", " + std::to_string(hi) + "]"));
            return v.get<int64_t>();
        };
        auto text = [&](const json& obj, const char* key) {
            const json& v = obj.at(key);
            if (!v.is_string())
                throw InputError(
                    damaged(where, "header field '" + std::string(key) + "' is not a string"));
            return v.get<std::string>();
        };
        // Image and env-map sizes as the scene file allows them (camera.width/height,
        // envmap.width/height).
        t.width = static_cast<int>(integer(h, "width", 1, 16384));
        t.height = static_cast<int>(integer(h, "height", 1, 16384));
        t.envWidth = static_cast<int>(integer(h, "env_width", 2, 4096));
        t.envHeight = static_cast<int>(integer(h, "env_height", 3, 2048));
        if (t.cols() > static_cast<size_t>(kMaxTransportTexels))
            throw InputError(damaged(where, "env map of " + std::to_string(t.cols()) +
                                                " texels, more than the limit " +
                                                std::to_string(kMaxTransportTexels)));
        t.channels = static_cast<int>(integer(h, "channels", 1, 3));
        t.planes = h.contains("planes") ? static_cast<int>(integer(h, "planes", 1, 2)) : 1;
        if (t.channels == 2) throw InputError(damaged(where, "channels is 2 (1 or 3 exist)"));
        const std::string storage = text(h, "storage");
        if (storage != "csr" && storage != "dense")
            throw InputError(damaged(where, "unknown storage '" + storage + "'"));
        t.storage = storage == "csr" ? TransportStorage::Sparse : TransportStorage::Dense;
        nnz = static_cast<uint64_t>(integer(h, "nnz", 0, INT64_MAX));
        out.provenance.fingerprint = text(h, "fingerprint");
        out.provenance.inputs = h.at("inputs").dump();
        out.provenance.spp = static_cast<int>(integer(h, "spp", 0, INT32_MAX));
        out.provenance.maxDepth = static_cast<int>(integer(h, "max_depth", 0, INT32_MAX));
        const json& seed = h.at("seed");
        if (!seed.is_number_unsigned() && !(seed.is_number_integer() && seed.get<int64_t>() >= 0))
            throw InputError(damaged(where, "header field 'seed' is not a whole number >= 0"));
        out.provenance.seed = seed.get<uint64_t>();
        if (text(h, "convention") != kTransportConvention)
            throw inputError(where, "made with a different env-map convention",
                             "recompute it with `scratchlight precompute`");
        const json& list = h.at("sections");
        if (!list.is_array()) throw InputError(damaged(where, "'sections' is not a list"));
        for (const json& s : list) {
            if (!s.is_object()) throw InputError(damaged(where, "a section is not an object"));
            SectionRef r;
            r.name = text(s, "name");
            r.hash = text(s, "hash");
            r.offset = static_cast<uint64_t>(integer(s, "offset", 0, INT64_MAX));
            r.bytes = static_cast<uint64_t>(integer(s, "bytes", 0, INT64_MAX));
            sections.push_back(std::move(r));
        }
    } catch (const json::exception& e) {
        throw InputError(damaged(where, std::string("bad header: ") + e.what()));
    }
    if (!expectedFingerprint.empty() && expectedFingerprint != out.provenance.fingerprint)
        throw inputError(where,
                         "stale transport matrix: it was made from other inputs (scene, height "
                         "map, spp, seed or max_depth) than the ones given",
                         "recompute it with `scratchlight precompute`");

    // The sections: each one once, each within the file (so nothing larger than the file is
    // allocated), their hashes matching, and together reaching exactly the end of the file.
    const std::vector<std::string> expected =
        t.storage == TransportStorage::Sparse
            ? std::vector<std::string>{"object_mask", "row_ptr", "col_idx", "values"}
            : std::vector<std::string>{"object_mask", "values"};
    std::vector<bool> seen(expected.size(), false);
    uint64_t end = 0;
    for (const SectionRef& s : sections) {
        const auto it = std::find(expected.begin(), expected.end(), s.name);
        if (it == expected.end())
            throw InputError(damaged(
                where, "unexpected section '" + s.name + "' for " +
                           (t.storage == TransportStorage::Sparse ? "csr" : "dense") + " storage"));
        const size_t idx = static_cast<size_t>(it - expected.begin());
        if (seen[idx]) throw InputError(damaged(where, "section '" + s.name + "' appears twice"));
        seen[idx] = true;
        if (s.offset > payloadBytes || s.bytes > payloadBytes - s.offset)
            throw InputError(damaged(where, "truncated section " + s.name));
        auto readInto = [&](auto& vec) {
            using T = typename std::decay_t<decltype(vec)>::value_type;
            if (s.bytes % sizeof(T)) throw InputError(damaged(where, "bad size of " + s.name));
            vec.resize(s.bytes / sizeof(T));
            in.seekg(base + static_cast<std::streamoff>(payloadStart + s.offset));
            in.read(reinterpret_cast<char*>(vec.data()), static_cast<std::streamsize>(s.bytes));
            if (!in) throw InputError(damaged(where, "cannot read section " + s.name));
            if (toHex(hash64(vec.data(), s.bytes)) != s.hash)
                throw InputError(damaged(where, "checksum mismatch in section " + s.name));
        };
        if (s.name == "object_mask")
            readInto(t.objectMask);
        else if (s.name == "row_ptr")
            readInto(t.rowPtr);
        else if (s.name == "col_idx")
            readInto(t.colIdx);
        else
            readInto(t.values);
        end = std::max(end, s.offset + s.bytes);
    }
    for (size_t k = 0; k < expected.size(); ++k)
        if (!seen[k]) throw InputError(damaged(where, "section '" + expected[k] + "' is missing"));
    if (end != payloadBytes) throw InputError(damaged(where, "unexpected trailing bytes"));

    // Structural consistency (no overflow: rows <= 2^28, cols <= 2^16, stride <= 6).
    const size_t rows = t.rows(), cols = t.cols();
    const size_t stride = static_cast<size_t>(t.stride());
    if (t.objectMask.size() != rows)
        throw InputError(damaged(where, "the object mask has " +
                                            std::to_string(t.objectMask.size()) + " entries for " +
                                            std::to_string(rows) + " pixels"));
    for (uint8_t m : t.objectMask)
        if (m > 1)
            throw InputError(damaged(where, "the object mask holds a value other than 0, 1"));
    bool ok;
    if (t.storage == TransportStorage::Sparse) {
        ok = t.rowPtr.size() == rows + 1 && t.rowPtr.front() == 0 &&
             t.rowPtr.back() == t.colIdx.size() && t.values.size() == t.colIdx.size() * stride;
        for (size_t r = 0; ok && r < rows; ++r) ok = t.rowPtr[r] <= t.rowPtr[r + 1];
        for (size_t k = 0; ok && k < t.colIdx.size(); ++k) ok = t.colIdx[k] < cols;
    } else {
        ok = t.values.size() == rows * cols * stride;
    }
    if (!ok) throw InputError(damaged(where, "inconsistent matrix structure"));
    if (nnz != t.nnz())
        throw InputError(damaged(where, "the header says " + std::to_string(nnz) +
                                            " non-zeros, the matrix holds " +
                                            std::to_string(t.nnz())));
    // Entries are path throughputs times bilinear weights: finite and >= 0.
    for (size_t k = 0; k < t.values.size(); ++k)
        if (!(t.values[k] >= 0.0f) || !std::isfinite(t.values[k]))
            throw InputError(damaged(where, "value " + std::to_string(k) + " is " +
                                                std::to_string(t.values[k]) +
                                                " (entries of T are finite and >= 0)"));
    return out;
}

}  // namespace sl
