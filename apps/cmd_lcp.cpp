// floesim lcp FILE.dat [--solver lemke|pgs] [--repeat R] [--fallback]
//                      [--factorization auto|dense|sparse]
// Solves one LCP stored in the Siconos text format and prints key: value lines:
// file, status, n, pivots (Lemke) or iterations (PGS), residual (the scaled
// complementarity residual of contact/lcp/lcp.hpp), time_ms (median over R
// solves, reading excluded); with --fallback also the chain's method and one
// `attempt:` line per step. Exit 0 when solved, 1 otherwise (ray, pivot limit,
// failure), 2 for a bad file or usage.
#include <algorithm>
#include <chrono>
#include <iostream>
#include <memory>
#include <vector>

#include "apps/commands.hpp"
#include "contact/lcp/fallback.hpp"
#include "contact/lcp/siconos_io.hpp"

namespace floesim::apps {

namespace {

struct LcpArgs {
  std::string file;
  std::string solver = "lemke";
  std::string factorization = "auto";
  int repeat = 1;
  bool fallback = false;
};

// Runs `solve` R times; returns the last result and the median time in ms.
template <class Solve>
auto timed(int repeat, Solve&& solve) {
  std::vector<double> ms;
  decltype(solve()) result{};
  for (int r = 0; r < repeat; ++r) {
    const auto start = std::chrono::steady_clock::now();
    result = solve();
    const auto stop = std::chrono::steady_clock::now();
    ms.push_back(std::chrono::duration<double, std::milli>(stop - start).count());
  }
  std::nth_element(ms.begin(), ms.begin() + static_cast<long>(ms.size() / 2), ms.end());
  return std::make_pair(std::move(result), ms[ms.size() / 2]);
}

int run_lcp(const LcpArgs& args) {
  using namespace floesim::lcp;
  const Lcp problem = read_siconos_lcp(args.file);
  FallbackOptions options;
  if (args.factorization == "dense") options.lemke.factorization = Factorization::dense;
  if (args.factorization == "sparse") options.lemke.factorization = Factorization::sparse;

  Result result;
  double ms = 0.0;
  std::vector<Attempt> attempts;
  std::string method = args.solver;
  if (args.fallback) {
    auto [chain, t] = timed(args.repeat, [&] { return solve_with_fallbacks(problem, options); });
    result = chain.result;
    attempts = chain.attempts;
    method = std::string(to_string(chain.method)) + (chain.flagged ? " (flagged)" : "");
    ms = t;
  } else if (args.solver == "pgs") {
    std::tie(result, ms) = timed(args.repeat, [&] { return solve_pgs(problem, options.pgs); });
  } else {
    std::tie(result, ms) = timed(args.repeat, [&] { return solve_lemke(problem, options.lemke); });
  }

  std::cout.precision(6);
  std::cout << "file: " << args.file << "\n"
            << "status: " << to_string(result.status) << "\n"
            << "n: " << problem.size() << "\n";
  if (args.fallback) std::cout << "method: " << method << "\n";
  if (method == "pgs")
    std::cout << "iterations: " << result.iterations << "\n";
  else
    std::cout << "pivots: " << result.pivots << "\n";
  std::cout << "residual: " << result.residual << "\n"
            << "time_ms: " << ms << "\n";
  for (const Attempt& a : attempts)
    std::cout << "attempt: " << to_string(a.method) << " " << to_string(a.status) << " "
              << a.pivots << " " << a.residual << "\n";
  return result.status == Status::solved ? 0 : 1;
}

}  // namespace

void add_lcp_command(CLI::App& app, Registry& registry) {
  auto args = std::make_shared<LcpArgs>();
  CLI::App* sub = app.add_subcommand(
      "lcp", "Solve one LCP in the Siconos text format (described in floesim's data/lcp/README.md)");
  sub->add_option("FILE", args->file, "LCP file (.dat)")->required();
  sub->add_option("--solver", args->solver, "lemke (default) or pgs")
      ->check(CLI::IsMember({"lemke", "pgs"}));
  sub->add_option("--repeat", args->repeat, "Solve R times, report the median time")
      ->check(CLI::Range(1, 1000000));
  sub->add_flag("--fallback", args->fallback,
                "Use the fallback chain (other covering, regularisation, PGS)");
  sub->add_option("--factorization", args->factorization,
                  "Lemke basis factorisation: auto (default), dense or sparse")
      ->check(CLI::IsMember({"auto", "dense", "sparse"}));
  registry[sub] = [args] { return run_lcp(*args); };
}

}  // namespace floesim::apps
