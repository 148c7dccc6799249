#pragma once
// Shapes and load helpers shared by the percussion-fracture tests.
#include <cmath>
#include <vector>

#include "contact/fracture/elastic.hpp"

namespace floesim::fracture::testing {

inline std::vector<Vec2> rectangle(double lx, double ly) {
  return {{-lx / 2, -ly / 2}, {lx / 2, -ly / 2}, {lx / 2, ly / 2}, {-lx / 2, ly / 2}};
}

// Regular polygon inscribed in a circle, one vertex at (0, r) and one at (0, -r).
inline std::vector<Vec2> disc(double r, int n) {
  std::vector<Vec2> v;
  for (int k = 0; k < n; ++k) {
    const double a = -0.5 * M_PI + 2.0 * M_PI * k / n;
    v.emplace_back(r * std::cos(a), r * std::sin(a));
  }
  return v;
}

// Consistent nodal forces of a uniform normal traction sigma (Pa) on the
// outline edges that lie on x_axis = x0 (outward normal along sign * e_axis).
inline void add_edge_traction(const ElasticModel& m, Eigen::VectorXd& f, int axis, double x0, double sigma,
                              double sign) {
  const Mesh& mesh = m.mesh();
  const double tol = 1e-9 * mesh.size;
  const double h = m.material().thickness;
  for (const auto& tri : mesh.triangles)
    for (int k = 0; k < 3; ++k) {
      const int a = tri[static_cast<std::size_t>(k)], b = tri[static_cast<std::size_t>((k + 1) % 3)];
      const Vec2 &pa = mesh.nodes[static_cast<std::size_t>(a)], &pb = mesh.nodes[static_cast<std::size_t>(b)];
      if (std::abs(pa[axis] - x0) > tol || std::abs(pb[axis] - x0) > tol) continue;
      const double half = 0.5 * sigma * h * (pa - pb).norm() * sign;
      f[2 * a + axis] += half;
      f[2 * b + axis] += half;
    }
}
inline void add_end_traction(const ElasticModel& m, Eigen::VectorXd& f, double x0, double sigma, double sign) {
  add_edge_traction(m, f, 0, x0, sigma, sign);
}

}  // namespace floesim::fracture::testing
