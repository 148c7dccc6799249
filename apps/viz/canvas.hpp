#pragma once
// A small drawing surface for floesim's pictures (render, plot): an RGB image
// in pixels (origin top-left, y down) with the few primitives the pictures
// need, written as PNG. Cairo stays behind this header (canvas.cpp).

#include <cstdint>
#include <memory>
#include <span>
#include <string>

namespace floesim::viz {

struct Rgb {
  double r = 0, g = 0, b = 0;  // each in [0, 1]
};
struct Point {
  double x = 0, y = 0;  // pixels
};
struct Rect {
  double x = 0, y = 0, w = 0, h = 0;  // pixels: left, top, width, height
};

enum class Align { left, centre, right };

class Canvas {
public:
  // A white image of width x height pixels.
  Canvas(int width, int height);
  ~Canvas();
  Canvas(const Canvas&) = delete;
  Canvas& operator=(const Canvas&) = delete;

  int width() const;
  int height() const;

  void fill_rect(const Rect& r, Rgb colour, double alpha = 1.0);
  void stroke_rect(const Rect& r, Rgb colour, double line_width);
  void line(Point a, Point b, Rgb colour, double line_width);
  // A closed polygon filled with `fill` and outlined with `outline`
  // (line_width 0: no outline).
  void polygon(std::span<const Point> points, Rgb fill, Rgb outline, double line_width);
  // An open polyline; a non-finite point breaks it into pieces.
  void polyline(std::span<const Point> points, Rgb colour, double line_width);

  // An image of w x h pixels (row-major, top row first, 0x00RRGGBB each),
  // stretched onto `target`; `smooth` interpolates bilinearly between pixel
  // centres (for fields sampled at points), otherwise nearest pixel.
  void image(std::span<const std::uint32_t> pixels, int w, int h, const Rect& target, bool smooth);

  // Text with its baseline at y (vertical_up: rotated to read bottom to top,
  // aligned along the rotated direction). Sizes in pixels.
  void text(Point at, const std::string& s, double size, Rgb colour, Align align = Align::left,
            bool vertical_up = false);
  double text_width(const std::string& s, double size) const;

  // Drawing is limited to r until reset_clip().
  void clip(const Rect& r);
  void reset_clip();

  // The colour of pixel (x, y), for tests.
  Rgb pixel(int x, int y) const;
  // Writes the PNG; InputError naming the path if it cannot be written.
  void save_png(const std::string& path) const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// 0x00RRGGBB of a colour, each channel rounded to 8 bits.
std::uint32_t pack(Rgb c);

}  // namespace floesim::viz
