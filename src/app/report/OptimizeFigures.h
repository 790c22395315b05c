// The report's three figures of one optimize run, drawn in-process (app/host/Canvas.h) from what
// the run holds, with the content scripts/plot_optimize.py draws from an OUTDIR's files (the script
// stays for a person who runs it by hand):
//   plot-envmap.png  E* as a lat-long plot (azimuth 0..360° on x, elevation −90..90° on y, the
//                    horizon, the camera and mirror directions, the brightest directions
//                    labelled, a colour bar) beside a polar plot of the upper hemisphere seen
//                    from above (0° = −z at the top, clockwise)
//   plot-loss.png    the training loss on a log axis (linear when a value is ≤ 0) with the
//                    held-out loss
//   overview.png     the renders under your lamp and under E*, the lat-long plot and the loss
// Directions are given as the plot shows them (azimuth u·360°, elevation 90° − v·180°, u and v
// of scene/EnvMapBasis.h); nothing here restates the convention. The same input gives the same
// PNG bytes.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "app/host/Canvas.h"
#include "core/Image.h"

namespace sl {

/// A light on the env-map grid as the plots show it: a luminance per texel (row-major, row 0
/// at the top: elevation 90°), each column's azimuth and each row's elevation in degrees.
struct EnvMapPlot {
    int width = 0, height = 0;
    std::vector<double> azimuthDeg;    // width values, increasing in [0, 360]
    std::vector<double> elevationDeg;  // height values, decreasing in [−90, 90]
    std::vector<double> luminance;     // width × height values ≥ 0
};

struct PlotDirection {
    double azimuthDeg = 0, elevationDeg = 0;
};

/// What the env-map plots mark: toward the camera, the mirror direction, the brightest peaks.
struct PlotDirections {
    std::optional<PlotDirection> camera, mirror;
    std::vector<PlotDirection> brightest;  // brightest first, labelled 1, 2, ...
};

/// The loss curve: the training loss per iteration and, at some iterations, the held-out loss.
struct LossCurve {
    std::vector<double> iteration, loss;
    std::vector<double> heldIteration, held;
};

struct OptimizeFiguresInput {
    EnvMapPlot envmap;
    PlotDirections directions;
    LossCurve loss;
    std::string lossTitle;  // e.g. "lbfgs on unbiased, λ = 30"
    std::string title;      // the overview's, e.g. "scratchlight optimize: loss 9.99 → 6.08"
    std::string lampTitle;  // e.g. "your lamp (studio preset)"
    Image lampView, optimizedView;  // the renders as the report shows them (exposed, linear)
};

/// Each figure alone. Throws std::invalid_argument naming what is wrong for input it cannot
/// draw: an env map whose sizes disagree, a negative or non-finite luminance, unsorted
/// azimuths or elevations, an empty loss curve or one whose lengths disagree, an empty render.
Canvas envMapFigure(const EnvMapPlot& envmap, const PlotDirections& directions);
Canvas lossFigure(const LossCurve& loss, const std::string& title);
Canvas overviewFigure(const OptimizeFiguresInput& in);

/// envMapFigure's polar panel alone, for other figures (the lamps' plot): the upper hemisphere of
/// `envmap` seen from above, zenith at `centre`, the horizon on the circle of `radius`,
/// colours over [0, vmax] (vmax ≤ 0: the light's own maximum), `title` above it; and where a
/// direction lies on it.
void drawEnvMapHemisphere(Canvas& c, const EnvMapPlot& envmap, Point centre, double radius,
                          double vmax, const std::string& title);
Point hemispherePoint(Point centre, double radius, double azimuthDeg, double elevationDeg);
/// The figures' colour bar of [0, vmax] in (x, y, w, h), labelled "E (luminance)".
void drawEnvMapColourBar(Canvas& c, double vmax, double x, double y, double w, double h);

/// Writes plot-envmap.png, plot-loss.png and overview.png into `dir` (each atomically) and
/// returns their paths; throws as above (nothing written then) or when a file cannot be written.
std::vector<std::filesystem::path> writeOptimizeFigures(const std::filesystem::path& dir,
                                                        const OptimizeFiguresInput& in);

}  // namespace sl
