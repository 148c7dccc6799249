// The products' routes (docs/parallel.md, "The products' routes (answer30)")
// over the ranks mpirun started, run by ctest as mpi.product_routes_ranks_N
// under `mpirun --oversubscribe -np N` (N = 1, 2, 3) and serially without MPI.
//
// A pack on a 128^2 spectral sea in slabs, stepped with the explicit kicks
// (the contact by owner, whose coverage opens the cells' routes), and a
// serial run side by side. After every step each rank calls
// FloeSeaContact::cell_product with random values on its floes' pieces
// (a function of the floe, the piece and the step, so the serial run's are
// the same) and a stand-in for the sea's response on the rows it holds,
// r_c = v_c (1 + c) + sin(c) (v_c the cell's sum, c its global index: any
// per-cell function of the sum shows whether the sum is the serial one, and
// the cell's index whether it came from the right cell). Each rank's values
// read back at its pieces must equal, bit for bit, the serial computation:
// the whole grid's sums from zero, the floes by first cell (the coverage's
// serial order), each floe's pieces in order, r_c on every cell, read at
// each piece's cell; and the serial run's own cell_product must equal it.
//
// The layout makes the routes' hard cases (asserted present on 2 and 3
// ranks, else the test fails as weak): at each slab boundary (rows 64 on 2
// ranks; 48 and 88 on 3) a small floe just below the cut between two tall
// floes whose centroids are above it, all three with pieces in one cell of
// the lower slab: a shared cell whose serial order (by first cell: the tall
// floes first) is not the ranks' (the lower slab's rank first), with three
// terms, so that rank order gives other bits; and the tall floes' pieces
// deeper in the lower slab, under no other rank's floe: cells one rank
// sums alone in another rank's slab.
// Mutations this catches (checked): a shared cell summed in rank order
// (CellRoutes without the sort by key), the answer skipped for one route.
//
// With --config FILE --steps N it measures instead: the run of FILE stepped
// N steps, one product after each, and rank 0's bytes a product received
// from the other ranks (FloeSeaContact::cell_product_stats) printed.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "core/config.hpp"
#include "coupling/scenario.hpp"
#include "coupling/simulation.hpp"
#include "parallel/cell_routes.hpp"
#include "parallel/comm.hpp"
#include "tests/parallel/ranks_main.hpp"

using namespace floesim;

namespace {

constexpr int kCells = 128;
constexpr double kBox = 200.0, kCell = kBox / kCells;
constexpr int kSteps = 4;

// A rectangle [x0, x1] x [y0, y1] as a floe.
void rectangle(std::ostringstream& t, double x0, double x1, double y0, double y1) {
  t << "[[floes.floe]]\nvertices = [[" << x0 << ", " << y0 << "], [" << x1 << ", " << y0 << "], [" << x1 << ", " << y1
    << "], [" << x0 << ", " << y1 << "]]\n";
}

std::string pack_on_sea() {
  std::ostringstream t;
  t.precision(17);
  t << "[run]\nt_end = 10.0\ndt_max = 0.05\nseed = 3\nthreads = 1\n"
    << "[sea]\nmodel = \"spectral\"\ndims = 2\nsize = [" << kBox << ", " << kBox << "]\ncells = [" << kCells << ", "
    << kCells << "]\ndepth = 50.0\n"
    << "[sea.waves]\nkind = \"jonswap\"\nhs = 0.5\ntp = 6.0\n"
    << "[contact]\ndomain = \"periodic\"\nbox = [0.0, " << kBox << ", 0.0, " << kBox << "]\n"
    << "[coupling]\nlaw = \"strong\"\nstiffness = 100.0\nstart = \"given\"\n";
  // At each cut (row 64 on 2 ranks, 48 and 88 on 3), four combs: the cell
  // (cut - 1, column) holds the tall floes' edges and the small floe between.
  for (const int cut : {48, 64, 88})
    for (const int column : {20, 70, 80, 118}) {
      const double y = cut * kCell, x = column * kCell;
      rectangle(t, x - 6.0, x + 0.1, y - 3.0, y + 10.0);  // centroid above the cut
      rectangle(t, x + 0.3, x + 1.2, y - 1.5, y - 0.1);   // below it
      rectangle(t, x + 1.4, x + 7.0, y - 3.5, y + 10.0);  // above it
    }
  // Floes across the cuts and elsewhere (corner, side), clear of the combs.
  const double squares[][3] = {{55, 70, 12},   {75, 95, 12},  {140, 130, 14}, {160, 92, 10}, {60, 130, 12},
                               {170, 40, 12},  {10, 160, 12}, {130, 10, 12},  {80, 170, 14}, {150, 180, 10},
                               {40, 20, 12}};
  for (const auto& q : squares) rectangle(t, q[0], q[0] + q[2], q[1], q[1] + q[2]);
  return t.str();
}

// A random value for piece j of floe i at product `step`, spread over ten
// decades (full mantissas: sums in another order give other bits).
double piece_value(std::size_t i, std::size_t j, int step) {
  std::uint64_t z = (static_cast<std::uint64_t>(i) << 40) ^ (static_cast<std::uint64_t>(j) << 8) ^
                    static_cast<std::uint64_t>(step) ^ 0x9e3779b97f4a7c15ULL;
  auto next = [&z]() {  // splitmix64
    z += 0x9e3779b97f4a7c15ULL;
    std::uint64_t x = z;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
    return x ^ (x >> 31);
  };
  const double a = static_cast<double>(next() >> 11) * 0x1.0p-53, b = static_cast<double>(next() >> 11) * 0x1.0p-53;
  return (2.0 * a - 1.0) * std::exp(11.5 * (b - 0.5));
}

// The stand-in for the sea's response of cell c to its value v.
double respond_cell(std::size_t c, double v) { return v * (1.0 + static_cast<double>(c)) + std::sin(static_cast<double>(c)); }

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; }
std::string exact(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", x);
  return text;
}

