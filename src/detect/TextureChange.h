// The defect map's texture-change regions (detect/DefectMap.h, method auto, step 8): where the
// local energy of a residual or of the texture stands above its median (chatter bands).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "detect/DefectMap.h"

namespace sl::defectmap {

/// Step 8 on v (W×H; consumed: replaced by |v| and then emptied): E = the separable running
/// median of |v| (energyWindow, on the 2×2-pooled values), marked (255 in `map`) where
/// E >= ratio × max(median E, floorSigma) outside the border (with seedTail > 0, and
/// E >= seedTail × E's tail per tile, tailQuantile on the pooled map) and, with energyGrowBorder,
/// grown outward into it layer by layer. lineExcess: the threshold in the border is raised by the
/// excess of the median of E along the sample's pooled row (top and bottom border) or column
/// (left and right) over median(E). Returns the samples it marked that were not marked before.
size_t markTextureChange(std::vector<float>& v, int W, int H, const DefectMapOptions& o,
                         double floorSigma, double ratio, bool lineExcess,
                         std::vector<uint8_t>& map);

}  // namespace sl::defectmap
