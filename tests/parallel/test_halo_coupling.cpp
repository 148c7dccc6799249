// The coupling's passes over the floes a rank needs (docs/parallel.md, "The
// coupling's passes over the held floes"), on simulated ranks in one process:
// each pass, given a copy poisoned outside the set it claims to need, gives
// bit for bit what it gives on the whole state, and a thinner set (the
// mutation each names) does not.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>
#include <vector>

#include "coupling/floe_sea.hpp"
#include "coupling/footprint.hpp"
#include "coupling/moving_footprint.hpp"
#include "coupling/shared_cells.hpp"
#include "parallel/cell_routes.hpp"
#include "parallel/place.hpp"
#include "tests/parallel/halo_case.hpp"
#include "tests/parallel/sea_case.hpp"

using namespace floesim;
using namespace floesim::test;

namespace {

// The dense moving pack of the halo proofs (400 floes, 2 km square) on the
// distributed sea tests' grid (8 m x 10 m cells, tests/parallel/sea_case.hpp),
// periodic, the pack's window moved to the grid's origin.
struct SeaPack {
  Floes floes;
  fluid::SurfaceGrid grid;
  std::vector<FloePose> poses;
  std::vector<double> radius;
};
SeaPack sea_pack(unsigned seed) {
  Pack p = moving_pack(seed, true);
  SeaPack s;
  s.floes = std::move(p.floes);
  const SeaParams sea = slab_sea_params(250, 200);
  s.grid.dims = 2;
  s.grid.nx = sea.cells[0];
  s.grid.ny = sea.cells[1];
  s.grid.lx = sea.size[0];
  s.grid.ly = sea.size[1];
  s.grid.edge = fluid::GridEdge::periodic;
  for (FloeState& st : s.floes.state) {
    st.x -= p.window[0];
    st.y -= p.window[2];
    s.poses.push_back({st.x, st.y, st.yaw});
  }
  s.radius.assign(s.floes.size(), 0.0);
  for (std::size_t i = 0; i < s.floes.size(); ++i)
    for (const Vec2& v : s.floes.vertices(i)) s.radius[i] = std::max(s.radius[i], v.norm());
  return s;
}

// The slabs of `ranks` ranks on `rows` rows: equal, or uneven (as after
// moves of the cuts: one slab twice the others, one empty with 7).
std::vector<int> slabs(int ranks, int rows, bool uneven) {
  std::vector<int> first(static_cast<std::size_t>(ranks) + 1);
  for (int r = 0; r <= ranks; ++r) first[static_cast<std::size_t>(r)] = r * rows / ranks;
  if (uneven) {
    first[1] = std::min(first[1] + rows / (2 * ranks), first[2]);
    if (ranks >= 7) first[3] = first[2];
  }
  return first;
}

constexpr std::uint8_t kOpen = 0, kInterior = 1, kShared = 2;

// What rank `rank` reads of the marks: at each cell of its own floes' pieces
// in a row outside the interior, whether it is shared and by which ranks.
struct Read {
  std::vector<std::uint8_t> shared;
  std::vector<std::uint64_t> ranks;
};
Read read_marks(const Footprints& fp, std::span<const int> owner, int rank, std::span<const std::uint8_t> interior_row,
                std::span<const std::uint8_t> kind, const SharedMarks& marks, int nx) {
  Read out;
  for (std::size_t i = 0; i < owner.size(); ++i) {
    if (owner[i] != rank) continue;
    for (std::size_t k = fp.offsets[i]; k < fp.offsets[i + 1]; ++k) {
      const std::uint32_t c = fp.cell[k];
      if (interior_row[c / static_cast<std::uint32_t>(nx)]) continue;
      const bool shared = kind[c] == kShared;
      out.shared.push_back(shared ? 1 : 0);
      out.ranks.push_back(shared ? marks.shared_ranks[marks.shared_at[c] - 1] : 0);
    }
  }
  return out;
}

}  // namespace

