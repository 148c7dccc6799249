#include "coupling/percussion.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <tuple>
#include <utility>

#include "contact/fracture/floe_fracture.hpp"
#include "contact/fracture/split.hpp"
#include "contact/shapes.hpp"
#include "parallel/bytes.hpp"

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

std::vector<CollisionEventRow> collision_rows(const Floes& floes, const contact::ImpulseRecord& record, double t) {
  // A contact between two dynamic floes is recorded on both: keep it once,
  // from the floe with the lower index (or the dynamic one against a static).
  struct Sum {
    double normal = 0.0;
    Vec2 point = Vec2::Zero(), weighted = Vec2::Zero();
    bool resting = true;
  };
  std::map<std::tuple<std::uint32_t, std::uint32_t, std::uint32_t>, Sum> pairs;  // (event, number a, number b)
  for (const contact::ImpulseRecord::Load& l : record.loads) {
    if (l.floe >= floes.size() || l.other >= floes.size()) continue;
    if (!floes.is_static[l.other] && l.other < l.floe) continue;
    std::uint32_t a = floes.id[l.floe], b = floes.id[l.other];
    if (!floes.is_static[l.other] && b < a) std::swap(a, b);
    Sum& s = pairs[{l.event, a, b}];
    s.normal += l.normal;
    s.weighted += l.normal * l.world;
    s.point = l.world;
    s.resting = s.resting && l.sustained;
  }
  std::vector<CollisionEventRow> rows;
  rows.reserve(pairs.size());
  for (const auto& [key, s] : pairs) {
    const Vec2 p = s.normal > 0.0 ? Vec2(s.weighted / s.normal) : s.point;
    rows.push_back({t, static_cast<double>(std::get<1>(key)), static_cast<double>(std::get<2>(key)), s.normal, p.x(),
                    p.y(), s.resting ? 1.0 : 0.0});
  }
  return rows;
}

Percussion::Percussion(const FractureParams& params, double gap, double screen)
    : params_(params), gap_(gap), screen_(screen) {}
Percussion::~Percussion() = default;
Percussion::Percussion(Percussion&&) noexcept = default;
Percussion& Percussion::operator=(Percussion&&) noexcept = default;

fracture::FloeFracture& Percussion::model_of(const Floes& floes, std::size_t i) {
  auto& slot = models_[floes.id[i]];
  if (!slot) {
    const auto begin = std::chrono::steady_clock::now();
    slot = std::make_unique<fracture::FloeFracture>(floes.vertices(i), floes.thickness[i], floes.density[i], params_);
    ++stats_.models;
    stats_.mesh_seconds += slot->mesh_seconds();
    if (slot->model().mesh().mesher == fracture::Mesher::lattice) ++stats_.lattice_meshes;
    stats_.model_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
  }
  return *slot;
}

// A floe's loads of a step (percussion.hpp): its sustained forces, and its
// impulses by event.
struct FloeLoads {
  std::vector<fracture::PointLoad> forces;  // N, the mean of the step
  double force_sum = 0.0, force_largest = 0.0;  // N
  double sustained_impulse = 0.0;  // N s, sum of |J| of the resting contacts
  struct Event {
    std::vector<fracture::PointLoad> impulses;  // N s
    double total = 0.0, largest = 0.0;  // N s
  };
  std::map<std::uint32_t, Event> events;  // by event number (time order)
};

bool Percussion::check(Floes& floes, const contact::ImpulseRecord& record, double t, double dt) {
  PercussionAnalyses all = analyse(floes, record, t, dt, PercussionShare{});
  return all.loaded && conclude(floes, std::move(all));
}

