// floesim_bench_lcp_newton: the semismooth Newton method on the LCP
// (contact/lcp/newton.hpp) and the contact Newton method (contact_newton.hpp)
// against Lemke (lemke.hpp) on the LCPs of a folder, alternating per file.
//
//   floesim_bench_lcp_newton DIR [--repeat R] [--csv OUT.csv] [--note TEXT] [--gs-sweeps S]
//                            [--sparse-lu umfpack|klu] [--refactor K]
//
// Every DIR/*.dat (Siconos format) is solved cold by all; when DIR/NAME.guess
// exists (one 0/1 flag per unknown, a warm start: which z were basic in the
// previous LCP of the same contacts), also warm by all. The contact Newton
// method runs only on Stewart–Trinkle LCPs (n = 4m, the alpha rows holding mu
// and -E^T: the layout of contact/impulse.hpp), with mu read from M. Per
// solve: status, residual (lcp.hpp, the one residual), iterations or pivots
// (Lemke: also its basis solves, entering columns and lexicographic
// tie-breaks), and the median wall time of R runs, the solvers alternating.
// "polish": Lemke started from the basis the contact Newton method ended
// with (repaired when singular, basis_repair.hpp), one run.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <vector>

#include "contact/lcp/contact_newton.hpp"
#include "contact/lcp/lemke.hpp"
#include "contact/lcp/newton.hpp"
#include "contact/lcp/siconos_io.hpp"

namespace {

using namespace floesim::lcp;
using Clock = std::chrono::steady_clock;

struct Timed {
  Result result;
  double seconds = 0.0;
};

template <class F>
Timed run(F&& solve) {
  const auto t0 = Clock::now();
  Timed t{solve(), 0.0};
  t.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  return t;
}

// The Stewart–Trinkle layout of contact/impulse.hpp, or contacts = 0.
FrictionLayout friction_layout(const Lcp& lcp) {
  const Index n = lcp.size();
  if (n % 4 != 0) return {};
  const Index m = n / 4;
  const SparseMatrix M = sparse_copy(lcp);
  const double mu = M.coeff(3 * m, 0);
  for (Index k = 0; k < m; ++k)
    if (M.coeff(3 * m + k, k) != mu || M.coeff(m + 2 * k, 3 * m + k) != 1.0 ||
        M.coeff(3 * m + k, m + 2 * k + 1) != -1.0 || lcp.q(3 * m + k) != 0.0)
      return {};
  return {static_cast<std::size_t>(m), mu};
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Newton against Lemke on a folder of LCPs"};
  std::string dir, csv;
  std::vector<std::string> notes;
  int repeat = 3;
  long gs_sweeps = 0;
  app.add_option("dir", dir, "folder of Siconos-format LCPs (*.dat, optional *.guess)")->required();
  app.add_option("--repeat", repeat, "timed runs per solver and start (median kept)");
  app.add_option("--csv", csv, "write the results as CSV");
  app.add_option("--note", notes, "comment lines for the CSV header");
  app.add_option("--gs-sweeps", gs_sweeps, "contact-wise Gauss–Seidel sweeps before the contact Newton method");
  std::string sparse_lu = LemkeOptions{}.sparse_lu == SparseLu::klu ? "klu" : "umfpack";
  app.add_option("--sparse-lu", sparse_lu, "Lemke's sparse LU of the reduced basis: umfpack or klu")
      ->check(CLI::IsMember({"umfpack", "klu"}));
  int refactor_interval = LemkeOptions{}.refactor_interval;
  app.add_option("--refactor", refactor_interval, "Lemke's pivots between basis refactorisations")
      ->check(CLI::Range(1, 100000));
  CLI11_PARSE(app, argc, argv);

  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.path().extension() == ".dat") files.push_back(e.path());
  std::sort(files.begin(), files.end());

