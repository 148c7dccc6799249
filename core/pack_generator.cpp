// Random floe packs: an area-constrained, Lloyd-relaxed power diagram (CGAL's
// regular triangulation gives its adjacency), each cell shrunk about its
// centroid. The method and its choices are described in the header.
#include "core/pack_generator.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Regular_triangulation_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <random>
#include <sstream>
#include <utility>

#include "core/error.hpp"

namespace floesim {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kMaxConcentration = 0.95;

// ---------------------------------------------------------------- random numbers

// mt19937_64's output sequence is fixed by the standard; the mapping to [0, 1)
// is ours (the top 53 bits times 2^-53), so the doubles are the same everywhere.
class Random {
public:
  explicit Random(std::uint64_t seed) : engine_(seed) {}
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  double uniform(double a, double b) { return a + (b - a) * uniform(); }

private:
  std::mt19937_64 engine_;
};

// ---------------------------------------------------------------- sizes

// Range [a, b] of the size law before scaling, defaults filled in.
std::array<double, 2> size_law_range(const SizeDistribution& s) {
  if (s.min_size > 0.0 && s.max_size > 0.0) return {s.min_size, s.max_size};
  return {1.0, s.kind == SizeDistribution::Kind::uniform ? 1.0 : 10.0};
}

// One draw d from the size law on [a, b] by inverting its distribution function.
// Power law p(d) ∝ d^-alpha: with q = 1 - alpha, F(d) = (d^q - a^q) / (b^q - a^q),
// so d = (a^q + u (b^q - a^q))^(1/q); alpha = 1 is the log-uniform law d = a (b/a)^u.
double draw_size(const SizeDistribution& s, const std::array<double, 2>& range, Random& rng) {
  const auto [a, b] = range;
  const double u = rng.uniform();
  if (s.kind == SizeDistribution::Kind::uniform) return a + (b - a) * u;
  const double q = 1.0 - s.exponent;
  if (std::abs(q) < 1e-12) return a * std::pow(b / a, u);
  const double aq = std::pow(a, q), bq = std::pow(b, q);
  return std::pow(aq + u * (bq - aq), 1.0 / q);
}

// ---------------------------------------------------------------- power cells

// A cell of the clipped power diagram: a convex polygon (CCW) whose edge k, from
// v[k] to v[k+1], lies on the bisector with site owner[k] (or on the box: -1).
struct Cell {
  std::vector<Vec2> v;
  std::vector<std::ptrdiff_t> owner;
  double area = 0.0;
  Vec2 centroid = Vec2::Zero();
};

// Keeps the part of a convex cell where n . x <= c; the new edge is owned by j.
void clip(Cell& cell, const Vec2& n, double c, std::ptrdiff_t j, std::vector<Vec2>& v,
          std::vector<std::ptrdiff_t>& owner) {
  v.clear();
  owner.clear();
  const std::size_t m = cell.v.size();
  for (std::size_t k = 0; k < m; ++k) {
    const Vec2& a = cell.v[k];
    const Vec2& b = cell.v[(k + 1) % m];
    const double da = n.dot(a) - c, db = n.dot(b) - c;
    if (da <= 0.0) {
      v.push_back(a);
      owner.push_back(cell.owner[k]);
      if (db > 0.0) {  // leaves: the cut point starts an edge on the new line
        v.push_back(a + (da / (da - db)) * (b - a));
        owner.push_back(j);
      }
    } else if (db <= 0.0) {  // enters: the cut point starts the rest of edge k
      v.push_back(a + (da / (da - db)) * (b - a));
      owner.push_back(cell.owner[k]);
    }
  }
  // Drop repeated points (a cut through a vertex); the later one's edge survives.
  cell.v.clear();
  cell.owner.clear();
  for (std::size_t k = 0; k < v.size(); ++k) {
    if (v[k] == v[(k + 1) % v.size()] && v.size() > 1) continue;
    cell.v.push_back(v[k]);
    cell.owner.push_back(owner[k]);
  }
}

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using VertexBase = CGAL::Triangulation_vertex_base_with_info_2<
    std::size_t, Kernel, CGAL::Regular_triangulation_vertex_base_2<Kernel>>;
using FaceBase = CGAL::Regular_triangulation_face_base_2<Kernel>;
using Tds = CGAL::Triangulation_data_structure_2<VertexBase, FaceBase>;
using Regular = CGAL::Regular_triangulation_2<Kernel, Tds>;

// The power diagram of (sites, weights) clipped to the box [0, W] x [0, H].
// Its adjacency is the regular triangulation's (CGAL); each cell is the box
// clipped by the power bisectors with its neighbours:
//   |x - p_i|² - w_i <= |x - p_j|² - w_j  <=>  2 (p_j - p_i) . x <= |p_j|² - |p_i|² + w_i - w_j.
// A site the triangulation hides (its power cell is empty) gets an empty cell.
void power_cells(const std::vector<Vec2>& sites, const std::vector<double>& weights, double W,
                 double H, std::vector<Cell>& cells) {
  const std::size_t n = sites.size();
  std::vector<std::pair<Regular::Weighted_point, std::size_t>> input;
  input.reserve(n);
  for (std::size_t i = 0; i < n; ++i)
    input.emplace_back(Regular::Weighted_point(Regular::Bare_point(sites[i].x(), sites[i].y()), weights[i]), i);
  Regular rt(input.begin(), input.end());

  // Adjacency in compressed rows: neighbours of i are adj[start[i] .. start[i+1]).
  std::vector<std::pair<std::size_t, std::size_t>> edges;
  edges.reserve(3 * n);
  for (auto e = rt.finite_edges_begin(); e != rt.finite_edges_end(); ++e)
    edges.emplace_back(e->first->vertex(Regular::cw(e->second))->info(),
                       e->first->vertex(Regular::ccw(e->second))->info());
  std::vector<std::size_t> start(n + 1, 0), adj(2 * edges.size());
  for (const auto& [a, b] : edges) ++start[a + 1], ++start[b + 1];
  for (std::size_t i = 0; i < n; ++i) start[i + 1] += start[i];
  std::vector<std::size_t> next(start.begin(), start.end() - 1);
  for (const auto& [a, b] : edges) adj[next[a]++] = b, adj[next[b]++] = a;
  // CGAL's edge order can depend on memory addresses (it differs between two
  // calls in one process); the clipping order sets the last bits of the cell
  // vertices, so fix it: neighbours by index.
  for (std::size_t i = 0; i < n; ++i)
    std::sort(adj.begin() + static_cast<std::ptrdiff_t>(start[i]), adj.begin() + static_cast<std::ptrdiff_t>(start[i + 1]));
  std::vector<char> present(n, 0);
  for (auto v = rt.finite_vertices_begin(); v != rt.finite_vertices_end(); ++v) present[v->info()] = 1;

  cells.resize(n);
  std::vector<Vec2> scratch_v;
  std::vector<std::ptrdiff_t> scratch_owner;
  for (std::size_t i = 0; i < n; ++i) {
    Cell& cell = cells[i];
    cell.v.assign({{0.0, 0.0}, {W, 0.0}, {W, H}, {0.0, H}});
    cell.owner.assign(4, -1);
    if (!present[i]) cell.v.clear(), cell.owner.clear();
    for (std::size_t e = start[i]; e < start[i + 1] && !cell.v.empty(); ++e) {
      const std::size_t j = adj[e];
      const Vec2 normal = 2.0 * (sites[j] - sites[i]);
      const double c = sites[j].squaredNorm() - sites[i].squaredNorm() + weights[i] - weights[j];
      clip(cell, normal, c, static_cast<std::ptrdiff_t>(j), scratch_v, scratch_owner);
    }
    if (cell.v.size() < 3) {
      cell.v.clear();
      cell.owner.clear();
      cell.area = 0.0;
      cell.centroid = sites[i];
      continue;
    }
    const PolygonMoments m = polygon_moments(cell.v);
    cell.area = m.area;
    cell.centroid = m.area > 0.0 ? m.centroid() : sites[i];
  }
}

// ---------------------------------------------------------------- cell areas

struct AreaSolve {
  std::vector<Vec2> sites;
  std::vector<double> weights;
  std::vector<double> targets;
  double width = 0.0, height = 0.0;
  std::vector<Cell> cells;
  std::size_t iterations = 0;  // Newton steps, all solves
};

double max_relative_error(const AreaSolve& s) {
  double e = 0.0;
  for (std::size_t i = 0; i < s.targets.size(); ++i)
    e = std::max(e, std::abs(s.cells[i].area - s.targets[i]) / s.targets[i]);
  return e;
}

double residual_norm(const std::vector<Cell>& cells, const std::vector<double>& targets) {
  double r = 0.0;
  for (std::size_t i = 0; i < targets.size(); ++i) r += std::pow(cells[i].area - targets[i], 2);
  return std::sqrt(r);
}

// Newton's method for the weights that give every cell its target area
// (damped as in Kitagawa, Mérigot & Thibert 2019: a step is halved until no
// cell falls below eps0 and the residual drops by the factor 1 - tau/2).
// The Jacobian ∂area_i/∂w_j = -l_ij / (2 |p_i - p_j|) (j != i), whose rows sum
// to 0, is a weighted graph Laplacian (a constant added to all weights changes
// nothing); a tiny diagonal shift makes it definite for the Cholesky solve.
void solve_areas(AreaSolve& s, double tolerance, int max_iterations) {
  const std::size_t n = s.sites.size();
  power_cells(s.sites, s.weights, s.width, s.height, s.cells);
  double min_area = kInf;
  for (const Cell& c : s.cells) min_area = std::min(min_area, c.area);
  if (!(min_area > 0.0)) {  // a Lloyd move emptied a cell: restart from Voronoi
    std::fill(s.weights.begin(), s.weights.end(), 0.0);
    power_cells(s.sites, s.weights, s.width, s.height, s.cells);
    min_area = kInf;
    for (const Cell& c : s.cells) min_area = std::min(min_area, c.area);
  }
  const double eps0 = 0.5 * std::min(min_area, *std::min_element(s.targets.begin(), s.targets.end()));

  std::vector<Cell> trial_cells;
  std::vector<double> trial_weights(n);
  std::vector<Eigen::Triplet<double>> triplets;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
  Eigen::VectorXd rhs(static_cast<Eigen::Index>(n));
  for (int it = 0; it < max_iterations && max_relative_error(s) > tolerance; ++it) {
    triplets.clear();
    double trace = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      const Cell& c = s.cells[i];
      double diag = 0.0;
      for (std::size_t k = 0; k < c.v.size(); ++k) {
        if (c.owner[k] < 0) continue;
        const auto j = static_cast<std::size_t>(c.owner[k]);
        const double l = (c.v[(k + 1) % c.v.size()] - c.v[k]).norm();
        const double h = l / (2.0 * (s.sites[j] - s.sites[i]).norm());
        if (j < i) triplets.emplace_back(static_cast<int>(i), static_cast<int>(j), -h);
        diag += h;
      }
      triplets.emplace_back(static_cast<int>(i), static_cast<int>(i), diag);
      trace += diag;
      rhs[static_cast<Eigen::Index>(i)] = s.targets[i] - c.area;
    }
    const double shift = 1e-9 * trace / static_cast<double>(n);
    for (std::size_t i = 0; i < n; ++i) triplets.emplace_back(static_cast<int>(i), static_cast<int>(i), shift);
    Eigen::SparseMatrix<double> jac(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
    jac.setFromTriplets(triplets.begin(), triplets.end());
    ldlt.compute(jac);  // reads the lower triangle
    const Eigen::VectorXd step = ldlt.solve(rhs);
    if (ldlt.info() != Eigen::Success) break;

    const double r0 = residual_norm(s.cells, s.targets);
    double tau = 1.0;
    bool accepted = false;
    for (int halvings = 0; halvings < 30 && !accepted; ++halvings, tau *= 0.5) {
      for (std::size_t i = 0; i < n; ++i) trial_weights[i] = s.weights[i] + tau * step[static_cast<Eigen::Index>(i)];
      power_cells(s.sites, trial_weights, s.width, s.height, trial_cells);
      double m = kInf;
      for (const Cell& c : trial_cells) m = std::min(m, c.area);
      accepted = m >= eps0 && residual_norm(trial_cells, s.targets) <= (1.0 - tau / 2.0) * r0;
    }
    ++s.iterations;
    if (!accepted) break;  // stalled at round-off; the caller reads the error
    s.weights.swap(trial_weights);
    s.cells.swap(trial_cells);
  }
}

// ---------------------------------------------------------------- floes from cells

// Drops vertices closer than `tiny` to the previous one. Removing a vertex of a
// convex polygon leaves the hull of the others, a subset: no new overlap.
void drop_short_edges(std::vector<Vec2>& v, double tiny) {
  for (std::size_t k = 0; v.size() > 3 && k < v.size();) {
    if ((v[(k + 1) % v.size()] - v[k]).norm() < tiny) v.erase(v.begin() + static_cast<std::ptrdiff_t>((k + 1) % v.size()));
    else ++k;
  }
}

// Distance from c to the nearest edge line of the convex CCW polygon v.
double inner_distance(const std::vector<Vec2>& v, const Vec2& c) {
  double h = kInf;
  for (std::size_t k = 0; k < v.size(); ++k) {
    const Vec2 e = v[(k + 1) % v.size()] - v[k];
    h = std::min(h, cross(e, c - v[k]) / e.norm());
  }
  return h;
}

double point_segment_distance(const Vec2& p, const Vec2& a, const Vec2& b) {
  const Vec2 ab = b - a;
  const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (p - (a + t * ab)).norm();
}

// Distance between two disjoint polygons: the nearest pair of points is a vertex
// of one and a point on an edge of the other.
double polygon_distance(std::span<const Vec2> a, std::span<const Vec2> b) {
  double d = kInf;
  for (int pass = 0; pass < 2; ++pass, std::swap(a, b))
    for (const Vec2& p : a)
      for (std::size_t k = 0; k < b.size(); ++k) d = std::min(d, point_segment_distance(p, b[k], b[(k + 1) % b.size()]));
  return d;
}

// Exact smallest gap between floes (pairs of static floes excluded). The cell
// neighbours give an upper bound m; then a sweep over x-sorted bounding boxes
// grown by m finds every pair that could be closer.
double smallest_gap(const std::vector<std::vector<Vec2>>& polys, const std::vector<char>& is_static,
                    const std::vector<std::pair<std::size_t, std::size_t>>& neighbours) {
  double m = kInf;
  for (const auto& [i, j] : neighbours) m = std::min(m, polygon_distance(polys[i], polys[j]));
  struct Box { double x0, x1, y0, y1; std::size_t i; };
  std::vector<Box> boxes;
  boxes.reserve(polys.size());
  for (std::size_t i = 0; i < polys.size(); ++i) {
    Box b{kInf, -kInf, kInf, -kInf, i};
    for (const Vec2& p : polys[i]) {
      b.x0 = std::min(b.x0, p.x()), b.x1 = std::max(b.x1, p.x());
      b.y0 = std::min(b.y0, p.y()), b.y1 = std::max(b.y1, p.y());
    }
    boxes.push_back(b);
  }
  std::sort(boxes.begin(), boxes.end(), [](const Box& a, const Box& b) { return a.x0 < b.x0; });
  for (std::size_t a = 0; a < boxes.size(); ++a)
    for (std::size_t b = a + 1; b < boxes.size() && boxes[b].x0 <= boxes[a].x1 + m; ++b) {
      const Box &p = boxes[a], &q = boxes[b];
      if (q.y0 > p.y1 + m || p.y0 > q.y1 + m || (is_static[p.i] && is_static[q.i])) continue;
      m = std::min(m, polygon_distance(polys[p.i], polys[q.i]));
    }
  return m;
}

std::string number(double x) {
  std::ostringstream s;
  s.precision(6);
  s << x;
  return s.str();
}

}  // namespace

