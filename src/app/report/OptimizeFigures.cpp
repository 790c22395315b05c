#include "app/report/OptimizeFigures.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>

#include "io/AtomicFile.h"
#include "io/OptimizeOutDir.h"

namespace sl {

namespace {

const Colour kBlack{0, 0, 0, 1};
const Colour kWhite{1, 1, 1, 1};
const Colour kHorizon = hexColour(0x7fd0ff);
const Colour kCamera = hexColour(0x00e5ff);
const Colour kMirror = hexColour(0x7CFC00);
const Colour kTraining = hexColour(0x1f77b4);
const Colour kHeld = hexColour(0xd62728);

std::string number(const char* format, double v) {
    char b[64];
    std::snprintf(b, sizeof b, format, v);
    return b;
}

std::string degrees(double v) {
    return number("%.0f", v + 0.0) + "°";
}

std::string directionLabel(const PlotDirection& d) {
    return "az " + degrees(d.azimuthDeg) + ", el " + degrees(d.elevationDeg);
}

bool finite(const std::vector<double>& v) {
    return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
}

void check(const EnvMapPlot& e) {
    auto bad = [](const std::string& why) { throw std::invalid_argument("env-map plot: " + why); };
    if (e.width < 1 || e.height < 2) bad("needs at least 1 column and 2 rows");
    if (e.azimuthDeg.size() != static_cast<size_t>(e.width) ||
        e.elevationDeg.size() != static_cast<size_t>(e.height) ||
        e.luminance.size() != static_cast<size_t>(e.width) * static_cast<size_t>(e.height))
        bad(std::to_string(e.azimuthDeg.size()) + " azimuths, " +
            std::to_string(e.elevationDeg.size()) + " elevations and " +
            std::to_string(e.luminance.size()) + " texels do not make a " +
            std::to_string(e.width) + " x " + std::to_string(e.height) + " grid");
    if (!finite(e.azimuthDeg) || !finite(e.elevationDeg) || !finite(e.luminance))
        bad("a value is not finite");
    if (std::any_of(e.luminance.begin(), e.luminance.end(), [](double v) { return v < 0; }))
        bad("a texel is negative");
    if (!std::is_sorted(e.azimuthDeg.begin(), e.azimuthDeg.end()) ||
        !std::is_sorted(e.elevationDeg.rbegin(), e.elevationDeg.rend()))
        bad("azimuths must increase and elevations decrease");
}

void check(const LossCurve& l) {
    if (l.iteration.empty() || l.iteration.size() != l.loss.size() ||
        l.heldIteration.size() != l.held.size())
        throw std::invalid_argument(
            "loss plot: " + std::to_string(l.iteration.size()) + " iterations, " +
            std::to_string(l.loss.size()) + " losses, " + std::to_string(l.heldIteration.size()) +
            " held-out iterations and " + std::to_string(l.held.size()) +
            " held-out losses: needs at least one loss and as many iterations as values");
}

/// Cell edges around sorted (or reverse-sorted) centres, clipped to [lo, hi].
std::vector<double> edges(const std::vector<double>& c, double lo, double hi) {
    std::vector<double> e;
    if (c.size() == 1) {
        e = {c[0] - 1, c[0] + 1};
    } else {
        e.push_back(c[0] - (c[1] - c[0]) / 2);
        for (size_t k = 0; k + 1 < c.size(); ++k) e.push_back((c[k] + c[k + 1]) / 2);
        e.push_back(c.back() + (c.back() - c[c.size() - 2]) / 2);
    }
    for (double& v : e) v = std::clamp(v, lo, hi);
    return e;
}

double maxOf(const std::vector<double>& v) {
    return std::max(1e-9, *std::max_element(v.begin(), v.end()));
}

/// Sizes of one drawing of the lat-long plot (the overview draws it smaller).
struct Scale {
    double font, small, title;  // pixels
};

/// The markers of the directions on a plot, at `pos(d)`, clipped to `clip` (the plot's frame
/// or disc); the brightest labelled beside their star, each label at the first of a few offsets
/// where it covers no marker and no label before it (nor `placed`: text already drawn), and all
/// labels under the markers.
template <class Pos, class Clip>
void markDirections(Canvas& c, const PlotDirections& dirs, Pos pos, bool polar, double small,
                    double unit, Clip clip, std::vector<Box> placed = {}) {
    auto shown = [&](const PlotDirection& d) { return !polar || d.elevationDeg >= 0; };
    auto markerBox = [&](const PlotDirection& d, double size) {
        const Point p = pos(d);
        return Box{p.x - size / 2, p.y - size / 2, size, size};
    };
    for (const auto& d : {dirs.camera, dirs.mirror})
        if (d && shown(*d)) placed.push_back(markerBox(*d, 8 * unit));
    for (const PlotDirection& d : dirs.brightest)
        if (shown(d)) placed.push_back(markerBox(d, 12 * unit));
    const double offsets[][2] = {{10, 10}, {10, -16}, {-10, 14}, {-10, -16},
                                 {10, 26}, {10, -30}, {-10, 28}, {-10, -30}};  // points, y up
    for (size_t k = 0; k < dirs.brightest.size(); ++k) {
        const PlotDirection& d = dirs.brightest[k];
        if (!shown(d)) continue;
        const Point p = pos(d);
        const std::string text = std::to_string(k + 1) + ": " + directionLabel(d);
        TextStyle ts{small, kBlack};
        ts.v = Align::Centre;
        Point at{};
        for (size_t tried = 0; tried < std::size(offsets); ++tried) {
            // The first choice alternates as the brightest do, as plot_optimize.py's does.
            const auto& o = offsets[tried == 0 ? k % 3 : tried];
            double dx = o[0];
            if (!polar && d.azimuthDeg > 300) dx = -std::abs(dx);
            ts.h = dx > 0 ? Align::Start : Align::End;
            at = {p.x + dx * unit, p.y - o[1] * unit};
            const Box box = c.labelBox(at, text, ts);
            if (std::none_of(placed.begin(), placed.end(),
                             [&](const Box& b) { return b.overlaps(box); }))
                break;
            if (tried + 1 == std::size(offsets)) {  // crowded: the first choice after all
                const auto& first = offsets[k % 3];
                dx = !polar && d.azimuthDeg > 300 ? -std::abs(first[0]) : first[0];
                ts.h = dx > 0 ? Align::Start : Align::End;
                at = {p.x + dx * unit, p.y - first[1] * unit};
            }
        }
        placed.push_back(c.labelBox(at, text, ts));
        c.label(at, text, ts, Colour{1, 1, 1, 0.85});
    }
    clip();
    if (dirs.camera && shown(*dirs.camera))
        c.marker(pos(*dirs.camera), Marker::Circle, 8 * unit, kCamera, kBlack);
    if (dirs.mirror && shown(*dirs.mirror))
        c.marker(pos(*dirs.mirror), Marker::Cross, 8 * unit, kMirror, kBlack);
    for (const PlotDirection& d : dirs.brightest)
        if (shown(d)) c.marker(pos(d), Marker::Star, 12 * unit, kWhite, kBlack);
    c.unclip();
}

/// The lat-long plot of E in the frame (x, y, w, h); `unit`: pixels per point.
void drawLatLong(Canvas& c, const EnvMapPlot& e, const PlotDirections& dirs, double x, double y,
                 double w, double h, const Scale& s, double unit, bool legend) {
    AxisSpec ax{0, 360, false, {}, degrees, "azimuth (0° toward −z, 90° toward +x)"};
    for (int a = 0; a <= 360; a += 45) ax.ticks.push_back(a);
    AxisSpec ay{-90, 90, false, {}, degrees, "elevation (90° = up, +Y)"};
    for (int a = -90; a <= 90; a += 30) ay.ticks.push_back(a);
    Axes axes(c, x, y, w, h, ax, ay);
    const std::vector<double> xe = edges(e.azimuthDeg, 0, 360), ye = edges(e.elevationDeg, -90, 90);
    const double vmax = maxOf(e.luminance);
    for (int j = 0; j < e.height; ++j)
        for (int i = 0; i < e.width; ++i) {
            const Point a = axes.at(xe[i], ye[j]), b = axes.at(xe[i + 1], ye[j + 1]);
            const std::vector<Point> cell{{a.x, a.y}, {b.x, a.y}, {b.x, b.y}, {a.x, b.y}};
            c.fill(cell, inferno(e.luminance[static_cast<size_t>(j) * e.width + i] / vmax), true);
        }
    axes.decorate("optimized env map E*", false, s.font, s.title);
    c.polyline(std::vector<Point>{axes.at(0, 0), axes.at(360, 0)}, kHorizon, 1.2 * unit, true);
    TextStyle ts{s.small, kHorizon};
    ts.h = Align::End;
    ts.v = Align::End;
    c.text(axes.at(358, 2), "horizon", ts);
    markDirections(
        c, dirs, [&](const PlotDirection& d) { return axes.at(d.azimuthDeg, d.elevationDeg); },
        false, s.small, unit, [&] { c.clipRect(x, y, w, h); });
    if (legend) {
        std::vector<LegendEntry> entries;
        if (dirs.camera)
            entries.push_back({"camera (" + directionLabel(*dirs.camera) + ")", kCamera, false,
                               false, Marker::Circle});
        if (dirs.mirror)
            entries.push_back({"mirror (" + directionLabel(*dirs.mirror) + ")", kMirror, false,
                               false, Marker::Cross});
        axes.legend(entries, false, s.small);
    }
}

/// A vertical colour bar of [0, vmax] in (x, y, w, h) with its label on the right.
void drawColourBar(Canvas& c, double vmax, double x, double y, double w, double h, double font) {
    const int steps = static_cast<int>(std::ceil(h));
    for (int k = 0; k < steps; ++k) {
        const double y0 = y + h - (k + 1) * h / steps, y1 = y + h - k * h / steps;
        c.fill(std::vector<Point>{{x, y0}, {x + w, y0}, {x + w, y1}, {x, y1}},
               inferno((k + 0.5) / steps), true);
    }
    Axes bar(c, x, y, w, h, AxisSpec{0, 1, false, {}, {}, ""},
             AxisSpec{0, vmax, false, {}, {}, ""});
    c.strokeRect(x, y, w, h, kBlack, 1.0);
    TextStyle ts{font, kBlack};
    ts.v = Align::Centre;
    double widest = 0;
    for (double v : niceTicks(0, vmax, 5)) {
        const double py = bar.at(0, v).y;
        c.polyline(std::vector<Point>{{x + w, py}, {x + w + 0.35 * font, py}}, kBlack, 1.0);
        const std::string s = number("%g", v);
        widest = std::max(widest, c.textWidth(s, font));
        c.text({x + w + 0.7 * font, py}, s, ts);
    }
    ts.h = Align::Centre;
    ts.v = Align::Start;
    ts.angleDeg = 90;
    c.text({x + w + 0.9 * font + widest, y + h / 2}, "E (luminance)", ts);
}

/// The upper hemisphere seen from above: zenith at the centre, the horizon on the circle,
/// azimuth 0° (−z) at the top, clockwise; colours over [0, vmax].
void drawHemisphere(Canvas& c, const EnvMapPlot& e, const PlotDirections& dirs, Point centre,
                    double radius, const Scale& s, double vmax, const std::string& titleText) {
    auto pos = [&](double azDeg, double elDeg) {
        return hemispherePoint(centre, radius, azDeg, elDeg);
    };
    const std::vector<double> xe = edges(e.azimuthDeg, 0, 360);
    std::vector<int> rows;
    std::vector<double> el;
    for (int j = 0; j < e.height; ++j)
        if (e.elevationDeg[j] >= -1e-9) {
            rows.push_back(j);
            el.push_back(e.elevationDeg[j]);
        }
    c.fill(std::vector<Point>{pos(0, 0), pos(90, 0), pos(180, 0), pos(270, 0)}, kWhite);
    if (!rows.empty()) {
        const std::vector<double> ye = edges(el, 0, 90);
        for (size_t r = 0; r < rows.size(); ++r)
            for (int i = 0; i < e.width; ++i) {
                std::vector<Point> cell;
                const int n = 6;  // points along each arc
                for (int k = 0; k <= n; ++k)
                    cell.push_back(pos(xe[i] + (xe[i + 1] - xe[i]) * k / n, ye[r]));
                for (int k = n; k >= 0; --k)
                    cell.push_back(pos(xe[i] + (xe[i + 1] - xe[i]) * k / n, ye[r + 1]));
                c.fill(cell,
                       inferno(e.luminance[static_cast<size_t>(rows[r]) * e.width + i] / vmax),
                       true);
            }
    }
    const Colour grid{0.69, 0.69, 0.69, 0.4};
    for (double r : {30.0, 60.0}) c.circle(centre, r / 90 * radius, grid, 0.9);
    for (int a = 0; a < 360; a += 45) c.polyline(std::vector<Point>{centre, pos(a, 0)}, grid, 0.9);
    c.circle(centre, radius, kBlack, 1.0);
    const char* names[] = {"0° (−z)",   "45°",  "90° (+x)",  "135°",
                           "180° (+z)", "225°", "270° (−x)", "315°"};
    TextStyle ts{s.small * 1.0, kBlack};
    for (int k = 0; k < 8; ++k) {
        const double a = k * 45.0 * std::numbers::pi / 180;
        const double r = radius + 0.6 * s.small;
        const double sx = std::sin(a), sy = -std::cos(a);
        ts.h = sx > 0.3 ? Align::Start : sx < -0.3 ? Align::End : Align::Centre;
        ts.v = sy > 0.3 ? Align::Start : sy < -0.3 ? Align::End : Align::Centre;
        c.text({centre.x + r * sx, centre.y + r * sy}, names[k], ts);
    }
    TextStyle rs{s.small * 0.9, kBlack};
    rs.h = Align::Start;
    rs.v = Align::End;
    const std::pair<double, const char*> radial[] = {
        {60, "el 60°"}, {30, "el 30°"}, {0, "horizon"}};
    std::vector<Box> radialBoxes;
    for (const auto& [elv, text] : radial) {
        const Point p = pos(22.5, elv);
        c.label({p.x + 2, p.y - 2}, text, rs, Colour{1, 1, 1, 0.6});
        radialBoxes.push_back(c.labelBox({p.x + 2, p.y - 2}, text, rs));
    }
    TextStyle title{s.title, kBlack};
    title.h = Align::Centre;
    title.v = Align::End;
    c.text({centre.x, centre.y - radius - 1.9 * s.small - 0.4 * s.title}, titleText, title);
    markDirections(
        c, dirs, [&](const PlotDirection& d) { return pos(d.azimuthDeg, d.elevationDeg); }, true,
        s.small, s.small / 8, [&] { c.clipCircle(centre, radius + 6); }, radialBoxes);
}

/// The loss plot in the frame (x, y, w, h).
void drawLoss(Canvas& c, const LossCurve& l, const std::string& title, double x, double y, double w,
              double h, const Scale& s, double legendFont) {
    std::vector<double> values;
    for (const auto* v : {&l.loss, &l.held})
        for (double a : *v)
            if (std::isfinite(a)) values.push_back(a);
    const bool log = !values.empty() && *std::min_element(values.begin(), values.end()) > 0;
    double lo = values.empty() ? 0 : *std::min_element(values.begin(), values.end());
    double hi = values.empty() ? 1 : *std::max_element(values.begin(), values.end());
    AxisSpec ay;
    ay.log = log;
    ay.format = [](double v) { return number("%.3g", v); };
    if (log) {
        if (hi == lo) {
            lo /= 1.1;
            hi *= 1.1;
        }
        const double a = std::log10(lo), b = std::log10(hi), m = 0.05 * (b - a);
        ay.lo = std::pow(10.0, a - m);
        ay.hi = std::pow(10.0, b + m);
        const double coarse[] = {1, 2, 5}, fine[] = {1, 1.5, 2, 3, 4, 5, 7},
                     all[] = {1, 2, 3, 4, 5, 6, 7, 8, 9};
        ay.ticks = logTicks(
            ay.lo, ay.hi,
            hi / lo > 20 ? std::span<const double>(coarse) : std::span<const double>(fine));
        if (ay.ticks.size() < 3) ay.ticks = logTicks(ay.lo, ay.hi, all);
        if (ay.ticks.size() < 2) ay.ticks = niceTicks(ay.lo, ay.hi, 4);
        ay.label = "loss (log scale; lower is better)";
    } else {
        if (hi == lo) {
            lo -= std::max(1.0, std::abs(lo) * 0.1);
            hi += std::max(1.0, std::abs(hi) * 0.1);
        }
        const double m = 0.05 * (hi - lo);
        ay.lo = lo - m;
        ay.hi = hi + m;
        ay.ticks = niceTicks(ay.lo, ay.hi, 6);
        ay.label = "loss (lower is better; linear: some values ≤ 0)";
    }
    double x0 = l.iteration.front(), x1 = l.iteration.front();
    for (const auto* v : {&l.iteration, &l.heldIteration})
        for (double a : *v)
            if (std::isfinite(a)) {
                x0 = std::min(x0, a);
                x1 = std::max(x1, a);
            }
    if (!(x1 > x0)) {
        x0 -= 1;
        x1 += 1;
    }
    const double m = 0.05 * (x1 - x0);
    AxisSpec ax{x0 - m,
                x1 + m,
                false,
                niceTicks(x0, x1, 6, true),
                [](double v) { return number("%.0f", v + 0.0); },
                "iteration"};
    Axes axes(c, x, y, w, h, ax, ay);
    axes.decorate(title, true, s.font, s.title);
    const double unit = s.font / 10.0;  // pixels per point: the font is 10 pt
    axes.line(l.iteration, l.loss, kTraining, 1.5 * unit);
    std::vector<LegendEntry> entries{{"training loss", kTraining, true, false, {}}};
    if (!l.held.empty()) {
        axes.line(l.heldIteration, l.held, kHeld, 1.2 * unit, true, Marker::Circle);
        entries.push_back(
            {"the same loss on the independent estimate", kHeld, true, true, Marker::Circle});
    }
    axes.legend(entries, true, legendFont);
}

void checkView(const Image& img, const char* what) {
    if (img.width < 1 || img.height < 1 || (img.channels != 1 && img.channels != 3) ||
        img.data.size() != img.pixelCount() * static_cast<size_t>(img.channels))
        throw std::invalid_argument(std::string("overview: the render ") + what +
                                    " is empty or not 1 or 3 channels");
}

}  // namespace

Point hemispherePoint(Point centre, double radius, double azimuthDeg, double elevationDeg) {
    const double r = (90 - elevationDeg) / 90 * radius, a = azimuthDeg * std::numbers::pi / 180;
    return Point{centre.x + r * std::sin(a), centre.y - r * std::cos(a)};
}

void drawEnvMapHemisphere(Canvas& c, const EnvMapPlot& envmap, Point centre, double radius,
                          double vmax, const std::string& title) {
    check(envmap);
    drawHemisphere(c, envmap, PlotDirections{}, centre, radius, Scale{12.5, 10.0, 15.0},
                   vmax > 0 ? vmax : maxOf(envmap.luminance), title);
}

void drawEnvMapColourBar(Canvas& c, double vmax, double x, double y, double w, double h) {
    drawColourBar(c, std::max(vmax, 1e-9), x, y, w, h, 12.5);
}

Canvas envMapFigure(const EnvMapPlot& envmap, const PlotDirections& directions) {
    check(envmap);
    Canvas c(1170, 432);  // matplotlib's 13 × 4.8 in at 90 dpi
    const double unit = 90.0 / 72.0;
    const Scale s{12.5, 10.0, 15.0};
    drawLatLong(c, envmap, directions, 67, 32, 606, 348, s, unit, true);
    drawColourBar(c, maxOf(envmap.luminance), 686, 32, 20, 348, s.font);
    drawHemisphere(c, envmap, directions, {963, 222}, 150, s, maxOf(envmap.luminance),
                   "upper hemisphere seen from above");
    return c;
}

Canvas lossFigure(const LossCurve& loss, const std::string& title) {
    check(loss);
    Canvas c(675, 378);  // 7.5 × 4.2 in at 90 dpi
    drawLoss(c, loss, title, 78, 30, 582, 300, Scale{12.5, 10.0, 15.0}, 10.0);
    return c;
}

Canvas overviewFigure(const OptimizeFiguresInput& in) {
    check(in.envmap);
    check(in.loss);
    checkView(in.lampView, "under the lamp");
    checkView(in.optimizedView, "under E*");
    Canvas c(1360, 368);  // 17 × 4.6 in at 80 dpi
    const double unit = 80.0 / 72.0;
    const Scale s{11.1, 8.9, 13.3};
    TextStyle title{13.3, kBlack};
    title.h = Align::Centre;
    c.text({680, 6}, in.title, title);
    title.size = s.title;
    title.v = Align::End;
    const std::pair<const Image*, std::string> views[] = {
        {&in.lampView, in.lampTitle.empty() ? std::string("before") : in.lampTitle},
        {&in.optimizedView, "optimized"}};
    for (int k = 0; k < 2; ++k) {
        const double x = 12 + 292 * k, y = 72, size = 230;
        c.image(*views[k].first, x, y, size, size);
        c.text({x + size / 2, y - 0.5 * s.title}, views[k].second, title);
    }
    drawLatLong(c, in.envmap, in.directions, 597, 52, 391, 268, s, unit, false);
    drawLoss(c, in.loss, in.lossTitle, 1066, 52, 280, 268, s, 8.9);
    return c;
}

std::vector<std::filesystem::path> writeOptimizeFigures(const std::filesystem::path& dir,
                                                        const OptimizeFiguresInput& in) {
    // Every figure is drawn before any is written: bad input leaves no file behind.
    const std::vector<uint8_t> envmap = envMapFigure(in.envmap, in.directions).png();
    const std::vector<uint8_t> loss = lossFigure(in.loss, in.lossTitle).png();
    const std::vector<uint8_t> overview = overviewFigure(in).png();
    std::vector<std::filesystem::path> wrote;
    for (const auto& [name, bytes] :
         {std::pair{outdir::kPlotEnvMap, &envmap}, std::pair{outdir::kPlotLoss, &loss},
          std::pair{outdir::kOverview, &overview}}) {
        writeBytesAtomically(dir / name, bytes->data(), bytes->size());
        wrote.push_back(dir / name);
    }
    return wrote;
}

}  // namespace sl
