// Scene: everything the path tracer needs, built from a SceneDesc (the parsed scene file,
// see io/SceneFile.h for the JSON fields). The defaults of these structs are the scene file's:
// the parser applies them and sceneFileFields() lists them.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "perception/ViewingModel.h"
#include "scene/Camera.h"
#include "scene/Conductor.h"
#include "scene/EnvMapBasis.h"
#include "scene/Heightfield.h"
#include "scene/Levelling.h"
#include "scene/RenderDesc.h"

namespace sl {

struct HeightmapDesc {
    std::filesystem::path path;  // resolved against the scene file
    double pitch = 0.01;         // mm between samples
    bool pitchGiven = false;     // the scene file gave pixel_pitch (else a file's own pitch wins)
    std::optional<std::array<double, 2>> heightRange;  // integer maps: [min, max] in mm
    double heightScale = 1.0;                          // float maps: multiplier
    LevellingDesc levelling;  // form removal when loaded (scene/Levelling.h)
    /// heightmap.channel: which channel of an instrument file of several (its number or title,
    /// io/GwyddionReader.h); "" the height channel the reader's rule finds.
    std::string channel;
    /// heightmap.measured: the map is a measurement (an instrument's), or not (a simulator's
    /// or a generator's), whatever its file format; unset: the file says (io/HeightmapIO.h
    /// HeightmapData::measured). The defect map's auto method follows it (detect/DefectMap.h).
    std::optional<bool> measured;
};

/// What loading the height map did (io/SceneFile.h loadScene): printed when the part is loaded,
/// recorded in optimize's and judge's summaries (io/SceneFile.h heightmapLoadJson).
struct HeightmapLoad {
    std::string format;         // the reader's, e.g. "gwyddion opdfile, 809 invalid points filled"
    size_t invalidFilled = 0;   // invalid points of the file, filled
    std::string resampling;     // "" or how non-square pixels were made square
    std::string channel;        // "" or which channel of a file of several was read
    LevellingResult levelling;  // what was removed
    std::vector<std::string> warnings;  // the reader's
    bool measured = false;              // HeightmapDesc::measured, else the file's
    /// "736x560 at 1.634 um, gwyddion opdfile, ...; levelled: plane ...".
    std::string text(int width, int height, double pitch) const;
};

struct EnvMapDesc {
    int width = kDefaultEnvMapGrid.width, height = kDefaultEnvMapGrid.height;
    std::filesystem::path path;     // optional default env map for `render`
    std::optional<float> constant;  // optional constant value (used when no path)
    std::string preset;             // optional built-in map, see scene/EnvMapPresets.h
    /// The env map `render` uses when the scene names none.
    static constexpr const char* kDefaultPreset = "studio";
};

struct MaterialDesc {
    ConductorParams params;
    std::string name = "Al";  // named metal, or "custom" when eta/k were given
    std::string type = "roughconductor";
};

/// Camera fields as written in the scene; what is omitted comes from defaultCameraFor the part.
struct CameraSpec {
    CameraDesc::Type type = CameraDesc::Type::Perspective;
    std::optional<Vec3d> origin, target, up;
    double fovDeg = CameraDesc{}.fovDeg;
    /// Orthographic view width; default: kWidthMmFactor × the part's larger extent.
    std::optional<double> widthMm;
    static constexpr double kWidthMmFactor = 1.05;
    int width = CameraDesc{}.width, height = CameraDesc{}.height;
};

/// Resolve a CameraSpec against the part it looks at.
CameraDesc resolveCamera(const CameraSpec& spec, const Heightfield& surface);

struct SceneDesc {
    std::filesystem::path file;          // the scene file (empty if built in code)
    std::vector<std::string> overrides;  // -D key=value applied to the file (io/SceneFile.h)
    std::string canonicalJson;           // the scene as parsed, keys sorted (for fingerprints)
    HeightmapDesc heightmap;
    MaterialDesc material;
    CameraSpec camera;
    EnvMapDesc envmap;
    RenderDesc render;
    ViewingDesc viewing;  // how a person sees the images (the judge's JND)
};

struct Scene {
    /// heights: W×H row-major in scene units (already scaled). Builds the Embree surface.
    Scene(SceneDesc desc, int mapWidth, int mapHeight, std::vector<float> heights);

    SceneDesc desc;
    int mapWidth, mapHeight;
    std::vector<float> heights;
    /// What the height-map file was (io/SceneFile.h loadScene sets them; empty/0 in code).
    std::string mapFormat;     // e.g. "exr float32"
    size_t invalidFilled = 0;  // invalid points filled (X3P, SDF)
    std::unique_ptr<Heightfield> surface;
    Camera camera;
    ConductorBsdf bsdf;
    EnvMapBasis basis;
    HeightmapLoad load;  // set by loadScene
};

}  // namespace sl
