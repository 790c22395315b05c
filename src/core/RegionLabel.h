// A named region of a label image (truth masks: io/MaskIO.h; scores: objective/DefectVisibility.h).
#pragma once

#include <cstdint>
#include <string>

namespace sl {

struct RegionLabel {
    uint8_t value = 255;  // the label's pixel value (1..255; 0 = unlabelled)
    std::string name = "defect";
};

}  // namespace sl
