// The spectral sea in slabs over the ranks mpirun started (fluid/spectral.hpp,
// docs/parallel.md stage six): each rank allocates only its share of the
// modes, and the sea stays the serial one to the bit.
//
// Memory: the bank and every per-mode array hold this rank's columns of each
// row (ny x its slab's column count) and nothing more: the bytes sized by
// the modes are the whole sea's times that share, exactly; a regression to
// whole arrays on any rank fails. The transforms' scratch is bounded by this
// rank's rows and columns (a whole-grid array in it fails the bound).
//
// Answers, against a serial sea (SeaOptions without ranks) stepped alike on
// every rank: after kicks (pressures with structure in every row), repeated
// kicks, flows and fields read in between, the energy (summed by rank 0 in
// the whole bank's order) equals the serial energy on every rank, the whole
// state gathered to rank 0 equals the serial bank, and the fields (whole,
// and in a halo of 2 rows: a window holding the slab's and the halo's rows
// only, read by global cell) equal the serial fields, a record's field
// gathered to rank 0 alone equals the serial one there, and so do a
// window's slab rows gathered to rank 0, all with memcmp; a whole state set on every rank and gathered
// back is unchanged. Grids with remainder blocks, ranks with empty row
// slabs, and on 3 ranks a rank with no columns.
// Run by ctest as mpi.sea_slab_ranks_N under `mpirun --oversubscribe -np N`
// (N = 1, 2, 3), and serially without MPI.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <vector>

#include "fluid/spectral.hpp"
#include "parallel/comm.hpp"
#include "parallel/sea_ranks.hpp"
#include "tests/parallel/sea_case.hpp"

using namespace floesim;

namespace {

using parallel::sea_ranks;

SeaParams params(int nx, int ny) { return test::slab_sea_params(nx, ny); }

template <class T>
bool same(std::span<const T> a, std::span<const T> b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size_bytes()) == 0);
}

struct Check {
  int failed = 0;
  void operator()(bool ok, const char* what, const parallel::Communicator& comm, int nx, int ny) {
    if (ok) return;
    ++failed;
    std::printf("rank %d of %d, %d x %d: %s\n", comm.rank(), comm.size(), nx, ny, what);
  }
};

