// The elastic floe: mesh quality, the patch test (a uniform strain is
// reproduced exactly by linear triangles on any mesh: Irons & Razzaque 1972;
// Zienkiewicz & Taylor, The Finite Element Method, vol. 1, §10.3) and the
// strain energy of a bar in uniform tension, sigma^2 L W h / (2 E).
#include <doctest/doctest.h>

#include <Eigen/Cholesky>
#include <cmath>

#include "cases.hpp"
#include "contact/fracture/response.hpp"
#include "core/error.hpp"

using namespace floesim;
using namespace floesim::fracture;
using namespace floesim::fracture::testing;

TEST_SUITE_BEGIN("contact");

TEST_CASE("fracture mesh: size and angle bounds and the polygon's area") {
  // A non-convex floe (an L shape) and a 40-gon.
  const std::vector<Vec2> ell{{0, 0}, {30, 0}, {30, 10}, {10, 10}, {10, 25}, {0, 25}};
  for (const auto& poly : {ell, disc(10.0, 40)}) {
    MeshOptions o;
    o.size = 1.5;
    const Mesh m = mesh_polygon(poly, o);
    CHECK(m.size == o.size);
    double area = 0.0, min_angle = M_PI, max_edge = 0.0;
    for (std::size_t t = 0; t < m.triangles.size(); ++t) {
      REQUIRE(m.area(t) > 0.0);
      area += m.area(t);
      for (int k = 0; k < 3; ++k) {
        const Vec2& a = m.nodes[static_cast<std::size_t>(m.triangles[t][static_cast<std::size_t>(k)])];
        const Vec2& b = m.nodes[static_cast<std::size_t>(m.triangles[t][static_cast<std::size_t>((k + 1) % 3)])];
        const Vec2& c = m.nodes[static_cast<std::size_t>(m.triangles[t][static_cast<std::size_t>((k + 2) % 3)])];
        max_edge = std::max(max_edge, (b - a).norm());
        min_angle = std::min(min_angle, std::acos((b - a).normalized().dot((c - a).normalized())));
      }
    }
    CHECK(area == doctest::Approx(signed_area(poly)).epsilon(1e-12));
    CHECK(max_edge <= o.size * (1.0 + 1e-9));
    // CGAL's bound B = 0.125 guarantees about 20.7 degrees away from small input angles.
    CHECK(min_angle * 180.0 / M_PI > 20.0);
  }
}

TEST_CASE("fracture mesh: a huge floe is meshed with a bounded number of triangles") {
  MeshOptions o;
  o.size = 1.0;
  o.max_triangles = 2000;
  const Mesh m = mesh_polygon(rectangle(400.0, 300.0), o);
  CHECK(m.size > 1.0);
  CHECK(m.triangles.size() < 3000);
  CHECK_THROWS_AS(mesh_polygon(std::vector<Vec2>{{0, 0}, {1, 0}}, o), RunError);
}

TEST_CASE("fracture elastic: patch test, a uniform strain is exact on an irregular mesh") {
  MeshOptions o;
  o.size = 1.3;
  const std::vector<Vec2> poly{{0, 0}, {9, -1}, {12, 6}, {5, 11}, {-2, 7}};
  Material mat{6.0e9, 0.3, 917.0, 1.2};
  const ElasticModel model(mesh_polygon(poly, o), mat);
  const Mesh& mesh = model.mesh();
  // u = G x + c with a general (non-symmetric) gradient: strain and a rotation.
  Eigen::Matrix2d g;
  g << 1.0e-4, -3.0e-5, 7.0e-5, -2.0e-4;
  const Vec2 c0{0.01, -0.02};
  const Eigen::Index n = model.dofs();
  Eigen::VectorXd exact(n);
  for (std::size_t i = 0; i < mesh.node_count(); ++i) exact.segment<2>(2 * static_cast<Eigen::Index>(i)) = g * mesh.nodes[i] + c0;
  // Impose it on the outline, solve K u = 0 for the interior nodes.
  std::vector<Eigen::Index> inner, outer;
  for (std::size_t i = 0; i < mesh.node_count(); ++i)
    for (int k = 0; k < 2; ++k) (mesh.on_boundary[i] ? outer : inner).push_back(2 * static_cast<Eigen::Index>(i) + k);
  REQUIRE(inner.size() > 20);
  const Eigen::MatrixXd k = Eigen::MatrixXd(model.stiffness());
  Eigen::MatrixXd kii(inner.size(), inner.size());
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(inner.size()));
  for (std::size_t a = 0; a < inner.size(); ++a) {
    for (std::size_t b = 0; b < inner.size(); ++b) kii(a, b) = k(inner[a], inner[b]);
    for (Eigen::Index j : outer) rhs[a] -= k(inner[a], j) * exact[j];
  }
  const Eigen::VectorXd ui = kii.llt().solve(rhs);
  double err = 0.0;
  for (std::size_t a = 0; a < inner.size(); ++a) err = std::max(err, std::abs(ui[a] - exact[inner[a]]));
  CHECK(err < 1e-12);
  // Every triangle carries the stress D (exx, eyy, gxy).
  const Eigen::Vector3d strain{g(0, 0), g(1, 1), g(0, 1) + g(1, 0)};
  const Eigen::Vector3d stress = model.elasticity() * strain;
  double serr = 0.0;
  for (const Eigen::Vector3d& s : model.element_stress(exact)) serr = std::max(serr, (s - stress).cwiseAbs().maxCoeff());
  CHECK(serr < 1e-9 * stress.cwiseAbs().maxCoeff());
}

