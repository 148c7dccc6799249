// The lattice mesher of convex floes (mesh.hpp): boundary nodes, a
// triangular lattice inside, and their constrained Delaunay triangulation.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>

#include "contact/fracture/mesh.hpp"
#include "contact/fracture/predicates.hpp"

namespace floesim::fracture {

namespace {

// A triangle of the triangulation: v counter-clockwise; n[k] the triangle
// across the edge opposite v[k] (from v[k+1] to v[k+2]), -1 on the outline.
struct Tri {
  std::array<int, 3> v;
  std::array<int, 3> n;
};

int next3(int k) { return k == 2 ? 0 : k + 1; }
int prev3(int k) { return k == 0 ? 2 : k - 1; }

class Triangulation {
public:
  explicit Triangulation(std::vector<Vec2>& points) : p_(points) {}

  // Triangulates the closed outline points[0..m) (counter-clockwise, convex
  // up to collinear points): a fan from the first of its strict corners
  // (`corners`, increasing), each outline edge then split at the points
  // between its corners, in order; then Delaunay by edge flips (Lawson).
  // False if a triangle would not be counter-clockwise (not convex).
  bool outline(int m, const std::vector<int>& corners) {
    const int c = static_cast<int>(corners.size());
    if (c < 3) return false;
    for (int k = 1; k + 1 < c; ++k) {
      const int t = add(corners[0], corners[static_cast<std::size_t>(k)], corners[static_cast<std::size_t>(k + 1)]);
      if (!positive(t)) return false;
      if (k > 1) {
        t_[static_cast<std::size_t>(t)].n[2] = t - 1;
        t_[static_cast<std::size_t>(t - 1)].n[1] = t;
      }
    }
    // Split each outline edge from corner a to the next corner at the points between.
    for (int k = 0; k < c; ++k) {
      const int a = corners[static_cast<std::size_t>(k)], b = corners[static_cast<std::size_t>((k + 1) % c)];
      int t = -1, e = -1;  // the triangle with outline edge (a, b), opposite v[e]
      for (int u = 0; u < static_cast<int>(t_.size()) && t < 0; ++u)
        for (int j = 0; j < 3; ++j)
          if (t_[static_cast<std::size_t>(u)].v[static_cast<std::size_t>(next3(j))] == a &&
              t_[static_cast<std::size_t>(u)].v[static_cast<std::size_t>(prev3(j))] == b &&
              t_[static_cast<std::size_t>(u)].n[static_cast<std::size_t>(j)] < 0) {
            t = u;
            e = j;
          }
      if (t < 0) return false;
      for (int s = (a + 1) % m; s != b; s = (s + 1) % m) {
        // t = (x, a', b) with a' the last point placed: (x, a', s) and (x, s, b).
        const Tri old = t_[static_cast<std::size_t>(t)];
        const int x = old.v[static_cast<std::size_t>(e)], from = old.v[static_cast<std::size_t>(next3(e))];
        const int n_bx = old.n[static_cast<std::size_t>(next3(e))];  // across (b, x)
        const int n_xa = old.n[static_cast<std::size_t>(prev3(e))];  // across (x, a')
        const int t2 = add(x, s, b);
        t_[static_cast<std::size_t>(t)] = {{x, from, s}, {-1, t2, n_xa}};
        t_[static_cast<std::size_t>(t2)].n = {-1, n_bx, t};
        if (n_bx >= 0)
          for (int& w : t_[static_cast<std::size_t>(n_bx)].n)
            if (w == t) w = t2;
        if (!positive(t) || !positive(t2)) return false;
        t = t2;
        e = 0;
      }
    }
    // Lawson's flips: an edge whose opposite vertex lies inside the other
    // triangle's circumcircle is flipped until none is left.
    std::vector<std::pair<int, int>> stack;
    for (int t = 0; t < static_cast<int>(t_.size()); ++t)
      for (int k = 0; k < 3; ++k) stack.emplace_back(t, k);
    while (!stack.empty()) {
      const auto [t, k] = stack.back();
      stack.pop_back();
      flip_if_illegal(t, k, stack);
    }
    last_ = 0;
    return true;
  }

