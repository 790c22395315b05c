// The lamps' figure drawn in-process (app/report/LampsFigure.h): each lamp's outline lies on its
// sharp edge (a disk's points at its angular radius from the centre, a bar's on its rectangle,
// a ring's at its band's elevations), and the figure draws it where the hemisphere plot puts
// those directions (cyan there, none without lamps).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "app/report/LampsFigure.h"

using namespace sl;

namespace {

constexpr double kDeg = std::numbers::pi / 180;

Vec3d directionOf(const PlotDirection& d) {
    return lampDirection(d.azimuthDeg * kDeg, d.elevationDeg * kDeg);
}

EnvMapPlot grid(double value) {
    EnvMapPlot e;
    e.width = 50;
    e.height = 25;
    for (int i = 0; i < e.width; ++i) e.azimuthDeg.push_back((i + 0.5) * 360.0 / e.width);
    for (int j = 0; j < e.height; ++j) e.elevationDeg.push_back(90.0 - j * 180.0 / (e.height - 1));
    e.luminance.assign(static_cast<size_t>(e.width * e.height), value);
    return e;
}

}  // namespace

TEST(LampsFigure, OutlinesLieOnTheLampsSharpEdges) {
    Lamp disk;
    disk.kind = LampKind::Disk;
    disk.azimuth = 300 * kDeg;
    disk.elevation = 40 * kDeg;
    disk.size = 12 * kDeg;
    const auto d = lampOutline(disk);
    ASSERT_EQ(d.size(), 1u);
    const Vec3d c = lampDirection(disk.azimuth, disk.elevation);
    for (const PlotDirection& p : d[0])
        EXPECT_NEAR(std::acos(std::clamp(dot(directionOf(p), c), -1.0, 1.0)), disk.size, 1e-9);

    Lamp bar;
    bar.kind = LampKind::Bar;
    bar.azimuth = 20 * kDeg;
    bar.elevation = 30 * kDeg;
    bar.size = 25 * kDeg;
    bar.width = 6 * kDeg;
    bar.roll = 35 * kDeg;
    const auto f = lamp_detail::frame<double>(bar.azimuth, bar.elevation, bar.roll);
    const auto b = lampOutline(bar);
    ASSERT_EQ(b.size(), 1u);
    for (const PlotDirection& p : b[0]) {
        const Vec3d v = directionOf(p);
        const double x = std::atan2(lamp_detail::dotd(f.e1, v), lamp_detail::dotd(f.c, v));
        const double y = std::asin(lamp_detail::dotd(f.e2, v));
        EXPECT_LE(std::abs(x), bar.size + 1e-9);
        EXPECT_LE(std::abs(y), bar.width + 1e-9);
        EXPECT_NEAR(std::max(std::abs(x) - bar.size, std::abs(y) - bar.width), 0.0, 1e-9);
    }

    Lamp ring;
    ring.kind = LampKind::Ring;
    ring.elevation = 20 * kDeg;
    ring.size = 10 * kDeg;
    const auto r = lampOutline(ring);
    ASSERT_EQ(r.size(), 2u);
    for (const PlotDirection& p : r[0]) EXPECT_NEAR(p.elevationDeg, 30, 1e-9);
    for (const PlotDirection& p : r[1]) EXPECT_NEAR(p.elevationDeg, 10, 1e-9);
}

TEST(LampsFigure, DrawsEachOutlineWhereTheHemispherePutsIt) {
    Lamp disk;
    disk.kind = LampKind::Disk;
    disk.azimuth = 60 * kDeg;
    disk.elevation = 45 * kDeg;
    disk.size = 15 * kDeg;
    const EnvMapPlot dark = grid(0.0);
    EnvMapPlot target = grid(0.0);
    target.luminance[0] = 1;  // a scale
    const Canvas with = lampsFigure(target, dark, std::span<const Lamp>(&disk, 1));
    const Canvas without = lampsFigure(target, dark, {});
    ASSERT_EQ(with.width(), 1100);
    ASSERT_EQ(with.height(), 550);
    const std::vector<uint8_t> a = with.rgb(), b = without.rgb();
    auto cyanNear = [&](const std::vector<uint8_t>& px, Point p) {
        for (int dy = -2; dy <= 2; ++dy)
            for (int dx = -2; dx <= 2; ++dx) {
                const int x = static_cast<int>(std::lround(p.x)) + dx,
                          y = static_cast<int>(std::lround(p.y)) + dy;
                const size_t i = (static_cast<size_t>(y) * 1100 + static_cast<size_t>(x)) * 3;
                if (px[i] < 90 && px[i + 1] > 180 && px[i + 2] > 180) return true;
            }
        return false;
    };
    const auto outline = lampOutline(disk).at(0);
    int found = 0;
    for (size_t k = 0; k < outline.size(); k += 10) {
        const Point p = hemispherePoint(kLampsFigureCentre, kLampsFigureRadius,
                                        outline[k].azimuthDeg, outline[k].elevationDeg);
        found += cyanNear(a, p);
        EXPECT_FALSE(cyanNear(b, p)) << k;
    }
    EXPECT_GE(found, static_cast<int>(outline.size() / 10) - 1);
}
