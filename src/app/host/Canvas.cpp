#include "app/host/Canvas.h"

#include <cairo/cairo.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>

#include "core/Color.h"
#include "io/PngBuffer.h"

namespace sl {

namespace {

// matplotlib's inferno at i/32, i = 0..32 (8-bit sRGB).
constexpr std::array<std::array<uint8_t, 3>, 33> kInferno{{
    {0, 0, 4},       {4, 3, 18},      {11, 7, 36},     {21, 11, 55},   {33, 12, 74},
    {47, 10, 91},    {61, 9, 101},    {74, 12, 107},   {87, 16, 110},  {100, 21, 110},
    {113, 25, 110},  {125, 30, 109},  {138, 34, 106},  {151, 39, 102}, {163, 44, 97},
    {176, 49, 91},   {188, 55, 84},   {199, 62, 76},   {210, 70, 68},  {219, 80, 59},
    {228, 90, 49},   {235, 102, 40},  {241, 115, 29},  {246, 128, 19}, {249, 142, 9},
    {251, 157, 7},   {252, 172, 17},  {251, 188, 33},  {249, 203, 53}, {245, 219, 76},
    {242, 234, 105}, {243, 246, 138}, {252, 255, 164},
}};

constexpr const char* kFace = "DejaVu Sans";

void setColour(cairo_t* cr, Colour c) {
    cairo_set_source_rgba(cr, c.r, c.g, c.b, c.a);
}

void path(cairo_t* cr, std::span<const Point> points) {
    cairo_new_path(cr);
    for (size_t k = 0; k < points.size(); ++k)
        if (k == 0)
            cairo_move_to(cr, points[k].x, points[k].y);
        else
            cairo_line_to(cr, points[k].x, points[k].y);
}

void setFont(cairo_t* cr, double size, bool bold) {
    cairo_select_font_face(cr, kFace, CAIRO_FONT_SLANT_NORMAL,
                           bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_font_size(cr, size);
}

uint8_t encoded(float linear) {
    return static_cast<uint8_t>(std::lround(255.0f * srgbEncode(linear)));
}

}  // namespace

Colour hexColour(uint32_t rgb, double alpha) {
    return {((rgb >> 16) & 0xFF) / 255.0, ((rgb >> 8) & 0xFF) / 255.0, (rgb & 0xFF) / 255.0, alpha};
}

Colour inferno(double t) {
    t = std::clamp(std::isfinite(t) ? t : 0.0, 0.0, 1.0) * 32.0;
    const size_t i = std::min<size_t>(static_cast<size_t>(t), 31);
    const double f = t - static_cast<double>(i);
    const auto& a = kInferno[i];
    const auto& b = kInferno[i + 1];
    auto mix = [&](int c) { return ((1 - f) * a[c] + f * b[c]) / 255.0; };
    return {mix(0), mix(1), mix(2), 1.0};
}

struct Canvas::State {
    cairo_surface_t* surface = nullptr;
    cairo_t* cr = nullptr;
    ~State() {
        if (cr) cairo_destroy(cr);
        if (surface) cairo_surface_destroy(surface);
    }
};

Canvas::Canvas(int width, int height) : s_(std::make_unique<State>()) {
    if (width < 1 || height < 1 || width > 16384 || height > 16384)
        throw std::invalid_argument("a canvas of " + std::to_string(width) + " x " +
                                    std::to_string(height) +
                                    " pixels: each side must be 1 to 16384");
    width_ = width;
    height_ = height;
    s_->surface = cairo_image_surface_create(CAIRO_FORMAT_RGB24, width, height);
    s_->cr = cairo_create(s_->surface);
    if (cairo_status(s_->cr) != CAIRO_STATUS_SUCCESS)
        throw std::runtime_error(std::string("cairo: ") +
                                 cairo_status_to_string(cairo_status(s_->cr)));
    // Text metrics without hinting: the same layout at every size.
    cairo_font_options_t* fo = cairo_font_options_create();
    cairo_font_options_set_hint_metrics(fo, CAIRO_HINT_METRICS_OFF);
    cairo_font_options_set_hint_style(fo, CAIRO_HINT_STYLE_NONE);
    cairo_font_options_set_antialias(fo, CAIRO_ANTIALIAS_GRAY);
    cairo_set_font_options(s_->cr, fo);
    cairo_font_options_destroy(fo);
    cairo_set_source_rgb(s_->cr, 1, 1, 1);
    cairo_paint(s_->cr);
}

Canvas::~Canvas() = default;
Canvas::Canvas(Canvas&&) noexcept = default;
Canvas& Canvas::operator=(Canvas&&) noexcept = default;

void Canvas::text(Point at, const std::string& utf8, const TextStyle& style) {
    cairo_t* cr = s_->cr;
    cairo_save(cr);
    setFont(cr, style.size, style.bold);
    cairo_text_extents_t te;
    cairo_text_extents(cr, utf8.c_str(), &te);
    cairo_font_extents_t fe;
    cairo_font_extents(cr, &fe);
    const double w = te.x_advance;
    const double dx = style.h == Align::Start ? 0 : style.h == Align::Centre ? -w / 2 : -w;
    const double dy = style.v == Align::Start    ? fe.ascent
                      : style.v == Align::Centre ? (fe.ascent - fe.descent) / 2
                                                 : -fe.descent;
    cairo_translate(cr, at.x, at.y);
    cairo_rotate(cr, -style.angleDeg * std::numbers::pi / 180.0);
    cairo_move_to(cr, dx, dy);
    setColour(cr, style.colour);
    cairo_show_text(cr, utf8.c_str());
    cairo_restore(cr);
}

double Canvas::textWidth(const std::string& utf8, double size, bool bold) const {
    cairo_t* cr = s_->cr;
    cairo_save(cr);
    setFont(cr, size, bold);
    cairo_text_extents_t te;
    cairo_text_extents(cr, utf8.c_str(), &te);
    cairo_restore(cr);
    return te.x_advance;
}

Box Canvas::labelBox(Point at, const std::string& utf8, const TextStyle& style) const {
    const double w = textWidth(utf8, style.size, style.bold);
    const double h = style.size * 1.17;  // DejaVu Sans: ascent + descent
    const double pad = 0.25 * style.size;
    double x = style.h == Align::Start ? at.x : style.h == Align::Centre ? at.x - w / 2 : at.x - w;
    double y = style.v == Align::Start ? at.y : style.v == Align::Centre ? at.y - h / 2 : at.y - h;
    // Inside the canvas, whatever the anchor asked.
    x = std::clamp(x, pad + 1, std::max(pad + 1, width_ - w - pad - 1));
    y = std::clamp(y, pad + 1, std::max(pad + 1, height_ - h - pad - 1));
    return {x - pad, y - pad, w + 2 * pad, h + 2 * pad};
}

void Canvas::label(Point at, const std::string& utf8, const TextStyle& style, Colour fill) {
    const Box box = labelBox(at, utf8, style);
    const double pad = 0.25 * style.size, x = box.x + pad, y = box.y + pad;
    cairo_t* cr = s_->cr;
    const double r = pad, bx = box.x, by = box.y, bw = box.w, bh = box.h;
    const double pi = std::numbers::pi;
    cairo_new_path(cr);
    cairo_arc(cr, bx + bw - r, by + r, r, -pi / 2, 0);
    cairo_arc(cr, bx + bw - r, by + bh - r, r, 0, pi / 2);
    cairo_arc(cr, bx + r, by + bh - r, r, pi / 2, pi);
    cairo_arc(cr, bx + r, by + r, r, pi, 3 * pi / 2);
    cairo_close_path(cr);
    setColour(cr, fill);
    cairo_fill(cr);
    TextStyle t = style;
    t.h = Align::Start;
    t.v = Align::Start;
    text({x, y}, utf8, t);
}

void Canvas::polyline(std::span<const Point> points, Colour colour, double lineWidth, bool dashed) {
    if (points.size() < 2) return;
    cairo_t* cr = s_->cr;
    cairo_save(cr);
    path(cr, points);
    if (dashed) {
        const double d[] = {3.7 * lineWidth, 1.6 * lineWidth};  // matplotlib's "--"
        cairo_set_dash(cr, d, 2, 0);
    }
    cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
    cairo_set_line_cap(cr, dashed ? CAIRO_LINE_CAP_BUTT : CAIRO_LINE_CAP_SQUARE);
    cairo_set_line_width(cr, lineWidth);
    setColour(cr, colour);
    cairo_stroke(cr);
    cairo_restore(cr);
}

void Canvas::fill(std::span<const Point> points, Colour colour, bool crisp) {
    if (points.size() < 3) return;
    cairo_t* cr = s_->cr;
    cairo_save(cr);
    if (crisp) cairo_set_antialias(cr, CAIRO_ANTIALIAS_NONE);
    path(cr, points);
    cairo_close_path(cr);
    setColour(cr, colour);
    cairo_fill(cr);
    cairo_restore(cr);
}

void Canvas::strokeRect(double x, double y, double w, double h, Colour colour, double lineWidth) {
    cairo_t* cr = s_->cr;
    cairo_new_path(cr);
    cairo_rectangle(cr, x, y, w, h);
    cairo_set_line_width(cr, lineWidth);
    setColour(cr, colour);
    cairo_stroke(cr);
}

void Canvas::circle(Point centre, double radius, Colour colour, double lineWidth) {
    cairo_t* cr = s_->cr;
    cairo_new_path(cr);
    cairo_arc(cr, centre.x, centre.y, radius, 0, 2 * std::numbers::pi);
    cairo_set_line_width(cr, lineWidth);
    setColour(cr, colour);
    cairo_stroke(cr);
}

void Canvas::marker(Point at, Marker shape, double size, Colour fillColour, Colour edge) {
    cairo_t* cr = s_->cr;
    const double r = size / 2;
    cairo_new_path(cr);
    switch (shape) {
        case Marker::Circle:
            cairo_arc(cr, at.x, at.y, r, 0, 2 * std::numbers::pi);
            break;
        case Marker::Cross: {  // matplotlib's filled "X"
            const double a = r, b = r * 0.33;
            const Point p[] = {{0, b},  {a - b, a},  {a, a - b},  {b, 0},  {a, b - a},  {a - b, -a},
                               {0, -b}, {b - a, -a}, {-a, b - a}, {-b, 0}, {-a, a - b}, {b - a, a}};
            for (size_t k = 0; k < std::size(p); ++k)
                (k ? cairo_line_to : cairo_move_to)(cr, at.x + p[k].x, at.y + p[k].y);
            cairo_close_path(cr);
            break;
        }
        case Marker::Star:
            for (int k = 0; k < 10; ++k) {
                const double rr = k % 2 ? r * 0.38 : r;
                const double ang = -std::numbers::pi / 2 + k * std::numbers::pi / 5;
                (k ? cairo_line_to : cairo_move_to)(cr, at.x + rr * std::cos(ang),
                                                    at.y + rr * std::sin(ang));
            }
            cairo_close_path(cr);
            break;
    }
    setColour(cr, fillColour);
    cairo_fill_preserve(cr);
    cairo_set_line_width(cr, 1.0);
    setColour(cr, edge);
    cairo_stroke(cr);
}

void Canvas::image(const Image& img, double x, double y, double w, double h) {
    if (img.width < 1 || img.height < 1 || (img.channels != 1 && img.channels != 3) ||
        img.data.size() != img.pixelCount() * static_cast<size_t>(img.channels))
        throw std::invalid_argument("an image of " + std::to_string(img.width) + " x " +
                                    std::to_string(img.height) + " x " +
                                    std::to_string(img.channels) +
                                    " values: a figure shows 1 or 3 channels of at least 1 pixel");
    cairo_surface_t* src = cairo_image_surface_create(CAIRO_FORMAT_RGB24, img.width, img.height);
    cairo_surface_flush(src);
    unsigned char* data = cairo_image_surface_get_data(src);
    const int stride = cairo_image_surface_get_stride(src);
    for (int row = 0; row < img.height; ++row) {
        auto* px = reinterpret_cast<uint32_t*>(data + static_cast<ptrdiff_t>(row) * stride);
        for (int col = 0; col < img.width; ++col) {
            const uint32_t r = encoded(img.at(col, row, 0));
            const uint32_t g = img.channels == 3 ? encoded(img.at(col, row, 1)) : r;
            const uint32_t b = img.channels == 3 ? encoded(img.at(col, row, 2)) : r;
            px[col] = (r << 16) | (g << 8) | b;
        }
    }
    cairo_surface_mark_dirty(src);
    const double scale = std::min(w / img.width, h / img.height);
    const double ox = x + (w - scale * img.width) / 2, oy = y + (h - scale * img.height) / 2;
    cairo_t* cr = s_->cr;
    cairo_save(cr);
    cairo_translate(cr, ox, oy);
    cairo_scale(cr, scale, scale);
    cairo_set_source_surface(cr, src, 0, 0);
    cairo_pattern_set_filter(cairo_get_source(cr), CAIRO_FILTER_NEAREST);
    cairo_rectangle(cr, 0, 0, img.width, img.height);
    cairo_fill(cr);
    cairo_restore(cr);
    cairo_surface_destroy(src);
}

void Canvas::clipRect(double x, double y, double w, double h) {
    cairo_save(s_->cr);
    cairo_new_path(s_->cr);
    cairo_rectangle(s_->cr, x, y, w, h);
    cairo_clip(s_->cr);
}

void Canvas::clipCircle(Point centre, double radius) {
    cairo_save(s_->cr);
    cairo_new_path(s_->cr);
    cairo_arc(s_->cr, centre.x, centre.y, radius, 0, 2 * std::numbers::pi);
    cairo_clip(s_->cr);
}

void Canvas::unclip() {
    cairo_restore(s_->cr);
}

std::vector<uint8_t> Canvas::png() const {
    // zlib directly (io/PngBuffer.h), no row filter: cairo's writer (libpng's adaptive filters)
    // took ~8 % of a cached optimize run for the same pixels; at zlib's fastest level, as the
    // previews (level 6 was ~5 % of such a run's CPU).
    const std::vector<uint8_t> px = rgb();
    const std::string bytes = encodePng(px.data(), width_, height_, 3, 8, PngColour::None, 1);
    return std::vector<uint8_t>(bytes.begin(), bytes.end());
}

std::vector<uint8_t> Canvas::rgb() const {
    cairo_surface_flush(s_->surface);
    const unsigned char* data = cairo_image_surface_get_data(s_->surface);
    const int stride = cairo_image_surface_get_stride(s_->surface);
    std::vector<uint8_t> out(static_cast<size_t>(width_) * height_ * 3);
    for (int row = 0; row < height_; ++row) {
        const auto* px =
            reinterpret_cast<const uint32_t*>(data + static_cast<ptrdiff_t>(row) * stride);
        for (int col = 0; col < width_; ++col) {
            const size_t o = (static_cast<size_t>(row) * width_ + col) * 3;
            out[o] = static_cast<uint8_t>(px[col] >> 16);
            out[o + 1] = static_cast<uint8_t>(px[col] >> 8);
            out[o + 2] = static_cast<uint8_t>(px[col]);
        }
    }
    return out;
}

// ---- Axes ----

std::vector<double> niceTicks(double lo, double hi, int bins, bool integer) {
    if (!(hi > lo) || !std::isfinite(lo) || !std::isfinite(hi) || bins < 1) return {lo};
    const double raw = (hi - lo) / bins;
    const double mag = std::pow(10.0, std::floor(std::log10(raw)));
    double step = 10 * mag;
    for (double m : {1.0, 2.0, 2.5, 5.0, 10.0})
        if (m * mag >= raw && (!integer || m * mag >= 1.0)) {
            step = m * mag;
            break;
        }
    if (integer) step = std::max(1.0, std::round(step));
    std::vector<double> t;
    for (double v = std::ceil(lo / step - 1e-9) * step; v <= hi + 1e-9 * step; v += step)
        t.push_back(std::abs(v) < 1e-12 * step ? 0.0 : v);
    return t;
}

std::vector<double> logTicks(double lo, double hi, std::span<const double> subs) {
    std::vector<double> t;
    if (!(lo > 0) || !(hi >= lo) || !std::isfinite(hi)) return t;
    for (int k = static_cast<int>(std::floor(std::log10(lo))) - 1;
         k <= static_cast<int>(std::ceil(std::log10(hi))); ++k)
        for (double s : subs) {
            const double v = s * std::pow(10.0, k);
            if (v >= lo * (1 - 1e-12) && v <= hi * (1 + 1e-12)) t.push_back(v);
        }
    std::sort(t.begin(), t.end());
    return t;
}

Axes::Axes(Canvas& canvas, double x, double y, double w, double h, AxisSpec xAxis, AxisSpec yAxis)
    : c_(canvas), x_(x), y_(y), w_(w), h_(h), xa_(std::move(xAxis)), ya_(std::move(yAxis)) {
    if (!(w > 0 && h > 0)) throw std::invalid_argument("axes with an empty frame");
    for (const AxisSpec* a : {&xa_, &ya_}) {
        if (!std::isfinite(a->lo) || !std::isfinite(a->hi) || !(a->hi > a->lo))
            throw std::invalid_argument("an axis from " + std::to_string(a->lo) + " to " +
                                        std::to_string(a->hi) + ": needs finite lo < hi");
        if (a->log && !(a->lo > 0)) throw std::invalid_argument("a log axis needs a range above 0");
    }
}

double Axes::map(const AxisSpec& a, double v) const {
    if (a.log) return (std::log10(v) - std::log10(a.lo)) / (std::log10(a.hi) - std::log10(a.lo));
    return (v - a.lo) / (a.hi - a.lo);
}

Point Axes::at(double x, double y) const {
    return {x_ + map(xa_, x) * w_, y_ + (1 - map(ya_, y)) * h_};
}

void Axes::decorate(const std::string& title, bool grid, double fontSize, double titleSize) {
    const Colour black{0, 0, 0, 1}, gridColour{0.69, 0.69, 0.69, 0.5};
    const double tick = 0.35 * fontSize, pad = 0.35 * fontSize;
    auto fmt = [](const AxisSpec& a, double v) {
        if (a.format) return a.format(v);
        char b[32];
        std::snprintf(b, sizeof b, "%g", v);
        return std::string(b);
    };
    TextStyle ts{fontSize, black};
    for (double v : xa_.ticks) {
        const double px = at(v, ya_.lo).x;
        if (px < x_ - 0.5 || px > x_ + w_ + 0.5) continue;
        if (grid) c_.polyline(std::vector<Point>{{px, y_}, {px, y_ + h_}}, gridColour, 0.9);
        c_.polyline(std::vector<Point>{{px, y_ + h_}, {px, y_ + h_ + tick}}, black, 1.0);
        ts.h = Align::Centre;
        ts.v = Align::Start;
        c_.text({px, y_ + h_ + tick + pad}, fmt(xa_, v), ts);
    }
    double widest = 0;
    for (double v : ya_.ticks) {
        const double py = at(xa_.lo, v).y;
        if (py < y_ - 0.5 || py > y_ + h_ + 0.5) continue;
        if (grid) c_.polyline(std::vector<Point>{{x_, py}, {x_ + w_, py}}, gridColour, 0.9);
        c_.polyline(std::vector<Point>{{x_ - tick, py}, {x_, py}}, black, 1.0);
        const std::string s = fmt(ya_, v);
        widest = std::max(widest, c_.textWidth(s, fontSize));
        ts.h = Align::End;
        ts.v = Align::Centre;
        c_.text({x_ - tick - pad, py}, s, ts);
    }
    c_.strokeRect(x_, y_, w_, h_, black, 1.0);
    ts.h = Align::Centre;
    // An axis label longer than its side (and a little more) is set smaller to fit.
    auto fitted = [&](const std::string& s, double side) {
        const double w = c_.textWidth(s, fontSize);
        return w > side + 2 * fontSize ? fontSize * (side + 2 * fontSize) / w : fontSize;
    };
    if (!xa_.label.empty()) {
        ts.v = Align::Start;
        ts.size = fitted(xa_.label, w_);
        c_.text({x_ + w_ / 2, y_ + h_ + tick + 2 * pad + 1.2 * fontSize}, xa_.label, ts);
    }
    if (!ya_.label.empty()) {
        ts.v = Align::End;
        ts.angleDeg = 90;
        ts.size = fitted(ya_.label, h_);
        c_.text({x_ - tick - 2 * pad - widest, y_ + h_ / 2}, ya_.label, ts);
        ts.angleDeg = 0;
    }
    ts.size = fontSize;
    if (!title.empty()) {
        ts.size = titleSize;
        ts.v = Align::End;
        c_.text({x_ + w_ / 2, y_ - 0.5 * titleSize}, title, ts);
    }
}

void Axes::line(std::span<const double> xs, std::span<const double> ys, Colour colour,
                double lineWidth, bool dashed, std::optional<Marker> marker) {
    std::vector<Point> pts;
    const size_t n = std::min(xs.size(), ys.size());
    for (size_t k = 0; k < n; ++k) {
        const bool ok = std::isfinite(xs[k]) && std::isfinite(ys[k]) && (!xa_.log || xs[k] > 0) &&
                        (!ya_.log || ys[k] > 0);
        if (ok) pts.push_back(at(xs[k], ys[k]));
    }
    c_.clipRect(x_, y_, w_, h_);
    c_.polyline(pts, colour, lineWidth, dashed);
    if (marker)
        for (const Point& p : pts) c_.marker(p, *marker, 5.5, colour, colour);
    c_.unclip();
}

void Axes::legend(const std::vector<LegendEntry>& entries, bool upperRight, double fontSize) {
    if (entries.empty()) return;
    double textW = 0;
    for (const LegendEntry& e : entries) textW = std::max(textW, c_.textWidth(e.text, fontSize));
    const double handle = 2.0 * fontSize, gap = 0.8 * fontSize, rowH = 1.5 * fontSize;
    const double pad = 0.5 * fontSize, margin = 0.5 * fontSize;
    const double bw = pad + handle + gap + textW + pad;
    const double bh = pad + rowH * static_cast<double>(entries.size()) + pad - 0.3 * fontSize;
    const double bx = upperRight ? x_ + w_ - margin - bw : x_ + margin;
    const double by = upperRight ? y_ + margin : y_ + h_ - margin - bh;
    const std::vector<Point> box{{bx, by}, {bx + bw, by}, {bx + bw, by + bh}, {bx, by + bh}};
    c_.fill(box, Colour{1, 1, 1, 0.85});
    c_.strokeRect(bx, by, bw, bh, Colour{0.8, 0.8, 0.8, 1}, 1.0);
    TextStyle ts{fontSize, Colour{0, 0, 0, 1}};
    ts.v = Align::Centre;
    for (size_t k = 0; k < entries.size(); ++k) {
        const LegendEntry& e = entries[k];
        const double cy = by + pad + rowH * (static_cast<double>(k) + 0.5) - 0.15 * fontSize;
        if (e.line)
            c_.polyline(std::vector<Point>{{bx + pad, cy}, {bx + pad + handle, cy}}, e.colour, 1.5,
                        e.dashed);
        if (e.marker)
            c_.marker({bx + pad + handle / 2, cy}, *e.marker, e.line ? 5.5 : 0.8 * fontSize,
                      e.colour, e.line ? e.colour : Colour{0, 0, 0, 1});
        c_.text({bx + pad + handle + gap, cy}, e.text, ts);
    }
}

}  // namespace sl
