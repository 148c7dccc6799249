// floesim_bench_lcp: our Lemke against Siconos Numerics' lcp_lexicolemke (when
// built with it) on the rigid-body contact LCPs of data/lcp/contact/.
//
//   floesim_bench_lcp [--data DIR] [--repeat R] [--factorization auto|dense|sparse]
//                     [--sparse-lu umfpack|klu] [--refactor K] [--csv OUT.csv] [--filter SUBSTRING] [--no-siconos]
//
// Per file: warm-up solve, then R timed solves of each solver in this process;
// the median is kept. Both answers are judged by the same residual
// (contact/lcp/lcp.hpp): "solved" means status solved (Siconos: info 0) AND
// residual <= 1e-9. ratio = our median time / Siconos's median time.
// Prints a table; with --csv also writes it as CSV, headed by the command line.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <vector>

#include "contact/lcp/lemke.hpp"
#include "contact/lcp/siconos_io.hpp"

#ifdef FLOESIM_HAVE_SICONOS
#include <siconos/numerics/LCP_Solvers.h>
#include <siconos/numerics/LinearComplementarityProblem.h>
#include <siconos/numerics/NumericsMatrix.h>
#include <siconos/numerics/NumericsVerbose.h>
#include <siconos/numerics/SolverOptions.h>
#include <siconos/numerics/lcp_cst.h>
#endif

namespace {

using namespace floesim::lcp;

constexpr double kSolvedResidual = 1e-9;

struct Outcome {
  std::string status = "-";
  long pivots = 0;
  double residual = 0.0;
  double ms = 0.0;
};

// Median of `repeat` timed calls after one warm-up; a solver whose warm-up takes
// over a second (Siconos cycling to its pivot limit) is timed by fewer calls.
template <class Solve>
double median_ms(int repeat, Solve&& solve) {
  const auto warm = std::chrono::steady_clock::now();
  solve();
  const double warm_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - warm).count();
  if (warm_ms > 1000.0) repeat = std::max(1, std::min(repeat, static_cast<int>(5000.0 / warm_ms)));
  std::vector<double> ms;
  for (int r = 0; r < repeat; ++r) {
    const auto start = std::chrono::steady_clock::now();
    solve();
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                     .count());
  }
  std::nth_element(ms.begin(), ms.begin() + static_cast<long>(ms.size() / 2), ms.end());
  return ms[ms.size() / 2];
}

Outcome run_ours(const Lcp& lcp, const LemkeOptions& options, int repeat, LemkeStats& stats) {
  Result result;
  Outcome out;
  out.ms = median_ms(repeat, [&] { result = solve_lemke(lcp, options, &stats); });
  out.status = std::string(to_string(result.status));
  if (result.status == Status::solved && result.residual > kSolvedResidual) out.status = "inaccurate";
  out.pivots = result.pivots;
  out.residual = result.residual;
  return out;
}

