#include "render/Footprint.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <utility>

#include "scene/Scene.h"

namespace sl {

namespace {

using Point = std::pair<double, double>;

double crossZ(const Point& o, const Point& a, const Point& b) {
    return (a.first - o.first) * (b.second - o.second) -
           (a.second - o.second) * (b.first - o.first);
}

/// Andrew's monotone chain: the convex hull, counter-clockwise, without repeated points.
std::vector<Point> convexHull(std::vector<Point> p) {
    std::sort(p.begin(), p.end());
    p.erase(std::unique(p.begin(), p.end()), p.end());
    if (p.size() < 3) return p;
    std::vector<Point> h(2 * p.size());
    size_t k = 0;
    for (size_t i = 0; i < p.size(); ++i) {
        while (k >= 2 && crossZ(h[k - 2], h[k - 1], p[i]) <= 0) --k;
        h[k++] = p[i];
    }
    for (size_t i = p.size() - 1, t = k + 1; i > 0; --i) {
        while (k >= t && crossZ(h[k - 2], h[k - 1], p[i - 1]) <= 0) --k;
        h[k++] = p[i - 1];
    }
    h.resize(k - 1);
    return h;
}

/// The part of the closed polygon `poly` where sign·(y − bound) <= 0 (Sutherland–Hodgman).
std::vector<Point> clipY(const std::vector<Point>& poly, double bound, double sign) {
    std::vector<Point> out;
    const size_t n = poly.size();
    for (size_t i = 0; i < n; ++i) {
        const Point& a = poly[i];
        const Point& b = poly[(i + 1) % n];
        const double da = sign * (a.second - bound), db = sign * (b.second - bound);
        if (da <= 0) out.push_back(a);
        if ((da < 0 && db > 0) || (da > 0 && db < 0)) {
            const double t = da / (da - db);
            out.push_back({a.first + t * (b.first - a.first), bound});
        }
    }
    return out;
}

}  // namespace

std::vector<PixelSpan> partFootprint(const Scene& scene) {
    const int W = scene.camera.width(), H = scene.camera.height();
    std::vector<PixelSpan> spans(static_cast<size_t>(H), PixelSpan{0, W});
    const Heightfield& hf = *scene.surface;
    const double hx = 0.5 * hf.extentX(), hz = 0.5 * hf.extentZ();
    const double lo = hf.minHeight(), hi = hf.maxHeight();
    const double pad =
        1e-5 * std::max({hf.extentX(), hf.extentZ(), std::abs(lo), std::abs(hi), 1e-3});
    std::vector<Point> film;
    for (double x : {-hx - pad, hx + pad})
        for (double y : {lo - pad, hi + pad})
            for (double z : {-hz - pad, hz + pad}) {
                const auto p = scene.camera.project(Vec3d{x, y, z});
                if (!p || !std::isfinite(p->first) || !std::isfinite(p->second)) return spans;
                film.push_back(*p);
            }
    const std::vector<Point> hull = convexHull(std::move(film));
    if (hull.size() < 3) return spans;  // seen edge-on: no area to bound, keep every pixel
    constexpr double kMargin = 0.01;    // film pixels
    for (int y = 0; y < H; ++y) {
        // The hull within the row's strip [y, y + 1] (widened): its x extent.
        std::vector<Point> strip = clipY(hull, y - kMargin, -1.0);
        strip = clipY(strip, y + 1 + kMargin, 1.0);
        PixelSpan& s = spans[static_cast<size_t>(y)];
        if (strip.empty()) {
            s = {0, 0};
            continue;
        }
        double xmin = strip.front().first, xmax = xmin;
        for (const Point& p : strip) {
            xmin = std::min(xmin, p.first);
            xmax = std::max(xmax, p.first);
        }
        // Pixel x covers [x, x + 1]: it meets [xmin, xmax] (widened) when x + 1 >= xmin − m
        // and x <= xmax + m.
        const double b = std::ceil(xmin - kMargin - 1.0), e = std::floor(xmax + kMargin) + 1.0;
        s.begin = static_cast<int>(std::clamp(b, 0.0, static_cast<double>(W)));
        s.end = static_cast<int>(std::clamp(e, 0.0, static_cast<double>(W)));
        if (s.end < s.begin) s.end = s.begin;
    }
    return spans;
}

}  // namespace sl
