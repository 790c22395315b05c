// report.html of `optimize`: its own page for one run (renderOptimizeReportHtml), built for the
// inspector (app/report/Report.h is the figures page of `report`, `judge` and a sweep), in five
// sections: #headline (in words: how many times as visible the defects are under E* as under the
// user's lamp and the paper's light, by the judge; said plainly when it is not better), #renders
// (full-size renders under the lamp and E*, an A/B slider, the defect regions' outline, 4× crops
// where clicked), #envmap (matplotlib's lat-long and hemisphere plots), #loss (log axis, held-out
// loss), #metrics (the three lights side by side). It is one file with one inline script, which
// also fills <pre id="selfcheck"> on load for scripts/check-report --selfcheck (headless Chromium).
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

namespace sl {

/// optimize's own page for one OUTDIR (or one λ of a sweep), built for the inspector: a
/// headline in words (docs/DESIGN.md "The optimize report"), full-size before/after renders with
/// an A/B slider, a 1:1 crop and the defect outline, the env map as a plot with axes, the loss
/// curve, and the metrics of the lamp, the paper's light and E* side by side. Reads the files
/// app/jobs/OptimizeJob.h lists; `figureProblem`: why the matplotlib figures were not made ("" =
/// they were; a missing figure file is then named instead). Throws InputError naming a bad file.
std::string renderOptimizeReportHtml(const std::filesystem::path& outDir,
                                     const std::string& figureProblem = "");

/// The headline sentence of an optimize summary.json (its "compare" section): how much better
/// (or not) E* is than the user's lamp and the paper's light, with the numbers behind it.
std::string optimizeHeadline(const nlohmann::json& summary);
/// The same from an optimize OUTDIR (its summary.json; InputError when missing or malformed).
std::string optimizeHeadlineOf(const std::filesystem::path& outDir);

/// One sentence on the part from a summary's "heightmap" object (io/SceneFile.h
/// heightmapLoadJson): file, reader, grid and pitch, resampling, invalid points, levelling.
std::string heightmapSentence(const nlohmann::json& heightmap);

}  // namespace sl
