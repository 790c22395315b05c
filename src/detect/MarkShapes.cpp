#include "detect/MarkShapes.h"

#include <algorithm>
#include <stdexcept>

#include "detect/Extent.h"
#include "detect/Hysteresis.h"

namespace sl {

std::vector<RegionLabel> markShapeLegend() {
    return {{kMarkLine, "lines"},
            {kMarkSpot, "spots"},
            {kMarkLargeLine, "large lines"},
            {kMarkLargeSpot, "large spots"}};
}

std::vector<uint8_t> labelMarksByShape(std::span<const uint8_t> map, int width, int height) {
    if (width < 0 || height < 0 ||
        map.size() != static_cast<size_t>(width) * static_cast<size_t>(height))
        throw std::invalid_argument("labelMarksByShape: the map is not width x height");
    struct Mark {
        std::vector<size_t> samples;
        bool line;
    };
    std::vector<Mark> marks;
    const auto marked = [&](size_t k) { return map[k] != 0; };
    defectmap::forEachRegion(
        width, height, 1, marked, marked, [&](const std::vector<size_t>& samples) {
            marks.push_back({samples, extentOf(samples, width).elongation >= kLineElongation});
        });
    // each shape's median area (the lower median), 0 when the shape has no mark
    auto medianArea = [&](bool line) {
        std::vector<size_t> areas;
        for (const Mark& m : marks)
            if (m.line == line) areas.push_back(m.samples.size());
        if (areas.empty()) return size_t{0};
        const auto mid = areas.begin() + static_cast<std::ptrdiff_t>((areas.size() - 1) / 2);
        std::nth_element(areas.begin(), mid, areas.end());
        return *mid;
    };
    const double largeLine = kLargeMarkFactor * static_cast<double>(medianArea(true));
    const double largeSpot = kLargeMarkFactor * static_cast<double>(medianArea(false));
    std::vector<uint8_t> labels(map.size(), 0);
    for (const Mark& m : marks) {
        const double area = static_cast<double>(m.samples.size());
        const uint8_t v = m.line ? (area > largeLine ? kMarkLargeLine : kMarkLine)
                                 : (area > largeSpot ? kMarkLargeSpot : kMarkSpot);
        for (const size_t k : m.samples) labels[k] = v;
    }
    return labels;
}

}  // namespace sl
