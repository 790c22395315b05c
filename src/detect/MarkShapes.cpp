#include "detect/MarkShapes.h"

#include <stdexcept>

#include "detect/Extent.h"
#include "detect/Hysteresis.h"

namespace sl {

std::vector<RegionLabel> markShapeLegend() {
    return {{kMarkLine, "lines"}, {kMarkSpot, "spots"}};
}

std::vector<uint8_t> labelMarksByShape(std::span<const uint8_t> map, int width, int height) {
    if (width < 0 || height < 0 ||
        map.size() != static_cast<size_t>(width) * static_cast<size_t>(height))
        throw std::invalid_argument("labelMarksByShape: the map is not width x height");
    std::vector<uint8_t> labels(map.size(), 0);
    const auto marked = [&](size_t k) { return map[k] != 0; };
    defectmap::forEachRegion(
        width, height, 1, marked, marked, [&](const std::vector<size_t>& samples) {
            const uint8_t v =
                extentOf(samples, width).elongation >= kLineElongation ? kMarkLine : kMarkSpot;
            for (const size_t k : samples) labels[k] = v;
        });
    return labels;
}

}  // namespace sl
