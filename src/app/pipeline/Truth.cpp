#include "app/pipeline/Truth.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <stdexcept>

#include "core/Error.h"
#include "core/Image.h"
#include "core/Text.h"
#include "detect/DefectMap.h"
#include "detect/MarkShapes.h"
#include "io/ImageIO.h"
#include "objective/ImageSpace.h"
#include "scene/Scene.h"

namespace sl {

std::vector<uint8_t> projectMaskFile(const Scene& scene, const std::filesystem::path& file,
                                     int threads) {
    const std::vector<uint8_t> m = loadHeightMapMask(file, scene.mapWidth, scene.mapHeight);
    return projectToImage(tracePrimaryHits(scene, threads), m);
}

LabelMask projectTruth(const Scene& scene, const std::filesystem::path& truth, int threads) {
    LabelMask m = readLabelMask(truth, scene.mapWidth, scene.mapHeight);
    const PrimaryHits hits = tracePrimaryHits(scene, threads);
    LabelMask out;
    out.width = hits.width;
    out.height = hits.height;
    out.legend = std::move(m.legend);
    out.labels = projectLabelsToImage(hits, m.labels);
    return out;
}

namespace {

bool hasImageExtension(const std::filesystem::path& p) {
    const std::string e = lower(p.extension().string());
    return e == ".png" || e == ".tif" || e == ".tiff" || e == ".exr" || e == ".npy";
}

std::vector<std::string> splitList(std::string_view s) {
    std::vector<std::string> out;
    size_t start = 0;
    while (start <= s.size()) {
        const size_t comma = std::min(s.find(',', start), s.size());
        out.emplace_back(s.substr(start, comma - start));
        start = comma + 1;
    }
    return out;
}

/// The defect map a region "auto" is: the default method and options, on a measured map the
/// method for measured textures (detect/DefectMap.h).
DefectMap autoDefectMap(std::span<const float> heights, int width, int height, bool measured) {
    DefectMapOptions o;
    o.measured = measured;
    return detectDefects(heights, width, height, o);
}

}  // namespace

std::string RegionSpec::text() const {
    if (automatic) return std::string(kAutoRegion);
    std::string t = file.string();
    for (size_t k = 0; k < labels.size(); ++k) {
        t += k ? "," : ":";
        t += labels[k];
    }
    return t;
}

RegionSpec parseRegionSpec(std::string_view text, std::string_view optionName) {
    RegionSpec r;
    if (text == kAutoRegion) {
        r.automatic = true;
        return r;
    }
    const size_t colon = text.rfind(':');
    if (colon != std::string_view::npos &&
        hasImageExtension(std::filesystem::path(std::string(text.substr(0, colon))))) {
        r.file = std::string(text.substr(0, colon));
        r.labels = splitList(text.substr(colon + 1));
        for (const std::string& l : r.labels)
            if (l.empty())
                throw inputError(option(std::string(optionName)) + " '" + std::string(text) + "'",
                                 "an empty label in the list after ':'",
                                 "write FILE:LABEL[,LABEL...] with legend names or values, e.g. "
                                 "part-truth.png:chatter");
        return r;
    }
    r.file = std::string(text);
    return r;
}

std::vector<uint8_t> regionInHeightMap(const RegionSpec& region, int mapWidth, int mapHeight,
                                       std::span<const float> heights, bool measured) {
    if (region.automatic) {
        if (heights.size() != static_cast<size_t>(mapWidth) * static_cast<size_t>(mapHeight))
            throw std::invalid_argument("regionInHeightMap: auto needs the height map");
        return autoDefectMap(heights, mapWidth, mapHeight, measured).map;
    }
    if (region.labels.empty()) return loadHeightMapMask(region.file, mapWidth, mapHeight);
    const LabelMask m = readLabelMask(region.file, mapWidth, mapHeight);
    bool wanted[256] = {};
    for (const std::string& l : region.labels) {
        int value = -1;
        if (std::all_of(l.begin(), l.end(), [](unsigned char c) { return std::isdigit(c); }) &&
            l.size() <= 3)
            value = std::stoi(l);
        else if (lower(l) == "none")
            value = 0;
        else
            for (const RegionLabel& r : m.legend)
                if (r.name == l) value = r.value;
        if (value < 0 || value > 255) {
            std::string names = "none (0)";
            for (const RegionLabel& r : m.legend)
                names += ", " + r.name + " (" + std::to_string(r.value) + ")";
            throw inputError(region.file.string(), "has no label '" + l + "'",
                             "Its labels are " + names);
        }
        wanted[value] = true;
    }
    std::vector<uint8_t> out(m.labels.size(), 0);
    // The labels keep their values (the defects objective scores each: objective/
    // DefectObjective.h); "none" (0) is 255 inside.
    for (size_t p = 0; p < out.size(); ++p)
        out[p] = wanted[m.labels[p]] ? (m.labels[p] ? m.labels[p] : 255) : 0;
    return out;
}

std::vector<uint8_t> projectRegion(const Scene& scene, const RegionSpec& region, int threads) {
    const std::vector<uint8_t> m = regionInHeightMap(region, scene.mapWidth, scene.mapHeight,
                                                     scene.heights, scene.load.measured);
    return projectToImage(tracePrimaryHits(scene, threads), m);
}

RegionSpec defectRegionSpec(const RegionSpec& defects, const std::filesystem::path& truth) {
    if (!defects.empty()) return defects;
    if (!truth.empty()) return RegionSpec{truth, {}, false};
    RegionSpec r;
    r.automatic = true;
    return r;
}

std::string unjudgedRegionsWarning(size_t unjudgedRegions, double unjudgedShare) {
    if (unjudgedRegions == 0) return {};
    return "the defect map could not judge " + std::to_string(unjudgedRegions) +
           (unjudgedRegions == 1 ? " region that stands" : " regions that stand") +
           " out of the texture but reach its border (" + formatNumber(100.0 * unjudgedShare, 2) +
           " % of the height map): they count as texture here, so the light was not asked to "
           "show them; look there yourself (defectmap writes them as <stem>-unjudged.png)";
}

DefectRegions defectRegionsInImage(const Scene& scene, const RegionSpec& defectSpec,
                                   const std::filesystem::path& truth,
                                   const RegionSpec& reference) {
    DefectRegions r;
    const RegionSpec defects = defectRegionSpec(defectSpec, truth);
    // The truth itself: every label, with its value.
    std::string whyNothingMarked;
    if (defectSpec.empty() && !truth.empty())
        r.defects = projectTruth(scene, truth).labels;
    else if (defects.automatic) {  // each mark labelled by its shape, as the judge scores it
        const DefectMap m =
            autoDefectMap(scene.heights, scene.mapWidth, scene.mapHeight, scene.load.measured);
        whyNothingMarked = m.whyNothingMarked();
        r.defects = projectLabelsToImage(tracePrimaryHits(scene),
                                         labelMarksByShape(m.map, scene.mapWidth, scene.mapHeight));
        r.unjudgedRegions = m.unjudgedRegions;
        if (!m.unjudged.empty())
            r.unjudgedShare =
                static_cast<double>(m.unjudgedCount()) / static_cast<double>(m.unjudged.size());
    } else
        r.defects = projectRegion(scene, defects);
    if (defects.automatic &&
        std::none_of(r.defects.begin(), r.defects.end(), [](uint8_t v) { return v != 0; }))
        throw inputError(
            option("defects") + " auto",
            "the defect map of the height map marks nothing the camera sees" +
                (whyNothingMarked.empty() ? "" : " (" + whyNothingMarked + ")"),
            "give a defect mask with " + option("defects") + " or a truth with " + option("truth"));
    if (reference.automatic) {
        // The part the defect map finds clean and that is not a defect region pixel (with the
        // defects auto too, the map is theirs: not made and traced again).
        const std::vector<uint8_t> marked =
            defects.automatic ? r.defects : projectRegion(scene, reference);
        r.reference.assign(marked.size(), 0);
        for (size_t q = 0; q < marked.size(); ++q)
            r.reference[q] = !marked[q] && !r.defects[q] ? 255 : 0;
    } else if (!reference.empty()) {
        r.reference = projectRegion(scene, reference);
    }
    return r;
}

JudgedDefectLabels judgedDefectLabels(std::span<const uint8_t> defects, bool byShape) {
    JudgedDefectLabels r;
    r.labels.assign(defects.begin(), defects.end());
    if (byShape) {
        bool present[256] = {};
        for (const uint8_t v : r.labels) present[v] = true;
        for (const RegionLabel& l : markShapeLegend())
            if (present[l.value]) r.legend.push_back(l);
    } else {
        for (uint8_t& v : r.labels) v = v ? 255 : 0;
        r.legend = {RegionLabel{255, "defects"}};
    }
    return r;
}

void writeDefectRegions(const std::filesystem::path& dir, const DefectRegions& regions, int width,
                        int height) {
    auto visible = [](const std::vector<uint8_t>& m) {
        std::vector<uint8_t> v(m.size());
        for (size_t q = 0; q < m.size(); ++q) v[q] = m[q] ? 255 : 0;
        return v;
    };
    writeMaskPng(dir / kRegionsDefectsFile, regions.defects, width, height);  // the labels
    if (!regions.reference.empty())
        writeMaskPng(dir / kRegionsReferenceFile, visible(regions.reference), width, height);
}

std::optional<DefectRegions> readDefectRegions(const std::filesystem::path& dir, int width,
                                               int height) {
    if (!std::filesystem::exists(dir / kRegionsDefectsFile)) return std::nullopt;
    DefectRegions r;
    const std::filesystem::path file = dir / kRegionsDefectsFile;
    const Image labels = readImage(file);
    if (labels.width != width || labels.height != height)
        throw inputError(file.string(),
                         "is " + std::to_string(labels.width) + "x" +
                             std::to_string(labels.height) + ", T's image " +
                             std::to_string(width) + "x" + std::to_string(height),
                         "view the output with the transport matrix it was optimized on");
    r.defects.resize(static_cast<size_t>(width) * static_cast<size_t>(height));
    for (size_t q = 0; q < r.defects.size(); ++q)  // written verbatim, tagged linear
        r.defects[q] = static_cast<uint8_t>(
            std::lround(std::clamp(labels.data[q * labels.channels] * 255.0f, 0.0f, 255.0f)));
    if (std::filesystem::exists(dir / kRegionsReferenceFile))
        r.reference = loadImageMask(dir / kRegionsReferenceFile, width, height);
    return r;
}

}  // namespace sl
