// floesim_bench_fracture: two studies behind docs/fracture.md.
//  1. Why linear triangles and not a lattice of springs: on the same
//     irregular Delaunay meshes, a central-spring lattice calibrated on the
//     regular triangular lattice (k_e = sum over the triangles of the edge of
//     E h A_t / L_e^2, exact there, with nu fixed at 1/3) is given a uniform
//     strain on its outline; the inner nodes do not follow it (the patch test
//     fails), so its stresses are wrong locally. Linear triangles are exact.
//  2. What a percussion analysis costs: the model (mesh, matrices), the first
//     analysis (which also factorises) and the next ones, for square floes
//     of growing size (mesh 2 m, at most 12000 triangles).
//  3. The meshers per floe: every cell of the drift_500 bench's pack (500
//     floes, 50% of a 2 km box, seed 1) meshed at 20, 10 and 5 m by CGAL's
//     refinement, by the default (the lattice where it meets its bounds,
//     else CGAL) and by the lattice mesher alone (its attempts that miss the
//     bounds included), the median over R runs of the time per floe.
// usage: floesim_bench_fracture [--repeat R] [--meshers]   (R runs of parts 2 and 3;
// --meshers: part 3 only)
#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <map>

#include "contact/fracture/floe_fracture.hpp"
#include "core/pack_generator.hpp"

using namespace floesim;
using namespace floesim::fracture;