  bool positive(int t) const {
    const Tri& tr = t_[static_cast<std::size_t>(t)];
    return orientation(p_[static_cast<std::size_t>(tr.v[0])], p_[static_cast<std::size_t>(tr.v[1])],
                       p_[static_cast<std::size_t>(tr.v[2])]) > 0;
  }

  // Inserts point q (index into points) strictly inside the domain
  // (Bowyer–Watson: the triangles whose circumcircle holds q are replaced by
  // the fan of q to their outline). False if it cannot be done validly.
  bool insert(int q) {
    const Vec2& pq = p_[static_cast<std::size_t>(q)];
    const int start = locate(pq);
    if (start < 0) return false;
    // The cavity, grown across edges (never across the outline).
    cavity_.assign(1, start);
    mark(start, q);
    for (std::size_t c = 0; c < cavity_.size(); ++c) {
      const Tri tr = t_[static_cast<std::size_t>(cavity_[c])];
      for (int k = 0; k < 3; ++k) {
        const int u = tr.n[static_cast<std::size_t>(k)];
        if (u < 0 || stamp_[static_cast<std::size_t>(u)] == q) continue;
        const Tri& tu = t_[static_cast<std::size_t>(u)];
        if (in_circle(p_[static_cast<std::size_t>(tu.v[0])], p_[static_cast<std::size_t>(tu.v[1])],
                      p_[static_cast<std::size_t>(tu.v[2])], pq) > 0) {
          mark(u, q);
          cavity_.push_back(u);
        }
      }
    }
    // Its outline edges (a, b, the triangle outside or -1), counter-clockwise.
    rim_.clear();
    for (int c : cavity_) {
      const Tri& tr = t_[static_cast<std::size_t>(c)];
      for (int k = 0; k < 3; ++k) {
        const int u = tr.n[static_cast<std::size_t>(k)];
        if (u >= 0 && stamp_[static_cast<std::size_t>(u)] == q) continue;
        const int a = tr.v[static_cast<std::size_t>(next3(k))], b = tr.v[static_cast<std::size_t>(prev3(k))];
        if (orientation(p_[static_cast<std::size_t>(a)], p_[static_cast<std::size_t>(b)], pq) <= 0) return false;
        rim_.push_back({a, b, u});
      }
    }
    // New triangles (a, b, q): reuse the cavity's slots, then append.
    made_.resize(rim_.size());
    std::vector<int>& made = made_;
    for (std::size_t r = 0; r < rim_.size(); ++r) {
      int t;
      if (r < cavity_.size()) {
        t = cavity_[r];
        t_[static_cast<std::size_t>(t)] = {{rim_[r][0], rim_[r][1], q}, {-1, -1, rim_[r][2]}};
      } else {
        t = add(rim_[r][0], rim_[r][1], q);
        t_[static_cast<std::size_t>(t)].n[2] = rim_[r][2];
      }
      made[r] = t;
      stamp_[static_cast<std::size_t>(t)] = -1;
      const int u = rim_[r][2];
      if (u >= 0) {
        Tri& tu = t_[static_cast<std::size_t>(u)];
        for (int k = 0; k < 3; ++k)
          if (tu.v[static_cast<std::size_t>(k)] != rim_[r][0] && tu.v[static_cast<std::size_t>(k)] != rim_[r][1])
            tu.n[static_cast<std::size_t>(k)] = t;
      }
    }
    // The fan's own edges: (b, q) of the triangle from a to b is (q, b) of
    // the one that starts at b (found through a per-point slot).
    if (starts_.size() < p_.size()) starts_.resize(p_.size(), -1);
    for (std::size_t r = 0; r < rim_.size(); ++r) starts_[static_cast<std::size_t>(rim_[r][0])] = made[r];
    for (std::size_t r = 0; r < rim_.size(); ++r) {
      const int s = starts_[static_cast<std::size_t>(rim_[r][1])];
      t_[static_cast<std::size_t>(made[r])].n[0] = s;  // across (b, q), opposite a
      t_[static_cast<std::size_t>(s)].n[1] = made[r];  // across (q, b), opposite its own second vertex
    }
    last_ = made[0];
    return true;
  }

