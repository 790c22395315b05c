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
// optimize's own page for one run is app/report/OptimizeReport.h.
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
