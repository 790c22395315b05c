// Masks drawn in height-map space, read and projected into a scene's image through each
// pixel's centre ray (objective/ImageSpace.h): the truth masks of optimize and the judge.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/RegionLabel.h"
#include "io/MaskIO.h"
#include "io/OptimizeOutDir.h"

namespace sl {

struct Scene;

/// loadHeightMapMask (e.g. gen-surface's <stem>-truth.png) projected into the image (255/0).
std::vector<uint8_t> projectMaskFile(const Scene& scene, const std::filesystem::path& file,
                                     int threads = 0);

/// readLabelMask projected into the image: the labels keep their values, the legend its names.
LabelMask projectTruth(const Scene& scene, const std::filesystem::path& truth, int threads = 0);

/// How a region names the defect map of the scene's own height map (RegionSpec::automatic).
inline constexpr std::string_view kAutoRegion = "auto";

/// A region drawn in height-map space, given as "FILE" (a mask: nonzero inside) or
/// "auto" (the defect map of the scene's own height map, found without labels:
/// detect/DefectMap.h with its default method and options), or
/// "FILE:LABEL[,LABEL...]" (the pixels of a truth label file, e.g. gen-surface's
/// part-truth.png, whose label is one of those listed: by legend name or by value; 0 or
/// "none" is the unlabelled surface). With labels, FILE is read with its legend
/// (readLabelMask). How `optimize --objective defects` takes its regions, and so the
/// region-comparison mode: region A (e.g. "part-truth.png:chatter") against region B (e.g.
/// "part-truth.png:none").
struct RegionSpec {
    std::filesystem::path file;       // empty: no region given
    std::vector<std::string> labels;  // empty: the whole mask
    bool automatic = false;           // "auto": the scene's defect map (detect/DefectMap.h)
    bool empty() const { return file.empty() && !automatic; }
    std::string text() const;  // as it was written
};

/// Parses a RegionSpec ("" gives an empty one). Only splits at the last ':' when what follows
/// is a list of labels and FILE has an image extension, so other paths are left whole. Throws
/// InputError naming `optionName` for an empty label list.
RegionSpec parseRegionSpec(std::string_view text, std::string_view optionName);

/// The region in height-map space (255/0): the mask, the pixels whose label is listed, or (auto)
/// the defect map of `heights` (mapWidth×mapHeight; needed only for auto). Throws InputError
/// naming the file for a label its legend does not have, or when the file cannot be read or has
/// the wrong size.
/// `measured`: the map is a measurement (Scene's load.measured), which auto's method follows.
std::vector<uint8_t> regionInHeightMap(const RegionSpec& region, int mapWidth, int mapHeight,
                                       std::span<const float> heights = {}, bool measured = false);

/// regionInHeightMap projected into the scene's image through the centre rays (255/0).
std::vector<uint8_t> projectRegion(const Scene& scene, const RegionSpec& region, int threads = 0);

/// The defects objective's defect region as the user named it: `defects`, else the truth (the
/// whole mask), else the defect map found without labels (auto).
RegionSpec defectRegionSpec(const RegionSpec& defects, const std::filesystem::path& truth);

/// The defects objective's two regions in the scene's image (255/0).
struct DefectRegions {
    std::vector<uint8_t> defects;
    std::vector<uint8_t> reference;  // empty: the objective's default (the part off the defects)
    // auto only: the regions the defect map could not judge (DefectMap::unjudgedRegions: they
    // stand out of the texture but reach its border, left unmarked, so they are in the
    // reference) and their share of the height map's samples
    size_t unjudgedRegions = 0;
    double unjudgedShare = 0;
};
/// defects: defectRegionSpec(defects, truth) projected (auto: each mark labelled by its shape
/// and size, detect/MarkShapes.h labelMarksByShape, so the objective asks each kind to show);
/// reference: empty when not given, auto: the part the defect map leaves unmarked and outside
/// the defects, else the region given.
/// Throws InputError when an automatic defect region marks nothing the camera sees.
DefectRegions defectRegionsInImage(const Scene& scene, const RegionSpec& defects,
                                   const std::filesystem::path& truth, const RegionSpec& reference);

/// The warning a job gives when the defect map could not judge some regions (`auto`): "" when
/// it judged everywhere. `unjudgedRegions` and `unjudgedShare` as DefectRegions holds them.
std::string unjudgedRegionsWarning(size_t unjudgedRegions, double unjudgedShare);

/// A defect region's labels as the judge scores them and the reports outline and name them.
struct JudgedDefectLabels {
    std::vector<uint8_t> labels;      // 0 outside the region
    std::vector<RegionLabel> legend;  // the labels present
};
/// `byShape` (the region is the defect map's own, `auto`): the marks' shapes as labelled
/// (detect/MarkShapes.h: lines, spots, large lines, large spots), else one region "defects"
/// (255) over every nonzero value.
JudgedDefectLabels judgedDefectLabels(std::span<const uint8_t> defects, bool byShape);

/// The defects objective's regions as an optimize output keeps them, in image space:
/// regions-defects.png (the label values, 8-bit, tagged linear) and (when not the default)
/// regions-reference.png (255/0), written losslessly, so the viewer runs the objective on the
/// regions that made the output.
inline constexpr const char* kRegionsDefectsFile = outdir::kRegionsDefects;
inline constexpr const char* kRegionsReferenceFile = outdir::kRegionsReference;
void writeDefectRegions(const std::filesystem::path& dir, const DefectRegions& regions, int width,
                        int height);
/// The regions writeDefectRegions wrote into dir (nullopt when dir has no regions-defects.png);
/// InputError naming the file when one does not fit width×height.
std::optional<DefectRegions> readDefectRegions(const std::filesystem::path& dir, int width,
                                               int height);

}  // namespace sl
