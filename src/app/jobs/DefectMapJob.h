// `scratchlight defectmap`: the defect map of a height map or a scene's height map
// (detect/DefectMap.h), written in height-map space and, for a scene, projected into its
// camera's image (objective/ImageSpace.h, as the truth masks are); scored against a truth
// label mask (gen-surface's <stem>-truth.png) per kind when one is given.
//
// Order: every input is read and checked (height map or scene, truth and its legend) and the
// map, its projection and its score are computed before the first file is written; each file
// is written atomically (io/AtomicFile.h), so bad input leaves no output behind.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "detect/DefectMap.h"

namespace sl {

struct DefectMapJobOptions {
    std::filesystem::path input;  // height map (EXR/TIFF/PNG/.npy) or scene file (.json)
    std::vector<std::string> sceneOverrides;         // -D key=value on the scene (io/SceneFile.h)
    std::filesystem::path output = "defectmap.png";  // height-map-space mask, 255/0 PNG
    std::filesystem::path imageOutput;  // projected mask (PNG); needs a scene; empty: none
    std::filesystem::path truth;        // truth label PNG in height-map space; empty: no score
    std::filesystem::path csv;          // the score's CSV; empty: <output stem>-score.csv
    // where the map could not judge (DefectMap::unjudged, 255 / 128 / 0 PNG in height-map
    // space), written when the method in force records it (selfsim, and auto on a measured
    // texture); empty: <output stem>-unjudged.png
    std::filesystem::path unjudgedOutput;
    // a picture of the map (app/report/Preview.h defectMapPreview: the hill-shaded heights, the
    // marks outlined red, where it could not judge blue); empty: <output stem>-preview.png
    std::filesystem::path previewOutput;
    // Truth values counted as defect-free when scoring (a mark there is a false positive):
    // the confined chatter region (128), a texture change the map is not meant to mark.
    std::vector<uint8_t> negatives{128};
    DefectMapOptions map;
};

struct DefectMapJobSummary {
    int width = 0, height = 0;  // height map
    DefectMap map;
    std::optional<DefectScore> score;
    int imageWidth = 0, imageHeight = 0;  // with imageOutput
    size_t imageMarked = 0, imagePartPixels = 0;
    std::vector<std::filesystem::path> written;
    double seconds = 0;  // whole job
};

/// Runs the job. Throws InputError naming the file or option for bad input.
DefectMapJobSummary runDefectMapJob(const DefectMapJobOptions& options);

/// kind,value,truth,hits,marked,precision,recall,f1 (the overall row first, named "all").
std::string defectScoreCsv(const DefectScore& score);

}  // namespace sl
