#include "contact/fracture/criteria.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "contact/fracture/crack.hpp"
#include "core/error.hpp"

namespace floesim::fracture {

namespace {

// Directions of lines are taken in [0, pi).
double line_direction(double angle) {
  double a = std::fmod(angle, M_PI);
  if (a < 0.0) a += M_PI;
  return a;
}
// The crack runs perpendicular to sigma_1.
double crack_direction(double sigma_angle) { return line_direction(sigma_angle + 0.5 * M_PI); }

Vec2 unit(double angle) { return {std::cos(angle), std::sin(angle)}; }

Initiation judge_stress(const Responder& responder, const Response& response, std::span<const Vec2> polygon,
                        const CriterionOptions& options) {
  const Snapshot& s = response.peak_stress;
  Initiation r;
  r.stress = s.max_principal;
  r.point = responder.model().mesh().nodes[s.node];
  r.direction = crack_direction(s.angle);
  r.time = s.time;
  r.load_factor = s.max_principal > 0.0 ? options.strength / s.max_principal : std::numeric_limits<double>::infinity();
  r.initiates = s.max_principal >= options.strength;
  const Chord c = chord_through(polygon, r.point, unit(r.direction));
  if (c.valid) {
    r.crack_from = c.from;
    r.crack_to = c.to;
    r.through = true;
  } else {
    r.crack_from = r.crack_to = r.point;
  }
  return r;
}

struct Candidate {
  double angle = 0.0;
  double first_ratio = 0.0;  // released / needed over the first increment
  bool initiates = false, through = false;
  Vec2 from = Vec2::Zero(), to = Vec2::Zero();
  double released = 0.0, needed = 0.0;
  int downdates = 0;
};

Candidate grow(Responder& responder, const Eigen::VectorXd& f, const Eigen::VectorXd& u0, const Vec2& p,
               double angle, std::span<const Vec2> polygon, double gc_h) {
  Candidate c;
  c.angle = angle;
  c.from = c.to = p;
  const Vec2 d = unit(angle);
  const Chord chord = chord_through(polygon, p, d);
  if (!chord.valid || !(chord.length() > 0.0)) return c;
  const Mesh& mesh = responder.model().mesh();
  const double step = mesh.size;
  SpdFactor factor = responder.static_factor().copy();
  std::vector<char> cut(mesh.triangles.size(), 0);
  double lo = 0.0, hi = 0.0, released_prev = 0.0, length_prev = 0.0;
  for (bool first = true;; first = false) {
    lo = std::max(chord.s0, lo - step);
    hi = std::min(chord.s1, hi + step);
    const Vec2 a = p + lo * d, b = p + hi * d;
    std::vector<int> fresh;
    for (int t : triangles_cut(mesh, a, b))
      if (!cut[static_cast<std::size_t>(t)]) fresh.push_back(t);
    const bool at_ends = lo <= chord.s0 && hi >= chord.s1;
    double released = released_prev;
    if (!fresh.empty()) {
      try {
        factor.modify(responder.model().element_factors(fresh), /*downdate=*/true);
      } catch (const RunError&) {
        break;  // numerically singular: the crack is not followed further
      }
      c.downdates += static_cast<int>(fresh.size());
      for (int t : fresh) cut[static_cast<std::size_t>(t)] = 1;
      released = 0.5 * f.dot(factor.solve(f) - u0);
    }
    const double length = hi - lo;
    if (first) {
      c.released = released;
      c.needed = gc_h * length;
      c.first_ratio = c.needed > 0.0 ? released / c.needed : 0.0;
      c.initiates = released >= c.needed;
      if (!c.initiates) {
        c.from = a;
        c.to = b;
        return c;
      }
    } else if (released - released_prev < gc_h * (length - length_prev)) {
      return c;  // arrest: the last increment did not pay for itself
    }
    c.from = a;
    c.to = b;
    c.released = released;
    c.needed = gc_h * length;
    released_prev = released;
    length_prev = length;
    if (at_ends) {
      c.through = true;
      return c;
    }
  }
  return c;
}

Initiation judge_griffith(Responder& responder, const Response& response, std::span<const Vec2> polygon,
                          const CriterionOptions& options) {
  const ElasticModel& model = responder.model();
  const Snapshot& s = response.peak_energy;
  Initiation r;
  r.stress = s.max_principal;
  r.point = model.mesh().nodes[s.node];
  r.time = s.time;
  r.direction = crack_direction(s.angle);
  r.load_factor = s.max_principal > 0.0 ? options.strength / s.max_principal : std::numeric_limits<double>::infinity();
  r.crack_from = r.crack_to = r.point;
  if (!(s.strain_energy > 0.0)) return r;
  const Eigen::VectorXd f = model.relieve(model.stiffness() * s.u);
  const Eigen::VectorXd u0 = responder.static_factor().solve(f);
  const double gc_h = options.toughness * model.material().thickness;
  const int half = static_cast<int>(std::floor(options.angle_range / options.angle_step + 1e-9));
  Candidate best;
  best.first_ratio = -1.0;
  for (int k = 0; k <= 2 * half; ++k) {
    // 0, +1, -1, +2, -2, ...: the principal direction first.
    const int offset = (k % 2 == 1) ? (k + 1) / 2 : -(k / 2);
    const Candidate c = grow(responder, f, u0, r.point, r.direction + offset * options.angle_step, polygon, gc_h);
    ++r.candidates;
    r.downdates += c.downdates;
    if (c.first_ratio > best.first_ratio) best = c;
  }
  r.initiates = best.initiates;
  r.direction = line_direction(best.angle);
  r.crack_from = best.from;
  r.crack_to = best.to;
  r.through = best.through;
  r.energy_released = best.released;
  r.energy_needed = best.needed;
  return r;
}

}  // namespace

Initiation judge(Responder& responder, const Response& response, std::span<const Vec2> polygon,
                 const CriterionOptions& options) {
  return options.criterion == Criterion::stress ? judge_stress(responder, response, polygon, options)
                                                : judge_griffith(responder, response, polygon, options);
}

double energy_release(Responder& responder, const Eigen::VectorXd& f, std::span<const int> triangles) {
  const Eigen::VectorXd fr = responder.model().relieve(f);
  const Eigen::VectorXd u0 = responder.static_factor().solve(fr);
  SpdFactor factor = responder.static_factor().copy();
  factor.modify(responder.model().element_factors(triangles), /*downdate=*/true);
  return 0.5 * fr.dot(factor.solve(fr) - u0);
}

}  // namespace floesim::fracture
