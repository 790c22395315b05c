#include "app/jobs/InfoJob.h"

#include <algorithm>
#include <cmath>

#include "app/report/PartSummary.h"
#include "io/SceneFile.h"

namespace sl {

InfoJobSummary runInfoJob(const InfoJobOptions& o) {
    const HeightSource src = loadHeightSource(o.input, o.sceneOverrides);
    InfoJobSummary s;
    const HeightmapLoad& load = src.scene ? src.scene->load : src.load;
    s.width = src.width();
    s.height = src.height();
    s.reader = load.format;
    s.measured = src.measured();
    s.resampling = load.resampling;
    s.channel = load.channel;
    s.invalidFilled = load.invalidFilled;
    s.levelling = load.levelling;
    s.warnings = load.warnings;
    if (src.scene) {
        const HeightmapDesc& h = src.scene->desc.heightmap;
        s.file = h.path.string();
        s.scene = o.input.string();
        s.pitch = h.pitch;
        s.pitchFrom = h.pitchGiven ? "scene" : "file";
        s.heightsInMm = true;
        s.part = partSummaryJson(*src.scene);
    } else {
        s.file = o.input.string();
        s.pitch = src.map.pitch;
        s.pitchFrom = src.map.pitch ? "file" : "none";
        s.heightsInMm = src.map.measured();
    }
    const std::vector<float>& h = src.heights();
    if (!h.empty()) {
        const auto [lo, hi] = std::minmax_element(h.begin(), h.end());
        s.minHeight = *lo;
        s.maxHeight = *hi;
        double mean = 0;
        for (float v : h) mean += v;
        mean /= static_cast<double>(h.size());
        double ss = 0;
        for (float v : h) ss += (v - mean) * (v - mean);
        s.sq = std::sqrt(ss / static_cast<double>(h.size()));
    }
    return s;
}

nlohmann::ordered_json infoJson(const InfoJobSummary& s) {
    nlohmann::ordered_json j;
    j["file"] = s.file;
    j["scene"] =
        s.scene.empty() ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(s.scene);
    j["reader"] = s.reader;
    j["measured"] = s.measured;
    j["size_px"] = {s.width, s.height};
    j["pixel_pitch_mm"] =
        s.pitch ? nlohmann::ordered_json(*s.pitch) : nlohmann::ordered_json(nullptr);
    j["pitch_from"] = s.pitchFrom;
    j["size_mm"] = s.pitch
                       ? nlohmann::ordered_json{(s.width - 1) * *s.pitch, (s.height - 1) * *s.pitch}
                       : nlohmann::ordered_json(nullptr);
    j["resampled"] = !s.resampling.empty();
    j["resampling"] = s.resampling;
    j["channel"] = s.channel;
    j["invalid_points_filled"] = s.invalidFilled;
    nlohmann::ordered_json lev;
    lev["mode"] = levellingName(s.levelling.applied);
    lev["auto"] = s.levelling.automatic;
    if (s.levelling.applied.mode != LevellingDesc::Mode::None) {
        lev["points"] = s.levelling.points;
        lev["rms_before"] = s.levelling.rmsBefore;
        lev["rms_after"] = s.levelling.rmsAfter;
    }
    j["levelling"] = lev;
    j["heights_unit"] = s.heightsInMm ? "mm" : "as stored";
    j["height_range"] = {s.minHeight, s.maxHeight};
    j["sq"] = s.sq;
    j["warnings"] = s.warnings;
    if (!s.part.is_null()) {
        j["material"] = s.part.at("material");
        j["camera"] = s.part.at("camera");
    }
    return j;
}

}  // namespace sl