double equivalent_diameter(double area) { return 2.0 * std::sqrt(area / std::numbers::pi); }

void validate(const PackOptions& o) {
  auto fail = [](const std::string& what) { throw InputError("pack: " + what); };
  auto positive = [&](double x, const char* name, const char* unit) {
    if (!(std::isfinite(x) && x > 0.0))
      fail(std::string(name) + " must be a finite number > 0 (" + unit + "), got " + number(x));
  };
  if (o.floes < 1) fail("floes must be at least 1, got 0");
  if (o.floes > 10'000'000) fail("floes must be at most 10^7, got " + std::to_string(o.floes));
  if (!(o.concentration > 0.0 && o.concentration <= kMaxConcentration))
    fail("concentration must be in (0, " + number(kMaxConcentration) + "], got " + number(o.concentration));
  positive(o.width, "box width", "m");
  positive(o.height, "box height", "m");
  const SizeDistribution& s = o.sizes;
  if ((s.min_size > 0.0) != (s.max_size > 0.0))
    fail("give both min_size and max_size, or neither");
  if (s.min_size > 0.0) {
    positive(s.min_size, "min_size", "m");
    positive(s.max_size, "max_size", "m");
    if (s.max_size < s.min_size) fail("max_size (" + number(s.max_size) + ") is below min_size (" + number(s.min_size) + ")");
  }
  if (s.kind == SizeDistribution::Kind::power_law && !(std::isfinite(s.exponent) && s.exponent > 0.0))
    fail("the power-law exponent must be a finite number > 0, got " + number(s.exponent));
  positive(o.thickness_min, "thickness", "m");
  positive(o.thickness_max, "thickness", "m");
  if (o.thickness_max < o.thickness_min) fail("the thickness range is reversed (max < min)");
  positive(o.density, "density", "kg/m^3");
  if (!std::isfinite(o.min_gap)) fail("min_gap must be finite");
  if (o.relax_iterations < 0 || o.relax_iterations > 1000) fail("relax_iterations must be in [0, 1000]");
  if (!(std::isfinite(o.wall_width) && o.wall_width >= 0.0)) fail("wall width must be a finite number >= 0 (m)");
}

