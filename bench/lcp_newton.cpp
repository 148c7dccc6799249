// floesim_bench_lcp_newton: the semismooth Newton method (contact/lcp/newton.hpp)
// against Lemke (lemke.hpp) on the LCPs of a folder, alternating A/B per file.
//
//   floesim_bench_lcp_newton DIR [--repeat R] [--csv OUT.csv] [--note TEXT]
//
// Every DIR/*.dat (Siconos format) is solved cold by both; when DIR/NAME.guess
// exists (one 0/1 flag per unknown, a warm start: which z were basic in the
// previous LCP of the same contacts), also warm by both. Per solve: status,
// residual (lcp.hpp, the one residual), Newton iterations or Lemke pivots, and
// the median wall time of R runs, Newton and Lemke alternating.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <vector>

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
  app.add_option("dir", dir, "folder of Siconos-format LCPs (*.dat, optional *.guess)")->required();
  app.add_option("--repeat", repeat, "timed runs per solver and start (median kept)");
  app.add_option("--csv", csv, "write the results as CSV");
  app.add_option("--note", notes, "comment lines for the CSV header");
  CLI11_PARSE(app, argc, argv);

  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.path().extension() == ".dat") files.push_back(e.path());
  std::sort(files.begin(), files.end());

  std::ostringstream table;
  table << "file,n,start,newton_status,newton_residual,newton_iterations,newton_s,lemke_status,lemke_residual,"
           "lemke_pivots,lemke_s\n";
  for (const auto& path : files) {
    const Lcp lcp = read_siconos_lcp(path.string());
    const Index n = lcp.size();
    std::vector<std::uint8_t> guess;
    if (std::ifstream g(std::filesystem::path(path).replace_extension(".guess")); g) {
      int v = 0;
      while (g >> v) guess.push_back(static_cast<std::uint8_t>(v != 0));
      if (static_cast<Index>(guess.size()) != n) guess.clear();
    }
    for (const bool warm : {false, true}) {
      if (warm && guess.empty()) continue;
      NewtonOptions no;
      LemkeOptions lo;
      lo.max_pivots = 15 * n + 1000;  // the collision LCPs' limit (contact/impulse.hpp)
      if (warm) {
        no.start = &guess;
        lo.start = &guess;
      }
      std::vector<double> tn, tl;
      Timed a, b;
      for (int r = 0; r < std::max(1, repeat); ++r) {
        a = run([&] { return solve_newton(lcp, no); });
        b = run([&] { return solve_lemke(lcp, lo); });
        tn.push_back(a.seconds);
        tl.push_back(b.seconds);
      }
      table << path.filename().string() << "," << n << "," << (warm ? "warm" : "cold") << ","
            << to_string(a.result.status) << "," << a.result.residual << "," << a.result.iterations << ","
            << median(tn) << "," << to_string(b.result.status) << "," << b.result.residual << ","
            << b.result.pivots << "," << median(tl) << "\n";
      std::cout << std::setw(28) << path.filename().string() << " n " << std::setw(5) << n << " "
                << (warm ? "warm" : "cold") << "  newton " << to_string(a.result.status) << " "
                << a.result.residual << " it " << a.result.iterations << " " << median(tn) << " s   lemke "
                << to_string(b.result.status) << " " << b.result.residual << " piv " << b.result.pivots << " "
                << median(tl) << " s\n";
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
