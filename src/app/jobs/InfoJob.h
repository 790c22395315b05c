// `scratchlight info FILE|SCENE.json`: what the readers found in a height map or a scene's, as
// every other command would read it (io/SceneFile.h loadHeightSource: a scene through loadScene,
// its levelling, pitch and overrides; a bare map through loadHeightmap and the default
// levelling, auto). Nothing is written.
//
// The summary: the reader (its format text), whether the map is a measurement, its size in
// samples and mm, its pitch and where it came from (the file's, the scene's, or none: a bare
// EXR, PNG, TIFF or .npy carries none), how non-square pixels were resampled (or not), the
// invalid points filled, the levelling in force (mode, auto or given, RMS before and after),
// the height range and Sq after levelling (Sq: the RMS of every sample about the mean, the
// filled ones included: the surface as it is rendered) and the reader's warnings; for a scene,
// its part summary (app/report/PartSummary.h: material and camera).
#pragma once

#include <cstddef>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "scene/Levelling.h"

namespace sl {

struct InfoJobOptions {
    std::filesystem::path input;              // height map or scene file (.json)
    std::vector<std::string> sceneOverrides;  // -D key=value on the scene
};

struct InfoJobSummary {
    std::string file;             // the height map read
    std::string scene;            // the scene file ("" for a bare map)
    std::string reader;           // the reader's format text, e.g. "exr float32"
    bool measured = false;        // a measurement (the defect map's auto method follows it)
    int width = 0, height = 0;    // samples
    std::optional<double> pitch;  // mm per sample; none for a bare map without one
    std::string pitchFrom;        // "file", "scene" or "none"
    std::string resampling;       // "" or how non-square pixels were made square
    std::string channel;          // "" or which channel of a file of several was read
    size_t invalidFilled = 0;     // invalid points of the file, filled
    LevellingResult levelling;    // the levelling in force and what it removed
    double minHeight = 0, maxHeight = 0, sq = 0;  // after levelling; mm when `heightsInMm`
    bool heightsInMm = false;  // a scene's or a measured map's; a bare float map's are as stored
    std::vector<std::string> warnings;  // the reader's
    nlohmann::json part;                // a scene: partSummaryJson (material, camera); else null
};

InfoJobSummary runInfoJob(const InfoJobOptions& options);

/// The summary as JSON (`info --json`): the fields above by their snake_case names.
nlohmann::ordered_json infoJson(const InfoJobSummary& summary);

}  // namespace sl
