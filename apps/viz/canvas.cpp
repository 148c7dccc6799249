#include "apps/viz/canvas.hpp"

#include <cairo.h>

#include <algorithm>
#include <cmath>

#include "core/error.hpp"

namespace floesim::viz {

struct Canvas::Impl {
  cairo_surface_t* surface = nullptr;
  cairo_t* cr = nullptr;
  int width = 0, height = 0;
  ~Impl() {
    if (cr) cairo_destroy(cr);
    if (surface) cairo_surface_destroy(surface);
  }
  void colour(Rgb c, double alpha = 1.0) const { cairo_set_source_rgba(cr, c.r, c.g, c.b, alpha); }
  void font(double size) const {
    cairo_select_font_face(cr, "DejaVu Sans", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_font_size(cr, size);
  }
};

Canvas::Canvas(int width, int height) : impl_(std::make_unique<Impl>()) {
  if (width < 1 || height < 1 || width > 16384 || height > 16384)
    throw InputError("picture size " + std::to_string(width) + "x" + std::to_string(height) +
                     ": expected 1 to 16384 pixels each way");
  impl_->width = width;
  impl_->height = height;
  impl_->surface = cairo_image_surface_create(CAIRO_FORMAT_RGB24, width, height);
  impl_->cr = cairo_create(impl_->surface);
  if (cairo_status(impl_->cr) != CAIRO_STATUS_SUCCESS) throw RunError("cairo: cannot create a picture of this size");
  cairo_set_source_rgb(impl_->cr, 1, 1, 1);
  cairo_paint(impl_->cr);
  cairo_set_line_join(impl_->cr, CAIRO_LINE_JOIN_ROUND);
}

Canvas::~Canvas() = default;

int Canvas::width() const { return impl_->width; }
int Canvas::height() const { return impl_->height; }

void Canvas::fill_rect(const Rect& r, Rgb colour, double alpha) {
  cairo_rectangle(impl_->cr, r.x, r.y, r.w, r.h);
  impl_->colour(colour, alpha);
  cairo_fill(impl_->cr);
}

void Canvas::stroke_rect(const Rect& r, Rgb colour, double line_width) {
  cairo_rectangle(impl_->cr, r.x, r.y, r.w, r.h);
  impl_->colour(colour);
  cairo_set_line_width(impl_->cr, line_width);
  cairo_stroke(impl_->cr);
}

void Canvas::line(Point a, Point b, Rgb colour, double line_width) {
  cairo_move_to(impl_->cr, a.x, a.y);
  cairo_line_to(impl_->cr, b.x, b.y);
  impl_->colour(colour);
  cairo_set_line_width(impl_->cr, line_width);
  cairo_stroke(impl_->cr);
}

void Canvas::polygon(std::span<const Point> points, Rgb fill, Rgb outline, double line_width) {
  if (points.size() < 3) return;
  cairo_t* cr = impl_->cr;
  cairo_move_to(cr, points[0].x, points[0].y);
  for (std::size_t k = 1; k < points.size(); ++k) cairo_line_to(cr, points[k].x, points[k].y);
  cairo_close_path(cr);
  impl_->colour(fill);
  if (line_width <= 0) {
    cairo_fill(cr);
    return;
  }
  cairo_fill_preserve(cr);
  impl_->colour(outline);
  cairo_set_line_width(cr, line_width);
  cairo_stroke(cr);
}

void Canvas::polyline(std::span<const Point> points, Rgb colour, double line_width) {
  cairo_t* cr = impl_->cr;
  bool open = false;
  for (const Point& p : points) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y)) { open = false; continue; }
    if (open) cairo_line_to(cr, p.x, p.y);
    else cairo_move_to(cr, p.x, p.y);
    open = true;
  }
  impl_->colour(colour);
  cairo_set_line_width(cr, line_width);
  cairo_stroke(cr);
}

