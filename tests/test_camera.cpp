// Camera conventions (Mitsuba look_at, fov along x, top row toward up, not mirrored).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/Error.h"
#include "scene/Camera.h"

using namespace sl;

namespace {
double angleDeg(const Vec3f& a, const Vec3d& b) {
    return std::acos(std::clamp(dot(Vec3d(a), normalize(b)), -1.0, 1.0)) * 180.0 / std::numbers::pi;
}
}  // namespace

TEST(Camera, PerspectiveFovAlongX) {
    CameraDesc d;
    d.origin = {0, 0, 10};
    d.target = {0, 0, 0};
    d.up = {0, 1, 0};
    d.fovDeg = 40;
    d.width = 200;
    d.height = 100;
    Camera c(d);
    // Centre ray looks at the target.
    EXPECT_LT(angleDeg(c.generateRay(100, 50).direction, {0, 0, -1}), 1e-5);
    // Left edge: half the horizontal fov, toward left = cross(up, forward) = -x.
    Ray l = c.generateRay(0, 50);
    EXPECT_NEAR(angleDeg(l.direction, {0, 0, -1}), 20.0, 1e-4);
    EXPECT_LT(l.direction.x, 0);
    // Top edge: toward +up, with the vertical half-angle atan(tan(20°)/aspect).
    Ray t = c.generateRay(100, 0);
    EXPECT_GT(t.direction.y, 0);
    double vert = std::atan(std::tan(20.0 * std::numbers::pi / 180) / 2.0) * 180 / std::numbers::pi;
    EXPECT_NEAR(angleDeg(t.direction, {0, 0, -1}), vert, 1e-4);
}

TEST(Camera, OrthographicWidth) {
    CameraDesc d;
    d.type = CameraDesc::Type::Orthographic;
    d.origin = {0, 10, 0};
    d.target = {0, 0, 0};
    d.up = {0, 0, -1};
    d.widthMm = 4.0;
    d.width = d.height = 64;
    Camera c(d);
    Ray centre = c.generateRay(32, 32);
    EXPECT_NEAR(centre.origin.x, 0, 1e-6);
    EXPECT_NEAR(centre.direction.y, -1, 1e-6);
    // Looking down with up = -z: left = cross(up, f) = cross(-z, -y) = -x.
    Ray left = c.generateRay(0, 32);
    EXPECT_NEAR(left.origin.x, -2.0, 1e-5);
    Ray top = c.generateRay(32, 0);
    EXPECT_NEAR(top.origin.z, -2.0, 1e-5);  // top row toward up = -z
}

TEST(Camera, DefaultFramesThePartFrom45Degrees) {
    CameraDesc d = defaultCameraFor(10, 6, -0.1, 0.1);
    Vec3d v = d.origin - d.target;
    EXPECT_NEAR(std::atan2(v.y, v.z) * 180 / std::numbers::pi, 45.0, 1e-9);
    Camera c(d);
    // All four corners of the part project inside the image.
    for (double x : {-5.0, 5.0})
        for (double z : {-3.0, 3.0}) {
            Vec3d p{x, 0, z};
            Vec3d dir = normalize(p - d.origin);
            Vec3d f = normalize(d.target - d.origin);
            double tanHalf = std::tan(d.fovDeg * std::numbers::pi / 360);
            Vec3d left = normalize(cross(d.up, f)), up = cross(f, left);
            double nx = dot(dir, left) / dot(dir, f) / tanHalf;
            double ny = dot(dir, up) / dot(dir, f) / tanHalf;
            EXPECT_LT(std::abs(nx), 1.0);
            EXPECT_LT(std::abs(ny), 1.0);
        }
}

TEST(Camera, RejectsBadInput) {
    CameraDesc d;
    d.target = d.origin;
    EXPECT_THROW(Camera{d}, InputError);
    d = CameraDesc{};
    d.up = d.target - d.origin;
    EXPECT_THROW(Camera{d}, InputError);
    d = CameraDesc{};
    d.fovDeg = 0;
    EXPECT_THROW(Camera{d}, InputError);
}