TEST_CASE("the shared cells' marks on a rank read only the boxes of other ranks' floes with a row within R_max and two cells of its slab (simulated ranks)") {
  // FloeSeaContact::sum_coverage_by_owner's marking of the cells other
  // ranks' floes' boxes cover, on the cells of each rank's own pieces: from
  // every other floe's box (as before), and from box_neighbours' floes only
  // (chosen by their boxes' rows, no pose read) with every other box
  // poisoned (a box over the whole grid, which would mark every cell shared
  // if read). Equal on every rank, for 2, 3 and 7 slabs, equal and uneven,
  // both kernels, footprints rebuilt at every placement and with a window of
  // 0.3 cells. The mutation named: the boxes with a row in the slab alone
  // (own_rows = 0) miss shared cells on some rank.
  const SeaPack s = sea_pack(7);
  const std::size_t n = s.floes.size();
  const int nx = s.grid.nx, ny = s.grid.ny;
  std::vector<std::uint32_t> all(n);
  std::iota(all.begin(), all.end(), 0u);
  for (const FootprintKernel kernel : {FootprintKernel::cell, FootprintKernel::tent})
    for (const double reach : {0.0, 0.3}) {
      Footprints fp;
      const std::vector<std::uint8_t> include(n, 1);
      build_footprints(s.floes, include, s.grid, fp, kernel, 1, s.poses);
      std::vector<parallel::CellBox> box(n);
      for (std::size_t i = 0; i < n; ++i)
        box[i] = parallel::CellBox::of(std::span(fp.cell.data() + fp.offsets[i], fp.offsets[i + 1] - fp.offsets[i]), nx, ny);
      const int own_rows = piece_rows_of(*std::max_element(s.radius.begin(), s.radius.end()), reach, s.grid.dy());
      std::size_t read_full = 0, read_near = 0, thin_misses = 0;
      for (const int ranks : {2, 3, 7})
        for (const bool uneven : {false, true}) {
          CAPTURE(ranks);
          CAPTURE(uneven);
          const std::vector<int> first = slabs(ranks, ny, uneven);
          const std::vector<int> row_owner = parallel::row_owners(first);
          std::vector<int> owner(n);
          for (std::size_t i = 0; i < n; ++i)
            owner[i] = row_owner[static_cast<std::size_t>(parallel::grid_row(s.poses[i].y, s.grid.dy(), ny))];
          const std::vector<std::uint8_t> interior_row = parallel::CellRoutes(first, static_cast<std::size_t>(nx)).interior_rows(own_rows);
          std::vector<std::uint8_t> kind0(s.grid.size());
          for (std::size_t c = 0; c < kind0.size(); ++c) kind0[c] = interior_row[c / static_cast<std::size_t>(nx)] ? kInterior : kOpen;
          const std::size_t words = (static_cast<std::size_t>(ranks) + 63) / 64;
          for (int r = 0; r < ranks; ++r) {
            CAPTURE(r);
            // As before: every other rank's floe's box.
            std::vector<std::uint32_t> others;
            for (const std::uint32_t i : all)
              if (owner[i] != r) others.push_back(i);
            std::vector<std::uint8_t> kind_full = kind0;
            SharedMarks full;
            mark_shared_cells(others, box, owner, nx, ny, interior_row, kind_full, kOpen, kShared, words, full);
            // The claimed set, every other box poisoned.
            const std::vector<std::uint32_t> near =
                box_neighbours(all, owner, r, first, box, s.grid, own_rows);
            std::vector<parallel::CellBox> poisoned_box(n);
            for (parallel::CellBox& b : poisoned_box) {
              b.first_cell = 0;
              b.row_lo = 0;
              b.row_hi = static_cast<std::int16_t>(ny - 1);
              b.column_lo = 0;
              b.column_hi = static_cast<std::int16_t>(nx - 1);
            }
            for (const std::uint32_t j : near) poisoned_box[j] = box[j];
            std::vector<std::uint8_t> kind_near = kind0;
            SharedMarks marks;
            mark_shared_cells(near, poisoned_box, owner, nx, ny, interior_row, kind_near, kOpen, kShared, words, marks);
            const Read a = read_marks(fp, owner, r, interior_row, kind_full, full, nx);
            const Read b = read_marks(fp, owner, r, interior_row, kind_near, marks, nx);
            CHECK(a.shared == b.shared);
            CHECK(a.ranks == b.ranks);
            // The senders' side (order_by_owner): each floe's owner sends
            // its box to the ranks box_readers names, which are exactly the
            // ranks whose box_neighbours keep it.
            std::vector<std::uint32_t> sent;
            std::vector<int> readers;
            for (const std::uint32_t j : all) {
              readers.clear();
              box_readers(box[j], owner[j], row_owner, nx, own_rows, readers);
              CHECK(std::is_sorted(readers.begin(), readers.end()));
              if (std::find(readers.begin(), readers.end(), r) != readers.end()) sent.push_back(j);
            }
            CHECK(sent == near);
            read_full += others.size();
            read_near += near.size();
            // The mutation: without the own floes' rows.
            std::vector<std::uint32_t> thin;
            for (const std::uint32_t j : near) {
              const std::vector<std::uint32_t> one{j};
              if (!box_neighbours(one, owner, r, first, box, s.grid, 0).empty()) thin.push_back(j);
            }
            std::vector<std::uint8_t> kind_thin = kind0;
            SharedMarks thin_marks;
            mark_shared_cells(thin, box, owner, nx, ny, interior_row, kind_thin, kOpen, kShared, words, thin_marks);
            const Read t = read_marks(fp, owner, r, interior_row, kind_thin, thin_marks, nx);
            if (t.shared != a.shared || t.ranks != a.ranks) ++thin_misses;
          }
        }
      MESSAGE("kernel " << (kernel == FootprintKernel::cell ? "cell" : "tent") << ", reach " << reach
                        << ": boxes read " << read_near << " of " << read_full << " (all ranks and slabs); the thin set missed on "
                        << thin_misses << " of 24 ranks");
      CHECK(read_near < read_full);
      CHECK(thin_misses > 0);
    }
}