PercussionAnalyses Percussion::analyse(const Floes& floes, const contact::ImpulseRecord& record, double t, double dt,
                                       const PercussionShare& share) {
  const auto phase_begin = std::chrono::steady_clock::now();
  PercussionAnalyses out;
  struct PhaseClock {  // adds the analyses' wall time on every return
    std::chrono::steady_clock::time_point begin;
    double& total;
    double& mine;
    ~PhaseClock() {
      mine = std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
      total += mine;
    }
  } phase_clock{phase_begin, stats_.phase_seconds, out.seconds};
  if (t != fresh_time_) {
    fresh_.clear();
    fresh_time_ = t;
  }
  // Every share reads the whole record (whether any floe is loaded is the
  // same on all) and keeps its own floes' loads.
  std::map<std::size_t, FloeLoads> loaded;  // by floe index
  for (const contact::ImpulseRecord::Load& l : record.loads) {
    if (l.floe >= floes.size() || floes.is_static[l.floe] || fresh_.count(floes.id[l.floe])) continue;
    out.loaded = true;
    if (!share.mine(l.floe)) continue;
    FloeLoads& fl = loaded[l.floe];
    const double size = l.impulse.norm();
    if (l.sustained) {
      fl.forces.push_back({l.point, l.impulse / dt, false});
      fl.sustained_impulse += size;
    } else {
      FloeLoads::Event& e = fl.events[l.event];
      e.impulses.push_back({l.point, l.impulse, true});
      e.total += size;
      e.largest = std::max(e.largest, size);
    }
  }

  const double needed = params_.criterion == FractureCriterion::stress
                            ? params_.strength
                            : std::sqrt(params_.young * params_.toughness / (M_PI * params_.mesh_size));
  PercussionCounts& counts = out.counts;
  for (auto& [i, fl] : loaded) {
    const double h = floes.thickness[i];
    const double radius = params_.load_radius > 0.0 ? params_.load_radius : h;
    // Sustained: the forces of the resting contacts, summed at each point
    // (one contact point hit in several sub-steps is one force), and their
    // stress scale.
    double sustained_scale = 0.0;
    if (!fl.forces.empty()) {
      std::map<std::pair<double, double>, Vec2> at;
      for (const fracture::PointLoad& f : fl.forces)
        at.try_emplace({f.point.x(), f.point.y()}, Vec2::Zero()).first->second += f.value;  // Eigen does not zero
      fl.forces.clear();
      for (const auto& [p, v] : at) {
        fl.forces.push_back({Vec2{p.first, p.second}, v, false});
        fl.force_sum += v.norm();
        fl.force_largest = std::max(fl.force_largest, v.norm());
      }
      const double diameter = 2.0 * radius_of(floes, i);
      const double depth = floes.area[i] / diameter;
      sustained_scale = std::max(fl.force_largest / (h * 2.0 * radius),
                                 0.75 * fl.force_sum * diameter / (h * depth * depth));
    }
    // The analyses to run: each event whose scale (with the sustained one)
    // reaches the screen, or the sustained forces alone.
    std::vector<const FloeLoads::Event*> cases;
    for (const auto& [number, e] : fl.events) {
      const double impact_scale = M_PI * e.largest / (2.0 * params_.duration) / (h * 2.0 * radius);
      if (impact_scale + sustained_scale >= screen_ * needed) cases.push_back(&e);
    }
    if (cases.empty() && !fl.forces.empty() && sustained_scale >= screen_ * needed) cases.push_back(nullptr);
    if (cases.empty()) {
      ++counts.screened;
      continue;
    }
    for (const FloeLoads::Event* e : cases) {
      std::vector<fracture::PointLoad> loads = fl.forces;
      if (e) loads.insert(loads.end(), e->impulses.begin(), e->impulses.end());
      const auto begin = std::chrono::steady_clock::now();
      fracture::FloeFracture& model = model_of(floes, i);
      const double factor_before = model.responder().factor_seconds();
      // The stress criterion cannot initiate below the strength: a case whose
      // bound (Responder::stress_bound) is below it needs no time loop.
      if (params_.criterion == FractureCriterion::stress) {
        const auto bound_begin = std::chrono::steady_clock::now();
        const bool below = model.responder().stress_bound(loads) < params_.strength;
        const auto bound_end = std::chrono::steady_clock::now();
        stats_.bound_seconds += std::chrono::duration<double>(bound_end - bound_begin).count();
        if (below) {
          stats_.seconds += std::chrono::duration<double>(bound_end - begin).count();
          stats_.factor_seconds += model.responder().factor_seconds() - factor_before;
          ++counts.bounded;
          continue;
        }
      }
      const fracture::FloeFracture::Result result = model.decide(loads);
      stats_.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
      stats_.factor_seconds += model.responder().factor_seconds() - factor_before;
      ++counts.checks;
      if (!e) ++counts.sustained;
      if (result.response.cut_short) ++counts.cut_short;
      counts.loop_steps += result.response.steps;
      const fracture::Initiation& init = result.initiation;
      if (!init.initiates) continue;
      // The event in world coordinates at the step's end: floe i's state is
      // the same when conclude() reaches it (earlier splits leave it).
      const FloeState& s = floes.state[i];
      const Vec2 g{s.x, s.y};
      FloeInitiation fi;
      fi.floe = i;
      fi.through = init.through ? 1 : 0;
      fi.point_x = init.point.x();
      fi.point_y = init.point.y();
      fi.direction = init.direction;
      FractureEventRow& ev = fi.event;
      ev.time = t;
      ev.floe = floes.id[i];
      const Vec2 at = g + rotate(init.point, s.yaw), from = g + rotate(init.crack_from, s.yaw),
                 to = g + rotate(init.crack_to, s.yaw);
      ev.x = at.x();
      ev.y = at.y();
      ev.direction = line_degrees(init.direction + s.yaw);
      ev.load = (e ? e->total : 0.0) + fl.sustained_impulse;
      ev.stress = init.stress;
      ev.x0 = from.x();
      ev.y0 = from.y();
      ev.x1 = to.x();
      ev.y1 = to.y();
      ev.criterion = params_.criterion == FractureCriterion::stress ? 0.0 : 1.0;
      ev.energy_released = init.energy_released;
      ev.energy_needed = init.energy_needed;
      ev.delay = init.time;  // 0 for a static analysis (sustained contact alone), > 0 for an impact
      out.initiations.push_back(fi);
      break;  // one initiation per floe and step: the floe has cracked
    }
  }
  // The splits of this share's floes, decided against the floes the step
  // ended with (conclude decides again one that an earlier split of the
  // step came within reach of).
  if (params_.split) {
    const auto cut = std::chrono::steady_clock::now();
    for (FloeInitiation& fi : out.initiations)
      if (fi.through) fi.split = decide_split(floes, fi.floe, fi, share.held);
    stats_.split_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - cut).count();
  }
  return out;
}

