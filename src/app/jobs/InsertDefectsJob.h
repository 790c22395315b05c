// `scratchlight insert-defects`: defects of known shape (synth/DefectInsert.h) inserted into any
// height map or a scene's height map, written as gen-surface writes a part (app/jobs/PartFiles.h):
// OUT.exr (float32 heights, mm), OUT-truth.png (labels, height-map space), OUT-truth.json (the
// legend, plus "inserted": every defect with its kind, depth, box and whether it is labelled,
// and "texture": the input's Sq and the depths used) and a scene file OUT.json that renders it
// with its pitch, so optimize --truth, defectmap --truth and judge --truth take them.
//
// Depth: `depthSq` × the texture's Sq (synth/DefectInsert.h textureSq: about its quadratic
// form) or `depthUm` µm; the faint defects (unlabelled, below what any light shows) at
// `faintSq` × Sq. The map is optionally resampled first to `size` samples on its longer side
// (box average; the pitch grows by the same factor).
//
// Order: the input is read and checked and every array is computed before the first file is
// written; each file is written atomically.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "synth/DefectInsert.h"

namespace sl {

struct InsertDefectsJobOptions {
    std::filesystem::path input;                   // height map or scene file (.json)
    std::vector<std::string> sceneOverrides;       // -D key=value on the scene
    std::filesystem::path output = "defects.exr";  // must end in .exr
    InsertSpec spec;                               // model, kinds, count, faint, seed, ...
    double depthSq = 3.0;                          // depth = depthSq × Sq, unless depthUm > 0
    double depthUm = 0;                            // absolute depth, µm (> 0 overrides depthSq)
    double faintSq = 0.03;                         // faint defects' depth, × Sq
    int size = 0;       // resample to this many samples on the longer side (0: as read)
    double pitch = 0;   // mm, for a bare map that carries none (EXR, PNG, ...)
    int imageSize = 0;  // the scene file's camera width = height (0: the scene default)
};

struct InsertDefectsJobSummary {
    int width = 0, height = 0;         // written
    double pitch = 0;                  // mm, written
    double resampled = 1;              // old size / new size
    double sq = 0;                     // the texture's Sq (mm), after resampling
    double depth = 0, faintDepth = 0;  // mm
    InsertResult result;
    std::vector<std::filesystem::path> written;
};

InsertDefectsJobSummary runInsertDefectsJob(const InsertDefectsJobOptions& options);

}  // namespace sl
