// The OUTDIR contract: what `optimize -o OUTDIR` writes that others read, written once. The
// writer (app/jobs/OptimizeOutputs.cpp, the figures app/report/OptimizeFigures.cpp) names its files
// by these constants, and its readers read through them: the viewer (app/viewer/ViewerSession.cpp:
// the objective that made the output, T, the lights), the report (app/report/Report.cpp: a run's
// pictures, loss and metrics; OptimizeReport.cpp: optimize's page), both reading summary.json
// through its typed reader (io/OptimizeSummary.h), judge (an OUTDIR as a light: its envmap.exr) and
// the plot scripts (scripts/plot_optimize.py, scripts/plot_before_after.py), which cannot include
// this header: the names they open and the summary keys they read are listed in
// optimizeOutDirFiles() and optimizeSummaryKeys(), and README's "What you get" table documents
// every file listed (tests/test_outdir.cpp checks that optimize writes what the tables say, that
// the scripts read nothing the tables do not list, and that README names every file).
#pragma once

#include <span>

namespace sl::outdir {

inline constexpr const char* kSummary = "summary.json";
inline constexpr const char* kReport = "report.html";
inline constexpr const char* kEnvMap = "envmap.exr";
inline constexpr const char* kEnvMapPng = "envmap.png";
inline constexpr const char* kRender = "render.exr";
inline constexpr const char* kRenderPng = "render.png";
inline constexpr const char* kInitialPng = "initial.png";
inline constexpr const char* kInitialEnvMapPng = "initial-envmap.png";
inline constexpr const char* kLossCsv = "loss.csv";
inline constexpr const char* kMaskPng = "mask.png";
inline constexpr const char* kScratchMapPng = "scratchmap.png";
inline constexpr const char* kRegionsPng = "regions.png";
inline constexpr const char* kRegionsDefects = "regions-defects.png";
inline constexpr const char* kRegionsReference = "regions-reference.png";
inline constexpr const char* kCompareLamp = "compare-lamp.exr";
inline constexpr const char* kCompareLampPng = "compare-lamp.png";
inline constexpr const char* kLampEnvMap = "compare-lamp-envmap.exr";  // the lamp as T's E
inline constexpr const char* kComparePaper = "compare-paper.exr";
inline constexpr const char* kComparePaperPng = "compare-paper.png";
inline constexpr const char* kPaperEnvMap = "compare-paper-envmap.exr";
inline constexpr const char* kViewLamp = "view-lamp.png";
inline constexpr const char* kViewOptimized = "view-optimized.png";
inline constexpr const char* kViewPaper = "view-paper.png";
inline constexpr const char* kViewRegions = "view-regions.png";
inline constexpr const char* kPlotData = "plot-data.json";
inline constexpr const char* kPlotEnvMap = "plot-envmap.png";
inline constexpr const char* kPlotLoss = "plot-loss.png";
inline constexpr const char* kOverview = "overview.png";
// When a reference beat E* on validation (the answer is the reference; E* beside it).
inline constexpr const char* kEnvMapOptimized = "envmap-optimized.exr";
inline constexpr const char* kEnvMapOptimizedPng = "envmap-optimized.png";
inline constexpr const char* kRenderOptimized = "render-optimized.exr";
inline constexpr const char* kRenderOptimizedPng = "render-optimized.png";

/// When a file is written.
enum class Written {
    Always,            // every run (one λ; a sweep: every lambda-<λ>/ folder)
    Figures,           // with the figures on (the default)
    DefectsObjective,  // the defects objective
    Reference,         // the defects objective with a reference region given
    ScratchMask,       // the scratch loss mask
    Regions,           // regions to outline: a truth, the defects objective's or a drawn mask
    ReferenceWon,      // a reference beat E* on validation and is the answer
};

struct OutDirFile {
    const char* name;
    Written when;
    const char* readers;  // who reads it besides a person
};
/// Every file of the contract, in README's order.
std::span<const OutDirFile> optimizeOutDirFiles();

/// A key of summary.json that a reader uses, as a JSON pointer ("/compare/judge_spp").
struct SummaryKey {
    const char* pointer;
    bool always;  // written by every run (else: with the judge's estimate, or a given truth)
    const char* readers;
    bool referenceWon = false;  // written only when a reference is the answer (ReferenceWon)
};
std::span<const SummaryKey> optimizeSummaryKeys();

}  // namespace sl::outdir
