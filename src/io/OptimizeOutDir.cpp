#include "io/OptimizeOutDir.h"

namespace sl::outdir {

namespace {

constexpr const char* kPlot = "scripts/plot_optimize.py";
constexpr const char* kPlots = "scripts/plot_optimize.py, scripts/plot_before_after.py";

constexpr OutDirFile kFiles[] = {
    {kReport, Written::Always, ""},
    {kEnvMap, Written::Always, "view, judge OUTDIR"},
    {kEnvMapPng, Written::Always, "report, scripts/plot_optimize.py"},
    {kRender, Written::Always, ""},
    {kRenderPng, Written::Always, "report, scripts/plot_optimize.py"},
    {kEnvMapOptimized, Written::ReferenceWon, ""},
    {kEnvMapOptimizedPng, Written::ReferenceWon, ""},
    {kRenderOptimized, Written::ReferenceWon, ""},
    {kRenderOptimizedPng, Written::ReferenceWon, ""},
    {kCompareLamp, Written::Always, ""},
    {kCompareLampPng, Written::Always, ""},
    {kLampEnvMap, Written::Always, "view"},
    {kComparePaper, Written::Always, ""},
    {kComparePaperPng, Written::Always, ""},
    {kPaperEnvMap, Written::Always, "view"},
    {kPlotEnvMap, Written::Figures, "report"},
    {kPlotLoss, Written::Figures, "report"},
    {kOverview, Written::Figures, "report"},
    {kSummary, Written::Always,
     "view, report, scripts/plot_optimize.py, scripts/plot_before_after.py"},
    {kLossCsv, Written::Always, "report, scripts/plot_optimize.py"},
    {kRegionsPng, Written::DefectsObjective, "report"},
    {kMaskPng, Written::Always, "view, report"},
    {kInitialPng, Written::Always, "report, scripts/plot_optimize.py"},
    {kInitialEnvMapPng, Written::Always, "report"},
    {kScratchMapPng, Written::ScratchMask, "report"},
    {kRegionsDefects, Written::DefectsObjective, "view"},
    {kRegionsReference, Written::Reference, "view"},
    {kViewLamp, Written::Always, "report, scripts/plot_optimize.py, scripts/plot_before_after.py"},
    {kViewOptimized, Written::Always,
     "report, scripts/plot_optimize.py, scripts/plot_before_after.py"},
    {kViewPaper, Written::Always, "report, scripts/plot_before_after.py"},
    {kViewRegions, Written::Regions, "view, report"},
    {kPlotData, Written::Always, kPlot},
};

constexpr SummaryKey kKeys[] = {
    {"/objective", true, "view, report, scripts/plot_optimize.py"},
    {"/lambda", true, "view, report, scripts/plot_optimize.py"},
    {"/smooth_abs", true, "view"},
    {"/reg", true, "view"},
    {"/defects_measure", false, "view"},
    {"/defects", false, "view"},  // the defects objective's region as written (auto: by shape)
    {"/optimizer", true, "report, scripts/plot_optimize.py"},
    {"/transport/file", true, "view"},
    {"/truth", false, "view"},
    {"/initial_loss", true, "report, scripts/plot_optimize.py"},
    {"/final_loss", true, "report, scripts/plot_optimize.py"},
    {"/metrics", true, "report"},
    {"/metrics_initial", true, "report"},
    {"/envmap_directions", true, "report, scripts/plot_optimize.py"},
    {"/envmap_directions/brightest", true, "report, scripts/plot_optimize.py"},
    {"/envmap_directions/camera", false, "report, scripts/plot_optimize.py"},  // with a scene
    {"/envmap_directions/mirror", false, "report, scripts/plot_optimize.py"},
    {"/transport/image", true, "report"},
    {"/warnings", true, "report"},
    {"/heightmap", false, "report"},  // with a scene (not from a .tm)
    {"/heldout_loss", true, "report"},
    {"/heldout_U", false, "report"},
    // The self-check (app/pipeline/Answer.h answerJson); each candidate has this shape.
    {"/answer", false, "report"},
    {"/answer/light", false, "report"},
    {"/answer/kind", false, "report"},
    {"/answer/merit", false, "report"},
    {"/answer/candidates", false, "report"},
    {"/answer/candidates/0/name", false, "report"},
    {"/answer/candidates/0/kind", false, "report"},
    {"/answer/candidates/0/merit", false, "report"},
    {"/answer/candidates/0/eligible", false, "report"},
    {"/answer/candidates/0/why", false, "report"},
    {"/compare", true, "report, scripts/plot_optimize.py, scripts/plot_before_after.py"},
    {"/compare/objective", true, "report"},
    {"/compare/regions", true, "report"},
    {"/compare/viewing/text", false, "report"},
    {"/compare/lamp/name", true, kPlots},
    {"/compare/lamp/training/loss", true, "report"},
    {"/compare/paper/training/loss", true, "report"},
    {"/compare/optimized/training/loss", true, "report"},
    {"/compare/lamp/judge", false, "report, scripts/plot_before_after.py"},
    {"/compare/paper/judge", false, "report, scripts/plot_before_after.py"},
    {"/compare/optimized/judge", false, "report, scripts/plot_before_after.py"},
    // Each light's judge score has this shape (app/pipeline/Judge.h toJson; each region of
    // visibility: name, pixels, visibility, jnd, contrast), the answer's too.
    {"/compare/optimized/judge/unbiased", false, "report"},
    {"/compare/optimized/judge/eq2", false, "report"},
    {"/compare/optimized/judge/brightness", false, "report"},
    {"/compare/optimized/judge/mean_E", false, "report"},
    {"/compare/optimized/judge/sparsity", false, "report"},
    {"/compare/lamp/judge/visibility", false, "report, scripts/plot_before_after.py"},
    {"/compare/paper/judge/visibility", false, "report, scripts/plot_before_after.py"},
    {"/compare/optimized/judge/visibility", false, "report, scripts/plot_before_after.py"},
    {"/compare/optimized/judge/se/least_visible_jnd", false, "report"},
    {"/compare/judge_spp", false, "view, report, scripts/plot_before_after.py"},
    {"/compare/answer", false, "report", true},
    {"/compare/answer/name", false, "report", true},
    {"/compare/answer/merit", false, "report", true},
    {"/compare/answer/merit_answer", false, "report", true},
    {"/compare/answer/merit_optimized", false, "report", true},
    {"/compare/answer/optimized_why", false, "report", true},
    {"/compare/answer/judge", false, "report", true},
};

}  // namespace

std::span<const OutDirFile> optimizeOutDirFiles() {
    return kFiles;
}

std::span<const SummaryKey> optimizeSummaryKeys() {
    return kKeys;
}

}  // namespace sl::outdir