TEST_CASE("fracture elastic: bar in tension, energy sigma^2 L W h / (2 E) through the inertia-relief solve") {
  const double lx = 20.0, ly = 4.0, sigma = 2.0e5;
  Material mat{6.0e9, 0.3, 917.0, 0.8};
  MeshOptions o;
  o.size = 0.9;
  const ElasticModel model(mesh_polygon(rectangle(lx, ly), o), mat);
  ResponseOptions ro;
  Responder responder(model, ro);
  Eigen::VectorXd f = Eigen::VectorXd::Zero(model.dofs());
  add_end_traction(model, f, lx / 2, sigma, +1.0);
  add_end_traction(model, f, -lx / 2, sigma, -1.0);
  const Eigen::VectorXd u = responder.solve_static(f);
  const double exact = sigma * sigma * lx * ly * mat.thickness / (2.0 * mat.young);
  CHECK(model.strain_energy(u) == doctest::Approx(exact).epsilon(1e-9));
  // The uniform state: sxx = sigma, syy = sxy = 0 everywhere.
  double err = 0.0;
  for (const Eigen::Vector3d& s : model.element_stress(u)) err = std::max(err, (s - Eigen::Vector3d(sigma, 0, 0)).norm());
  CHECK(err < 1e-8 * sigma);
  // Rigid part removed: no net displacement or rotation (M-weighted).
  const Eigen::VectorXd& m = model.lumped_mass();
  double px = 0.0, py = 0.0;
  for (Eigen::Index i = 0; i < model.dofs(); i += 2) { px += m[i] * u[i]; py += m[i + 1] * u[i + 1]; }
  CHECK(std::abs(px) < 1e-12 * m.sum() * u.cwiseAbs().maxCoeff());
  CHECK(std::abs(py) < 1e-12 * m.sum() * u.cwiseAbs().maxCoeff());
}

TEST_CASE("fracture elastic: a load that is not self-equilibrated is balanced by the floe's inertia") {
  // One end pulled: inertia relief turns the rest into a uniform body force,
  // so the tension falls linearly from sigma at the pulled end to 0 at the
  // free end (d sxx/dx = rho a, a = sigma W h / M): sxx(x) = sigma (x + L/2) / L.
  const double lx = 30.0, ly = 3.0, sigma = 1.0e5;
  Material mat{6.0e9, 0.3, 917.0, 1.0};
  MeshOptions o;
  o.size = 0.75;
  const ElasticModel model(mesh_polygon(rectangle(lx, ly), o), mat);
  Responder responder(model, ResponseOptions{});
  Eigen::VectorXd f = Eigen::VectorXd::Zero(model.dofs());
  add_end_traction(model, f, lx / 2, sigma, +1.0);
  const Eigen::VectorXd u = responder.solve_static(f);
  const auto stress = model.nodal_stress(u);
  for (double x : {-10.0, -5.0, 0.0, 5.0, 10.0}) {
    Eigen::Vector3d s;
    REQUIRE(model.interpolate(stress, Vec2{x, 0.3}, s));
    CHECK(s[0] == doctest::Approx(sigma * (x + lx / 2) / lx).epsilon(0.02));
  }
}

TEST_SUITE_END();