bool Percussion::conclude(Floes& floes, PercussionAnalyses all, std::vector<std::uint32_t>* split,
                          std::span<const std::uint8_t> readable) {
  const auto begin = std::chrono::steady_clock::now();
  stats_.counts += all.counts;
  std::vector<FloeInitiation>& initiations = all.initiations;
  // The serial order: by floe index (each floe at most once).
  std::sort(initiations.begin(), initiations.end(),
            [](const FloeInitiation& a, const FloeInitiation& b) { return a.floe < b.floe; });
  // The splits made so far in this step: their parent's centroid and radius
  // (the neighbours' reach, as decide_split measures it) and the two pieces.
  struct Made {
    double x, y, radius;
    std::size_t a, b;
  };
  std::vector<Made> made;
  // Whether a split made so far was within reach of floe i, before or after
  // it: then floe i's neighbours are not those its split was decided
  // against. Otherwise they are the same floes, with the same data, in the
  // same order (a split changes only its parent and appends a piece), and
  // so is the decision (decide_split reads no other floe).
  auto changed_near = [&](std::size_t i) {
    const double ri = radius_of(floes, i);
    auto reaches = [&](double x, double y, double r) {
      return std::hypot(x - floes.state[i].x, y - floes.state[i].y) <= ri + r + gap_;  // as decide_split
    };
    auto piece_reaches = [&](std::size_t j) {
      return reaches(floes.state[j].x, floes.state[j].y, radius_of(floes, j));
    };
    return std::any_of(made.begin(), made.end(), [&](const Made& m) {
      return reaches(m.x, m.y, m.radius) || piece_reaches(m.a) || piece_reaches(m.b);
    });
  };
  bool changed = false;
  for (FloeInitiation& fi : initiations) {
    ++stats_.initiations;
    if (params_.split && fi.through) {
      const auto cut = std::chrono::steady_clock::now();
      const std::size_t i = fi.floe;
      SplitDecision decision = fi.split;
      // Decisions made without the neighbours (a piece too small, no two
      // polygons) stand whatever the other splits.
      const bool again = decided_against_neighbours(decision.verdict) && changed_near(i);
      if (again) ++stats_.splits_redone;
      if (again || decision.verdict == SplitVerdict::undecided) decision = decide_split(floes, i, fi, readable);
      const Made before{floes.state[i].x, floes.state[i].y, radius_of(floes, i), i, floes.size()};
      if (apply_split(floes, i, fi, decision, fi.event)) {
        changed = true;
        made.push_back(before);
        if (split) split->push_back(static_cast<std::uint32_t>(i));
      }
      stats_.split_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - cut).count();
    }
    events_.push_back(fi.event);
  }
  stats_.phase_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
  return changed;
}

