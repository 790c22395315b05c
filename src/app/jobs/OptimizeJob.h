// The `optimize` job: T (traced or cached, or read from a .tm), the objective on a mask, one
// optimization per λ, and the outputs a person looks at.
//
// OUTDIR (or OUTDIR/lambda-<λ>/ per λ of a sweep) holds:
//   envmap.exr   the optimized E on the env-map grid (data)      envmap.png  enlarged preview
//   render.exr   T·E* (luminance, or RGB with an RGB T)          render.png  its sRGB preview
//   initial.png  T·E0 under the initial env map
//   loss.csv     iteration, evaluations, loss, L_grad, L_reg, seconds, and every few iterations
//                the held-out score (own objective and the paper's eq. 2)
//   summary.json optimizer, lambda, iterations, initial/final loss and parts, timings, T's facts,
//                held-out scores, visibility metrics (final and initial)
//   report.html  one self-contained page for the inspector (app/report/OptimizeReport.h
//                renderOptimizeReportHtml): (1) a headline in words, how much better E* shows
//                the defects than the user's lamp and the paper's light, with the judge's
//                numbers; (2) full-size renders under the lamp and E* with an A/B slider, the
//                defect regions outlined and 4× crops; (3) the env map as a plot with axes;
//                (4) the loss on a log axis with the held-out loss; (5) the three lights' metrics
//   initial-envmap.png, mask.png (the loss mask), scratchmap.png (with the scratch mask),
//   regions.png (objective defects: the render with the defect region outlined red and a given
//   reference region blue), regions-defects.png and regions-reference.png (the same regions as
//   masks, app/pipeline/Truth.h writeDefectRegions: what the viewer optimizes and judges with)
// The comparisons (summary.json "compare": lamp, paper, optimized; each with its training loss
// and, with the held-out estimate, the judge's scores):
//   compare-lamp.{exr,png}    T·E under the user's lamp (--compare ENV; default: studio preset)
//   compare-paper.{exr,png}   T·E under the paper's light: the paper's method (eq. 2, λ 30, Adam
//                             lr 0.02 × 100 from E0 = 0.5) run on this T; compare-paper-envmap.exr
//   view-lamp.png, view-optimized.png, view-paper.png  the same, each exposed on its own
//   view-regions.png          the defect regions' outlines (truth, else the defects objective's
//                             region, else a drawn loss mask) on a transparent layer
//   plot-data.json            the lights' texel luminances and the grid's directions
//   plot-envmap.png, plot-loss.png, overview.png  the report's figures, drawn in-process
//                             (app/report/OptimizeFigures.h; absent with figures off, and the
//                             report says why); scripts/plot_optimize.py redraws them from the
//                             files
// A sweep also writes OUTDIR/sweep.csv (one row per λ).
//
// OUTDIR is checked before any work and replaced as a unit (io/StagedDirectory.h): a failure
// leaves the previous results untouched, and so does an interrupt (core/Interrupt.h): it stops
// the running optimizer at its next iteration (tracing at its next row) and nothing is written.
// With `keepInterrupted` (--keep-interrupted) the optimizer's best iterate so far is written
// instead, with "interrupted": true, replacing OUTDIR, and the λs after it are not run.
#pragma once

#include "app/jobs/OptimizeOptions.h"

namespace sl {

/// The job (its stages: app/jobs/OptimizePlan.h, OptimizeStages.h, OptimizeOutputs.h).
OptimizeJobSummary runOptimizeJob(const OptimizeJobOptions& options);

}  // namespace sl