TEST_CASE("not in slabs, the boxes that meet a rank's box of its pieces' cells mark its pieces' cells as every other rank's box does (simulated ranks)") {
  // FloeSeaContact::order_by_owner on a sea not in slabs (BEM, a tank, a
  // flume: every row a boundary row): a floe's box goes to the ranks whose
  // box of all their pieces' cells (parallel::CellBox::of, gathered) it
  // meets (boxes_meet). The marks of rank r's pieces' cells from those boxes
  // only, every other box poisoned, equal the marks from every other rank's
  // box. Owners by strips of rows (the drift's) and by index (every floe
  // anywhere), 2, 3 and 7 ranks. The mutation, named: one box that meets
  // left out changes some rank's marks.
  const SeaPack s = sea_pack(7);
  const std::size_t n = s.floes.size();
  const int nx = s.grid.nx, ny = s.grid.ny;
  Footprints fp;
  build_footprints(s.floes, std::vector<std::uint8_t>(n, 1), s.grid, fp, FootprintKernel::cell, 1, s.poses);
  std::vector<parallel::CellBox> box(n);
  for (std::size_t i = 0; i < n; ++i)
    box[i] = parallel::CellBox::of(std::span(fp.cell.data() + fp.offsets[i], fp.offsets[i + 1] - fp.offsets[i]), nx, ny);
  const std::vector<std::uint8_t> interior_row(static_cast<std::size_t>(ny), 0);
  const std::vector<std::uint8_t> kind0(s.grid.size(), kOpen);
  std::size_t read_full = 0, read_meet = 0, misses = 0, tries = 0;
  for (const int ranks : {2, 3, 7})
    for (const bool strips : {true, false}) {
      CAPTURE(ranks);
      CAPTURE(strips);
      const std::vector<int> row_owner = parallel::row_owners(slabs(ranks, ny, false));
      std::vector<int> owner(n);
      for (std::size_t i = 0; i < n; ++i)
        owner[i] = strips ? row_owner[static_cast<std::size_t>(parallel::grid_row(s.poses[i].y, s.grid.dy(), ny))]
                          : static_cast<int>(i % static_cast<std::size_t>(ranks));
      // Each rank's box of its pieces' cells, the first cell first.
      std::vector<parallel::CellBox> rank_box(static_cast<std::size_t>(ranks));
      for (int r = 0; r < ranks; ++r) {
        std::vector<std::uint32_t> cells;
        for (std::size_t i = 0; i < n; ++i)
          if (owner[i] == r) cells.insert(cells.end(), fp.cell.begin() + fp.offsets[i], fp.cell.begin() + fp.offsets[i + 1]);
        rank_box[static_cast<std::size_t>(r)] = parallel::CellBox::of(cells, nx, ny);
      }
      const std::size_t words = (static_cast<std::size_t>(ranks) + 63) / 64;
      for (int r = 0; r < ranks; ++r) {
        CAPTURE(r);
        std::vector<std::uint32_t> others, meet;
        for (std::uint32_t j = 0; j < n; ++j)
          if (owner[j] != r) {
            others.push_back(j);
            if (boxes_meet(box[j], rank_box[static_cast<std::size_t>(r)], nx, ny)) meet.push_back(j);
            // Symmetric, as the test of two arcs is.
            CHECK(boxes_meet(box[j], rank_box[static_cast<std::size_t>(r)], nx, ny) ==
                  boxes_meet(rank_box[static_cast<std::size_t>(r)], box[j], nx, ny));
          }
        std::vector<std::uint8_t> kind_full = kind0;
        SharedMarks full;
        mark_shared_cells(others, box, owner, nx, ny, interior_row, kind_full, kOpen, kShared, words, full);
        std::vector<parallel::CellBox> poisoned_box(n);
        for (parallel::CellBox& b : poisoned_box) {
          b.first_cell = 0;
          b.row_hi = static_cast<std::int16_t>(ny - 1);
          b.column_hi = static_cast<std::int16_t>(nx - 1);
        }
        for (const std::uint32_t j : meet) poisoned_box[j] = box[j];
        std::vector<std::uint8_t> kind_meet = kind0;
        SharedMarks marks;
        mark_shared_cells(meet, poisoned_box, owner, nx, ny, interior_row, kind_meet, kOpen, kShared, words, marks);
        const Read a = read_marks(fp, owner, r, interior_row, kind_full, full, nx);
        const Read b = read_marks(fp, owner, r, interior_row, kind_meet, marks, nx);
        CHECK(a.shared == b.shared);
        CHECK(a.ranks == b.ranks);
        read_full += others.size();
        read_meet += meet.size();
        // The mutation: each box that meets left out in turn.
        for (std::size_t q = 0; q < meet.size(); ++q) {
          std::vector<std::uint32_t> less = meet;
          less.erase(less.begin() + static_cast<std::ptrdiff_t>(q));
          std::vector<std::uint8_t> kind_less = kind0;
          SharedMarks less_marks;
          mark_shared_cells(less, box, owner, nx, ny, interior_row, kind_less, kOpen, kShared, words, less_marks);
          const Read t = read_marks(fp, owner, r, interior_row, kind_less, less_marks, nx);
          ++tries;
          if (t.shared != a.shared || t.ranks != a.ranks) ++misses;
        }
      }
    }
  MESSAGE("boxes read " << read_meet << " of " << read_full << "; one box left out changed the marks in " << misses
                        << " of " << tries);
  CHECK(read_meet < read_full);
  CHECK(misses > 0);
}