namespace {

void lattice_study() {
  std::printf("# patch test: uniform strain imposed on the outline, inner nodes solved\n");
  std::printf("mesh_size,strain,lattice_displacement_error,lattice_stress_error,triangles_stress_error\n");
  const std::vector<Vec2> poly{{0, 0}, {9, -1}, {12, 6}, {5, 11}, {-2, 7}};
  const Material mat{6.0e9, 1.0 / 3.0, 917.0, 1.0};
  for (double size : {1.3, 0.65, 0.45}) {
    MeshOptions o;
    o.size = size;
    o.mesher = Mesher::cgal;  // irregular meshes: on a regular lattice the springs would pass
    const ElasticModel fe(mesh_polygon(poly, o), mat);
    const Mesh& mesh = fe.mesh();
    const auto n = static_cast<Eigen::Index>(2 * mesh.node_count());
    std::map<std::pair<int, int>, double> k;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
      for (int a = 0; a < 3; ++a) {
        const int i = mesh.triangles[t][static_cast<std::size_t>(a)];
        const int j = mesh.triangles[t][static_cast<std::size_t>((a + 1) % 3)];
        const double l2 = (mesh.nodes[static_cast<std::size_t>(i)] - mesh.nodes[static_cast<std::size_t>(j)]).squaredNorm();
        k[{std::min(i, j), std::max(i, j)}] += mat.young * mat.thickness * mesh.area(t) / l2;
      }
    Eigen::MatrixXd lattice = Eigen::MatrixXd::Zero(n, n);
    for (const auto& [e, ke] : k) {
      const Vec2 d = (mesh.nodes[static_cast<std::size_t>(e.second)] - mesh.nodes[static_cast<std::size_t>(e.first)]).normalized();
      const Eigen::Matrix2d b = ke * d * d.transpose();
      lattice.block<2, 2>(2 * e.first, 2 * e.first) += b;
      lattice.block<2, 2>(2 * e.second, 2 * e.second) += b;
      lattice.block<2, 2>(2 * e.first, 2 * e.second) -= b;
      lattice.block<2, 2>(2 * e.second, 2 * e.first) -= b;
    }
    const Eigen::MatrixXd triangles = Eigen::MatrixXd(fe.stiffness());
    const char* names[3] = {"uniaxial", "shear", "dilatation"};
    for (int c = 0; c < 3; ++c) {
      Eigen::Matrix2d g;
      if (c == 0) g << 1e-4, 0.0, 0.0, 0.0;
      if (c == 1) g << 0.0, 5e-5, 5e-5, 0.0;
      if (c == 2) g << 1e-4, 0.0, 0.0, 1e-4;
      Eigen::VectorXd exact(n);
      for (std::size_t i = 0; i < mesh.node_count(); ++i) exact.segment<2>(2 * static_cast<Eigen::Index>(i)) = g * mesh.nodes[i];
      std::vector<Eigen::Index> in, out;
      for (std::size_t i = 0; i < mesh.node_count(); ++i)
        for (int q = 0; q < 2; ++q) (mesh.on_boundary[i] ? out : in).push_back(2 * static_cast<Eigen::Index>(i) + q);
      auto solve = [&](const Eigen::MatrixXd& kk) {
        const auto m = static_cast<Eigen::Index>(in.size());
        Eigen::MatrixXd a(m, m);
        Eigen::VectorXd r = Eigen::VectorXd::Zero(m);
        for (Eigen::Index p = 0; p < m; ++p) {
          for (Eigen::Index q = 0; q < m; ++q) a(p, q) = kk(in[static_cast<std::size_t>(p)], in[static_cast<std::size_t>(q)]);
          for (Eigen::Index j : out) r[p] -= kk(in[static_cast<std::size_t>(p)], j) * exact[j];
        }
        const Eigen::VectorXd u = a.ldlt().solve(r);
        Eigen::VectorXd full = exact;
        for (Eigen::Index p = 0; p < m; ++p) full[in[static_cast<std::size_t>(p)]] = u[p];
        return full;
      };
      // Stress of a displacement field, element by element, against the exact uniform one.
      const Eigen::Vector3d strain{g(0, 0), g(1, 1), g(0, 1) + g(1, 0)};
      const Eigen::Vector3d stress = fe.elasticity() * strain;
      auto stress_error = [&](const Eigen::VectorXd& u) {
        double worst = 0.0;
        for (const Eigen::Vector3d& s : fe.element_stress(u)) worst = std::max(worst, (s - stress).norm());
        return worst / stress.norm();
      };
      const Eigen::VectorXd ul = solve(lattice), ut = solve(triangles);
      std::printf("%g,%s,%.3g,%.3g,%.3g\n", size, names[c], (ul - exact).cwiseAbs().maxCoeff() / exact.cwiseAbs().maxCoeff(),
                  stress_error(ul), stress_error(ut));
    }
  }
}

void cost_study(int repeat) {
  std::printf("# cost of a percussion analysis: square floe, impulse at the middle of a side, mesh 2 m, tau 0.01 s\n");
  std::printf("side_m,nodes,triangles,model_ms,first_analysis_ms,next_analysis_ms,steps\n");
  for (double side : {20.0, 40.0, 80.0, 160.0, 320.0}) {
    double model = 1e300, first = 1e300, next = 1e300;
    std::size_t nodes = 0, triangles = 0;
    int steps = 0;
    for (int r = 0; r < repeat; ++r) {
      FractureParams p;
      p.mesh_size = 2.0;
      const std::vector<Vec2> square{{-side / 2, -side / 2}, {side / 2, -side / 2}, {side / 2, side / 2}, {-side / 2, side / 2}};
      const auto t0 = std::chrono::steady_clock::now();
      FloeFracture floe(square, 1.0, 917.0, p);
      const PointLoad hit{{-side / 2, 0.0}, {1.0e4, 0.0}, true};
      const auto t1 = std::chrono::steady_clock::now();
      floe.analyse(std::span<const PointLoad>(&hit, 1));  // the first builds the dynamic factor
      const auto t2 = std::chrono::steady_clock::now();
      const FloeFracture::Result res = floe.analyse(std::span<const PointLoad>(&hit, 1));
      const auto t3 = std::chrono::steady_clock::now();
      model = std::min(model, std::chrono::duration<double, std::milli>(t1 - t0).count());
      first = std::min(first, std::chrono::duration<double, std::milli>(t2 - t1).count());
      next = std::min(next, std::chrono::duration<double, std::milli>(t3 - t2).count());
      nodes = floe.model().mesh().node_count();
      triangles = floe.model().mesh().triangles.size();
      steps = res.response.steps;
    }
    std::printf("%g,%zu,%zu,%.1f,%.1f,%.1f,%d\n", side, nodes, triangles, model, first, next, steps);
  }
}

void mesher_study(int repeat) {
  PackOptions po;
  po.floes = 500;
  po.width = po.height = 2000.0;
  po.concentration = 0.5;
  const GeneratedPack pack = generate_pack(po);
  std::printf("# meshers per floe: the %zu cells of a 500-floe pack (drift_500), median of %d runs\n",
              pack.floes.size(), repeat);
  std::printf("mesh_size,mesher,us_per_floe,lattice_meshes,triangles_per_floe\n");
  for (double size : {20.0, 10.0, 5.0})
    for (Mesher mesher : {Mesher::cgal, Mesher::automatic, Mesher::lattice}) {
      std::vector<double> times;
      std::size_t lattice = 0, triangles = 0;
      for (int r = 0; r < repeat; ++r) {
        MeshOptions o;
        o.size = size;
        o.mesher = mesher;
        lattice = triangles = 0;
        const auto t0 = std::chrono::steady_clock::now();
        for (std::size_t i = 0; i < pack.floes.size(); ++i) {
          if (mesher == Mesher::lattice) {
            const std::optional<Mesh> m = mesh_lattice(pack.floes.vertices(i), size, o);
            lattice += m.has_value();
            triangles += m ? m->triangles.size() : 0;
            continue;
          }
          const Mesh m = mesh_polygon(pack.floes.vertices(i), o);
          lattice += m.mesher == Mesher::lattice;
          triangles += m.triangles.size();
        }
        times.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count() /
                        static_cast<double>(pack.floes.size()));
      }
      std::sort(times.begin(), times.end());
      const char* name = mesher == Mesher::cgal ? "cgal" : mesher == Mesher::automatic ? "auto" : "lattice_alone";
      std::printf("%g,%s,%.1f,%zu,%.1f\n", size, name, times[times.size() / 2], lattice,
                  static_cast<double>(triangles) / static_cast<double>(mesher == Mesher::lattice ? std::max<std::size_t>(lattice, 1)
                                                                                               : pack.floes.size()));
    }
}

}  // namespace

int main(int argc, char** argv) {
  int repeat = 3;
  bool meshers_only = false;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--repeat") == 0 && i + 1 < argc) repeat = std::max(1, std::atoi(argv[i + 1]));
    if (std::strcmp(argv[i], "--meshers") == 0) meshers_only = true;
  }
  if (!meshers_only) {
    lattice_study();
    cost_study(repeat);
  }
  mesher_study(repeat);
}
