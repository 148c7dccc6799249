#include "coupling/percussion.hpp"

#include <chrono>
#include <cmath>
#include <map>
#include <utility>

#include "contact/fracture/floe_fracture.hpp"
#include "contact/fracture/split.hpp"
#include "contact/shapes.hpp"

namespace floesim {

namespace {

double line_degrees(double angle) {
  double a = std::fmod(angle, M_PI);
  if (a < 0.0) a += M_PI;
  return a * 180.0 / M_PI;
}

// Whether any two of the floes overlap (after a split, before accepting it).
bool any_overlap(const Floes& floes) {
  const contact::CollisionShapes shapes = contact::build_collision_shapes(floes);
  contact::DetectionOptions o;
  o.collision_distance = 0.0;
  o.search_margin = 0.0;
  for (const contact::NearPair& p : contact::detect(floes, shapes, o).pairs)
    if (p.overlap) return true;
  return false;
}

double radius_of(const Floes& floes, std::size_t i) {
  double r = 0.0;
  for (const Vec2& p : floes.vertices(i)) r = std::max(r, p.norm());
  return r;
}

}  // namespace

Percussion::Percussion(const FractureParams& params, double gap, double screen)
    : params_(params), gap_(gap), screen_(screen) {}
Percussion::~Percussion() = default;
Percussion::Percussion(Percussion&&) noexcept = default;
Percussion& Percussion::operator=(Percussion&&) noexcept = default;

fracture::FloeFracture& Percussion::model_of(const Floes& floes, std::size_t i) {
  auto& slot = models_[floes.id[i]];
  if (!slot)
    slot = std::make_unique<fracture::FloeFracture>(floes.vertices(i), floes.thickness[i], floes.density[i], params_);
  return *slot;
}

bool Percussion::check(Floes& floes, const std::vector<contact::ContactPoint>& contacts,
                       const std::vector<contact::ContactImpulse>& impulses, double t, std::vector<FloeState>& start) {
  if (t != fresh_time_) {
    fresh_.clear();
    fresh_time_ = t;
  } else {
    // The step is being redone: its initiations without a split are found again.
    stats_.initiations -= static_cast<long>(
        std::erase_if(events_, [&](const FractureEventRow& e) { return e.time == t && e.piece_a < 0.0; }));
  }
  // The impulses on each floe, in its body frame (ordered by floe index).
  struct Struck {
    std::vector<fracture::PointLoad> loads;
    double total = 0.0, largest = 0.0;  // N s
  };
  std::map<std::size_t, Struck> struck;
  for (std::size_t j = 0; j < contacts.size() && j < impulses.size(); ++j) {
    const contact::ContactPoint& c = contacts[j];
    const Vec2& impulse = impulses[j].vector;  // on b
    const double size = impulse.norm();
    if (!(size > 0.0)) continue;
    const std::pair<std::size_t, double> sides[2] = {{c.a, -1.0}, {c.b, 1.0}};
    for (const auto& [f, sign] : sides) {
      if (floes.is_static[f] || fresh_.count(floes.id[f])) continue;
      const FloeState& s = floes.state[f];
      const Vec2 point = sign > 0.0 ? Vec2(impulses[j].point - c.shift) : impulses[j].point;
      Struck& st = struck[f];
      st.loads.push_back({rotate(point - Vec2{s.x, s.y}, -s.yaw), rotate(sign * impulse, -s.yaw), true});
      st.total += size;
      st.largest = std::max(st.largest, size);
    }
  }
  if (struck.empty()) return false;

  const double needed = params_.criterion == FractureCriterion::stress
                            ? params_.strength
                            : std::sqrt(params_.young * params_.toughness / (M_PI * params_.mesh_size));
  bool changed = false;
  for (auto& [i, st] : struck) {
    const double radius = params_.load_radius > 0.0 ? params_.load_radius : floes.thickness[i];
    const double pressure = M_PI * st.largest / (2.0 * params_.duration) / (floes.thickness[i] * 2.0 * radius);
    if (pressure < screen_ * needed) {
      ++stats_.screened;
      continue;
    }
    const auto begin = std::chrono::steady_clock::now();
    fracture::FloeFracture& model = model_of(floes, i);
    const fracture::FloeFracture::Result result = model.analyse(st.loads);
    stats_.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
    ++stats_.checks;
    const fracture::Initiation& init = result.initiation;
    if (!init.initiates) continue;
    ++stats_.initiations;
    const FloeState& s = floes.state[i];
    const Vec2 g{s.x, s.y};
    FractureEventRow e;
    e.time = t;
    e.floe = floes.id[i];
    const Vec2 at = g + rotate(init.point, s.yaw), from = g + rotate(init.crack_from, s.yaw),
               to = g + rotate(init.crack_to, s.yaw);
    e.x = at.x();
    e.y = at.y();
    e.direction = line_degrees(init.direction + s.yaw);
    e.load = st.total;
    e.stress = init.stress;
    e.x0 = from.x();
    e.y0 = from.y();
    e.x1 = to.x();
    e.y1 = to.y();
    e.criterion = params_.criterion == FractureCriterion::stress ? 0.0 : 1.0;
    e.energy_released = init.energy_released;
    e.energy_needed = init.energy_needed;
    e.delay = init.time;
    if (params_.split && init.through && split(floes, i, init.point, init.direction, start, e)) changed = true;
    events_.push_back(e);
  }
  return changed;
}

bool Percussion::split(Floes& floes, std::size_t i, const Vec2& point, double direction,
                       std::vector<FloeState>& start, FractureEventRow& event) {
  const fracture::Chord chord =
      fracture::chord_through(floes.vertices(i), point, Vec2{std::cos(direction), std::sin(direction)});
  // Pieces smaller than a mesh cell are not resolved by the model: no split.
  const double min_area = params_.mesh_size * params_.mesh_size;
  // The floes that could touch a piece: within reach of the parent.
  std::vector<std::size_t> near{i};
  const double ri = radius_of(floes, i);
  for (std::size_t j = 0; j < floes.size(); ++j) {
    if (j == i) continue;
    const double d = std::hypot(floes.state[j].x - floes.state[i].x, floes.state[j].y - floes.state[i].y);
    if (d <= ri + radius_of(floes, j) + gap_) near.push_back(j);
  }
  // Open the crack by gap, or less if that would push a piece into a neighbour.
  for (double gap = gap_; gap >= 1e-3 * gap_; gap *= 0.25) {
    const auto plan = fracture::plan_split(floes, i, chord, gap, min_area);
    if (!plan) break;
    const auto states = fracture::piece_states(*plan, floes.state[i], floes.inertia_z[i]);
    Floes trial = floes.select(near);
    fracture::apply_split(trial, 0, *plan, states);
    if (any_overlap(trial)) continue;
    const auto before = fracture::piece_states(*plan, start[i], floes.inertia_z[i]);
    const std::uint32_t parent = floes.id[i];
    const std::size_t second = fracture::apply_split(floes, i, *plan, states);
    start[i] = before[0];
    start.push_back(before[1]);
    models_.erase(parent);
    fresh_.insert(floes.id[i]);
    fresh_.insert(floes.id[second]);
    event.piece_a = floes.id[i];
    event.piece_b = floes.id[second];
    ++stats_.splits;
    return true;
  }
  ++stats_.failed_splits;
  return false;
}

std::vector<FractureEventRow> Percussion::take_events() { return std::exchange(events_, {}); }

}  // namespace floesim
