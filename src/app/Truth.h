// Masks drawn in height-map space, read and projected into a scene's image through each
// pixel's centre ray (objective/ImageSpace.h): the truth masks of optimize and the judge.
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "io/MaskIO.h"

namespace sl {

struct Scene;

/// loadHeightMapMask (e.g. gen-surface's <stem>-truth.png) projected into the image (255/0).
std::vector<uint8_t> projectMaskFile(const Scene& scene, const std::filesystem::path& file,
                                     int threads = 0);

/// readLabelMask projected into the image: the labels keep their values, the legend its names.
LabelMask projectTruth(const Scene& scene, const std::filesystem::path& truth, int threads = 0);

}  // namespace sl
