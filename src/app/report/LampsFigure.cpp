#include "app/report/LampsFigure.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace sl {

namespace {

constexpr double kDeg = std::numbers::pi / 180;
const Colour kOutline = hexColour(0x00ffff);  // matplotlib's "cyan", as the script

PlotDirection plotDirection(const Vec3d& d) {
    // The inverse of lampDirection (scene/Lamp.h): azimuth from −z toward +x.
    double az = std::atan2(d.x, -d.z) / kDeg;
    if (az < 0) az += 360;
    return {az, std::asin(std::clamp(d.y, -1.0, 1.0)) / kDeg};
}

}  // namespace

std::vector<std::vector<PlotDirection>> lampOutline(const Lamp& lamp) {
    std::vector<std::vector<PlotDirection>> out;
    if (lamp.kind == LampKind::Ring) {
        for (double e : {lamp.elevation + lamp.size, lamp.elevation - lamp.size}) {
            std::vector<PlotDirection> circle;
            const double el = std::clamp(e / kDeg, -90.0, 90.0);
            for (int k = 0; k <= 200; ++k) circle.push_back({360.0 * k / 200, el});
            out.push_back(std::move(circle));
        }
        return out;
    }
    const auto f = lamp_detail::frame<double>(lamp.azimuth, lamp.elevation, lamp.roll);
    const Vec3d c{f.c[0], f.c[1], f.c[2]}, e1{f.e1[0], f.e1[1], f.e1[2]},
        e2{f.e2[0], f.e2[1], f.e2[2]};
    std::vector<PlotDirection> curve;
    if (lamp.kind == LampKind::Disk) {
        const double r = lamp.size;
        for (int k = 0; k <= 100; ++k) {
            const double t = 2 * std::numbers::pi * k / 100;
            curve.push_back(plotDirection(c * std::cos(r) +
                                          (e1 * std::cos(t) + e2 * std::sin(t)) * std::sin(r)));
        }
    } else {  // a bar: its rectangle in (x along e1, y along e2), scene/Lamp.h
        const double a = lamp.size, b = lamp.width;
        std::vector<std::pair<double, double>> edge;
        for (int k = 0; k < 40; ++k) edge.emplace_back(-a + 2 * a * k / 40, -b);
        for (int k = 0; k < 10; ++k) edge.emplace_back(a, -b + 2 * b * k / 10);
        for (int k = 0; k < 40; ++k) edge.emplace_back(a - 2 * a * k / 40, b);
        for (int k = 0; k <= 10; ++k) edge.emplace_back(-a, b - 2 * b * k / 10);
        for (const auto& [x, y] : edge)
            curve.push_back(plotDirection((c * std::cos(x) + e1 * std::sin(x)) * std::cos(y) +
                                          e2 * std::sin(y)));
    }
    out.push_back(std::move(curve));
    return out;
}

Canvas lampsFigure(const EnvMapPlot& target, const EnvMapPlot& lampsEnvMap,
                   std::span<const Lamp> lamps) {
    Canvas c(1100, 550);  // the script's 10 × 5 in at 110 dpi
    if (target.width != lampsEnvMap.width || target.height != lampsEnvMap.height)
        throw std::invalid_argument("lamps plot: E* and the lamps' env map are on other grids");
    const double radius = kLampsFigureRadius;
    double vmax = 0;  // E*'s, the scale of both (each panel checks its plot)
    for (double v : target.luminance) vmax = std::max(vmax, v);
    const Point centres[2] = {kLampsFigureCentre,
                              {kLampsFigureCentre.x + 520, kLampsFigureCentre.y}};
    drawEnvMapHemisphere(c, target, centres[0], radius, vmax, "E* and the lamps");
    drawEnvMapHemisphere(c, lampsEnvMap, centres[1], radius, vmax, "the lamps' env map");
    for (const Point& p : centres)
        drawEnvMapColourBar(c, vmax, p.x + radius + 70, p.y - 0.7 * radius, 16, 1.4 * radius);
    // The outlines over E*, inside the horizon's disc (a lamp may reach below it).
    auto at = [&](const PlotDirection& d) {
        return hemispherePoint(centres[0], radius, d.azimuthDeg, d.elevationDeg);
    };
    c.clipCircle(centres[0], radius);
    TextStyle number{15, kOutline, true, Align::Centre, Align::Centre};
    for (size_t i = 0; i < lamps.size(); ++i) {
        for (const std::vector<PlotDirection>& curve : lampOutline(lamps[i])) {
            std::vector<Point> pts;
            for (const PlotDirection& d : curve) pts.push_back(at(d));
            c.polyline(pts, kOutline, 1.9);
        }
        if (lamps[i].kind != LampKind::Ring)
            c.text(at(plotDirection(lampDirection(lamps[i].azimuth, lamps[i].elevation))),
                   std::to_string(i + 1), number);
    }
    c.unclip();
    TextStyle title{16, Colour{0, 0, 0, 1}, false, Align::Centre, Align::Start};
    c.text({550, 10},
           "zenith at the centre, horizon at the rim; azimuth 0° toward −z, 90° toward +x", title);
    return c;
}

}  // namespace sl