// The stand-in on the rows a rank holds (the slab's, or every row).
FloeSeaContact::SlabResponse stand_in(std::vector<std::string>& wrong) {
  return [&wrong](int first_row, std::span<const double> cells, std::span<double> response) {
    const std::size_t first = static_cast<std::size_t>(first_row) * kCells;
    if (cells.size() != response.size() || cells.size() % kCells != 0 || first + cells.size() > std::size_t{kCells} * kCells)
      wrong.push_back("the response asked on rows that are not the grid's");
    for (std::size_t c = 0; c < cells.size() && c < response.size(); ++c) response[c] = respond_cell(first + c, cells[c]);
  };
}

// The serial floes' values and the serial computation, as the plan's rule
// says (docs/parallel.md, implan29): the floes by first cell (std::sort from
// index order, as FloeSeaContact::place_footprints), the pieces in order.
struct SerialProduct {
  std::vector<double> u, out;  // per piece of the serial footprints
  std::vector<std::uint32_t> order;
};
SerialProduct serial_product(const Footprints& fp, double scale, int step) {
  SerialProduct s;
  s.u.resize(fp.cell.size());
  for (std::size_t i = 0; i < fp.floes(); ++i)
    for (std::size_t k = fp.offsets[i]; k < fp.offsets[i + 1]; ++k) s.u[k] = piece_value(i, k - fp.offsets[i], step);
  for (std::size_t i = 0; i < fp.floes(); ++i)
    if (fp.offsets[i] < fp.offsets[i + 1]) s.order.push_back(static_cast<std::uint32_t>(i));
  std::sort(s.order.begin(), s.order.end(),
            [&](std::uint32_t x, std::uint32_t y) { return fp.cell[fp.offsets[x]] < fp.cell[fp.offsets[y]]; });
  std::vector<double> cells(std::size_t{kCells} * kCells, 0.0);
  for (const std::uint32_t i : s.order)
    for (std::size_t k = fp.offsets[i]; k < fp.offsets[i + 1]; ++k) cells[fp.cell[k]] += s.u[k] * scale;
  s.out.resize(fp.cell.size());
  for (std::size_t k = 0; k < fp.cell.size(); ++k) s.out[k] = respond_cell(fp.cell[k], cells[fp.cell[k]]);
  return s;
}

