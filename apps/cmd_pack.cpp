// floesim pack --floes N --concentration C --box W H [--seed S]
//   [--size-distribution uniform|power:ALPHA] [--min-size A --max-size B]
//   [--thickness H | --thickness-range A B] [--density R] [--min-gap G]
//   [--relax K] [--walls WIDTH] -o PACK.h5
// A random pack of non-overlapping floes (core/pack_generator.hpp), written as
// a floesim-pack-1 file; prints key: value lines.
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>

#include "apps/commands.hpp"
#include "core/error.hpp"
#include "core/pack.hpp"
#include "core/pack_generator.hpp"

namespace floesim::apps {

namespace {

// "uniform" or "power:ALPHA".
SizeDistribution parse_size_distribution(const std::string& text) {
  SizeDistribution s;
  if (text == "uniform") return s;
  const std::string prefix = "power:";
  if (text.rfind(prefix, 0) == 0) {
    const std::string number = text.substr(prefix.size());
    std::size_t used = 0;
    double alpha = std::nan("");
    try {
      alpha = std::stod(number, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == number.size() && !number.empty()) {
      s.kind = SizeDistribution::Kind::power_law;
      s.exponent = alpha;
      return s;
    }
  }
  throw InputError("--size-distribution: expected 'uniform' or 'power:ALPHA' (e.g. power:2.5), got '" + text + "'");
}

}  // namespace

void add_pack_command(CLI::App& app, Registry& registry) {
  struct Args {
    PackOptions options;
    std::vector<double> box;
    std::string sizes = "uniform";
    double min_size = 0.0, max_size = 0.0;
    double thickness = 1.0;
    std::vector<double> thickness_range;
    std::string output;
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand(
      "pack", "Write a random pack of non-overlapping floes (power diagram, shrunk cells)");
  sub->add_option("--floes", args->options.floes, "Number of floes N")->required()->check(unsigned_count());
  sub->add_option("--concentration", args->options.concentration,
                  "Ice concentration C in (0, 0.95]: floe area / box area")->required();
  sub->add_option("--box", args->box, "Box width and height W H (m); the box is [0, W] x [0, H]")
      ->required()->expected(2);
  sub->add_option("--seed", args->options.seed, "Random seed (default 1)");
  sub->add_option("--size-distribution", args->sizes,
                  "uniform (default) or power:ALPHA, p(d) ~ d^-ALPHA for the equivalent diameter d");
  sub->add_option("--min-size", args->min_size,
                  "Smallest size of the law (m; with --max-size; only the ratio is kept, "
                  "the scale follows from N, C and the box)");
  sub->add_option("--max-size", args->max_size, "Largest size of the law (m)");
  auto* thickness = sub->add_option("--thickness", args->thickness, "Floe thickness (m, default 1)");
  sub->add_option("--thickness-range", args->thickness_range, "Thickness uniform in [A, B] (m)")
      ->expected(2)->excludes(thickness);
  sub->add_option("--density", args->options.density, "Ice density (kg/m^3, default 917)");
  sub->add_option("--min-gap", args->options.min_gap,
                  "Smallest distance between floes (m; default 1e-3 of the mean floe size)");
  sub->add_option("--relax", args->options.relax_iterations, "Lloyd relaxation steps (default 3)");
  sub->add_option("--walls", args->options.wall_width,
                  "Add four static walls of this width (m) around the box");
  sub->add_option("-o,--output", args->output, "Pack file to write (.h5)")->required();

  registry[sub] = [args] {
    PackOptions o = args->options;
    o.width = args->box[0];
    o.height = args->box[1];
    o.sizes = parse_size_distribution(args->sizes);
    o.sizes.min_size = args->min_size;
    o.sizes.max_size = args->max_size;
    if (args->thickness_range.empty()) {
      o.thickness_min = o.thickness_max = args->thickness;
    } else {
      o.thickness_min = args->thickness_range[0];
      o.thickness_max = args->thickness_range[1];
    }
    validate(o);  // before timing and before touching the output file

    const auto start = std::chrono::steady_clock::now();
    const GeneratedPack pack = generate_pack(o);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    write_pack(args->output, pack.floes, pack.window);

    std::ostream& out = std::cout;
    out.precision(8);
    out << "floes: " << pack.floes.size() - pack.walls << "\nwalls: " << pack.walls
        << "\nconcentration: " << pack.concentration << "\nmin_gap: " << pack.min_gap << " m"
        << "\nrequired_gap: " << pack.required_gap << " m\nmean_size: " << pack.mean_size << " m"
        << "\nsize_range: " << pack.size_range[0] << " .. " << pack.size_range[1] << " m"
        << "\nseed: " << o.seed << "\ntime_ms: " << ms
        << "\noutput: " << std::filesystem::absolute(args->output).string() << "\n";
    return 0;
  };
}

}  // namespace floesim::apps
