// The defect map's marks told apart by their shape, so that whatever uses them as regions
// (the defects objective's labels, the judge's scores, the report's outlines) can ask for each
// kind to show, not for the marks pooled.
//
// A mark is an 8-connected set of marked samples. Its elongation is Extent's (detect/Extent.h:
// the square root of its coordinates' covariance eigenvalues' ratio). A mark at least
// kLineElongation times as long as it is wide is a line (a scratch, a gouge, a burr, a tool
// mark that broke off), any other a spot (a pit, a dent, a particle). Under a light the two
// differ: a line shows only where the light crosses it, a spot shows under most lights, so a
// light that pools them can buy the lines' visibility with the spots' disappearance (or the
// reverse). The defects objective's softmin over labels (objective/DefectObjective.h) then
// works on the kind that shows least, as it does on a truth's labels.
//
// kLineElongation = 3 was read off the map's marks of the DEV insertion seed 101 (scripts/
// eval-real, both defect models, the five measured textures): the inserted scratches, gouges
// and burrs were marked with elongation 3.6-26 (10th-90th percentile), the pits, dents and pit
// chains with 1.0-1.7.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "core/RegionLabel.h"

namespace sl {

inline constexpr double kLineElongation = 3.0;
// The labels' values, as outlines show them (app/report/Preview.h outlineOf): red, yellow.
inline constexpr uint8_t kMarkLine = 255;  // the label of a line-shaped mark
inline constexpr uint8_t kMarkSpot = 160;  // the label of any other mark

/// The labels' names, as a legend (kMarkLine "lines", kMarkSpot "spots").
std::vector<RegionLabel> markShapeLegend();

/// `map` (width×height, row-major, nonzero: marked) with each mark's samples set to kMarkLine
/// or kMarkSpot by its shape, 0 elsewhere.
std::vector<uint8_t> labelMarksByShape(std::span<const uint8_t> map, int width, int height);

}  // namespace sl