// The cells the routes' hard cases need, over the serial pieces with the
// distributed owners: shared by several ranks' floes; of one rank's floes in
// another rank's slab; shared where the ranks' order of the pieces (by rank,
// then key) sums to other bits than the serial order.
struct HardCells {
  long shared = 0, alone_elsewhere = 0, rank_order_differs = 0;
};
void count_hard_cells(const Footprints& fp, const SerialProduct& s, double scale, std::span<const int> owner,
                      std::span<const int> slabs, HardCells& h) {
  const std::vector<int> row_owner = parallel::row_owners(slabs);
  struct Piece {
    int rank;
    std::uint32_t key;
    double value;
  };
  std::vector<std::vector<Piece>> in(std::size_t{kCells} * kCells);
  for (std::size_t key = 0; key < s.order.size(); ++key) {
    const std::uint32_t i = s.order[key];
    for (std::size_t k = fp.offsets[i]; k < fp.offsets[i + 1]; ++k)
      in[fp.cell[k]].push_back({owner[i], static_cast<std::uint32_t>(key), s.u[k] * scale});
  }
  for (std::size_t c = 0; c < in.size(); ++c) {
    std::vector<Piece>& p = in[c];
    if (p.empty()) continue;
    std::set<int> ranks;
    for (const Piece& q : p) ranks.insert(q.rank);
    if (ranks.size() == 1) {
      if (*ranks.begin() != row_owner[c / kCells]) ++h.alone_elsewhere;
      continue;
    }
    ++h.shared;
    double by_key = 0.0, by_rank = 0.0;
    for (const Piece& q : p) by_key += q.value;  // listed by key
    std::stable_sort(p.begin(), p.end(), [](const Piece& a, const Piece& b) { return a.rank < b.rank; });
    for (const Piece& q : p) by_rank += q.value;
    if (!same_bits(by_key, by_rank)) ++h.rank_order_differs;
  }
}

void check_products(const parallel::Communicator& comm, test::Failures& failures) {
  const std::string text = pack_on_sea();
  Simulation ranks(build_scenario(parse_config(text, "product_routes.toml", ".")), comm);
  Simulation serial(build_scenario(parse_config(text, "product_routes.toml", ".")));
  const double scale = 1.0 / (kCell * kCell);
  HardCells hard;
  long checked = 0;
  for (int step = 1; step <= kSteps; ++step) {
    ranks.step(10.0);
    serial.step(10.0);
    std::vector<std::string> wrong;
    FloeSeaContact& r = *ranks.floe_sea();
    FloeSeaContact& s = *serial.floe_sea();
    const Footprints& whole = s.footprints();
    const SerialProduct expected = serial_product(whole, scale, step);
    // The serial run's own product.
    std::vector<double> out(whole.cell.size());
    s.cell_product(expected.u, scale, stand_in(wrong), out);
    for (std::size_t k = 0; k < out.size() && wrong.empty(); ++k)
      if (!same_bits(out[k], expected.out[k])) wrong.push_back("the serial run's product differs at piece " + std::to_string(k));
    // This rank's: its floes' pieces (the serial run's, foot28), their values.
    const Footprints& fp = r.footprints();
    const std::span<const int> owner = r.floe_owners();
    std::vector<double> u(fp.cell.size(), 0.0), mine(fp.cell.size());
    for (std::size_t i = 0; i < fp.floes(); ++i) {
      const std::size_t m = fp.offsets[i + 1] - fp.offsets[i];
      if (m == 0) continue;
      if (m != whole.offsets[i + 1] - whole.offsets[i] ||
          std::memcmp(fp.cell.data() + fp.offsets[i], whole.cell.data() + whole.offsets[i], m * sizeof(std::uint32_t)) != 0)
        wrong.push_back("floe " + std::to_string(i) + "'s pieces are not the serial run's");
      for (std::size_t j = 0; j < m; ++j) u[fp.offsets[i] + j] = piece_value(i, j, step);
    }
    r.cell_product(u, scale, stand_in(wrong), mine);  // collective: on every rank, whatever it found
    for (std::size_t i = 0; i < fp.floes() && wrong.empty(); ++i)
      for (std::size_t j = 0; j < fp.offsets[i + 1] - fp.offsets[i]; ++j, ++checked)
        if (!same_bits(mine[fp.offsets[i] + j], expected.out[whole.offsets[i] + j])) {
          wrong.push_back("floe " + std::to_string(i) + " (rank " + std::to_string(owner.empty() ? 0 : owner[i]) +
                          "), piece " + std::to_string(j) + " (cell " + std::to_string(fp.cell[fp.offsets[i] + j]) +
                          "): " + exact(mine[fp.offsets[i] + j]) + ", the serial " +
                          exact(expected.out[whole.offsets[i] + j]));
          break;
        }
    if (!comm.serial()) count_hard_cells(whole, expected, scale, owner, r.owner_slabs(), hard);
    for (const std::string& w : wrong) failures.push_back("step " + std::to_string(step) + ": " + w);
    if (comm.any(!wrong.empty())) return;  // every rank stops at the same step
  }
  const long every = comm.sum(checked);
  if (every == 0) failures.push_back("no piece checked");
  if (!comm.serial() && (hard.shared == 0 || hard.alone_elsewhere == 0 || hard.rank_order_differs == 0))
    failures.push_back("a weak test: shared cells " + std::to_string(hard.shared) + ", alone in another slab " +
                       std::to_string(hard.alone_elsewhere) + ", summed in rank order to other bits " +
                       std::to_string(hard.rank_order_differs));
  const FloeSeaContact::CellProductStats& st = ranks.floe_sea()->cell_product_stats();
  if (comm.rank() == 0)
    std::printf("%d rank(s): %d steps, %ld pieces checked over the ranks; cells shared %ld, alone in another slab %ld, "
                "summed in rank order to other bits %ld (over the steps); rank 0 received %.0f B a product from the "
                "others (scatter %lld B, answer %lld B over %ld products)\n",
                comm.size(), kSteps, every, hard.shared, hard.alone_elsewhere, hard.rank_order_differs,
                st.products > 0 ? static_cast<double>(st.scatter_bytes + st.answer_bytes) / static_cast<double>(st.products) : 0.0,
                st.scatter_bytes, st.answer_bytes, st.products);
}

