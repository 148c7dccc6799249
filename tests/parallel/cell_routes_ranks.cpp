// Sums per cell routed to the cells' owners (parallel::CellRoutes, stage
// five) against stage three's merge, over the ranks mpirun started: every
// rank receives every rank's cells and parts (an allgather) and adds them in
// rank order from zero into the whole grid. The owners' totals of their
// slabs' cells, the totals sent back to each rank for its cells, and the
// summed extra must equal that merge to the bit (memcmp), and an owner must
// hold exactly the cells of its slab that some rank sent. Each rank has
// random distinct cells all over the grid (many shared by several ranks),
// parts of random sign and size; slabs of uneven height, one empty on 3
// ranks. Then pieces with order keys (pieces_in_key_order), and the same
// summed by every rank named a receiver (pieces_summed_by_receivers), on
// slabs and on routes where every rank holds every cell (replicated). Run
// by ctest as mpi.cell_routes_ranks_N under `mpirun --oversubscribe -np N`
// (N = 1, 2, 3), and serially without MPI.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <utility>
#include <vector>

#include "parallel/cell_routes.hpp"
#include "parallel/comm.hpp"

using namespace floesim;

namespace {

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; }

// A rank's random pieces: the cells of n where a uniform draw in (-1, 1) is
// below `below`, shuffled; 1 to 3 pieces a cell with 8 keys, 0 or 1 in
// each of the keys' two 32-bit halves' low bits (the high half orders
// first: a key cut to 32 bits orders them otherwise; a sender's pieces of
// a cell come in key order, first[j] the first of cell j's); one value a
// piece (`one`) and two (`two`), spread over ten decades.
struct RandomPieces {
  std::vector<std::uint32_t> cells, first;
  std::vector<parallel::PieceKey> keys;
  std::vector<double> one, two;
};
RandomPieces random_pieces(std::size_t n, double below, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  RandomPieces r;
  r.first.push_back(0);
  for (std::uint32_t c = 0; c < n; ++c)
    if (u(rng) < below) r.cells.push_back(c);
  std::shuffle(r.cells.begin(), r.cells.end(), rng);
  for (std::size_t j = 0; j < r.cells.size(); ++j) {
    const int count = 1 + static_cast<int>(rng() % 3);
    std::vector<parallel::PieceKey> k;
    for (int q = 0; q < count; ++q) k.push_back((parallel::PieceKey{rng() % 4} << 32) | (rng() % 2));
    std::sort(k.begin(), k.end());
    r.keys.insert(r.keys.end(), k.begin(), k.end());
    r.first.push_back(static_cast<std::uint32_t>(r.keys.size()));
  }
  r.one.resize(r.keys.size());
  r.two.resize(2 * r.keys.size());
  for (double& x : r.one) x = u(rng) * std::exp(10.0 * u(rng));
  for (double& x : r.two) x = u(rng) * std::exp(10.0 * u(rng));
  return r;
}

