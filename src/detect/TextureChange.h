// The defect map's texture-change regions (detect/DefectMap.h, method auto, step 8): where the
// local energy of a residual or of the texture stands above its median (chatter bands).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "detect/DefectMap.h"

namespace sl::defectmap {

/// Step 8's local energy of one residual v: E = the separable running median of |v|
/// (energyWindow, on the 2×2-pooled values: sample (x, y) reads cell (x/2, y/2)), the threshold's
/// base ratio × max(median E, floorSigma), and (with seedTail > 0 and seedTailWide > 0) the wide
/// changes: the 8-connected regions of cells with E >= base outside the border (halved) that
/// hold at least seedTailWide × a tail tile's samples (step 7b's tiles, in pooled cells).
struct ChangeEnergy {
    std::vector<float> E;  // W2×H2
    int W2 = 0, H2 = 0;
    double medE = 0;            // max(median E, floorSigma)
    double base = 0;            // ratio × medE; 0: nothing is marked
    bool lineExcess = false;    // see markTextureChange
    std::vector<uint8_t> wide;  // W2×H2: 1 in a wide change (empty: none)
};

/// v (W×H) is consumed: replaced by |v| and then emptied.
ChangeEnergy changeEnergy(std::vector<float>& v, int W, int H, const DefectMapOptions& o,
                          double floorSigma, double ratio, bool lineExcess);

/// The wide changes of every energy: `pooled` (W2×H2) and at the samples (W×H), 1 where a cell
/// of any is wide. Both empty when there is none.
void wideChanges(const std::vector<ChangeEnergy>& energies, int W, int H,
                 std::vector<uint8_t>& pooled, std::vector<uint8_t>& samples);

/// Step 8 on one energy: marked (255 in `map`) where E >= base outside the border (with
/// seedTail > 0, where E >= seedTail × E's tail per tile, tailQuantile on the pooled map with the
/// wide changes of `wide` (pooled, W2×H2; may be empty) left out, when that is higher; and on
/// every wide change of `e` at E >= base) and, with energyGrowBorder, grown outward into it layer
/// by layer, each mark at its own threshold. lineExcess: the threshold in the border is raised by
/// the excess of the median of E along the sample's pooled row (top and bottom border) or column
/// (left and right) over median(E). Returns the samples it marked that were not marked before.
size_t markTextureChange(const ChangeEnergy& e, const std::vector<uint8_t>& wide, int W, int H,
                         const DefectMapOptions& o, std::vector<uint8_t>& map);

}  // namespace sl::defectmap