// --config FILE --steps N: the bytes a product on FILE's run.
int measure(const parallel::Communicator& comm, const std::string& file, int steps) {
  Simulation sim(build_scenario(load_config(file)), comm);
  const std::size_t nx = static_cast<std::size_t>(sim.sea_grid().cells[0]);
  long routed = 0, pieces = 0;
  for (int step = 1; step <= steps; ++step) {
    sim.step(1e9);
    FloeSeaContact& contact = *sim.floe_sea();
    const Footprints& fp = contact.footprints();
    std::vector<double> u(fp.cell.size()), out(fp.cell.size());
    for (std::size_t i = 0; i < fp.floes(); ++i)
      for (std::size_t k = fp.offsets[i]; k < fp.offsets[i + 1]; ++k) u[k] = piece_value(i, k - fp.offsets[i], step);
    contact.cell_product(u, 1.0, [nx](int first_row, std::span<const double> cells, std::span<double> response) {
      const std::size_t first = static_cast<std::size_t>(first_row) * nx;
      for (std::size_t c = 0; c < cells.size(); ++c) response[c] = respond_cell(first + c, cells[c]);
    }, out);
    pieces += static_cast<long>(fp.cell.size());
  }
  const FloeSeaContact::RoutedCells& cells = sim.floe_sea()->routed_cells();
  routed = cells.shared;
  const FloeSeaContact::CellProductStats& st = sim.floe_sea()->cell_product_stats();
  const double products = static_cast<double>(std::max(st.products, 1L));
  if (comm.rank() == 0)
    std::printf("%s on %d rank(s), %d steps, one product a step: rank 0 received from the others %.1f B a product "
                "(scatter %.1f, answer %.1f); its pieces %.1f a step; its routed cells since the start %ld, alone "
                "cells sent %ld, over %ld evaluations' worth\n",
                file.c_str(), comm.size(), steps, static_cast<double>(st.scatter_bytes + st.answer_bytes) / products,
                static_cast<double>(st.scatter_bytes) / products, static_cast<double>(st.answer_bytes) / products,
                static_cast<double>(pieces) / steps, routed, cells.alone_sent, static_cast<long>(steps));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  parallel::Session session;
  std::string config;
  int steps = 0;
  for (int a = 1; a + 1 < argc; a += 2) {
    const std::string key = argv[a];
    if (key == "--config") config = argv[a + 1];
    else if (key == "--steps") steps = std::stoi(argv[a + 1]);
  }
  if (!config.empty()) return measure(session.world(), config, steps > 0 ? steps : 10);
  return test::run_checks(session.world(), "the products' routes: every rank's pieces read the serial response", check_products);
}
