#include "fluid/sea.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/error.hpp"
#include "fluid/bem.hpp"
#include "fluid/bem3d.hpp"
#include "fluid/spectral.hpp"
#include "fluid/waves.hpp"

namespace floesim::fluid {

Sea::Sea(const SurfaceGrid& grid) : grid_(grid) {}

Sea::~Sea() = default;

void Sea::step(double dt, const PressureFn& pressure) {
  if (p_scratch_.size() != grid_.size()) p_scratch_.assign(grid_.size(), 0.0);
  pressure(*this, time_, p_scratch_);
  kick(p_scratch_, 0.5 * dt);
  flow(dt);
  pressure(*this, time_, p_scratch_);
  kick(p_scratch_, 0.5 * dt);
}

void Sea::midpoint_free_elevation(double h, std::span<double> eta) {
  settle();
  modal_a_.resize(bank_.q().size());
  bank_.midpoint_free(h, modal_a_);
  synthesize(modal_a_, eta);
}

void Sea::midpoint_response(std::span<const double> p, double h, std::span<double> eta) {
  modal_a_.resize(bank_.q().size());
  modal_b_.resize(bank_.q().size());
  project(p, modal_a_);
  bank_.midpoint_response(modal_a_, h, modal_b_);
  synthesize(modal_b_, eta);
  add_static_response(p, modal_a_, eta);
}

void Sea::midpoint_step(std::span<const double> p, double h) {
  settle();
  modal_a_.resize(bank_.q().size());
  project(p, modal_a_);
  bank_.midpoint(modal_a_, h);
  hold(p, modal_a_);
  time_ += h;
  invalidate();
}

void Sea::hold_pressure(std::span<const double> p) {
  if (!has_static_part()) return;
  settle();
  modal_a_.resize(bank_.q().size());
  project(p, modal_a_);
  hold(p, modal_a_);
  invalidate();
}

namespace {
bool all_finite(std::span<const double> values) {
  return std::all_of(values.begin(), values.end(), [](double x) { return std::isfinite(x); });
}
}  // namespace

bool Sea::finite_state() const {
  return all_finite(bank_.q()) && all_finite(bank_.v()) && all_finite(held_pressure());
}

void Sea::gather_modal_state(std::vector<double>& q, std::vector<double>& v) {
  settle();
  q.assign(bank_.q().begin(), bank_.q().end());
  v.assign(bank_.v().begin(), bank_.v().end());
}

void Sea::set_modal_state(std::span<const double> q, std::span<const double> v) {
  ModalBank& bank = modes();
  FLOESIM_ASSERT(q.size() == bank.q().size() && v.size() == bank.v().size());
  std::copy(q.begin(), q.end(), bank.q().begin());
  std::copy(v.begin(), v.end(), bank.v().begin());
}

void Sea::invalidate_rates() {
  for (Field f : {Field::velocity_x, Field::velocity_y, Field::velocity_z})
    valid_[static_cast<std::size_t>(f)] = false;
}

RowWindow Sea::field(Field f) {
  const auto i = static_cast<std::size_t>(f);
  // A field computed whole on every rank serves any window. The test is on
  // the halos alone, which every rank has alike, so that every rank makes
  // the same collective calls (a window that happens to be whole on one
  // rank is not whole on another).
  const bool whole_everywhere = !in_slabs() || computed_halo_[i] == -1;
  const bool covers = whole_everywhere || computed_halo_[i] == field_halo_;
  if (!valid_[i] || !covers) {
    const WindowRows w = field_rows(field_halo_);
    const std::size_t size = static_cast<std::size_t>(w.rows) * static_cast<std::size_t>(grid_.nx);
    // A new array when the window's size changes, so that a whole field's
    // storage is given back when a smaller window follows.
    if (fields_[i].size() != size) AlignedVector(size, 0.0).swap(fields_[i]);
    compute_field(f, fields_[i]);
    valid_[i] = true;
    computed_halo_[i] = field_halo_;
    windows_[i] = w;
  }
  return RowWindow(windows_[i].first, windows_[i].rows, grid_.nx, grid_.ny, fields_[i]);
}

void Sea::release_field(Field f) {
  const auto i = static_cast<std::size_t>(f);
  valid_[i] = false;
  AlignedVector().swap(fields_[i]);
}

void Sea::gather_to_writer_rows(const RowWindow& w, std::vector<double>& whole) {
  const std::span<const double> all = w.all();
  whole.assign(all.begin(), all.end());
}

std::span<const double> Sea::field_on_writer(Field f) {
  if (!in_slabs()) return field(f).all();
  const int halo = field_halo_;
  field_halo_ = gather_to_writer;
  const RowWindow w = field(f);  // may be a whole field computed before
  field_halo_ = halo;
  const WindowRows mine = field_rows(gather_to_writer);
  const bool writer = mine.first == 0 && mine.rows == grid_.ny;
  FLOESIM_ASSERT(!writer || w.whole());
  return writer ? w.values() : std::span<const double>();
}

SurfaceSample Sea::sample(double x, double y) {
  // Parities at the walls x = const (then y = const): a derivative across a wall is odd.
  auto at = [&](Field f, Parity parity, Parity parity_y = Parity::even) {
    return interpolate(grid_, field(f).all(), x, y, parity, parity_y);
  };
  SurfaceSample s;
  s.eta = at(Field::elevation, Parity::even);
  s.slope_x = at(Field::slope_x, Parity::odd);
  s.u = at(Field::velocity_x, Parity::odd);
  s.w = at(Field::velocity_z, Parity::even);
  if (grid_.dims == 2) {
    s.slope_y = at(Field::slope_y, Parity::even, Parity::odd);
    s.v = at(Field::velocity_y, Parity::even, Parity::odd);
  }
  return s;
}

namespace {

template <class T>
std::string str(const T& v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

[[noreturn]] void bad(const std::string& key, const std::string& what) {
  throw InputError("[sea] " + key + ": " + what);
}

// Precondition (checked at load, core/config.cpp): the bottom is below the
// surface, x increasing, spanning the basin.
[[maybe_unused]] bool bottom_valid(const SeaParams& p) {
  const auto& b = p.bottom;
  if (b.size() < 2 || b.front()[0] > 0.0 || b.back()[0] < p.size[0]) return false;
  for (std::size_t i = 0; i < b.size(); ++i)
    if (!(std::isfinite(b[i][0]) && b[i][1] < 0.0) || (i > 0 && !(b[i][0] > b[i - 1][0]))) return false;
  return true;
}

}  // namespace

void validate(const SeaParams& p) {
  if (!(p.rho > 0.0) || !std::isfinite(p.rho))
    bad("rho", "expected a water density > 0 kg/m^3, got " + str(p.rho));
  if (p.model == SeaModel::none) return;
  if (p.dims != 1 && p.dims != 2) bad("dims", "expected 1 or 2, got " + str(p.dims));
  if (!(p.size[0] > 0.0) || !std::isfinite(p.size[0]))
    bad("size", "expected a length > 0 m along x, got " + str(p.size[0]));
  if (!(p.size[1] > 0.0) || !std::isfinite(p.size[1]))
    bad("size", std::string("expected a ") + (p.dims == 1 ? "width" : "length") +
                    " > 0 m along y, got " + str(p.size[1]));
  const int min_cells = p.model == SeaModel::bem ? 4 : 2;
  if (p.cells[0] < min_cells)
    bad("cells", "expected at least " + str(min_cells) + " cells along x, got " +
                     str(p.cells[0]));
  if (p.dims == 2 && p.cells[1] < 2)
    bad("cells", "expected at least 2 cells along y, got " + str(p.cells[1]));
  if (!(p.depth > 0.0))
    bad("depth", "expected a depth > 0 m (inf for deep water), got " + str(p.depth));
  if (!(p.g >= 0.0) || !std::isfinite(p.g)) bad("g", "expected g >= 0 m/s^2, got " + str(p.g));
  if (!(p.sigma >= 0.0) || !std::isfinite(p.sigma))
    bad("sigma", "expected a surface tension >= 0 N/m, got " + str(p.sigma));
  if (p.g == 0.0 && p.sigma == 0.0)
    bad("g", "with g = 0 and sigma = 0 the surface has no restoring force");
  FLOESIM_ASSERT(p.bottom.empty() || (p.model == SeaModel::bem && bottom_valid(p)));
  // A bottom grid only on the 3D basin (checked at load, core/config.cpp).
  FLOESIM_ASSERT(p.bottom_grid.empty() ||
                 (p.model == SeaModel::bem && p.dims == 2 && p.bottom.empty() &&
                  p.bottom_grid.size() == static_cast<std::size_t>(p.bottom_nx) * static_cast<std::size_t>(p.bottom_ny)));
  if (p.bem_static_correction && !(p.model == SeaModel::bem && p.dims == 2 && p.bem_modes > 0))
    bad("bem_static_correction", "corrects the lowest modes of a 3D basin only (model = \"bem\", dims = 2, bem_modes > 0)");
  if (p.model == SeaModel::bem && p.bottom.empty() && p.bottom_grid.empty() && !std::isfinite(p.depth))
    bad("depth", "model = \"bem\" needs a finite depth, a [sea] bottom polyline or a bottom_file");
}

std::unique_ptr<Sea> make_sea(const SeaParams& params, unsigned long seed,
                              const SeaOptions& options) {
  validate(params);
  std::unique_ptr<Sea> sea;
  switch (params.model) {
    case SeaModel::none:
      return nullptr;
    case SeaModel::spectral:
      sea = std::make_unique<SpectralSea>(params, options);
      break;
    case SeaModel::bem:
      FLOESIM_ASSERT(!options.tank.enabled || params.dims == 2);  // refused at load (core/config.cpp)
      if (params.dims == 1)
        sea = std::make_unique<BemSea>(params, options);
      else
        sea = std::make_unique<Bem3dSea>(params, options);
      break;
  }
  if (!options.tank.enabled) {
    const std::size_t n = sea->grid().size();
    std::vector<double> eta(n), eta_t(n);
    initial_surface(params, sea->grid(), seed, eta, eta_t);
    sea->set_surface(eta, eta_t);
  }
  return sea;
}

}  // namespace floesim::fluid