TEST_CASE("the footprints' window test over each rank's own floes, agreed by one minimum, is the whole verdict (simulated ranks, lured poses)") {
  // MovingFootprints::movable: each rank tests the floes it owns for the
  // coupling (mine(), by the row of the centroid at the reference poses)
  // and the ranks' verdicts are combined by a minimum (Communicator::min).
  // On 2, 3 and 7 slabs, equal and uneven, periodic and walled grids, a
  // window of 0.3 cells: with every floe inside its window, and with one
  // floe (each of a few) pushed out of it. Each rank reads its own floes'
  // poses only: every other pose is a lure (moved 10 cells, out of any
  // window), which a read would turn into "outside". The mutation, named:
  // each rank's own verdict with no reduction differs from the whole
  // verdict on some rank whenever one floe is out.
  SeaPack s = sea_pack(11);
  const std::size_t n = s.floes.size();
  const double reach = 0.3;
  std::vector<std::uint32_t> all(n);
  std::iota(all.begin(), all.end(), 0u);
  std::vector<std::uint8_t> include(n, 1);
  include[5] = 0;  // a static floe is never tested
  // Poses within the window: a small displacement and turn, each floe its own.
  std::vector<FloePose> inside = s.poses;
  for (std::size_t i = 0; i < n; ++i) {
    const double f = static_cast<double>((i * 37) % 11) / 11.0 - 0.5;  // in [-0.5, 0.5)
    inside[i].x += 0.2 * reach * s.grid.dx() * f;
    inside[i].y -= 0.2 * reach * s.grid.dy() * f;
    inside[i].yaw += 0.1 * reach * s.grid.dy() * f / std::max(s.radius[i], 1.0);
  }
  std::size_t cases = 0, lone_verdicts_wrong = 0, lured_whole_wrong = 0;
  for (const fluid::GridEdge edge : {fluid::GridEdge::periodic, fluid::GridEdge::wall}) {
    fluid::SurfaceGrid grid = s.grid;
    grid.edge = edge;
    // The floe pushed out: none, or one of a few (each along y, or by a turn;
    // floe 5 is not included, so pushing it changes nothing).
    for (const int out : {-1, 0, 5, 123, 399}) {
      std::vector<FloePose> poses = inside;
      if (out >= 0) {
        const std::size_t j = static_cast<std::size_t>(out);
        if (out % 2) poses[j].y += 2.0 * reach * grid.dy();
        else poses[j].yaw += 2.0 * reach * grid.dx() / s.radius[j];
      }
      const bool whole = inside_windows(all, include, s.poses, poses, s.radius, grid, reach);
      CHECK(whole == (out < 0 || out == 5));
      for (const int ranks : {2, 3, 7})
        for (const bool uneven : {false, true}) {
          CAPTURE(ranks);
          CAPTURE(uneven);
          CAPTURE(out);
          const std::vector<int> row_owner = parallel::row_owners(slabs(ranks, grid.ny, uneven));
          int agreed = 1;
          for (int r = 0; r < ranks; ++r) {
            std::vector<std::uint32_t> mine;
            std::vector<FloePose> lured = poses;
            for (std::size_t i = 0; i < n; ++i) {
              if (row_owner[static_cast<std::size_t>(parallel::grid_row(s.poses[i].y, grid.dy(), grid.ny))] == r) {
                mine.push_back(static_cast<std::uint32_t>(i));
              } else {
                lured[i].x += 10.0 * grid.dx();
                lured[i].y += 10.0 * grid.dy();
              }
            }
            const bool own = inside_windows(mine, include, s.poses, lured, s.radius, grid, reach);
            agreed = std::min(agreed, own ? 1 : 0);
            if (own != whole) ++lone_verdicts_wrong;
            if (inside_windows(all, include, s.poses, lured, s.radius, grid, reach) != whole) ++lured_whole_wrong;
          }
          CHECK((agreed == 1) == whole);
          ++cases;
        }
    }
  }
  MESSAGE("window verdicts: " << cases << " cases; a rank's own verdict alone wrong " << lone_verdicts_wrong
                              << " times, the test over every floe on the lured copy wrong " << lured_whole_wrong << " times");
  CHECK(lone_verdicts_wrong > 0);
  CHECK(lured_whole_wrong > 0);
}