// One round on an nx x ny grid whose rows are cut at `cut` (ranks + 1 values).
bool routes_equal_merge(const parallel::Communicator& comm, int nx, int ny, const std::vector<int>& cut, unsigned seed) {
  const std::size_t n = static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny);
  std::mt19937_64 rng(seed * 100 + static_cast<unsigned>(comm.rank()));
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  // This rank's distinct cells, in a random order, about 40 % of the grid.
  std::vector<std::uint32_t> cells;
  for (std::uint32_t c = 0; c < n; ++c)
    if (u(rng) < -0.2) cells.push_back(c);
  std::shuffle(cells.begin(), cells.end(), rng);
  std::vector<double> first(cells.size()), second(2 * cells.size());
  for (double& x : first) x = u(rng) * std::exp(10.0 * u(rng));
  for (double& x : second) x = u(rng) * std::exp(10.0 * u(rng));
  const double extra = u(rng) * 1e3;

  // Stage three's merge: every rank's parts, added in rank order from zero.
  const std::vector<std::uint32_t> all_cells = comm.allgather<std::uint32_t>(cells);
  const std::vector<double> all_first = comm.allgather<double>(first), all_second = comm.allgather<double>(second);
  const std::vector<double> extras = comm.allgather<double>(std::span<const double>(&extra, 1));
  std::vector<double> merged1(n, 0.0), merged2(2 * n, 0.0);
  std::vector<std::uint8_t> sent(n, 0);
  for (std::size_t k = 0; k < all_cells.size(); ++k) {
    merged1[all_cells[k]] += all_first[k];
    merged2[2 * all_cells[k]] += all_second[2 * k];
    merged2[2 * all_cells[k] + 1] += all_second[2 * k + 1];
    sent[all_cells[k]] = 1;
  }
  double merged_extra = 0.0;
  for (double e : extras) merged_extra += e;

  parallel::CellRoutes routes(cut, static_cast<std::size_t>(nx));
  bool equal = true;
  auto owns_the_sent = [&] {
    std::vector<std::uint32_t> expected, got(routes.owned().begin(), routes.owned().end());
    for (int row = cut[static_cast<std::size_t>(comm.rank())]; row < cut[static_cast<std::size_t>(comm.rank()) + 1]; ++row)
      for (int x = 0; x < nx; ++x) {
        const std::uint32_t c = static_cast<std::uint32_t>(row * nx + x);
        if (sent[c]) expected.push_back(c);
      }
    std::sort(got.begin(), got.end());
    return got == expected;
  };
  routes.open(comm, cells, first, 1);
  equal = equal && owns_the_sent();
  for (std::size_t j = 0; j < routes.owned().size(); ++j) equal = equal && same_bits(routes.total(j, 0), merged1[routes.owned()[j]]);
  std::vector<double> back(cells.size());
  routes.reply(comm, 0, back);
  for (std::size_t k = 0; k < cells.size(); ++k) equal = equal && same_bits(back[k], merged1[cells[k]]);
  equal = equal && same_bits(routes.add(comm, second, 2, extra), merged_extra);
  equal = equal && owns_the_sent();
  for (std::size_t j = 0; j < routes.owned().size(); ++j)
    for (int w = 0; w < 2; ++w) equal = equal && same_bits(routes.total(j, w), merged2[2 * routes.owned()[j] + w]);
  routes.reply(comm, 1, back);
  for (std::size_t k = 0; k < cells.size(); ++k) equal = equal && same_bits(back[k], merged2[2 * cells[k] + 1]);
  std::printf("rank %d of %d, %d x %d, %zu cells, %zu owned: %s\n", comm.rank(), comm.size(), nx, ny, cells.size(),
              routes.owned().size(), equal ? "equal to the merge of every rank's parts, bit for bit" : "DIFFERENT");
  return equal;
}