  const std::vector<Tri>& triangles() const { return t_; }

private:
  int add(int a, int b, int c) {
    t_.push_back({{a, b, c}, {-1, -1, -1}});
    stamp_.push_back(-1);
    return static_cast<int>(t_.size()) - 1;
  }
  void mark(int t, int q) { stamp_[static_cast<std::size_t>(t)] = q; }

  // The triangle holding p, by a visibility walk from the last one made
  // (it ends on Delaunay triangulations), then by a scan; -1 if none.
  int locate(const Vec2& p) const {
    int t = last_;
    for (std::size_t step = 0; step < 4 * t_.size() + 16; ++step) {
      const Tri& tr = t_[static_cast<std::size_t>(t)];
      int across = -1;
      for (int k = 0; k < 3 && across < 0; ++k)
        if (orientation(p_[static_cast<std::size_t>(tr.v[static_cast<std::size_t>(next3(k))])],
                        p_[static_cast<std::size_t>(tr.v[static_cast<std::size_t>(prev3(k))])], p) < 0)
          across = k;
      if (across < 0) return t;
      t = tr.n[static_cast<std::size_t>(across)];
      if (t < 0) break;
    }
    for (std::size_t u = 0; u < t_.size(); ++u) {
      const Tri& tr = t_[u];
      if (orientation(p_[static_cast<std::size_t>(tr.v[0])], p_[static_cast<std::size_t>(tr.v[1])], p) >= 0 &&
          orientation(p_[static_cast<std::size_t>(tr.v[1])], p_[static_cast<std::size_t>(tr.v[2])], p) >= 0 &&
          orientation(p_[static_cast<std::size_t>(tr.v[2])], p_[static_cast<std::size_t>(tr.v[0])], p) >= 0)
        return static_cast<int>(u);
    }
    return -1;
  }

  // Flips the edge opposite v[k] of triangle t if the vertex across it lies
  // inside t's circumcircle and both new triangles are counter-clockwise.
  void flip_if_illegal(int t, int k, std::vector<std::pair<int, int>>& stack) {
    const int u = t_[static_cast<std::size_t>(t)].n[static_cast<std::size_t>(k)];
    if (u < 0) return;
    Tri& a = t_[static_cast<std::size_t>(t)];
    Tri& b = t_[static_cast<std::size_t>(u)];
    int j = 0;
    while (b.n[static_cast<std::size_t>(j)] != t) ++j;
    const int p0 = a.v[static_cast<std::size_t>(k)], p1 = a.v[static_cast<std::size_t>(next3(k))];
    const int p2 = a.v[static_cast<std::size_t>(prev3(k))], p3 = b.v[static_cast<std::size_t>(j)];
    const auto& P = p_;
    if (in_circle(P[static_cast<std::size_t>(p0)], P[static_cast<std::size_t>(p1)], P[static_cast<std::size_t>(p2)],
                  P[static_cast<std::size_t>(p3)]) <= 0)
      return;
    if (orientation(P[static_cast<std::size_t>(p0)], P[static_cast<std::size_t>(p1)], P[static_cast<std::size_t>(p3)]) <= 0 ||
        orientation(P[static_cast<std::size_t>(p0)], P[static_cast<std::size_t>(p3)], P[static_cast<std::size_t>(p2)]) <= 0)
      return;
    // Edge (p1, p2) becomes (p0, p3): t = (p0, p1, p3), u = (p0, p3, p2).
    const int n_a1 = a.n[static_cast<std::size_t>(prev3(k))];  // across (p0, p1)
    const int n_a2 = a.n[static_cast<std::size_t>(next3(k))];  // across (p2, p0)
    const int n_b1 = b.n[static_cast<std::size_t>(prev3(j))];  // across (p3, p2)... b = (p3, p2, p1) from j
    const int n_b2 = b.n[static_cast<std::size_t>(next3(j))];  // across (p1, p3)
    a = {{p0, p1, p3}, {n_b2, u, n_a1}};
    b = {{p0, p3, p2}, {n_b1, n_a2, t}};
    auto relink = [&](int w, int from, int to) {
      if (w < 0) return;
      for (int& x : t_[static_cast<std::size_t>(w)].n)
        if (x == from) x = to;
    };
    relink(n_b2, u, t);
    relink(n_a2, t, u);
    stack.emplace_back(t, 0);
    stack.emplace_back(t, 2);
    stack.emplace_back(u, 0);
    stack.emplace_back(u, 1);
  }

