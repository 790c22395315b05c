// `scratchlight bench scratchmap`: seconds of the paper's scratch map (detect/ScratchMap.h)
// on synthetic N×N height maps (a sine of tool marks along x, a slight tilt along y and one
// deep "scratch" sample at the centre), median over repeats.
#pragma once

#include <string>
#include <vector>

#include "detect/ScratchMap.h"

namespace sl {

struct ScratchMapBenchOptions {
    std::vector<int> sizes{1024, 5000};
    ScratchMapOptions map;  // kernel, patch, threshold (the paper's by default)
    int repeats = 3;
};

struct ScratchMapBenchRow {
    int size = 0;
    double seconds = 0;  // median of computeScratchMap's own timing
    int patches = 0, patchesMarked = 0;
    double markedFraction = 0;
};

struct ScratchMapBenchResult {
    ScratchMapBenchOptions options;
    std::vector<ScratchMapBenchRow> rows;
    std::string csv() const;  // header + one line per size
};

/// The synthetic N×N map: 0.01·sin(0.157·column) + 1e-5·row, minus 0.05 at the centre sample.
std::vector<float> scratchMapBenchHeights(int n);

/// Runs the benchmark. Throws InputError for a bad size or option.
ScratchMapBenchResult runScratchMapBench(const ScratchMapBenchOptions& options);

}  // namespace sl
