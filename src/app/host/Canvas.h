// A figure drawn in-process: a white RGB canvas of whole pixels with antialiased text (DejaVu
// Sans, matplotlib's default face), lines, markers, filled polygons and images, encoded as PNG
// in memory; and `Axes`, a rectangle of it with data coordinates (linear or log), ticks, grid,
// labels and a legend. The one file that includes cairo (Debian libcairo2-dev); no process is
// started and nothing is read. The same calls give the same PNG bytes (no date or software
// metadata). Coordinates are pixels, x to the right, y down, (0, 0) the top-left corner.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/Image.h"

namespace sl {

/// An sRGB colour with opacity, components in [0, 1].
struct Colour {
    double r = 0, g = 0, b = 0, a = 1;
};
/// 0xRRGGBB as a Colour.
Colour hexColour(uint32_t rgb, double alpha = 1.0);

/// The `inferno` colour map (matplotlib's, sampled at 33 points, interpolated linearly) at
/// t in [0, 1] (clamped).
Colour inferno(double t);

struct Point {
    double x = 0, y = 0;
};

struct Box {
    double x = 0, y = 0, w = 0, h = 0;
    bool overlaps(const Box& o) const {
        return x < o.x + o.w && o.x < x + w && y < o.y + o.h && o.y < y + h;
    }
};

enum class Align { Start, Centre, End };  // left/top, centre, right/bottom
enum class Marker { Circle, Cross, Star };

struct TextStyle {
    double size = 12.5;  // pixels (matplotlib's 10 pt at 90 dpi)
    Colour colour{};
    bool bold = false;
    Align h = Align::Start, v = Align::Start;
    double angleDeg = 0;  // counter-clockwise, about the anchor
};

class Canvas {
  public:
    /// A white canvas; throws std::invalid_argument unless 1 <= width, height <= 16384.
    Canvas(int width, int height);
    ~Canvas();
    Canvas(Canvas&&) noexcept;
    Canvas& operator=(Canvas&&) noexcept;
    Canvas(const Canvas&) = delete;
    Canvas& operator=(const Canvas&) = delete;

    int width() const { return width_; }
    int height() const { return height_; }

    /// UTF-8 text anchored at `at` as the style aligns it.
    void text(Point at, const std::string& utf8, const TextStyle& style);
    /// The width and height of text in pixels (its ink box's advance and the font's height).
    double textWidth(const std::string& utf8, double size, bool bold = false) const;
    /// Text on a rounded box of `fill` (an annotation), kept inside the canvas.
    void label(Point at, const std::string& utf8, const TextStyle& style, Colour fill);
    /// The box label() would fill, without drawing it.
    Box labelBox(Point at, const std::string& utf8, const TextStyle& style) const;

    void polyline(std::span<const Point> points, Colour colour, double lineWidth,
                  bool dashed = false);
    /// A closed polygon; `crisp`: no antialiasing (cells that tile without seams).
    void fill(std::span<const Point> points, Colour colour, bool crisp = false);
    void strokeRect(double x, double y, double w, double h, Colour colour, double lineWidth);
    void circle(Point centre, double radius, Colour colour, double lineWidth);
    /// A marker of `size` pixels across, filled with `fill` and edged with `edge`.
    void marker(Point at, Marker shape, double size, Colour fill, Colour edge);
    /// A linear image (1 or 3 channels; shown sRGB-encoded, clamped to [0, 1], as io/ImageIO.h's
    /// writePng shows it) scaled into the box with nearest-neighbour sampling, aspect kept and
    /// centred. Throws std::invalid_argument for an empty image or other channel counts.
    void image(const Image& img, double x, double y, double w, double h);

    /// Later drawing only inside the rectangle (or the circle) until unclip().
    void clipRect(double x, double y, double w, double h);
    void clipCircle(Point centre, double radius);
    void unclip();

    /// The canvas as an 8-bit RGB PNG.
    std::vector<uint8_t> png() const;
    /// The pixels, RGB, row-major, top row first (for checks).
    std::vector<uint8_t> rgb() const;

  private:
    struct State;
    std::unique_ptr<State> s_;
    int width_ = 0, height_ = 0;
};

/// One axis of an Axes: its range, scale and ticks (values and their labels).
struct AxisSpec {
    double lo = 0, hi = 1;
    bool log = false;
    std::vector<double> ticks;
    std::function<std::string(double)> format;  // tick label; unset: "%g"
    std::string label;
};

/// Up to `bins` + 1 ticks at a nice step (1, 2, 2.5, 5 × 10^k) covering [lo, hi]; integers
/// only when `integer` (matplotlib's MaxNLocator).
std::vector<double> niceTicks(double lo, double hi, int bins, bool integer = false);
/// The ticks of a log axis over [lo, hi] (lo > 0): 10^k × each of `subs` inside the range.
std::vector<double> logTicks(double lo, double hi, std::span<const double> subs);

/// A legend entry: a line sample, a marker, or both.
struct LegendEntry {
    std::string text;
    Colour colour{};
    bool line = false;
    bool dashed = false;
    std::optional<Marker> marker;
};

class Axes {
  public:
    /// The data rectangle's frame in pixels. Throws std::invalid_argument for an empty frame,
    /// an empty or non-finite range, or a log axis whose range is not > 0.
    Axes(Canvas& canvas, double x, double y, double w, double h, AxisSpec xAxis, AxisSpec yAxis);

    Point at(double x, double y) const;
    double left() const { return x_; }
    double top() const { return y_; }
    double width() const { return w_; }
    double height() const { return h_; }

    /// The frame, ticks and their labels, axis labels, the title and (when `grid`) grid lines.
    void decorate(const std::string& title, bool grid, double fontSize = 12.5,
                  double titleSize = 15.0);
    /// A data polyline (points outside a log axis' domain or non-finite are skipped).
    void line(std::span<const double> xs, std::span<const double> ys, Colour colour,
              double lineWidth, bool dashed = false, std::optional<Marker> marker = {});
    /// A legend box in the upper-right (upper = true) or lower-left corner.
    void legend(const std::vector<LegendEntry>& entries, bool upperRight, double fontSize);

  private:
    Canvas& c_;
    double x_, y_, w_, h_;
    AxisSpec xa_, ya_;
    double map(const AxisSpec& a, double v) const;  // 0..1 along the axis
};

}  // namespace sl
