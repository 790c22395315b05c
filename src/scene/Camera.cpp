#include "scene/Camera.h"

#include <cmath>
#include <numbers>
#include <string>

#include "core/Error.h"

namespace sl {

namespace {
bool finite(const Vec3d& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}
}  // namespace

Camera::Camera(const CameraDesc& desc) : desc_(desc) {
    if (desc.width < 1 || desc.height < 1 || desc.width > 16384 || desc.height > 16384)
        throw inputError("camera.width/height",
                         std::to_string(desc.width) + "x" + std::to_string(desc.height) +
                             " is not a valid image size",
                         "use 1..16384 pixels per side");
    if (!finite(desc.origin) || !finite(desc.target) || !finite(desc.up))
        throw inputError("camera", "origin, target and up must be finite numbers");
    Vec3d f = desc.target - desc.origin;
    if (length(f) <= 0)
        throw inputError("camera.target", "target equals origin",
                         "place the camera away from the point it looks at");
    forward_ = normalize(f);
    Vec3d l = cross(desc.up, forward_);
    if (length(l) <= 1e-9 * length(desc.up))
        throw inputError("camera.up", "up is parallel to the viewing direction",
                         "choose an up vector that is not parallel to target - origin");
    left_ = normalize(l);
    up_ = cross(forward_, left_);
    aspect_ = static_cast<double>(desc.width) / desc.height;
    if (desc.type == CameraDesc::Type::Perspective) {
        if (!(desc.fovDeg > 0 && desc.fovDeg < 180))
            throw inputError("camera.fov", "must be in (0, 180) degrees");
        tanHalfFov_ = std::tan(desc.fovDeg * std::numbers::pi / 360.0);
    } else if (!(desc.widthMm > 0 && std::isfinite(desc.widthMm))) {
        throw inputError("camera.width_mm", "must be a positive number of scene units",
                         "set the horizontal extent of the orthographic view");
    }
}

std::optional<std::pair<double, double>> Camera::project(const Vec3d& p) const {
    const Vec3d d = p - desc_.origin;
    const double z = dot(d, forward_);
    double nx = 0, ny = 0;
    if (desc_.type == CameraDesc::Type::Perspective) {
        if (!(z > 1e-9 * length(d))) return std::nullopt;
        nx = dot(d, left_) / (z * tanHalfFov_);
        ny = dot(d, up_) / (z * tanHalfFov_);
    } else {
        if (!(z > 0)) return std::nullopt;
        const double half = 0.5 * desc_.widthMm;
        nx = dot(d, left_) / half;
        ny = dot(d, up_) / half;
    }
    return std::pair{(1.0 - nx) * 0.5 * desc_.width, (1.0 - ny * aspect_) * 0.5 * desc_.height};
}

Ray Camera::generateRay(double x, double y) const {
    double nx = 1.0 - 2.0 * x / desc_.width;
    double ny = (1.0 - 2.0 * y / desc_.height) / aspect_;
    Ray r;
    if (desc_.type == CameraDesc::Type::Perspective) {
        Vec3d d = left_ * (nx * tanHalfFov_) + up_ * (ny * tanHalfFov_) + forward_;
        r.origin = Vec3f(desc_.origin);
        r.direction = Vec3f(normalize(d));
    } else {
        double half = 0.5 * desc_.widthMm;
        r.origin = Vec3f(desc_.origin + left_ * (nx * half) + up_ * (ny * half));
        r.direction = Vec3f(forward_);
    }
    return r;
}

CameraDesc defaultCameraFor(double extentX, double extentZ, double heightMin, double heightMax,
                            double fovDeg, int width, int height) {
    CameraDesc c;
    c.type = CameraDesc::Type::Perspective;
    c.fovDeg = fovDeg;
    c.width = width;
    c.height = height;
    double cy = 0.5 * (heightMin + heightMax);
    double dy = heightMax - heightMin;
    double radius = 0.5 * std::sqrt(extentX * extentX + extentZ * extentZ + dy * dy);
    // The narrower of the two fields of view must hold the bounding sphere.
    double tanH = std::tan(fovDeg * std::numbers::pi / 360.0);
    double tanMin = std::min(tanH, tanH * height / width);
    double dist = radius / std::sin(std::atan(tanMin)) * 1.02;
    double s = std::sqrt(0.5);
    c.target = {0, cy, 0};
    c.origin = {0, cy + dist * s, dist * s};
    c.up = {0, 1, 0};
    return c;
}

}  // namespace sl

namespace sl {

double Camera::mmPerPixel() const {
    if (desc_.type == CameraDesc::Type::Orthographic) return desc_.widthMm / desc_.width;
    const double distance = length(desc_.origin - desc_.target);
    return 2.0 * distance * std::tan(desc_.fovDeg * std::numbers::pi / 360.0) / desc_.width;
}

}  // namespace sl
