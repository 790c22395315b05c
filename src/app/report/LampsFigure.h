// The `lamps` job's figure, plot-lamps.png, drawn in-process (app/host/Canvas.h) with the
// content scripts/plot_lamps.py draws from OUTDIR/plot-lamps.json (the script stays for a
// person who runs it by hand): two polar plots of the upper hemisphere seen from above (zenith
// at the centre, the horizon at the rim, azimuth 0° toward −z at the top, clockwise: the
// env-map plots' convention, app/report/OptimizeFigures.h), E* with each lamp's outline and
// number, and the lamps' own env map, both on E*'s colour scale with a colour bar each.
// No Python start: the figure cost ~1 s of CPU (4–7 s wall on a loaded machine) of every run.
#pragma once

#include <span>
#include <vector>

#include "app/host/Canvas.h"
#include "app/report/OptimizeFigures.h"
#include "scene/Lamp.h"

namespace sl {

/// Points (azimuth, elevation in degrees, the plots' convention) around a lamp's edge at its
/// sharp size (scene/Lamp.h): one closed curve for a disk or bar, two circles (the band's upper
/// and lower edges, clamped to ±90°) for a ring.
std::vector<std::vector<PlotDirection>> lampOutline(const Lamp& lamp);

/// Where lampsFigure draws E*'s panel, the one with the outlines (pixels): the zenith and the
/// horizon's radius; the lamps' own panel is the same 520 pixels to the right.
inline constexpr Point kLampsFigureCentre{265, 290};
inline constexpr double kLampsFigureRadius = 150;

/// The figure. target and lamps: E* and the lamps' env map on one grid (as EnvMapPlot);
/// throws std::invalid_argument as envMapFigure does for a plot it cannot draw.
Canvas lampsFigure(const EnvMapPlot& target, const EnvMapPlot& lampsEnvMap,
                   std::span<const Lamp> lamps);

}  // namespace sl
