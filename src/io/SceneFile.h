// Scene files (JSON). Paths are relative to the scene file. Unknown fields are errors that name
// the field and list the valid ones. Every field, its default and its meaning are listed once, by
// sceneFileFields() beside the parser (SceneFile.cpp), with the defaults read from the structs of
// scene/Scene.h that the parser starts from; the README's "Scene file" table is that list
// (tests/test_readme.cpp fails when they disagree and prints the table to paste).
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "scene/Scene.h"

namespace sl {

/// Parse and validate a scene file. Throws InputError naming the file and field.
SceneDesc readSceneFile(const std::filesystem::path& file);
/// Parse a scene from JSON text; relative paths resolve against baseDir.
SceneDesc parseScene(const std::string& jsonText, const std::filesystem::path& baseDir,
                     const std::string& where = "scene");

/// Load the height map a SceneDesc names and build the Scene (Embree surface included).
std::unique_ptr<Scene> loadScene(const SceneDesc& desc);
std::unique_ptr<Scene> loadScene(const std::filesystem::path& file);

/// One row of the scene file's reference.
struct SceneFileField {
    std::string field;         // e.g. "material.alpha", "camera.width/height"
    std::string defaultValue;  // as the README shows it, e.g. "0.05", "`ggx`", "512 × 512"
    std::string meaning;
};

/// Every field of a scene file with its default, in the README's order.
std::vector<SceneFileField> sceneFileFields();

/// sceneFileFields() as the README's Markdown table (header, separator, one row per field).
std::string sceneFileTable();

}  // namespace sl
