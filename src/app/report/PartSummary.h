// PartSummary: what a command read, for its summary: the part (file, format, grid, pitch, size in
// mm, height range, invalid points filled) with the material and the camera it was seen with.
// The terminal's line is io/SceneFile.h describePart, logged by loadScene.
#pragma once

#include <nlohmann/json.hpp>

namespace sl {

struct Scene;

/// {"file", "format", "grid": [W, H], "pixel_pitch_mm", "pitch_from": "scene"|"file",
///  "size_mm": [x, z], "height_range_mm": [min, max], "invalid_points_filled",
///  "material": {...}, "camera": {...}}.
nlohmann::json partSummaryJson(const Scene& scene);

}  // namespace sl
