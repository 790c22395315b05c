// Scene files (JSON). Paths are relative to the scene file. Unknown fields are errors that name
// the field and list the valid ones. Every field, its default and its meaning are listed once, by
// sceneFileFields() beside the parser (SceneFile.cpp), with the defaults read from the structs of
// scene/Scene.h that the parser starts from; the README's "Scene file" table is that list
// (tests/test_readme.cpp fails when they disagree and prints the table to paste).
#pragma once

#include <filesystem>
#include <memory>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "io/HeightmapIO.h"
#include "scene/Scene.h"

namespace sl {

/// Parse and validate a scene file. Throws InputError naming the file and field.
/// `overrides` ("key.path=value", as Mitsuba's -D) replace or add fields of the file's JSON
/// before it is parsed, so they are checked as the file's own fields are: the value is read as
/// JSON (a number, true/false, [..], {..}, "..") and otherwise taken as a string; a key names
/// a field by its sections (e.g. material.alpha, camera.width, render.spp). Relative paths in
/// a value resolve against the scene file's folder, as in the file. The desc records them.
/// A file that is not JSON (not named .json, and its first non-blank byte not '{') is a height
/// map standing for the default scene around it, {"heightmap": {"path": FILE}}; said in the log.
SceneDesc readSceneFile(const std::filesystem::path& file,
                        const std::vector<std::string>& overrides = {});
/// Parse a scene from JSON text; relative paths resolve against baseDir.
SceneDesc parseScene(const std::string& jsonText, const std::filesystem::path& baseDir,
                     const std::string& where = "scene");

/// The files a scene reads: the scene file, its height map and its env map (those it names).
std::vector<std::filesystem::path> sceneInputFiles(const SceneDesc& desc);

/// Load the height map a SceneDesc names and build the Scene (Embree surface included).
/// Load the height map a SceneDesc names and build the Scene (Embree surface included). A map
/// that carries no pitch (EXR, TIFF, PNG, .npy) needs heightmap.pixel_pitch (pitchGiven): else an
/// InputError saying how to give it. Logs describePart (spdlog info) once loaded.
std::unique_ptr<Scene> loadScene(const SceneDesc& desc);
std::unique_ptr<Scene> loadScene(const std::filesystem::path& file,
                                 const std::vector<std::string>& overrides = {});

/// One line on what was read: "part part.exr (exr float32): 1024 x 1024 samples, pitch 0.01 mm,
/// 10.23 x 10.23 mm, heights -0.006 .. 0.002 mm, 0 invalid points filled".
std::string describePart(const Scene& scene);

/// The heights of a scene file's part (SCENE.json: the whole Scene, its camera included) or of a
/// bare height map (any other extension, io/HeightmapIO.h; an integer map without a height
/// range is read as [0, 1], for tools invariant to an affine change of the heights, such as
/// the defect and scratch maps). A bare map given with `overrides` (-D heightmap.channel=1,
/// heightmap.levelling=cylinder:x) is read as the default scene around it with them applied,
/// as render reads it (readSceneFile): a scene's rules hold then (a map without a pitch needs
/// heightmap.pixel_pitch, an integer map heightmap.height_range). Logs what was read (a bare
/// map: its grid, pitch when the file has one, height range and invalid points; a scene:
/// loadScene's describePart).
struct HeightSource {
    std::unique_ptr<Scene> scene;  // null for a bare height map
    HeightmapData map;             // the bare height map's data (empty for a scene)
    HeightmapLoad load;            // the bare map's reading and levelling (a scene: scene->load)
    const std::vector<float>& heights() const { return scene ? scene->heights : map.heights; }
    int width() const { return scene ? scene->mapWidth : map.width; }
    int height() const { return scene ? scene->mapHeight : map.height; }
    /// A measurement: the scene's heightmap.measured, else the file's (HeightmapData::measured).
    bool measured() const { return scene ? scene->load.measured : map.measured(); }
};
HeightSource loadHeightSource(const std::filesystem::path& file,
                              const std::vector<std::string>& overrides = {});

/// What loading a scene's height map did (Scene::load: reader, invalid points, resampling,
/// levelling) as JSON, for summaries (optimize's summary.json, judge.json).
nlohmann::ordered_json heightmapLoadJson(const Scene& scene);

/// Applies one "key.path=value" override to a scene's JSON (readSceneFile's rules); `where`
/// names the scene file for errors.
void applySceneOverride(nlohmann::json& scene, const std::string& override,
                        const std::string& where);

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