bool Percussion::may_split(const PercussionAnalyses& all) const {
  // conclude splits nothing unless some through crack may split on its own
  // (may_split_alone, percussion.hpp: the rule and why).
  return params_.split && std::any_of(all.initiations.begin(), all.initiations.end(), [](const FloeInitiation& fi) {
           return fi.through != 0 && may_split_alone(fi.split.verdict);
         });
}

std::vector<std::byte> pack(const PercussionAnalyses& analyses) {
  std::vector<std::byte> out(sizeof(PercussionCounts) + sizeof(double) + sizeof(std::uint64_t) +
                             analyses.initiations.size() * sizeof(FloeInitiation));
  const std::uint64_t n = analyses.initiations.size();
  std::byte* at = parallel::put(out.data(), &analyses.counts, 1);
  at = parallel::put(at, &analyses.seconds, 1);
  at = parallel::put(at, &n, 1);
  parallel::put(at, analyses.initiations.data(), analyses.initiations.size());
  return out;
}

PercussionAnalyses unpack_percussion(std::span<const std::byte> bytes) {
  PercussionAnalyses a;
  a.loaded = true;
  const std::byte* in = bytes.data();
  a.counts = parallel::take<PercussionCounts>(in, 1)[0];
  a.seconds = parallel::take<double>(in, 1)[0];
  const auto n = parallel::take<std::uint64_t>(in, 1)[0];
  a.initiations = parallel::take<FloeInitiation>(in, n);
  return a;
}

PercussionAnalyses combine(std::span<const PercussionAnalyses> parts, PercussionRanks& ranks) {
  PercussionAnalyses all;
  ranks.checks.resize(parts.size(), 0);
  ranks.seconds.resize(parts.size(), 0.0);
  ++ranks.steps;
  for (std::size_t r = 0; r < parts.size(); ++r) {
    const PercussionAnalyses& p = parts[r];
    all.loaded = all.loaded || p.loaded;
    ranks.checks[r] += p.counts.checks;
    ranks.seconds[r] += p.seconds;
    all.counts += p.counts;
    all.seconds += p.seconds;
    all.initiations.insert(all.initiations.end(), p.initiations.begin(), p.initiations.end());
  }
  return all;
}

double Percussion::min_fragment_area() const {
  return params_.min_fragment_area > 0.0 ? params_.min_fragment_area : params_.mesh_size * params_.mesh_size;
}