// Pieces with order keys (stage eight): each rank has random distinct
// cells, each with 1 to 3 pieces whose keys are drawn from a small range (so
// that pieces of several ranks interleave in a cell and some keys repeat);
// the owners' totals must equal, to the bit, the sum from zero of every
// rank's pieces of the cell sorted by key (equal keys in rank order, then in
// the sender's order), for open()'s values and for add()'s. Each rank also
// sums some other cells alone (none of any rank's pieces lie there): their
// owners must receive exactly the cells of their slab and the senders'
// totals, bit for bit.
// `narrow`: the keys mapped to 0..7 in the same order and sent as 4 bytes
// (CellRoutes::set_largest_key(8)).
bool pieces_in_key_order(const parallel::Communicator& comm, int nx, int ny, const std::vector<int>& cut, unsigned seed,
                         bool narrow) {
  const std::size_t n = static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny);
  std::mt19937_64 rng(seed * 7 + static_cast<unsigned>(comm.rank()));
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto [cells, first, keys, one, two] = random_pieces(n, 0.0, rng);
  if (narrow)
    for (parallel::PieceKey& k : keys) k = (k >> 32) * 2 + (k & 1);
  // The reference: every rank's pieces (cell, key, rank, index), sorted, summed from zero.
  std::vector<std::uint32_t> piece_cell(keys.size());
  for (std::size_t j = 0; j < cells.size(); ++j)
    for (std::uint32_t p = first[j]; p < first[j + 1]; ++p) piece_cell[p] = cells[j];
  std::vector<std::size_t> counts;
  const std::vector<std::uint32_t> all_cell = comm.allgather<std::uint32_t>(piece_cell);
  const std::vector<parallel::PieceKey> all_key = comm.allgather<parallel::PieceKey>(keys);
  const std::vector<double> all_one = comm.allgather<double>(one), all_two = comm.allgather<double>(two);
  std::vector<std::size_t> order(all_cell.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;  // index order is rank order, then the sender's
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return all_cell[a] != all_cell[b] ? all_cell[a] < all_cell[b] : all_key[a] < all_key[b];
  });
  std::vector<double> ref1(n, 0.0), ref2(2 * n, 0.0);
  for (std::size_t k : order) {
    ref1[all_cell[k]] += all_one[k];
    ref2[2 * all_cell[k]] += all_two[2 * k];
    ref2[2 * all_cell[k] + 1] += all_two[2 * k + 1];
  }
  // Cells this rank sums alone: none of any rank's cells above, each on
  // one rank (c % ranks), in a random order, with random totals.
  std::vector<std::uint8_t> any(n, 0);
  for (std::uint32_t c : all_cell) any[c] = 1;
  std::vector<std::uint32_t> alone;
  for (std::uint32_t c = 0; c < n; ++c)
    if (!any[c] && c % static_cast<std::uint32_t>(comm.size()) == static_cast<std::uint32_t>(comm.rank()) && u(rng) < 0.0)
      alone.push_back(c);
  std::shuffle(alone.begin(), alone.end(), rng);
  std::vector<double> alone_totals(alone.size());
  for (double& x : alone_totals) x = u(rng) * std::exp(10.0 * u(rng));
  const std::vector<std::uint32_t> all_alone = comm.allgather<std::uint32_t>(alone);
  const std::vector<double> all_alone_totals = comm.allgather<double>(alone_totals);
  std::vector<std::pair<std::uint32_t, double>> expected_alone;  // this rank's slab's, in rank order then the sender's
  const std::vector<int> row_owner = parallel::row_owners(cut);
  for (std::size_t k = 0; k < all_alone.size(); ++k)
    if (row_owner[all_alone[k] / static_cast<std::uint32_t>(nx)] == comm.rank()) expected_alone.push_back({all_alone[k], all_alone_totals[k]});
  parallel::CellRoutes routes(cut, static_cast<std::size_t>(nx));
  if (narrow) routes.set_largest_key(8);
  bool equal = true;
  routes.open(comm, cells, first, keys, one, 1, alone);
  for (std::size_t j = 0; j < routes.owned().size(); ++j) equal = equal && same_bits(routes.total(j, 0), ref1[routes.owned()[j]]);
  equal = equal && routes.alone_owned().size() == expected_alone.size();
  std::vector<double> back(cells.size());
  routes.reply(comm, 0, back);
  for (std::size_t k = 0; k < cells.size(); ++k) equal = equal && same_bits(back[k], ref1[cells[k]]);
  routes.add(comm, two, 2, 0.0, alone_totals);
  for (std::size_t j = 0; j < routes.owned().size(); ++j)
    for (int w = 0; w < 2; ++w) equal = equal && same_bits(routes.total(j, w), ref2[2 * routes.owned()[j] + w]);
  for (std::size_t j = 0; j < expected_alone.size() && j < routes.alone_owned().size(); ++j)
    equal = equal && routes.alone_owned()[j] == expected_alone[j].first && same_bits(routes.alone_total(j), expected_alone[j].second);
  routes.reply(comm, 1, back);
  for (std::size_t k = 0; k < cells.size(); ++k) equal = equal && same_bits(back[k], ref2[2 * cells[k] + 1]);
  // A test that could fail: summed in rank order instead, some cell differs.
  std::size_t differs = 0;
  {
    std::vector<double> by_rank(n, 0.0);
    for (std::size_t k = 0; k < all_cell.size(); ++k) by_rank[all_cell[k]] += all_one[k];
    for (std::size_t c = 0; c < n; ++c) differs += same_bits(by_rank[c], ref1[c]) ? 0 : 1;
  }
  std::printf("rank %d of %d, %d x %d, %zu cells, %zu pieces, %zu owned, %zu alone sent, %zu alone owned (%zu cells of the grid differ summed in rank order): %s\n",
              comm.rank(), comm.size(), nx, ny, cells.size(), keys.size(), routes.owned().size(), alone.size(),
              routes.alone_owned().size(), differs,
              equal ? "the pieces summed in key order, bit for bit" : "DIFFERENT");
  return equal && (comm.size() == 1 || differs > 0);
}