  std::ostringstream table;
  table << "file,n,start,newton_status,newton_residual,newton_iterations,newton_s,lemke_status,lemke_residual,"
           "lemke_pivots,lemke_solves,lemke_s,contact_newton_status,contact_newton_residual,contact_newton_solves,"
           "contact_newton_factorisations,contact_newton_s,polish_status,polish_residual,polish_pivots,polish_s\n";
  for (const auto& path : files) {
    const Lcp lcp = read_siconos_lcp(path.string());
    const Index n = lcp.size();
    const FrictionLayout layout = friction_layout(lcp);
    std::vector<std::uint8_t> guess;
    if (std::ifstream g(std::filesystem::path(path).replace_extension(".guess")); g) {
      int v = 0;
      while (g >> v) guess.push_back(static_cast<std::uint8_t>(v != 0));
      if (static_cast<Index>(guess.size()) != n) guess.clear();
    }
    for (const bool warm : {false, true}) {
      if (warm && guess.empty()) continue;
      NewtonOptions no;
      ContactNewtonOptions co;
      co.gs_sweeps = gs_sweeps;
      LemkeOptions lo;
      lo.max_pivots = 15 * n + 1000;  // the collision LCPs' limit (contact/impulse.hpp)
      lo.sparse_lu = sparse_lu == "klu" ? SparseLu::klu : SparseLu::umfpack;
      lo.refactor_interval = refactor_interval;
      if (warm) {
        no.start = &guess;
        lo.start = &guess;
        co.start = &guess;
      }
      std::vector<double> tn, tl, tc;
      Timed a, b, c;
      ContactNewtonStats cstats;
      LemkeStats lstats;
      for (int r = 0; r < std::max(1, repeat); ++r) {
        a = run([&] { return solve_newton(lcp, no); });
        b = run([&] { return solve_lemke(lcp, lo, &lstats); });
        tn.push_back(a.seconds);
        tl.push_back(b.seconds);
        if (layout.contacts > 0) {
          cstats = {};
          c = run([&] { return solve_contact_newton(lcp, layout, co, &cstats); });
          tc.push_back(c.seconds);
        }
      }
      const bool has_c = layout.contacts > 0;
      // Lemke from the basis the contact Newton method ended with (a polish).
      Timed d;
      if (has_c) {
        LemkeOptions po = lo;
        po.start = &c.result.z_basic;
        po.repair_start.rounds = 3;
        d = run([&] { return solve_lemke(lcp, po); });
      }
      table << path.filename().string() << "," << n << "," << (warm ? "warm" : "cold") << ","
            << to_string(a.result.status) << "," << a.result.residual << "," << a.result.iterations << ","
            << median(tn) << "," << to_string(b.result.status) << "," << b.result.residual << ","
            << b.result.pivots << "," << lstats.solves << "," << median(tl) << ",";
      if (has_c)
        table << to_string(c.result.status) << "," << c.result.residual << "," << cstats.solves << ","
              << cstats.factorisations << "," << median(tc) << "," << to_string(d.result.status) << ","
              << d.result.residual << "," << d.result.pivots << "," << d.seconds << "\n";
      else
        table << ",,,,,,,,\n";
      std::cout << std::setw(28) << path.filename().string() << " n " << std::setw(5) << n << " "
                << (warm ? "warm" : "cold") << "  newton " << to_string(a.result.status) << " "
                << a.result.residual << " it " << a.result.iterations << " " << median(tn) << " s   lemke "
                << to_string(b.result.status) << " " << b.result.residual << " piv " << b.result.pivots << " "
                << median(tl) << " s";
      if (has_c)
        std::cout << "   contact " << to_string(c.result.status) << " " << c.result.residual << " it "
                  << cstats.solves << " (" << cstats.factorisations << " f, " << cstats.rejected << " rej, "
                  << cstats.state_changes << " ch) " << median(tc) << " s  polish " << to_string(d.result.status)
                  << " piv " << d.result.pivots << " " << d.seconds << " s";
      std::cout << "\n";
    }
  }
  if (!csv.empty()) {
    std::ofstream out(csv);
    out << "# floesim_bench_lcp_newton";
    for (int i = 1; i < argc; ++i) out << " " << argv[i];
    out << "\n";
    for (const auto& note : notes) out << "# " << note << "\n";
    out << table.str();
  }
}
