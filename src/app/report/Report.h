// report.html: one self-contained page (no external file, font or style: images are inline
// base64 PNG data URIs, loss curves inline SVG drawn here) that shows runs side by side.
//
// Structure: ReportContent = title, notes, global settings, and figures; a figure = title,
// caption and runs shown side by side, then a metrics table and a settings table (one column per
// run) and, if asked, all its runs' loss curves in one plot (the paper's Fig. 8). A run = title,
// images (before/after renders, env map, ...), an optional loss curve, metrics and settings
// (JSON objects, nested objects flattened to "a.b" rows; null shown as "—").
//
// `scratchlight report` assembles many OUTDIRs into figures (scripts/reproduce-paper), and a
// λ sweep's OUTDIR/report.html shows its runs so (reportRunFromOutDir); `judge` uses it too.
//
// `optimize`'s own page for one run (renderOptimizeReportHtml) is built for the inspector
// instead, in five sections: #headline (in words: how many times as visible the defects are
// under E* as under the user's lamp and the paper's light, by the judge; said plainly when it is
// not better), #renders (full-size renders under the lamp and E*, an A/B slider, the defect
// regions' outline, 4× crops where clicked), #envmap (matplotlib's lat-long and hemisphere
// plots), #loss (log axis, held-out loss), #metrics (the three lights side by side). It is one
// file with one inline script, which also fills <pre id="selfcheck"> on load for
// scripts/check-report --selfcheck (headless Chromium).
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace sl {

struct ReportImage {
    std::string caption;
    std::filesystem::path png;  // read as bytes and inlined; a missing file is an error
};

struct LossSeries {
    std::string label;
    std::vector<double> iteration, loss;
};

struct ReportRun {
    std::string title;
    std::string caption;
    std::vector<ReportImage> images;
    LossSeries loss;          // empty: no curve
    nlohmann::json metrics;   // object (or null)
    nlohmann::json settings;  // object (or null)
};

struct ReportFigure {
    std::string title, caption;
    std::vector<ReportRun> runs;
    bool combinedLossPlot = false;  // one plot with every run's loss curve
};

struct ReportContent {
    std::string title = "scratchlight report";
    std::vector<std::string> notes;  // paragraphs under the title
    nlohmann::json settings;         // global settings (object or null)
    std::vector<ReportFigure> figures;
};

/// Which state of an optimize OUTDIR a run shows.
enum class RunState {
    Final,   // render.png (after), initial.png (before), envmap.png; summary "metrics"
    Initial  // initial.png and initial-envmap.png if present; summary "metrics_initial"
};

/// A run from an `optimize` OUTDIR: summary.json (settings: its scalar fields; metrics: its
/// "metrics" object (or "metrics_initial") plus initial/final loss), loss.csv (columns
/// "iteration" and "loss"), and the PNGs that exist (initial.png, render.png, envmap.png,
/// initial-envmap.png, scratchmap.png, mask.png). Throws InputError naming the file when
/// summary.json is missing or malformed.
ReportRun reportRunFromOutDir(const std::filesystem::path& outDir, const std::string& title = "",
                              RunState state = RunState::Final);

/// optimize's own page for one OUTDIR (or one λ of a sweep), built for the inspector: a
/// headline in words (docs/DESIGN.md "The optimize report"), full-size before/after renders with
/// an A/B slider, a 1:1 crop and the defect outline, the env map as a plot with axes, the loss
/// curve, and the metrics of the lamp, the paper's light and E* side by side. Reads the files
/// OptimizeJob.h lists; `figureProblem`: why the matplotlib figures were not made ("" = they
/// were; a missing figure file is then named instead). Throws InputError naming a bad file.
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

/// Reads a loss.csv (header with "iteration" and "loss" columns). Throws InputError.
LossSeries readLossCsv(const std::filesystem::path& file);

/// The page as a string (images read from disk). Throws InputError naming a missing image.
std::string renderReportHtml(const ReportContent& content);

/// renderReportHtml written atomically to `path`.
void writeReport(const std::filesystem::path& path, const ReportContent& content);

/// A report from a figures spec (JSON; `scratchlight report --help` shows its form): runs by
/// optimize OUTDIR or by images, paths relative to the spec's folder. Throws InputError naming
/// the spec file and the entry.
ReportContent readReportSpec(const std::filesystem::path& specFile);

/// Inline SVG of loss curves (linear y; log y when all losses > 0 and span > 100×).
std::string lossCurveSvg(const std::vector<LossSeries>& series, int width = 420, int height = 260);

/// RFC 4648 base64 of bytes.
std::string base64Encode(const std::string& bytes);

/// A PNG file as a data URI (data:image/png;base64,...) for a self-contained page. Throws
/// InputError naming a file that cannot be read.
std::string dataUri(const std::filesystem::path& png);

}  // namespace sl
