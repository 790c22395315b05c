#include "app/pipeline/PartOfTransport.h"

#include <spdlog/spdlog.h>

#include "app/pipeline/Cache.h"
#include "app/pipeline/Judge.h"
#include "core/Error.h"
#include "core/Hash.h"
#include "io/SceneFile.h"
#include "render/Render.h"

namespace sl {

namespace {

/// The record's key: T's scene inputs and the scene file as parsed (overrides applied).
std::string recordKey(const nlohmann::json& sceneInputs, const SceneDesc& desc) {
    const std::string what = "part 1; T's scene " + sceneInputs.dump() + "; scene file " +
                             desc.file.string() + "; as parsed " + desc.canonicalJson;
    return hexKey128(what);
}

}  // namespace

RenderOptions PartOfTransport::sceneRender() const {
    return renderOptionsFor(desc.render);
}

std::optional<PartOfTransport> partOfTransport(const TransportFile& t,
                                               const std::filesystem::path& cacheDir) {
    PartOfTransport p;
    try {
        p.sceneInputs = sceneInputsOfTransport(t.provenance);
        if (!p.sceneInputs.contains("scene_file")) return std::nullopt;
        p.desc = readSceneFile(p.sceneInputs.at("scene_file").get<std::string>(),
                               p.sceneInputs.value("scene_overrides", std::vector<std::string>{}));
        p.camera = cameraOfTransport(t.provenance);
    } catch (const std::exception& e) {  // the scene is loaded when needed, with its errors
        spdlog::debug("the part of {}: {}", t.provenance.fingerprint, e.what());
        return std::nullopt;
    }
    p.key = recordKey(p.sceneInputs, p.desc);
    if (const auto r = readPartRecord(cacheDir, p.key)) {
        try {
            p.part = r->at("part");
            p.heightmap = nlohmann::ordered_json::parse(r->at("heightmap").get<std::string>());
            ViewingModel v;
            v.pixelsPerDegree = r->at("viewing").at("pixels_per_degree").get<double>();
            v.whiteLuminance = r->at("viewing").at("white_cd_m2").get<double>();
            for (const auto& w : r->at("warnings")) spdlog::warn("{}", w.get<std::string>());
            for (const auto& line : r->at("lines")) spdlog::info("{}", line.get<std::string>());
            p.viewing = v;
        } catch (const std::exception& e) {
            spdlog::debug("ignoring the part's record {}: {}", p.key, e.what());
            p.part = nullptr;
            p.heightmap = nullptr;
        }
    }
    return p;
}

std::optional<PartOfTransport> keepPartOfTransport(const std::filesystem::path& cacheDir,
                                                   const TransportFile& t, const Scene& scene,
                                                   const nlohmann::json& part) {
    if (cacheDir.empty()) return std::nullopt;
    std::optional<PartOfTransport> p = partOfTransport(t, {});
    // Only the scene T was traced from (an edited height map has another content hash).
    if (!p || transportSceneInputs(scene) != p->sceneInputs ||
        scene.desc.canonicalJson != p->desc.canonicalJson)
        return std::nullopt;
    ViewingModel v;
    try {
        v = viewingFor(scene);
    } catch (const std::exception&) {  // said where the viewing model is used, as before
        return std::nullopt;
    }
    const std::string mapFile = scene.desc.heightmap.path.filename().string();
    nlohmann::json warnings = nlohmann::json::array();
    for (const std::string& w : scene.load.warnings) warnings.push_back(mapFile + ": " + w);
    p->part = part;
    p->heightmap = heightmapLoadJson(scene);
    p->viewing = v;
    const nlohmann::json record = {
        {"part", p->part},
        {"heightmap", p->heightmap.dump()},  // as text: its keys in their order
        {"viewing", {{"pixels_per_degree", v.pixelsPerDegree}, {"white_cd_m2", v.whiteLuminance}}},
        {"warnings", warnings},
        {"lines",
         {describePart(scene),
          mapFile + ": " +
              scene.load.text(scene.mapWidth, scene.mapHeight, scene.desc.heightmap.pitch)}}};
    writePartRecord(cacheDir, p->key, "part of T " + t.provenance.fingerprint, record);
    return p;
}

}  // namespace sl