TEST_CASE("the drift's owners by place are the footprints' owners by place at a rebuild, and name each rank's floes to pose (simulated ranks)") {
  // FloeSeaContact::take_place_owners: a rebuild of the footprints takes the
  // drift's owners (parallel::FloeOwners with the sea's slabs, assigned at
  // the floes' present places) instead of posing every floe to find them
  // (MovingFootprints::set_owners: the row of the centroid at the rebuild's
  // pose). Both rules on the same poses, on 2, 3 and 7 slabs, equal and
  // uneven, the pack on the periodic grid, moved half a grid up (some floes
  // beyond the seam, unwrapped) and 150 m below the grid (floes beyond an
  // open box's grid, owned by the row they wrap to), and with floes put on
  // the slabs' first rows' lines exactly: every floe's owner is the same,
  // and each rank's `mine` lists its floes. The owners by the coupling's
  // rule read only each floe's own pose (a rank poses its own floes: the
  // others' poses are NaN on its copy, and its own floes' owners are still
  // its rank). The mutation, named: the drift's owners on the slabs before
  // a move of the cuts (one block of rows) are not the rebuild's owners
  // (MovingFootprints::takes_owners refuses them).
  const SeaPack s = sea_pack(5);
  const std::size_t n = s.floes.size();
  const double dy = s.grid.dy();
  std::size_t compared = 0, moved_differs = 0;
  for (const double shift : {0.0, 0.5 * s.grid.ly, -150.0})
    for (const int ranks : {2, 3, 7})
      for (const bool uneven : {false, true}) {
        CAPTURE(shift);
        CAPTURE(ranks);
        CAPTURE(uneven);
        const std::vector<int> first = slabs(ranks, s.grid.ny, uneven);
        Floes floes = s.floes;
        for (std::size_t i = 0; i < n; ++i) floes.state[i].y += shift;
        // A few floes on a slab's first row's line, exactly.
        for (int r = 1; r < ranks; ++r) floes.state[static_cast<std::size_t>(17 * r)].y = dy * first[static_cast<std::size_t>(r)];
        contact::Domain domain;
        domain.periodic = shift >= 0.0;
        domain.xmin = 0.0;
        domain.xmax = s.grid.lx;
        domain.ymin = 0.0;
        domain.ymax = s.grid.ly;
        const std::vector<int> row_owner = parallel::row_owners(first);
        for (int r = 0; r < ranks; ++r) {
          parallel::FloeOwners drift(r, ranks, domain);
          drift.set_slabs({first, dy, 8});
          drift.assign(floes);
          // The coupling's rule, each rank posing its own floes only.
          std::vector<FloePose> poses(n, FloePose{std::nan(""), std::nan(""), std::nan("")});
          for (const std::uint32_t i : drift.mine()) poses[i] = {floes.state[i].x, floes.state[i].y, floes.state[i].yaw};
          for (std::size_t i = 0; i < n; ++i) {
            const FloePose at{floes.state[i].x, floes.state[i].y, floes.state[i].yaw};
            const int coupling = row_owner[static_cast<std::size_t>(parallel::grid_row(at.y, dy, s.grid.ny))];
            CHECK(drift.owner()[i] == coupling);
            if (drift.owner()[i] == r)
              CHECK(row_owner[static_cast<std::size_t>(parallel::grid_row(poses[i].y, dy, s.grid.ny))] == r);
            ++compared;
          }
          for (const std::uint32_t i : drift.mine()) CHECK(drift.owner()[i] == r);
          // The mutation: the cuts one block of rows off.
          std::vector<int> before = first;
          before[1] = std::max(0, before[1] - 8);
          parallel::FloeOwners old(r, ranks, domain);
          old.set_slabs({before, dy, 8});
          old.assign(floes);
          if (!std::ranges::equal(old.owner(), drift.owner())) ++moved_differs;
        }
      }
  MESSAGE("owners compared " << compared << "; the slabs before a move give other owners in " << moved_differs << " of "
                             << (3 * (2 + 3 + 7) * 2) << " rank cases");
  CHECK(moved_differs > 0);
}