SplitDecision Percussion::decide_split(const Floes& floes, std::size_t i, const FloeInitiation& fi,
                                       std::span<const std::uint8_t> held) const {
  const fracture::Chord chord = fracture::chord_through(
      floes.vertices(i), Vec2{fi.point_x, fi.point_y}, Vec2{std::cos(fi.direction), std::sin(fi.direction)});
  // No piece below the minimum fragment area (a sliver): the floe is not split.
  const double min_area = min_fragment_area();
  // The floes that could touch a piece: within reach of the parent (found
  // once two pieces are planned).
  std::vector<std::size_t> near;
  // Open the crack by gap, or less if that would push a piece into a neighbour.
  for (double gap = gap_; gap >= 1e-3 * gap_; gap *= 0.25) {
    const auto plan = fracture::plan_split(floes, i, chord, gap, min_area);
    if (!plan) break;
    if (near.empty()) near = split_neighbours(floes, i, held);
    Floes trial = floes.select(near);
    fracture::apply_split(trial, 0, *plan, fracture::piece_states(*plan, floes.state[i], floes.inertia_z[i]));
    if (!any_overlap(trial)) return {SplitVerdict::split, gap};
  }
  // Two valid pieces refused by the neighbours at every gap, or for the area of one.
  if (!near.empty()) return {SplitVerdict::refused_overlap, 0.0};
  if (fracture::plan_split(floes, i, chord, gap_, 0.0)) return {SplitVerdict::refused_small, 0.0};
  return {SplitVerdict::refused_chord, 0.0};
}

std::vector<std::size_t> Percussion::split_neighbours(const Floes& floes, std::size_t i,
                                                      std::span<const std::uint8_t> held) const {
  std::vector<std::size_t> near{i};
  const double ri = radius_of(floes, i);
  for (std::size_t j = 0; j < floes.size(); ++j) {
    if (j == i || (!held.empty() && j < held.size() && !held[j])) continue;
    const double d = std::hypot(floes.state[j].x - floes.state[i].x, floes.state[j].y - floes.state[i].y);
    if (d <= ri + radius_of(floes, j) + gap_) near.push_back(j);
  }
  return near;
}

std::vector<std::uint32_t> Percussion::split_readers(const Floes& floes, const PercussionAnalyses& mine,
                                                     std::span<const std::uint8_t> held) const {
  std::vector<std::uint32_t> out;
  if (!params_.split) return out;
  for (const FloeInitiation& fi : mine.initiations) {
    const SplitVerdict v = fi.split.verdict;
    if (!fi.through || !(decided_against_neighbours(v) || v == SplitVerdict::undecided)) continue;
    for (const std::size_t j : split_neighbours(floes, fi.floe, held)) out.push_back(static_cast<std::uint32_t>(j));
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

bool Percussion::apply_split(Floes& floes, std::size_t i, const FloeInitiation& fi, SplitDecision decision,
                             FractureEventRow& event) {
  if (decision.verdict != SplitVerdict::split) {
    ++stats_.failed_splits;
    if (decision.verdict == SplitVerdict::refused_overlap) ++stats_.refused_overlap;
    if (decision.verdict == SplitVerdict::refused_small) ++stats_.refused_small;
    return false;
  }
  // The plan at the decided opening, made again here from floe i alone (the
  // same bits as when it was decided: floe i is as it was).
  const fracture::Chord chord = fracture::chord_through(
      floes.vertices(i), Vec2{fi.point_x, fi.point_y}, Vec2{std::cos(fi.direction), std::sin(fi.direction)});
  const fracture::SplitPlan plan = fracture::plan_split(floes, i, chord, decision.gap, min_fragment_area()).value();
  const auto states = fracture::piece_states(plan, floes.state[i], floes.inertia_z[i]);
  const std::uint32_t parent = floes.id[i];
  const std::size_t second = fracture::apply_split(floes, i, plan, states);
  models_.erase(parent);
  fresh_.insert(floes.id[i]);
  fresh_.insert(floes.id[second]);
  event.piece_a = floes.id[i];
  event.piece_b = floes.id[second];
  ++stats_.splits;
  return true;
}

std::vector<FractureEventRow> Percussion::take_events() { return std::exchange(events_, {}); }

}  // namespace floesim