namespace {

// The floes numbered along a Z-order (Morton) curve of their centroids
// (`centres`, n of them) on a 2^16 x 2^16 grid of the box, the `total - n`
// walls last: floes near each other in space are then near each other in the
// floe arrays, which the detection and the contact sweeps read neighbour by
// neighbour.
std::vector<std::size_t> z_order(const std::vector<Vec2>& centres, std::size_t total, double W, double H) {
  auto spread = [](std::uint64_t v) {  // the 16 bits of v to the even bits
    v &= 0xFFFF;
    v = (v | (v << 8)) & 0x00FF00FF;
    v = (v | (v << 4)) & 0x0F0F0F0F;
    v = (v | (v << 2)) & 0x33333333;
    v = (v | (v << 1)) & 0x55555555;
    return v;
  };
  auto cell = [](double x, double L) {
    return static_cast<std::uint64_t>(std::clamp(x / L, 0.0, 1.0) * 65535.0);
  };
  const std::size_t n = centres.size();
  std::vector<std::uint64_t> key(n);
  for (std::size_t i = 0; i < n; ++i) key[i] = spread(cell(centres[i].x(), W)) | (spread(cell(centres[i].y(), H)) << 1);
  std::vector<std::size_t> order(total);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(n),
                   [&](std::size_t a, std::size_t b) { return key[a] < key[b]; });
  return order;
}

}  // namespace