#ifdef FLOESIM_HAVE_SICONOS
Outcome run_siconos(const Lcp& lcp, int repeat) {
  const int n = static_cast<int>(lcp.size());
  const DenseMatrix M = std::visit([](const auto& m) { return DenseMatrix(m); }, lcp.M);
  NumericsMatrix* nm = NM_create(NM_DENSE, n, n);
  std::copy(M.data(), M.data() + M.size(), nm->matrix0);  // both column-major
  Vector q = lcp.q;
  LinearComplementarityProblem problem{n, nm, q.data()};
  SolverOptions* options = solver_options_create(SICONOS_LCP_LEMKE);
  options->iparam[SICONOS_IPARAM_MAX_ITER] = static_cast<int>(50 * (n + 1) + 1000);
  Vector z(n), w(n);
  int info = 0;
  Outcome out;
  out.ms = median_ms(repeat, [&] {
    z.setZero();
    w.setZero();
    lcp_lexicolemke(&problem, z.data(), w.data(), &info, options);
  });
  out.pivots = options->iparam[SICONOS_IPARAM_ITER_DONE];
  out.residual = residual(lcp, z);
  out.status = info == 0 ? (out.residual <= kSolvedResidual ? "solved" : "wrong")
                         : "failed(" + std::to_string(info) + ")";
  solver_options_delete(options);
  NM_free(nm);  // frees the struct too
  return out;
}
#endif

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"floesim_bench_lcp: Lemke on the contact LCPs, against Siconos when available"};
  std::string data = FLOESIM_BENCH_LCP_DATA;
  std::string csv, filter, factorization = "auto";
  int repeat = 5;
  bool skip_siconos = false;
  int refactor_interval = LemkeOptions{}.refactor_interval;
  app.add_option("--data", data, "Folder of .dat LCPs");
  app.add_option("--repeat", repeat, "Timed solves per file (median kept)")->check(CLI::Range(1, 1000));
  app.add_option("--factorization", factorization, "auto, dense or sparse")
      ->check(CLI::IsMember({"auto", "dense", "sparse"}));
  std::string sparse_lu = LemkeOptions{}.sparse_lu == SparseLu::klu ? "klu" : "umfpack";
  app.add_option("--sparse-lu", sparse_lu, "the sparse LU of the reduced basis: umfpack or klu")
      ->check(CLI::IsMember({"umfpack", "klu"}));
  app.add_option("--refactor", refactor_interval, "Pivots between basis refactorisations")
      ->check(CLI::Range(1, 100000));
  app.add_option("--csv", csv, "Also write the table as CSV here");
  app.add_option("--filter", filter, "Only files whose name contains this");
  app.add_flag("--no-siconos", skip_siconos, "Do not run Siconos even when built with it");
  CLI11_PARSE(app, argc, argv);

  LemkeOptions options;
  options.refactor_interval = refactor_interval;
  options.sparse_lu = sparse_lu == "klu" ? SparseLu::klu : SparseLu::umfpack;
  if (factorization == "dense") options.factorization = Factorization::dense;
  if (factorization == "sparse") options.factorization = Factorization::sparse;
#ifdef FLOESIM_HAVE_SICONOS
  numerics_set_verbose(0);
  const bool with_siconos = !skip_siconos;
#else
  const bool with_siconos = false;
#endif

  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(data))
    if (e.path().extension() == ".dat" && e.path().filename().string().find(filter) != std::string::npos)
      files.push_back(e.path());
  std::sort(files.begin(), files.end());

  std::ostringstream table;
  table << "file,n,nnz,sparse_refactorisations,solves,ours_status,ours_pivots,ours_residual,ours_ms,"
           "siconos_status,siconos_pivots,siconos_residual,siconos_ms,ratio\n";
  std::cout << std::left << std::setw(26) << "file" << std::setw(6) << "n" << std::setw(12)
            << "ours" << std::setw(8) << "pivots" << std::setw(11) << "ms" << std::setw(12)
            << "siconos" << std::setw(8) << "pivots" << std::setw(11) << "ms" << "ratio\n";
  for (const auto& path : files) {
    const Lcp lcp = read_siconos_lcp(path.string());
    LemkeStats stats;
    const Outcome ours = run_ours(lcp, options, repeat, stats);
    Outcome theirs;
#ifdef FLOESIM_HAVE_SICONOS
    if (with_siconos) theirs = run_siconos(lcp, repeat);
#endif
    const double ratio = with_siconos ? ours.ms / theirs.ms : 0.0;
    const std::string name = path.stem().string();
    std::cout << std::setw(26) << name << std::setw(6) << lcp.size() << std::setw(12) << ours.status
              << std::setw(8) << ours.pivots << std::setw(11) << std::setprecision(4) << ours.ms
              << std::setw(12) << theirs.status << std::setw(8) << theirs.pivots << std::setw(11)
              << theirs.ms << (with_siconos ? std::to_string(ratio) : "-") << "\n";
    table << name << "," << lcp.size() << "," << nonzeros(lcp) << ","
          << stats.sparse_refactorisations << "/" << stats.refactorisations << "," << stats.solves << "," << ours.status << ","
          << ours.pivots << "," << ours.residual << "," << ours.ms << "," << theirs.status << ","
          << theirs.pivots << "," << theirs.residual << "," << theirs.ms << ","
          << (with_siconos ? std::to_string(ratio) : "") << "\n";
  }
  if (!csv.empty()) {
    std::ofstream out(csv);
    out << "# command:";
    for (int a = 0; a < argc; ++a) out << " " << argv[a];
    out << "\n# siconos: " << (with_siconos ? "lcp_lexicolemke (libsiconos-numerics-dev)" : "not built")
        << "; times in ms, median of " << repeat << " after one warm-up\n"
        << table.str();
    if (!out) {
      std::cerr << "floesim_bench_lcp: cannot write " << csv << "\n";
      return 2;
    }
  }
  return 0;
}
