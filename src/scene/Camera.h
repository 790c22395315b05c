// Camera: Mitsuba 3's `perspective` and `orthographic` sensors.
//
// CONVENTION (camera): `origin`, `target`, `up` as Mitsuba's look_at: forward f = normalize(target
// − origin), left = normalize(cross(up, f)), up' = cross(f, left); camera space is (left, up', f).
// A film position (x, y) in pixels, x to the right and y down from the top-left corner, maps to
//   sx = x / width, sy = y / height,  ndc = (1 − 2·sx, (1 − 2·sy) / aspect),  aspect = width/height
// (Mitsuba's camera_to_sample = scale(−½, −½·aspect, 1) · translate(−1, −1/aspect, 0) · proj).
//   perspective:  direction ∝ left·ndc.x·tan(fov/2) + up'·ndc.y·tan(fov/2) + f, from `origin`;
//                 `fov` in degrees along the image's horizontal axis (Mitsuba's fov_axis="x").
//   orthographic: origin + left·ndc.x·width_mm/2 + up'·ndc.y·width_mm/2, direction f
//                 (Mitsuba: to_world = look_at · scale(width_mm/2, width_mm/2, 1)).
// So the image's top row is toward `up`, its left column toward `left`, and it is not mirrored.
#pragma once

#include <optional>
#include <utility>

#include "core/Vec3.h"

namespace sl {

struct Ray {
    Vec3f origin, direction;
};

/// The defaults here are the scene file's (io/SceneFile.h) and defaultCameraFor's.
struct CameraDesc {
    enum class Type { Perspective, Orthographic } type = Type::Perspective;
    Vec3d origin{0, 40, 40}, target{0, 0, 0}, up{0, 1, 0};
    double fovDeg = 35.0;   // perspective: horizontal field of view
    double widthMm = 10.0;  // orthographic: horizontal extent of the view
    int width = 512, height = 512;
};

class Camera {
  public:
    explicit Camera(const CameraDesc& desc);  // validates, throws InputError naming camera.<field>

    /// Ray through film position (x, y) in pixels (x right, y down from the top-left corner).
    Ray generateRay(double x, double y) const;
    /// The inverse: the film position (x, y) whose ray passes through world point p, or nothing
    /// when p is not in front of the camera (perspective: depth along the view direction at
    /// most 1e-9 of its distance; orthographic: behind the film plane).
    std::optional<std::pair<double, double>> project(const Vec3d& p) const;

    /// The part's length (scene units, mm) one pixel spans at the target: orthographic
    /// widthMm / width; perspective 2·|origin − target|·tan(fov/2) / width.
    double mmPerPixel() const;

    const CameraDesc& desc() const { return desc_; }
    int width() const { return desc_.width; }
    int height() const { return desc_.height; }

  private:
    CameraDesc desc_;
    Vec3d left_, up_, forward_;
    double tanHalfFov_ = 0, aspect_ = 1;
};

/// The camera used when a scene omits one: looks at the part's centre from 45° above (from +z,
/// up = +Y), far enough that the bounding sphere of the part fits the horizontal field of view.
CameraDesc defaultCameraFor(double extentX, double extentZ, double heightMin, double heightMax,
                            double fovDeg = CameraDesc{}.fovDeg, int width = CameraDesc{}.width,
                            int height = CameraDesc{}.height);

}  // namespace sl