// Pieces summed by every rank that needs the total (open_shared, issue 21
// ocean12): each rank has random cells with 1 to 3 pieces, keys from a small
// range as above; a cell goes to the ranks with pieces there, its owner, and
// for some cells one more rank (as a floe's box covers a cell its pieces
// miss). Each rank must hold exactly the cells it was named a receiver of
// by some rank, and every total there, for open_shared()'s values and
// add()'s, must equal the sum from zero of every rank's pieces of the cell
// in key order (equal keys in rank order, then the sender's) to the bit:
// on the owner and on every other receiver alike. The alone cells' totals
// reach their owners as with open(). `replicated` (a sea not in slabs,
// CellRoutes::replicated, notslabs25): every rank holds every cell, so every
// cell goes to every rank, and an alone cell's total to every other rank
// (in rank order, then the sender's).
bool pieces_summed_by_receivers(const parallel::Communicator& comm, int nx, int ny, const std::vector<int>& cut,
                                unsigned seed, bool replicated) {
  const std::size_t n = static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny);
  const int ranks = comm.size(), rank = comm.rank();
  std::mt19937_64 rng(seed * 13 + static_cast<unsigned>(rank));
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto [cells, first, keys, one, two] = random_pieces(n, -0.4, rng);
  // Which ranks have pieces in each cell (every rank's cells gathered), and
  // the reference sums in key order.
  std::vector<std::uint32_t> piece_cell(keys.size());
  for (std::size_t j = 0; j < cells.size(); ++j)
    for (std::uint32_t p = first[j]; p < first[j + 1]; ++p) piece_cell[p] = cells[j];
  const std::vector<std::uint32_t> all_cell = comm.allgather<std::uint32_t>(piece_cell);
  const std::vector<parallel::PieceKey> all_key = comm.allgather<parallel::PieceKey>(keys);
  const std::vector<double> all_one = comm.allgather<double>(one), all_two = comm.allgather<double>(two);
  const std::vector<std::uint32_t> all_cells = comm.allgather<std::uint32_t>(cells);
  const std::vector<std::uint64_t> cell_counts = comm.allgather<std::uint64_t>(std::vector<std::uint64_t>{cells.size()});
  std::vector<std::uint64_t> has(n, 0);  // bit r: rank r has pieces in the cell
  for (std::size_t r = 0, k = 0; r < cell_counts.size(); ++r)
    for (std::uint64_t j = 0; j < cell_counts[r]; ++j, ++k) has[all_cells[k]] |= std::uint64_t{1} << r;
  std::vector<std::size_t> order(all_cell.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return all_cell[a] != all_cell[b] ? all_cell[a] < all_cell[b] : all_key[a] < all_key[b];
  });
  std::vector<double> ref1(n, 0.0), ref2(2 * n, 0.0);
  for (std::size_t k : order) {
    ref1[all_cell[k]] += all_one[k];
    ref2[2 * all_cell[k]] += all_two[2 * k];
    ref2[2 * all_cell[k] + 1] += all_two[2 * k + 1];
  }
  // The receivers: the ranks with pieces, the owner, and for a third of the
  // cells one more rank, drawn from the cell (the same on every rank).
  const std::vector<int> row_owner = parallel::row_owners(cut);
  auto receivers_of = [&](std::uint32_t c) {
    if (replicated) return (std::uint64_t{1} << ranks) - 1;
    std::uint64_t to = has[c] | std::uint64_t{1} << row_owner[c / static_cast<std::uint32_t>(nx)];
    if (c % 3 == 0) to |= std::uint64_t{1} << ((c / 3) % static_cast<std::uint32_t>(ranks));
    return to;
  };
  std::vector<std::uint32_t> receivers_first{0};
  std::vector<int> receivers;
  for (std::uint32_t c : cells) {
    const std::uint64_t to = receivers_of(c);
    for (int r = 0; r < ranks; ++r)
      if ((to >> r) & 1u) receivers.push_back(r);
    receivers_first.push_back(static_cast<std::uint32_t>(receivers.size()));
  }
  // Alone cells: no rank's pieces there, one rank's each, as above.
  std::vector<std::uint32_t> alone;
  for (std::uint32_t c = 0; c < n; ++c)
    if (has[c] == 0 && c % static_cast<std::uint32_t>(ranks) == static_cast<std::uint32_t>(rank) && u(rng) < 0.0)
      alone.push_back(c);
  std::vector<double> alone_totals(alone.size());
  for (double& x : alone_totals) x = u(rng) * std::exp(10.0 * u(rng));
  const std::vector<std::uint32_t> all_alone = comm.allgather<std::uint32_t>(alone);
  const std::vector<double> all_alone_totals = comm.allgather<double>(alone_totals);
  const std::vector<std::uint64_t> alone_counts = comm.allgather<std::uint64_t>(std::vector<std::uint64_t>{alone.size()});
  std::vector<std::pair<std::uint32_t, double>> expected_alone;
  for (std::size_t r = 0, k = 0; r < alone_counts.size(); ++r)
    for (std::uint64_t j = 0; j < alone_counts[r]; ++j, ++k)
      if (replicated ? static_cast<int>(r) != rank : row_owner[all_alone[k] / static_cast<std::uint32_t>(nx)] == rank)
        expected_alone.push_back({all_alone[k], all_alone_totals[k]});
  // The cells this rank must hold: those some rank with pieces names it for.
  std::vector<std::uint32_t> expected;
  for (std::uint32_t c = 0; c < n; ++c)
    if (has[c] != 0 && ((receivers_of(c) >> rank) & 1u)) expected.push_back(c);

  parallel::CellRoutes routes = replicated ? parallel::CellRoutes::replicated(ranks, static_cast<std::size_t>(nx),
                                                                             static_cast<std::size_t>(ny))
                                           : parallel::CellRoutes(cut, static_cast<std::size_t>(nx));
  bool equal = true;
  routes.open_shared(comm, cells, first, keys, one, 1, receivers_first, receivers, alone);
  std::vector<std::uint32_t> held(routes.owned().begin(), routes.owned().end());
  std::sort(held.begin(), held.end());
  equal = equal && held == expected;
  std::size_t others = 0;  // held cells another rank owns (replicated: where this rank has no pieces)
  for (std::uint32_t c : expected) {
    const std::size_t j = routes.index(c);
    equal = equal && j != parallel::CellRoutes::kNotHeld && same_bits(routes.total(j, 0), ref1[c]);
    others += (replicated ? ((has[c] >> rank) & 1u) == 0 : row_owner[c / static_cast<std::uint32_t>(nx)] != rank) ? 1 : 0;
  }
  const double extra = static_cast<double>(rank) + 0.25;
  double extras = 0.0;
  for (int r = 0; r < ranks; ++r) extras += static_cast<double>(r) + 0.25;
  equal = equal && same_bits(routes.add(comm, two, 2, extra, alone_totals), extras);
  for (std::uint32_t c : expected)
    for (int w = 0; w < 2; ++w) equal = equal && same_bits(routes.total(routes.index(c), w), ref2[2 * c + static_cast<std::uint32_t>(w)]);
  equal = equal && routes.alone_owned().size() == expected_alone.size();
  for (std::size_t j = 0; j < expected_alone.size() && j < routes.alone_owned().size(); ++j)
    equal = equal && routes.alone_owned()[j] == expected_alone[j].first && same_bits(routes.alone_total(j), expected_alone[j].second);
  std::printf("rank %d of %d, %d x %d%s, %zu cells, %zu held (%zu %s), %zu alone owned: %s\n", rank, ranks, nx, ny,
              replicated ? " replicated" : "", cells.size(), held.size(), others,
              replicated ? "without pieces here" : "of other slabs", routes.alone_owned().size(),
              equal ? "every receiver's totals the pieces summed in key order, bit for bit" : "DIFFERENT");
  // The check could fail: on several ranks, cells of other slabs (or
  // without this rank's pieces) are held.
  return equal && (ranks == 1 || others > 0);
}

}  // namespace