  std::vector<Vec2>& p_;
  std::vector<Tri> t_;
  std::vector<int> stamp_;  // per triangle: the point whose cavity holds it
  std::vector<int> cavity_;
  std::vector<std::array<int, 3>> rim_;
  std::vector<int> made_;
  std::vector<int> starts_;  // per point: the new triangle whose rim edge starts there
  int last_ = 0;
};

// Smallest angle (rad) of the triangle a, b, c and its longest edge (m).
std::pair<double, double> shape(const Vec2& a, const Vec2& b, const Vec2& c) {
  const double ab = (b - a).norm(), bc = (c - b).norm(), ca = (a - c).norm();
  const double longest = std::max({ab, bc, ca});
  // The smallest angle is opposite the shortest edge (law of cosines).
  double x = ab, y = bc, z = ca;  // z: the shortest after sorting
  if (x < z) std::swap(x, z);
  if (y < z) std::swap(y, z);
  const double cosine = std::clamp((x * x + y * y - z * z) / (2.0 * x * y), -1.0, 1.0);
  return {std::acos(cosine), longest};
}

}  // namespace

std::optional<Mesh> mesh_lattice(std::span<const Vec2> polygon, double size, const MeshOptions& options) {
  const std::size_t nv = polygon.size();
  // Convex (collinear vertices allowed), counter-clockwise; the smallest corner angle.
  double sharpest = M_PI;
  for (std::size_t i = 0; i < nv; ++i) {
    const Vec2 &a = polygon[(i + nv - 1) % nv], &b = polygon[i], &c = polygon[(i + 1) % nv];
    if (orientation(a, b, c) < 0) return std::nullopt;
    const Vec2 u = (a - b).normalized(), w = (c - b).normalized();
    sharpest = std::min(sharpest, std::acos(std::clamp(u.dot(w), -1.0, 1.0)));
  }
  const double a = options.lattice_spacing * size;
  // Outline nodes: the vertices, and each edge divided into equal parts no longer than a.
  std::vector<Vec2> points;
  std::vector<int> corners;  // the vertices where the outline turns left
  for (std::size_t i = 0; i < nv; ++i) {
    const Vec2 &p0 = polygon[i], &p1 = polygon[(i + 1) % nv];
    if (orientation(polygon[(i + nv - 1) % nv], p0, p1) > 0) corners.push_back(static_cast<int>(points.size()));
    const int parts = std::max(1, static_cast<int>(std::ceil((p1 - p0).norm() / a - 1e-9)));
    for (int k = 0; k < parts; ++k) points.push_back(p0 + (static_cast<double>(k) / parts) * (p1 - p0));
  }
  const int outline = static_cast<int>(points.size());

  // Inside: a triangular lattice of spacing a with rows along the longest
  // edge, its first row a row spacing from that edge, keeping the points at
  // least margin a from every edge.
  std::size_t longest = 0;
  for (std::size_t i = 1; i < nv; ++i)
    if ((polygon[(i + 1) % nv] - polygon[i]).squaredNorm() > (polygon[(longest + 1) % nv] - polygon[longest]).squaredNorm())
      longest = i;
  const Vec2 origin = polygon[longest];
  const Vec2 ex = (polygon[(longest + 1) % nv] - origin).normalized();
  const Vec2 ey{-ex.y(), ex.x()};  // inward (counter-clockwise outline)
  double lo = 0.0, hi = 0.0, top = 0.0;
  for (const Vec2& p : polygon) {
    lo = std::min(lo, (p - origin).dot(ex));
    hi = std::max(hi, (p - origin).dot(ex));
    top = std::max(top, (p - origin).dot(ey));
  }
  // Inward unit normals and offsets: a point x is inside by n.x - c.
  std::vector<std::pair<Vec2, double>> sides;
  for (std::size_t i = 0; i < nv; ++i) {
    const Vec2 d = polygon[(i + 1) % nv] - polygon[i];
    if (!(d.norm() > 0.0)) continue;
    const Vec2 n = Vec2{-d.y(), d.x()} / d.norm();
    sides.emplace_back(n, n.dot(polygon[i]));
  }
  const double margin = options.lattice_margin * a, row = a * std::sqrt(3.0) / 2.0;
  // The six neighbours of a lattice point lie on one circle, so exact
  // in-circle ties would be met at every insertion (and decided by the slow
  // exact arithmetic); each point is moved by at most 1e-7 a, a fixed
  // pseudo-random offset, which breaks them and changes no element measurably.
  std::uint64_t state = 0x9E3779B97F4A7C15ull;
  auto jitter = [&state, a]() {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return 1e-7 * a * (static_cast<double>(state >> 11) / 9007199254740992.0 * 2.0 - 1.0);
  };
  std::vector<Vec2> inside;
  for (int j = 1; j * row < top; ++j) {
    const double shift = (j % 2) * 0.5 * a;
    const int first = static_cast<int>(std::floor((lo - shift) / a)), last = static_cast<int>(std::ceil((hi - shift) / a));
    std::vector<Vec2> line;
    for (int i = first; i <= last; ++i) {
      const Vec2 x = origin + (shift + i * a) * ex + (j * row) * ey;
      bool keep = true;
      for (const auto& [n, c] : sides)
        if (n.dot(x) - c < margin) {
          keep = false;
          break;
        }
      if (keep) line.push_back(x + Vec2{jitter(), jitter()});
    }
    if (j % 2 == 0) std::reverse(line.begin(), line.end());  // a serpentine: each point next to the last
    inside.insert(inside.end(), line.begin(), line.end());
  }
  points.insert(points.end(), inside.begin(), inside.end());

  Triangulation tri(points);
  if (!tri.outline(outline, corners)) return std::nullopt;
  for (int q = outline; q < static_cast<int>(points.size()); ++q)
    if (!tri.insert(q)) return std::nullopt;

  Mesh mesh;
  mesh.size = size;
  mesh.mesher = Mesher::lattice;
  mesh.nodes = std::move(points);
  mesh.on_boundary.assign(mesh.nodes.size(), 0);
  std::fill(mesh.on_boundary.begin(), mesh.on_boundary.begin() + outline, 1);
  // The bounds the mesh is accepted under: every edge at most `size`, every
  // angle at least the smaller of `min_angle` and the polygon's sharpest corner.
  const double floor = std::min(options.min_angle * M_PI / 180.0, sharpest) - 1e-12;
  mesh.triangles.reserve(tri.triangles().size());
  for (const Tri& t : tri.triangles()) {
    const auto [angle, edge] = shape(mesh.nodes[static_cast<std::size_t>(t.v[0])], mesh.nodes[static_cast<std::size_t>(t.v[1])],
                                     mesh.nodes[static_cast<std::size_t>(t.v[2])]);
    if (angle < floor || edge > size * (1.0 + 1e-9)) return std::nullopt;
    mesh.triangles.push_back(t.v);
  }
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    if (!(mesh.area(t) > 0.0)) return std::nullopt;
  return mesh;
}

}  // namespace floesim::fracture
