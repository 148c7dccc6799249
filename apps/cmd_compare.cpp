// floesim compare A.h5 B.h5 [--rtol R --atol A]: regression comparison of two
// run files. Exit 0 when equal within tolerance, 1 with a report otherwise.
#include <iomanip>
#include <iostream>

#include "apps/commands.hpp"
#include "core/run_file.hpp"

namespace floesim::apps {

void add_compare_command(CLI::App& app, Registry& registry) {
  struct Args { std::string a, b; CompareOptions opt; };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand("compare", "Compare two run files dataset by dataset: "
                                                 "equal when |a - b| <= atol + rtol |b| everywhere");
  sub->add_option("A", args->a, "Run file A")->required();
  sub->add_option("B", args->b, "Run file B (the reference)")->required();
  // The tolerances' rule (finite, >= 0) is validate(CompareOptions), called by compare_runs.
  sub->add_option("--rtol", args->opt.rtol, "Relative tolerance (>= 0)")->capture_default_str();
  sub->add_option("--atol", args->opt.atol, "Absolute tolerance (>= 0)")->capture_default_str();
  registry[sub] = [args] {
    const CompareResult r = compare_runs(args->a, args->b, args->opt);
    std::cout << "datasets_compared: " << r.datasets_compared << "\n";
    std::cout << "differences: " << r.differences.size() << "\n";
    for (const DatasetDifference& d : r.differences) {
      std::cout << "  " << d.dataset << ": " << d.what;
      if (d.what == "values")
        std::cout << " (" << d.count << " elements out of tolerance, max |a - b| = " << std::setprecision(6)
                  << d.max_abs << " at flat index " << d.at << ")";
      std::cout << "\n";
    }
    std::cout << "equal: " << (r.equal() ? "true" : "false") << "\n";
    return r.equal() ? 0 : 1;
  };
}

}  // namespace floesim::apps
