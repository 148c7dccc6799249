#include "contact/fracture/criteria.hpp"

#include <algorithm>
#include <functional>
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
  Chord c = chord_through(polygon, r.point, unit(r.direction));
  if (!c.valid && s.u.size() > 0) {
    // A peak on the outline, at a corner the crack's line only touches from
    // outside: the mesh puts the peak on a node, and coarse meshes put it on
    // the polygon's corners, so the crack is started where the mesh resolves
    // it, at the centroid of the node's most stressed triangle (one element
    // from the node; the same place as the mesh is refined), with the node's
    // direction.
    const Mesh& mesh = responder.model().mesh();
    const std::vector<Eigen::Vector3d> stress = responder.model().element_stress(s.u);
    double best = -std::numeric_limits<double>::infinity();
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      const auto& tri = mesh.triangles[t];
      if (std::find(tri.begin(), tri.end(), static_cast<int>(s.node)) == tri.end()) continue;
      const double value = principal(stress[t]).value;
      if (!(value > best)) continue;
      const Vec2 centroid = (mesh.nodes[static_cast<std::size_t>(tri[0])] + mesh.nodes[static_cast<std::size_t>(tri[1])] +
                             mesh.nodes[static_cast<std::size_t>(tri[2])]) / 3.0;
      const Chord inside = chord_through(polygon, centroid, unit(r.direction));
      if (!inside.valid) continue;
      best = value;
      r.point = centroid;
      c = inside;
    }
  }
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
  double ratio = 0.0;  // released / needed over the first growth increment
  bool initiates = false, through = false;
  Vec2 from = Vec2::Zero(), to = Vec2::Zero();
  double released = 0.0, needed = 0.0;
  double growth_released = 0.0, growth_needed = 0.0;
  int downdates = 0;
};

// Grows one candidate crack (criteria.hpp). Increment 1 is the flaw,
// increment 2 decides initiation, later ones propagation.
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
  for (int increment = 1;; ++increment) {
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
        factor.modify(responder.model().crack_factors(fresh, angle), /*downdate=*/true);
      } catch (const RunError&) {
        return c;  // numerically singular: the crack is not followed further
      }
      c.downdates += static_cast<int>(fresh.size());
      for (int t : fresh) cut[static_cast<std::size_t>(t)] = 1;
      released = 0.5 * f.dot(factor.solve(f) - u0);
    }
    const double length = hi - lo;
    const double gained = released - released_prev, needed = gc_h * (length - length_prev);
    // A flaw that already spans the floe is judged on its own energy.
    const bool decides = increment == 2 || (increment == 1 && at_ends);
    if (decides) {
      c.growth_released = gained;
      c.growth_needed = needed;
      c.ratio = needed > 0.0 ? gained / needed : 0.0;
      c.initiates = gained >= needed;
      if (!c.initiates) return c;
    } else if (increment > 2 && gained < needed) {
      return c;  // arrest: the last increment did not pay for itself
    }
    c.from = a;
    c.to = b;
    c.released = released;
    c.needed = gc_h * length;
    released_prev = released;
    length_prev = length;
    if (at_ends) {
      c.through = c.initiates;
      return c;
    }
  }
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
  // The most stressed nodes, two mesh sizes apart at least.
  const Mesh& mesh = model.mesh();
  const std::vector<Eigen::Vector3d> stress = model.nodal_stress(s.u);
  std::vector<std::pair<double, std::size_t>> order;
  for (std::size_t i = 0; i < stress.size(); ++i) order.emplace_back(principal(stress[i]).value, i);
  std::sort(order.begin(), order.end(), std::greater<>());
  std::vector<std::size_t> seeds;
  for (const auto& [value, node] : order) {
    if (static_cast<int>(seeds.size()) >= options.candidates || value < options.region * order.front().first) break;
    bool apart = true;
    for (std::size_t other : seeds) apart = apart && (mesh.nodes[node] - mesh.nodes[other]).norm() >= 2.0 * mesh.size;
    if (apart) seeds.push_back(node);
  }
  Candidate best;
  best.ratio = -1.0;
  for (std::size_t node : seeds) {
    const double angle = crack_direction(principal(stress[node]).angle);
    Candidate c = grow(responder, f, u0, mesh.nodes[node], angle, polygon, gc_h);
    ++r.candidates;
    r.downdates += c.downdates;
    if (c.ratio > best.ratio) {
      best = c;
      r.point = mesh.nodes[node];
      r.stress = principal(stress[node]).value;
    }
  }
  r.initiates = best.initiates;
  r.direction = line_direction(best.angle);
  r.crack_from = best.from;
  r.crack_to = best.to;
  r.through = best.through;
  r.energy_released = best.released;
  r.energy_needed = best.needed;
  r.growth_released = best.growth_released;
  r.growth_needed = best.growth_needed;
  return r;
}

}  // namespace

Initiation judge(Responder& responder, const Response& response, std::span<const Vec2> polygon,
                 const CriterionOptions& options) {
  return options.criterion == Criterion::stress ? judge_stress(responder, response, polygon, options)
                                                : judge_griffith(responder, response, polygon, options);
}

double energy_release(Responder& responder, const Eigen::VectorXd& f, std::span<const int> triangles, double angle) {
  const Eigen::VectorXd fr = responder.model().relieve(f);
  const Eigen::VectorXd u0 = responder.static_factor().solve(fr);
  SpdFactor factor = responder.static_factor().copy();
  factor.modify(responder.model().crack_factors(triangles, angle), /*downdate=*/true);
  return 0.5 * fr.dot(factor.solve(fr) - u0);
}

}  // namespace floesim::fracture