void Canvas::image(std::span<const std::uint32_t> pixels, int w, int h, const Rect& target, bool smooth) {
  if (w < 1 || h < 1 || pixels.size() < static_cast<std::size_t>(w) * static_cast<std::size_t>(h)) return;
  cairo_surface_t* src = cairo_image_surface_create(CAIRO_FORMAT_RGB24, w, h);
  cairo_surface_flush(src);
  unsigned char* data = cairo_image_surface_get_data(src);
  const int stride = cairo_image_surface_get_stride(src);
  for (int j = 0; j < h; ++j)
    std::copy_n(pixels.data() + static_cast<std::size_t>(j) * static_cast<std::size_t>(w), w,
                reinterpret_cast<std::uint32_t*>(data + static_cast<std::ptrdiff_t>(j) * stride));
  cairo_surface_mark_dirty(src);
  cairo_t* cr = impl_->cr;
  cairo_save(cr);
  cairo_rectangle(cr, target.x, target.y, target.w, target.h);
  cairo_clip(cr);
  cairo_translate(cr, target.x, target.y);
  cairo_scale(cr, target.w / w, target.h / h);
  cairo_set_source_surface(cr, src, 0, 0);
  cairo_pattern_t* pattern = cairo_get_source(cr);
  // PAD: the outer half pixel keeps the edge value instead of fading out.
  cairo_pattern_set_extend(pattern, CAIRO_EXTEND_PAD);
  cairo_pattern_set_filter(pattern, smooth ? CAIRO_FILTER_BILINEAR : CAIRO_FILTER_NEAREST);
  cairo_paint(cr);
  cairo_restore(cr);
  cairo_surface_destroy(src);
}

void Canvas::text(Point at, const std::string& s, double size, Rgb colour, Align align, bool vertical_up) {
  cairo_t* cr = impl_->cr;
  impl_->font(size);
  cairo_text_extents_t e;
  cairo_text_extents(cr, s.c_str(), &e);
  const double shift = align == Align::left ? 0.0 : align == Align::centre ? -0.5 * e.x_advance : -e.x_advance;
  cairo_save(cr);
  cairo_translate(cr, at.x, at.y);
  if (vertical_up) cairo_rotate(cr, -M_PI / 2);
  cairo_move_to(cr, shift, 0);
  impl_->colour(colour);
  cairo_show_text(cr, s.c_str());
  cairo_restore(cr);
}

double Canvas::text_width(const std::string& s, double size) const {
  impl_->font(size);
  cairo_text_extents_t e;
  cairo_text_extents(impl_->cr, s.c_str(), &e);
  return e.x_advance;
}

void Canvas::clip(const Rect& r) {
  cairo_reset_clip(impl_->cr);
  cairo_rectangle(impl_->cr, r.x, r.y, r.w, r.h);
  cairo_clip(impl_->cr);
}

void Canvas::reset_clip() { cairo_reset_clip(impl_->cr); }

Rgb Canvas::pixel(int x, int y) const {
  if (x < 0 || y < 0 || x >= impl_->width || y >= impl_->height) return {};
  cairo_surface_flush(impl_->surface);
  const unsigned char* data = cairo_image_surface_get_data(impl_->surface);
  const int stride = cairo_image_surface_get_stride(impl_->surface);
  const std::uint32_t v = *reinterpret_cast<const std::uint32_t*>(data + static_cast<std::ptrdiff_t>(y) * stride + 4 * x);
  return {((v >> 16) & 255) / 255.0, ((v >> 8) & 255) / 255.0, (v & 255) / 255.0};
}

void Canvas::save_png(const std::string& path) const {
  cairo_surface_flush(impl_->surface);
  const cairo_status_t status = cairo_surface_write_to_png(impl_->surface, path.c_str());
  if (status != CAIRO_STATUS_SUCCESS)
    throw InputError(path + ": cannot write the PNG (" + cairo_status_to_string(status) + ")");
}

std::uint32_t pack(Rgb c) {
  auto channel = [](double v) {
    return static_cast<std::uint32_t>(std::lround(255.0 * std::clamp(v, 0.0, 1.0)));
  };
  return channel(c.r) << 16 | channel(c.g) << 8 | channel(c.b);
}

}  // namespace floesim::viz