int check_grid(const parallel::Communicator& comm, int nx, int ny) {
  Check check;
  const SeaParams p = params(nx, ny);
  fluid::SeaOptions options;
  options.ranks = sea_ranks(comm);
  auto whole_sea = fluid::make_sea(p, 11);
  auto slab_sea = fluid::make_sea(p, 11, options);
  auto& whole = dynamic_cast<fluid::SpectralSea&>(*whole_sea);
  auto& slab = dynamic_cast<fluid::SpectralSea&>(*slab_sea);
  const std::size_t hx = static_cast<std::size_t>(nx / 2 + 1), nc = hx * static_cast<std::size_t>(ny);

  // Memory: this rank's columns of every row, nothing more.
  const std::vector<int> rows = slab.slab_rows();
  std::size_t columns = hx;
  if (comm.size() > 1) {
    // The columns this rank's bank holds: its mode count over the rows, and
    // the shares of all ranks add up to the half spectrum's columns.
    columns = slab.memory().modes / static_cast<std::size_t>(ny);
    const long long total = comm.sum(static_cast<long long>(columns));
    check(total == static_cast<long long>(hx), "the ranks' columns do not add up to the half spectrum's", comm, nx, ny);
    check(rows.size() == static_cast<std::size_t>(comm.size()) + 1, "no slab rows", comm, nx, ny);
  }
  const fluid::SpectralSea::Memory w = whole.memory(), s = slab.memory();
  check(w.modes == nc, "the whole sea does not hold every mode", comm, nx, ny);
  check(s.modes == columns * static_cast<std::size_t>(ny) && slab.modes().modes() == s.modes &&
            slab.modes().q().size() == 2 * s.modes,
        "the bank does not hold this rank's columns of each row", comm, nx, ny);
  // (A rank without columns keeps one entry in each kick buffer.)
  check(w.mode_bytes % nc == 0 && (s.modes > 0 ? s.mode_bytes * nc == w.mode_bytes * s.modes
                                               : s.mode_bytes <= 2 * 2 * sizeof(double)),
        "the per-mode arrays are not this rank's share of the whole sea's", comm, nx, ny);
  // The transforms' scratch: serially the whole sea's; in slabs at most this
  // rank's rows of the real side (8 B a value), its column slab of the two
  // spectra (16 B an entry, ny rows of a stride of at most width + 3, or 8
  // for narrow slabs), its rows of the half spectrum for the row pass, and
  // the two transposes' buffers (each the larger of the blocks it sends
  // either way); arrays of at least one entry. A whole real array on a rank
  // that lacks some rows exceeds this bound (a whole spectrum too): tried,
  // it fails on 2 and 3 ranks.
  if (comm.size() == 1) {
    check(s.scratch_bytes == w.scratch_bytes, "the scratch differs from the serial sea's", comm, nx, ny);
  } else {
    const std::size_t own_rows = static_cast<std::size_t>(rows[static_cast<std::size_t>(comm.rank()) + 1] -
                                                          rows[static_cast<std::size_t>(comm.rank())]);
    const std::size_t ny_ = static_cast<std::size_t>(ny), stride = std::max<std::size_t>(columns + 3, 8);
    const std::size_t transpose = 16 * std::max(own_rows * (hx - columns), (ny_ - own_rows) * columns);
    const std::size_t bound = 8 * std::max<std::size_t>(own_rows * static_cast<std::size_t>(nx), 1) +
                              2 * 16 * ny_ * stride + 16 * std::max<std::size_t>(own_rows * hx, 1) + 2 * transpose;
    check(s.scratch_bytes <= bound, "the transforms' scratch is more than this rank's slabs", comm, nx, ny);
  }
  std::printf("rank %d of %d, %d x %d: %zu of %zu modes, %zu of %zu bytes by mode, %zu of %zu bytes of scratch\n",
              comm.rank(), comm.size(), nx, ny, s.modes, w.modes, s.mode_bytes, w.mode_bytes, s.scratch_bytes,
              w.scratch_bytes);

  // The same steps on both seas: kicks with every row loaded, a repeated
  // kick, flows, fields read between them (a field settles nothing).
  const std::size_t n = static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny);
  std::vector<double> pressure(n);
  // A halo's field is a window of the slab and the halo's rows and holds
  // those rows only (a whole array on a rank whose slab and halo lack some
  // rows fails), each equal to the serial field's row.
  auto compare_fields = [&](int halo, const char* what) {
    whole.set_field_halo(-1);
    slab.set_field_halo(halo);
    for (fluid::Field f : {fluid::Field::elevation, fluid::Field::velocity_x, fluid::Field::velocity_y,
                           fluid::Field::velocity_z, fluid::Field::slope_x}) {
      const std::span<const double> a = whole.field(f).all();
      const fluid::RowWindow b = slab.field(f);
      if (halo < 0 || comm.size() == 1) {
        check(b.whole() && same(a, b.values()), what, comm, nx, ny);
        continue;
      }
      const int begin = rows[static_cast<std::size_t>(comm.rank())], end = rows[static_cast<std::size_t>(comm.rank()) + 1];
      const int held = begin == end ? 0 : std::min(end - begin + 2 * halo, ny);
      check(b.rows() == held && b.values().size() == static_cast<std::size_t>(held) * static_cast<std::size_t>(nx),
            "a field in a halo holds other rows than its slab's and the halo's", comm, nx, ny);
      // Its slab rows gathered back to rank 0 (the incident sea's snapshots
      // at a checkpoint): the whole field there, nothing elsewhere.
      std::vector<double> gathered;
      slab.gather_to_writer_rows(b, gathered);
      if (comm.writer()) check(same<double>(a, gathered), "a window's rows gathered to rank 0 differ from the serial field", comm, nx, ny);
      else check(gathered.empty(), "a rank other than 0 received a window's rows gathered", comm, nx, ny);
      if (begin == end) continue;
      for (int y = begin - halo; y < end + halo; ++y) {
        const int gy = ((y % ny) + ny) % ny;
        const std::size_t row = static_cast<std::size_t>(gy) * static_cast<std::size_t>(nx);
        const std::size_t local = static_cast<std::size_t>(((gy - b.first_row()) % ny + ny) % ny) * static_cast<std::size_t>(nx);
        check(b.holds_row(y) && b[row] == a[row] && b[row + static_cast<std::size_t>(nx) - 1] == a[row + static_cast<std::size_t>(nx) - 1] &&
                  same(a.subspan(row, static_cast<std::size_t>(nx)), b.values().subspan(local, static_cast<std::size_t>(nx))),
              what, comm, nx, ny);
      }
    }
    slab.set_field_halo(-1);
  };
  // A record's field: whole on rank 0 (the writer) alone, the serial one.
  auto compare_on_writer = [&](const char* what) {
    for (fluid::Field f : {fluid::Field::elevation, fluid::Field::velocity_z}) {
      const std::span<const double> a = whole.field(f).all(), b = slab.field_on_writer(f);
      if (comm.writer() || comm.size() == 1) check(same(a, b), what, comm, nx, ny);
      else check(b.empty(), "a rank other than 0 received a record's whole field", comm, nx, ny);
    }
  };
  for (int step = 0; step < 4; ++step) {
    for (std::size_t c = 0; c < n; ++c)
      pressure[c] = 1e3 * std::sin(0.37 * static_cast<double>(c % static_cast<std::size_t>(nx)) + 0.11 * step) *
                    std::cos(0.23 * static_cast<double>(c / static_cast<std::size_t>(nx)));
    for (fluid::SpectralSea* sea : {&whole, &slab}) sea->kick(pressure, 0.05);
    compare_fields(step % 2 == 0 ? -1 : 2, "a field after a kick differs from the serial sea's");
    for (fluid::SpectralSea* sea : {&whole, &slab}) {
      sea->repeat_kick(0.05);
      sea->flow(0.1);
    }
    compare_fields(step % 2 == 0 ? 2 : -1, "a field after a flow differs from the serial sea's");
    compare_on_writer("a record's field differs from the serial sea's");
    compare_fields(step % 2 == 0 ? 2 : -1, "a field after a record differs from the serial sea's");
  }
  for (fluid::SpectralSea* sea : {&whole, &slab}) sea->kick(pressure, 0.05);  // left deferred

  const fluid::SeaEnergy ew = whole.energy(), es = slab.energy();
  check(std::memcmp(&ew.kinetic, &es.kinetic, sizeof(double)) == 0 &&
            std::memcmp(&ew.potential, &es.potential, sizeof(double)) == 0,
        "the energy differs from the serial sea's", comm, nx, ny);
  std::vector<double> qw, vw, qs, vs;
  whole.gather_modal_state(qw, vw);
  slab.gather_modal_state(qs, vs);
  if (comm.writer() || comm.size() == 1) {
    check(same<double>(qw, qs) && same<double>(vw, vs), "the gathered state differs from the serial bank", comm, nx, ny);
  } else {
    check(qs.empty() && vs.empty(), "a rank other than 0 received the whole state", comm, nx, ny);
  }
  // A whole state set on every rank (a checkpoint's) and gathered back.
  for (double& x : qw) x *= -0.5;
  slab.set_modal_state(qw, vw);
  whole.set_modal_state(qw, vw);
  slab.gather_modal_state(qs, vs);
  if (comm.writer()) check(same<double>(qw, qs) && same<double>(vw, vs), "a set state does not gather back", comm, nx, ny);
  compare_fields(-1, "a field after a set state differs from the serial sea's");
  return check.failed;
}

}  // namespace

int main() {
  parallel::Session session;
  const parallel::Communicator& comm = session.world();
  long long failed = 0;
  // 64 x 48: 33 columns (9 blocks of 4, the last short), 6 row blocks;
  // 30 x 21: remainder blocks both ways; 40 x 8: one row block, so on 2 and
  // 3 ranks the other ranks' row slabs are empty; 12 x 8: also only 2
  // column blocks, so on 3 ranks rank 2 holds no mode and no row.
  for (auto [nx, ny] : {std::pair{64, 48}, std::pair{30, 21}, std::pair{40, 8}, std::pair{12, 8}})
    failed += check_grid(comm, nx, ny);
  failed = comm.sum(failed);
  if (comm.writer()) std::printf("%s on %d ranks\n", failed == 0 ? "passed" : "FAILED", comm.size());
  return failed == 0 ? 0 : 1;
}
