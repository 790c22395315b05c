// A .tm's part without its height map: what a run on a transport matrix needs of its scene when
// every estimate it reads is cached (the validation estimate, the specular start, the paper's
// light, T's Gram), so that it does not decode the height map (io/SceneFile.h loadScene: 18 % of
// a cached re-optimization's CPU at 256², docs/RESEARCH.md "Issue 32, eighth pass").
//  - T's recorded inputs give the camera and the scene's share of every other estimate's
//    fingerprint (io/TransportFile.h sceneInputsOfTransport; app/pipeline/Transport.h
//    cachedTransport finds V by it);
//  - the scene file, parsed without its height map (io/SceneFile.h readSceneFile), gives the
//    render section;
//  - what only the loaded scene says (the part's summary and height-map load as the outputs record
//    them, the viewing model, the lines loadScene prints) a run that loaded it keeps in the cache
//    beside T (part-<key>.json, app/pipeline/Cache.h writePartRecord). The key covers T's scene
//    inputs (the heights' content hash, camera and material included) and the scene file as
//    parsed now with its overrides: an edited scene file is another key, and a record is written
//    only by a scene whose inputs are T's.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "io/TransportFile.h"
#include "perception/ViewingModel.h"
#include "render/PathTracer.h"
#include "scene/Camera.h"
#include "scene/Scene.h"

namespace sl {

struct PartOfTransport {
    nlohmann::json sceneInputs;  // T's (sceneInputsOfTransport)
    SceneDesc desc;              // the scene file as it reads now, heights unread
    CameraDesc camera;           // T's
    std::string key;             // the record's (part-<key>.json)
    /// From the cache (null/unset until a run that loaded the scene kept them): the part's
    /// summary (app/report/PartSummary.h partSummaryJson), its height-map load (io/SceneFile.h
    /// heightmapLoadJson), the viewing model (app/pipeline/Judge.h viewingFor).
    nlohmann::json part;
    nlohmann::ordered_json heightmap;
    std::optional<ViewingModel> viewing;
    /// What the scene's render section sets (render/Render.h renderOptionsFor).
    RenderOptions sceneRender() const;
    /// The record is there: a run needs the scene only to trace or to project masks.
    bool recorded() const { return viewing.has_value(); }
};

/// T's part as far as it is known without the height map; nullopt when T records no scene file
/// or the file does not read now (the scene, when needed, is then loaded with its errors). Logs
/// the lines loadScene printed when its record is in `cacheDir`.
std::optional<PartOfTransport> partOfTransport(const TransportFile& t,
                                               const std::filesystem::path& cacheDir);

/// Keeps what the loaded `scene` says of T's part in `cacheDir` for the next run on T (`part`:
/// its summary, partSummaryJson), unless the scene is not T's (its inputs differ from T's
/// recorded ones: an edited height map) or the cache is off. Returns the part with the record.
std::optional<PartOfTransport> keepPartOfTransport(const std::filesystem::path& cacheDir,
                                                   const TransportFile& t, const Scene& scene,
                                                   const nlohmann::json& part);

}  // namespace sl
