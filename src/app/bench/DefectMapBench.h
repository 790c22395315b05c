// `scratchlight bench defectmap`: seconds of the defect map (detect/DefectMap.h, method auto)
// next to the paper's scratch map (detect/ScratchMap.h) on the same N×N height map in the
// same run: the ball-end test part (synth/SurfaceGenerator.h testPartSpec, every defect kind) at
// N×N samples of 0.01 mm, seed 1. Medians over repeats, the two methods interleaved.
#pragma once

#include <string>
#include <vector>

#include "detect/DefectMap.h"

namespace sl {

struct DefectMapBenchOptions {
    std::vector<int> sizes{1024, 5000};
    DefectMapOptions map;  // the auto method's options (method is forced to auto)
    int repeats = 3;
};

struct DefectMapBenchRow {
    int size = 0;
    double secondsAuto = 0;                  // median of detectDefects' own timing
    double secondsPaper = 0;                 // median of computeScratchMap's own timing
    double ratio = 0;                        // secondsAuto / secondsPaper
    double markedAuto = 0, markedPaper = 0;  // fractions of the map
    double precision = 0, recall = 0;        // auto against the part's truth (128 negative)
};

struct DefectMapBenchResult {
    DefectMapBenchOptions options;
    std::vector<DefectMapBenchRow> rows;
    std::string csv() const;  // header + one line per size
};

/// Runs the benchmark. Throws InputError for a bad size or option.
DefectMapBenchResult runDefectMapBench(const DefectMapBenchOptions& options);

}  // namespace sl
