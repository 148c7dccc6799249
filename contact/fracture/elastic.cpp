#include "contact/fracture/elastic.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.hpp"

namespace floesim::fracture {

Principal principal(const Eigen::Vector3d& s) {
  const double mean = 0.5 * (s[0] + s[1]);
  const double half = 0.5 * (s[0] - s[1]);
  const double radius = std::hypot(half, s[2]);
  // tan(2 phi) = 2 sxy / (sxx - syy) for the direction of sigma_1.
  double angle = 0.5 * std::atan2(s[2], half);
  if (angle <= -0.5 * M_PI) angle += M_PI;
  return {mean + radius, angle};
}

ElasticModel::ElasticModel(Mesh mesh, const Material& material) : mesh_(std::move(mesh)), material_(material) {
  const double e = material.young, nu = material.poisson, h = material.thickness;
  if (!(e > 0.0) || !(nu > -1.0 && nu < 0.5) || !(h > 0.0) || !(material.density > 0.0))
    throw RunError("fracture: young > 0, -1 < poisson < 0.5, thickness > 0 and density > 0 are required");
  const double c = e / (1.0 - nu * nu);
  d_ << c, c * nu, 0.0, c * nu, c, 0.0, 0.0, 0.0, c * (1.0 - nu) / 2.0;
  d_factor_ = d_.llt().matrixL();

  const std::size_t nn = mesh_.node_count();
  const Eigen::Index n = dofs();
  m_ = Eigen::VectorXd::Zero(n);
  node_area_.assign(nn, 0.0);
  for (std::size_t t = 0; t < mesh_.triangles.size(); ++t) {
    const double area = mesh_.area(t);
    if (!(area > 0.0)) throw RunError("fracture: a mesh triangle has no area");
    for (int i : mesh_.triangles[t]) {
      node_area_[static_cast<std::size_t>(i)] += area / 3.0;
      const double mass = material.density * h * area / 3.0;
      m_[2 * i] += mass;
      m_[2 * i + 1] += mass;
    }
  }

  // Mass centre, rigid modes and (Phi^T M Phi)^-1.
  double total = 0.0;
  for (std::size_t i = 0; i < nn; ++i) {
    centre_ += m_[2 * static_cast<Eigen::Index>(i)] * mesh_.nodes[i];
    total += m_[2 * static_cast<Eigen::Index>(i)];
  }
  centre_ /= total;
  phi_ = Eigen::MatrixXd::Zero(n, 3);
  for (std::size_t i = 0; i < nn; ++i) {
    const Eigen::Index k = 2 * static_cast<Eigen::Index>(i);
    const Vec2 r = mesh_.nodes[i] - centre_;
    phi_(k, 0) = 1.0;
    phi_(k + 1, 1) = 1.0;
    phi_(k, 2) = -r.y();
    phi_(k + 1, 2) = r.x();
  }
  rigid_inv_ = (phi_.transpose() * m_.asDiagonal() * phi_).inverse();

  // Outline edges (in one triangle only) and each node's share of their
  // length; the edges in increasing (low, high) node order.
  std::vector<std::pair<int, int>> edges;
  edges.reserve(3 * mesh_.triangles.size());
  for (const auto& tri : mesh_.triangles)
    for (int k = 0; k < 3; ++k) {
      const int a = tri[static_cast<std::size_t>(k)], b = tri[static_cast<std::size_t>((k + 1) % 3)];
      edges.emplace_back(std::min(a, b), std::max(a, b));
    }
  std::sort(edges.begin(), edges.end());
  node_outline_.assign(nn, 0.0);
  for (std::size_t k = 0; k < edges.size();) {
    std::size_t next = k + 1;
    while (next < edges.size() && edges[next] == edges[k]) ++next;
    if (next - k == 1) {
      const auto [a, b] = edges[k];
      outline_edges_.push_back({a, b});
      const double len = (mesh_.nodes[static_cast<std::size_t>(a)] - mesh_.nodes[static_cast<std::size_t>(b)]).norm();
      node_outline_[static_cast<std::size_t>(a)] += 0.5 * len;
      node_outline_[static_cast<std::size_t>(b)] += 0.5 * len;
    }
    k = next;
  }

  // Diameter: the outline's nodes bound it.
  std::vector<Vec2> outline;
  for (std::size_t i = 0; i < nn; ++i)
    if (mesh_.on_boundary[i]) outline.push_back(mesh_.nodes[i]);
  for (std::size_t i = 0; i < outline.size(); ++i)
    for (std::size_t j = i + 1; j < outline.size(); ++j)
      diameter_ = std::max(diameter_, (outline[i] - outline[j]).norm());
}

double ElasticModel::wave_speed() const {
  return std::sqrt(material_.young / (material_.density * (1.0 - material_.poisson * material_.poisson)));
}

double ElasticModel::bar_speed() const { return std::sqrt(material_.young / material_.density); }

void ElasticModel::assemble_stiffness() const {
  if (!b_.empty()) return;
  const double h = material_.thickness;
  const Eigen::Index n = dofs();
  std::vector<Eigen::Matrix<double, 3, 6>> bs(mesh_.triangles.size());
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(36 * mesh_.triangles.size());
  for (std::size_t t = 0; t < mesh_.triangles.size(); ++t) {
    const auto& tri = mesh_.triangles[t];
    const double area = mesh_.area(t);
    // Shape function gradients: dN_i/dx = (y_j - y_k) / 2A, dN_i/dy = (x_k - x_j) / 2A.
    Eigen::Matrix<double, 3, 6> b = Eigen::Matrix<double, 3, 6>::Zero();
    for (int i = 0; i < 3; ++i) {
      const Vec2& pj = mesh_.nodes[static_cast<std::size_t>(tri[static_cast<std::size_t>((i + 1) % 3)])];
      const Vec2& pk = mesh_.nodes[static_cast<std::size_t>(tri[static_cast<std::size_t>((i + 2) % 3)])];
      const double bx = (pj.y() - pk.y()) / (2.0 * area), by = (pk.x() - pj.x()) / (2.0 * area);
      b(0, 2 * i) = bx;
      b(1, 2 * i + 1) = by;
      b(2, 2 * i) = by;
      b(2, 2 * i + 1) = bx;
    }
    bs[t] = b;
    const Eigen::Matrix<double, 6, 6> ke = h * area * b.transpose() * d_ * b;
    for (int i = 0; i < 6; ++i)
      for (int j = 0; j < 6; ++j)
        trip.emplace_back(2 * tri[static_cast<std::size_t>(i / 2)] + i % 2, 2 * tri[static_cast<std::size_t>(j / 2)] + j % 2,
                          ke(i, j));
  }
  k_.resize(n, n);
  k_.setFromTriplets(trip.begin(), trip.end());
  k_.makeCompressed();
  b_ = std::move(bs);
}

const Eigen::SparseMatrix<double>& ElasticModel::stiffness() const {
  assemble_stiffness();
  return k_;
}

Eigen::SparseMatrix<double> ElasticModel::element_factors(std::span<const int> triangles) const {
  assemble_stiffness();
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(18 * triangles.size());
  int col = 0;
  for (int t : triangles) {
    const auto ts = static_cast<std::size_t>(t);
    const Eigen::Matrix<double, 6, 3> w =
        std::sqrt(material_.thickness * mesh_.area(ts)) * b_[ts].transpose() * d_factor_;
    const auto& tri = mesh_.triangles[ts];
    for (int i = 0; i < 6; ++i)
      for (int j = 0; j < 3; ++j)
        if (w(i, j) != 0.0) trip.emplace_back(2 * tri[static_cast<std::size_t>(i / 2)] + i % 2, col + j, w(i, j));
    col += 3;
  }
  Eigen::SparseMatrix<double> out(dofs(), col);
  out.setFromTriplets(trip.begin(), trip.end());
  return out;
}

Eigen::SparseMatrix<double> ElasticModel::crack_factors(std::span<const int> triangles, double angle) const {
  assemble_stiffness();
  const double e = material_.young, nu = material_.poisson;
  const double c = std::cos(angle), s = std::sin(angle);
  // Strain in the crack frame: (eps_tt, eps_nn, gamma_tn) = T (exx, eyy, gxy).
  Eigen::Matrix3d t;
  t << c * c, s * s, c * s, s * s, c * c, -c * s, -2.0 * c * s, 2.0 * c * s, c * c - s * s;
  Eigen::Matrix<double, 3, 2> l = Eigen::Matrix<double, 3, 2>::Zero();
  l(0, 0) = nu * std::sqrt(e / (1.0 - nu * nu));
  l(1, 0) = std::sqrt(e / (1.0 - nu * nu));
  l(2, 1) = std::sqrt(e / (2.0 * (1.0 + nu)));
  const Eigen::Matrix<double, 3, 2> tl = t.transpose() * l;
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(12 * triangles.size());
  int col = 0;
  for (int tr : triangles) {
    const auto ts = static_cast<std::size_t>(tr);
    const Eigen::Matrix<double, 6, 2> w = std::sqrt(material_.thickness * mesh_.area(ts)) * b_[ts].transpose() * tl;
    const auto& tri = mesh_.triangles[ts];
    for (int i = 0; i < 6; ++i)
      for (int j = 0; j < 2; ++j)
        if (w(i, j) != 0.0) trip.emplace_back(2 * tri[static_cast<std::size_t>(i / 2)] + i % 2, col + j, w(i, j));
    col += 2;
  }
  Eigen::SparseMatrix<double> out(dofs(), col);
  out.setFromTriplets(trip.begin(), trip.end());
  return out;
}

std::vector<Eigen::Vector3d> ElasticModel::element_stress(const Eigen::VectorXd& u) const {
  assemble_stiffness();
  std::vector<Eigen::Vector3d> s(mesh_.triangles.size());
  for (std::size_t t = 0; t < mesh_.triangles.size(); ++t) {
    const auto& tri = mesh_.triangles[t];
    Eigen::Matrix<double, 6, 1> ue;
    for (int i = 0; i < 3; ++i) {
      ue[2 * i] = u[2 * tri[static_cast<std::size_t>(i)]];
      ue[2 * i + 1] = u[2 * tri[static_cast<std::size_t>(i)] + 1];
    }
    s[t] = d_ * (b_[t] * ue);
  }
  return s;
}

std::vector<Eigen::Vector3d> ElasticModel::nodal_stress(const Eigen::VectorXd& u) const {
  const std::vector<Eigen::Vector3d> se = element_stress(u);
  std::vector<Eigen::Vector3d> sn(mesh_.node_count(), Eigen::Vector3d::Zero());
  for (std::size_t t = 0; t < mesh_.triangles.size(); ++t) {
    const double a = mesh_.area(t) / 3.0;
    for (int i : mesh_.triangles[t]) sn[static_cast<std::size_t>(i)] += a * se[t];
  }
  for (std::size_t i = 0; i < sn.size(); ++i) sn[i] /= node_area_[i];
  return sn;
}

double ElasticModel::strain_energy(const Eigen::VectorXd& u) const { return 0.5 * u.dot(stiffness() * u); }

Eigen::VectorXd ElasticModel::relieve(const Eigen::VectorXd& f) const {
  const Eigen::Vector3d q = rigid_inv_ * (phi_.transpose() * f);
  return f - m_.cwiseProduct(phi_ * q);
}

void ElasticModel::remove_rigid(Eigen::VectorXd& u) const {
  const Eigen::Vector3d q = rigid_inv_ * (phi_.transpose() * m_.cwiseProduct(u));
  u -= phi_ * q;
}

void ElasticModel::add_point_load(Eigen::VectorXd& f, const Vec2& point, const Vec2& force, double radius) const {
  // On the outline? (distance to the nearest outline edge)
  double to_outline = std::numeric_limits<double>::infinity();
  for (const auto& e : outline_edges_) {
    const Vec2& a = mesh_.nodes[static_cast<std::size_t>(e[0])];
    const Vec2 ab = mesh_.nodes[static_cast<std::size_t>(e[1])] - a;
    const double s = std::clamp((point - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
    to_outline = std::min(to_outline, (a + s * ab - point).norm());
  }
  const bool surface = to_outline <= 0.25 * radius;
  std::vector<std::pair<std::size_t, double>> w;
  double sum = 0.0;
  for (std::size_t i = 0; i < mesh_.node_count(); ++i) {
    const double share = surface ? node_outline_[i] : node_area_[i];
    if (!(share > 0.0)) continue;
    const double d = (mesh_.nodes[i] - point).norm();
    if (d >= radius) continue;
    const double x = 1.0 - (d / radius) * (d / radius);
    w.emplace_back(i, share * x * x);
    sum += w.back().second;
  }
  if (w.empty() || !(sum > 0.0)) {
    std::size_t best = 0;
    double best_d = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < mesh_.node_count(); ++i) {
      const double d = (mesh_.nodes[i] - point).norm();
      if (d < best_d && (!surface || node_outline_[i] > 0.0)) {
        best_d = d;
        best = i;
      }
    }
    w.assign(1, {best, 1.0});
    sum = 1.0;
  }
  for (const auto& [i, wi] : w) {
    f[2 * static_cast<Eigen::Index>(i)] += wi / sum * force.x();
    f[2 * static_cast<Eigen::Index>(i) + 1] += wi / sum * force.y();
  }
}

bool ElasticModel::interpolate(const std::vector<Eigen::Vector3d>& nodal, const Vec2& p, Eigen::Vector3d& out) const {
  for (std::size_t t = 0; t < mesh_.triangles.size(); ++t) {
    const auto& tri = mesh_.triangles[t];
    const Vec2& a = mesh_.nodes[static_cast<std::size_t>(tri[0])];
    const Vec2& b = mesh_.nodes[static_cast<std::size_t>(tri[1])];
    const Vec2& c = mesh_.nodes[static_cast<std::size_t>(tri[2])];
    const double area2 = cross(b - a, c - a);
    const double l1 = cross(c - b, p - b) / area2, l2 = cross(a - c, p - c) / area2;
    const double l0 = 1.0 - l1 - l2;
    // Barycentric weights: l1 of a is area(b, c, p) / area(a, b, c), and so on.
    const double tol = -1e-12;
    if (l1 < tol || l2 < tol || l0 < tol) continue;
    out = l1 * nodal[static_cast<std::size_t>(tri[0])] + l2 * nodal[static_cast<std::size_t>(tri[1])] +
          l0 * nodal[static_cast<std::size_t>(tri[2])];
    return true;
  }
  return false;
}

}  // namespace floesim::fracture
