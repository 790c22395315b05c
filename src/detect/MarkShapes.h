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
// Within each shape, a mark more than kLargeMarkFactor times the area of the shape's median mark
// is labelled apart, as a large line or a large spot. The objective and the judge pool a label's
// pixel pairs, so a mark weighs by its area: one crater of 18 000 samples among pits of 250-3 000
// (the NanoFocus B's own, with the inserted pits beside it) makes the spots' score the crater's,
// and a light may then give the pits up without the softmin seeing it. Labelled apart, each size
// is a kind the softmin asks to show. The factor is a ratio of areas, so it holds at any map
// resolution; 8 was set before it was measured (a mark eight times the median weighs as much as
// eight median marks) and was not tuned.
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
inline constexpr double kLargeMarkFactor = 8.0;
// The labels' values, as outlines show them (app/report/Preview.h outlineOf): red, yellow,
// orange, cyan.
inline constexpr uint8_t kMarkLine = 255;       // the label of a line-shaped mark
inline constexpr uint8_t kMarkSpot = 160;       // the label of any other mark
inline constexpr uint8_t kMarkLargeLine = 224;  // a line > kLargeMarkFactor × the median line
inline constexpr uint8_t kMarkLargeSpot = 144;  // a spot > kLargeMarkFactor × the median spot

/// Whether v is one of the labels above.
constexpr bool isMarkShapeLabel(uint8_t v) {
    return v == kMarkLine || v == kMarkSpot || v == kMarkLargeLine || v == kMarkLargeSpot;
}

/// The labels' names, as a legend (kMarkLine "lines", kMarkSpot "spots", kMarkLargeLine
/// "large lines", kMarkLargeSpot "large spots").
std::vector<RegionLabel> markShapeLegend();

/// `map` (width×height, row-major, nonzero: marked) with each mark's samples set to its label
/// by its shape and size (above), 0 elsewhere. The median of a shape's marks is the lower one
/// (of two marks, the smaller).
std::vector<uint8_t> labelMarksByShape(std::span<const uint8_t> map, int width, int height);

}  // namespace sl
