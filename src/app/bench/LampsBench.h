// `scratchlight bench lamps`: K physical lamps against the unconstrained E* on the judge's parts
// (the bundled part and the race's generated parts), for each objective, and the fit's seconds
// with the products over the lamps' texels only (transport/TransportColumns.h) against the
// products over all of T, measured one after the other in the same run on the same T and E*.
//
// Every run is the `lamps` job (app/jobs/LampsJob.h) at the parts' 256² view: E* optimized on T,
// lamps fitted greedily, both scored by the judge's held-out estimate with the objective itself
// (eq. 2 or U, lower is better) or, for the defects objective, by the defect region's visibility
// (higher is better); gap = how much worse the lamps are, relative; and by the visibility of
// the first truth region.
// The defects objective uses each part's truth as its defect region.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "objective/ObjectiveKind.h"
#include "optimize/LampFit.h"

namespace sl {

struct LampsBenchOptions {
    /// "bundled" (scenes/default) and race parts (app/bench/Race.h raceParts).
    std::vector<std::string> parts{"bundled", "ballend-chatter", "facemill-scratches", "pocket"};
    std::vector<ObjectiveKind> objectives{ObjectiveKind::Unbiased, ObjectiveKind::Paper,
                                          ObjectiveKind::Defects};
    int count = 3;  // K
    int size = 256;
    std::filesystem::path workDir = "out/bench-lamps";
};

struct LampsBenchRow {
    std::string part;
    ObjectiveKind objective = ObjectiveKind::Unbiased;
    double secondsTarget = 0;            // E* on T
    double secondsRows = 0;              // the fit, products over all of T (baseline)
    double secondsColumns = 0;           // the fit, products over the lamps' texels
    double speedup = 0;                  // secondsRows / secondsColumns
    double cpuRows = 0, cpuColumns = 0;  // the same fits' CPU seconds (all threads)
    double trainRatio = 0;               // the lamps' training loss over E*'s
    std::string measure;                 // the judge's measure for the objective (app/jobs/LampsJob.h)
    double judgeTarget = 0, judgeLamps = 0, judgeStudio = 0, gap = 0;
    std::string region;  // the first truth label the visibilities are of
    double visTarget = 0, visLamps = 0, visStudio = 0;
};

struct LampsBenchResult {
    std::vector<LampsBenchRow> rows;
    std::string csv() const;
    std::string table() const;
};

LampsBenchResult runLampsBench(const LampsBenchOptions& options);

}  // namespace sl
