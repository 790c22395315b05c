#include "app/report/PartSummary.h"

#include <algorithm>

#include "scene/Scene.h"

namespace sl {

nlohmann::json partSummaryJson(const Scene& scene) {
    using json = nlohmann::json;
    const HeightmapDesc& h = scene.desc.heightmap;
    json j;
    j["file"] = h.path.string();
    j["format"] = scene.mapFormat;
    j["grid"] = {scene.mapWidth, scene.mapHeight};
    j["pixel_pitch_mm"] = h.pitch;
    j["pitch_from"] = h.pitchGiven ? "scene" : "file";
    j["size_mm"] = {(scene.mapWidth - 1) * h.pitch, (scene.mapHeight - 1) * h.pitch};
    if (!scene.heights.empty()) {
        const auto [lo, hi] = std::minmax_element(scene.heights.begin(), scene.heights.end());
        j["height_range_mm"] = {*lo, *hi};
    }
    j["invalid_points_filled"] = scene.invalidFilled;
    const MaterialDesc& m = scene.desc.material;
    j["material"] = {{"name", m.name},
                     {"type", m.type},
                     {"distribution", microfacetName(m.params.distribution)},
                     {"alpha", {m.params.alphaU, m.params.alphaV}}};
    const CameraDesc& c = scene.camera.desc();
    json cam = {{"type", c.type == CameraDesc::Type::Perspective ? "perspective" : "orthographic"},
                {"width", c.width},
                {"height", c.height},
                {"origin", {c.origin.x, c.origin.y, c.origin.z}},
                {"target", {c.target.x, c.target.y, c.target.z}}};
    if (c.type == CameraDesc::Type::Perspective)
        cam["fov_deg"] = c.fovDeg;
    else
        cam["width_mm"] = c.widthMm;
    j["camera"] = cam;
    return j;
}

}  // namespace sl