GeneratedPack generate_pack(const PackOptions& o) {
  validate(o);
  const std::size_t n = o.floes;
  const double W = o.width, H = o.height, C = o.concentration;
  Random rng(o.seed);
  GeneratedPack out;
  out.window = {0.0, W, 0.0, H};

  // 1. Sizes, scaled so the floes cover C W H: A_i = k² pi d_i² / 4.
  const auto range = size_law_range(o.sizes);
  std::vector<double> d(n);
  double sum_d2 = 0.0;
  for (double& x : d) {
    x = draw_size(o.sizes, range, rng);
    sum_d2 += x * x;
  }
  const double k = std::sqrt(C * W * H / (std::numbers::pi / 4.0 * sum_d2));
  out.size_range = {k * range[0], k * range[1]};

  // 2. Cells of area a_i = A_i / C; sites uniform in the box, then relaxed.
  AreaSolve solve;
  solve.width = W;
  solve.height = H;
  solve.targets.resize(n);
  for (std::size_t i = 0; i < n; ++i) solve.targets[i] = W * H * d[i] * d[i] / sum_d2;
  solve.sites.resize(n);
  for (Vec2& p : solve.sites) {
    const double x = rng.uniform(0.0, W);
    p = {x, rng.uniform(0.0, H)};
  }
  solve.weights.assign(n, 0.0);
  for (int it = 0; it < o.relax_iterations; ++it) {
    solve_areas(solve, 1e-2, 8);  // loose: the sites move again next
    for (std::size_t i = 0; i < n; ++i) solve.sites[i] = solve.cells[i].centroid;
  }
  solve_areas(solve, 1e-9, 50);
  out.max_area_error = max_relative_error(solve);
  out.newton_iterations = solve.iterations;
  for (const Cell& c : solve.cells)
    if (c.v.size() < 3) throw RunError("pack: a power cell came out empty (internal error); try another seed");

  // 3. Floes: cells shrunk about their centroids.
  const double mean_size_target = std::sqrt(4.0 * C * W * H / (std::numbers::pi * static_cast<double>(n)));
  const double gap = o.min_gap >= 0.0 ? o.min_gap : 1e-3 * mean_size_target;
  out.required_gap = gap;
  const double s = std::sqrt(C);
  std::vector<std::vector<Vec2>> polys(n);
  std::vector<Vec2> centres(n);  // shrinking about the centroid keeps it
  double floe_area = 0.0, size_sum = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    std::vector<Vec2> v = solve.cells[i].v;
    drop_short_edges(v, 1e-6 * mean_size_target);
    const Vec2 c = centres[i] = polygon_moments(v).centroid();
    const double h = inner_distance(v, c);
    const double si = std::min(s, 1.0 - 0.5 * gap / h);
    if (!(si > 0.0))
      throw InputError("pack: floe cell " + std::to_string(i) + " is too thin for min_gap " + number(gap) +
                       " m (lower the concentration, the size ratio or the gap)");
    for (Vec2& p : v) p = c + si * (p - c);
    const double a = polygon_moments(v).area;
    floe_area += a;
    size_sum += equivalent_diameter(a);
    polys[i] = std::move(v);
  }
  out.concentration = floe_area / (W * H);
  out.mean_size = size_sum / static_cast<double>(n);
  if (out.concentration < 0.99 * C)
    throw InputError("pack: concentration " + number(C) + " cannot be reached with min_gap " + number(gap) +
                     " m (got " + number(out.concentration) + "); lower the gap or the concentration");

  // 4. Walls: static rectangles outside the box, gap/2 beyond its sides.
  if (o.wall_width > 0.0) {
    const double g = 0.5 * gap, w = o.wall_width;
    auto rect = [](double x0, double x1, double y0, double y1) {
      return std::vector<Vec2>{{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
    };
    polys.push_back(rect(-g - w, -g, -g - w, H + g + w));         // left, full height
    polys.push_back(rect(W + g, W + g + w, -g - w, H + g + w));   // right
    polys.push_back(rect(g, W - g, -g - w, -g));                  // bottom, between them
    polys.push_back(rect(g, W - g, H + g, H + g + w));            // top
    out.walls = 4;
  }

  // Neighbour pairs of the diagram, for the gap's first bound.
  std::vector<std::pair<std::size_t, std::size_t>> neighbours;
  for (std::size_t i = 0; i < n; ++i)
    for (std::ptrdiff_t j : solve.cells[i].owner)
      if (j > static_cast<std::ptrdiff_t>(i)) neighbours.emplace_back(i, static_cast<std::size_t>(j));
  std::vector<char> is_static(polys.size(), 0);
  std::fill(is_static.begin() + static_cast<std::ptrdiff_t>(n), is_static.end(), 1);
  out.min_gap = smallest_gap(polys, is_static, neighbours);

  const std::vector<std::size_t> order = z_order(centres, polys.size(), W, H);
  for (std::size_t i : order) {
    FloeInput in;
    in.vertices = std::move(polys[i]);
    in.is_static = is_static[i] != 0;
    in.thickness = o.thickness_min == o.thickness_max || in.is_static
                       ? o.thickness_max
                       : rng.uniform(o.thickness_min, o.thickness_max);
    in.density = o.density;
    in.origin = in.is_static ? "generated wall " + std::to_string(i - n)
                             : "generated floe " + std::to_string(out.floes.size());
    out.floes.add(make_floe_shape(in), in);
  }
  return out;
}

}  // namespace floesim
