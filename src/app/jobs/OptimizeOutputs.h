// The optimize job's stages 5 and 6 (app/jobs/OptimizeJob.h lists the files): one run's OUTDIR
// (summary.json, plot data, renders and previews, figures, report) and a sweep's sweep.csv and
// report.
#pragma once

#include <vector>

#include "app/jobs/OptimizeStages.h"
#include "app/report/Report.h"

namespace sl::optimizejob {

/// Stage 5: one run's files (the header of OptimizeJob.h lists them); returns its report entry.
ReportRun writeRunOutputs(const Plan& p, const Inputs& in, const OptimizeJobSummary& job,
                          const LambdaResult& r);

/// Stage 6: a sweep's sweep.csv and its report of every λ.
void writeSweep(const Plan& p, const Inputs& in, const OptimizeJobSummary& job,
                const std::vector<ReportRun>& reportRuns);

}  // namespace sl::optimizejob
