// `scratchlight bench defectmap`: seconds of the defect map (detect/DefectMap.h, method auto)
// next to the paper's scratch map (detect/ScratchMap.h) on the same N×N height map in the
// same run: the ball-end test part (synth/SurfaceGenerator.h testPartSpec, every defect kind) at
// N×N samples of 0.01 mm, seed 1. Auto runs twice: on the part as a simulator's map (the
// tool-path model) and on the same heights read as a measured texture (DefectMapOptions::
// measured: the selfsim method, what an instrument file runs). Medians over repeats, the
// methods interleaved.
#pragma once

#include <string>
#include <vector>

#include "detect/DefectMap.h"

namespace sl {

struct DefectMapBenchOptions {
    std::vector<int> sizes{1024, 5000};
    DefectMapOptions map;  // the auto method's options (method forced to auto, measured set
                           // for the measured column)
    bool measured = true;  // also time auto on the heights read as a measured texture
    int repeats = 3;
};

struct DefectMapBenchRow {
    int size = 0;
    double secondsAuto = 0;      // median of detectDefects' own timing
    double secondsMeasured = 0;  // ... of auto on the heights read as measured
    double secondsPaper = 0;     // median of computeScratchMap's own timing
    double ratio = 0;            // secondsAuto / secondsPaper
    double ratioMeasured = 0;    // secondsMeasured / secondsPaper
    double markedAuto = 0, markedMeasured = 0, markedPaper = 0;  // fractions of the map
    double precision = 0, recall = 0;  // auto against the part's truth (128 negative)
    double precisionMeasured = 0, recallMeasured = 0;  // ... read as measured (selfsim)
};

struct DefectMapBenchResult {
    DefectMapBenchOptions options;
    std::vector<DefectMapBenchRow> rows;
    std::string csv() const;  // header + one line per size
};

/// Runs the benchmark. Throws InputError for a bad size or option.
DefectMapBenchResult runDefectMapBench(const DefectMapBenchOptions& options);

}  // namespace sl