int main() {
  parallel::Session session;
  const parallel::Communicator& comm = session.world();
  const int ranks = comm.size();
  long long failed = 0;
  // Slabs of uneven height: rank r holds (r + 1) shares of the rows; and on 3
  // ranks or more, rank 1 holds none.
  for (auto [nx, ny] : {std::pair{37, 23}, std::pair{64, 64}}) {
    std::vector<int> cut{0};
    int weights = 0;
    for (int r = 0; r < ranks; ++r) weights += r + 1;
    for (int r = 0, acc = 0; r < ranks; ++r) {
      acc += r + 1;
      cut.push_back(r + 1 == ranks ? ny : ny * acc / weights);
    }
    if (ranks >= 3) cut[2] = cut[1];
    if (!routes_equal_merge(comm, nx, ny, cut, static_cast<unsigned>(nx))) ++failed;
    if (!pieces_in_key_order(comm, nx, ny, cut, static_cast<unsigned>(ny), false)) ++failed;
    if (!pieces_in_key_order(comm, nx, ny, cut, static_cast<unsigned>(ny), true)) ++failed;
    if (!pieces_summed_by_receivers(comm, nx, ny, cut, static_cast<unsigned>(nx + ny), false)) ++failed;
    if (!pieces_summed_by_receivers(comm, nx, ny, cut, static_cast<unsigned>(nx + ny + 1), true)) ++failed;
  }
  failed = comm.sum(failed);
  if (comm.writer()) std::printf("%s on %d ranks\n", failed == 0 ? "passed" : "FAILED", ranks);
  return failed == 0 ? 0 : 1;
}
