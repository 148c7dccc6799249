#pragma once
// The held sets announced by the owners (docs/parallel.md, "The held sets
// announced by the owners (band18)"): each rank tests only the floes it owns
// against the other ranks' strips and tells each rank which of them its band
// holds, with their reaches. No rank reads another rank's floes' speeds,
// places or reaches: what the state held by owner (piece 8 of the halo plan)
// needs, and what its exchange (b), the states of the floes entering a band,
// will be carried with.
//
// The mathematics. Rank s holds its own floes and its band
//
//     B_s = { j not owned by s : dist(y_j, S_s) <= H + h_j }
//
// (parallel/place.hpp: S_s the strip widened to the places of s's own
// floes, the distance on the circle in a periodic box, h_j = R_j + reach_j +
// xi/2 with its round-off margin, H = max_j h_j). The test of floe j reads
// y_j and h_j, which only j's owner o(j) computes (reach_j is a function of
// j's velocities and the pack's rms speed), and S_s and H, which are each
// rank's own (band_strip: its cuts and its floes' places) and one maximum:
// so each rank gathers every rank's widened strip and part of H (one
// allgather of 24 bytes a rank, in place of held17's max reduction of 8),
// H being the largest part (a max is exact: the same bits as the
// reduction), and o(j) evaluates the same comparison with the same doubles
// as parallel::held_floes does on rank s: the same set, floe for floe.
// Nearest image: in a periodic box every place lies in [ymin, ymax), so the
// nearest of the images y_j - L, y_j, y_j + L is the nearest of all
// (strip_distance). The floes beyond the grid (an open box with the sea's
// slabs: owned by the row they wrap to, far from their owner's cut strip)
// are in their owner's widened strip: the strip that every rank tests
// against is the one s gathered, widened by s itself.
//
// The announcement, one all-to-all: rank r sends rank s the indices of its
// floes in B_s, ascending, and their reaches (12 bytes a floe and holder;
// two calls: the counts, then the records). Rank s's held set is its own
// floes and the indices it receives; it writes the reaches it receives into
// its reach array, so that it holds the reach of every floe it holds (its
// own it computed). The reaches of the floes it does not hold are not
// written.
#include <cstdint>
#include <span>
#include <vector>

#include "contact/detection.hpp"
#include "contact/shapes.hpp"
#include "core/floes.hpp"
#include "parallel/comm.hpp"
#include "parallel/place.hpp"

namespace floesim::parallel {

// What one rank tells another: those of its floes that the other's band
// holds (ascending), with their reaches (m).
struct BandNotice {
  std::vector<std::uint32_t> floe;
  std::vector<double> reach;
};

// The floes `rank` owns, ascending (owners.mine() for the calling rank; for
// a simulated rank, from the owner array).
std::vector<std::uint32_t> own_floes(const FloeOwners& owners, int rank);

// Rank `rank`'s notices, one per rank in rank order (its own empty): each
// floe j it owns goes to every other rank s with
// strip_distance(y_j, strips[s]) <= largest + h_j. Reads only the floes
// `rank` owns (their places, radii and reaches in options). `strips`: every
// rank's band_strip; `largest`: H, the largest of their parts.
std::vector<BandNotice> band_notices(const FloeOwners& owners, int rank, const Floes& floes,
                                     const contact::CollisionShapes& shapes, const contact::DetectionOptions& options,
                                     std::span<const BandStrip> strips, double largest);

// A rank's held floes from its own (ascending) and the notices it received
// (any order of senders): the union, as an ascending index and a mask over
// n floes, with H = `largest`. The notices' reaches are written into
// `reach` (n values) when it is not empty.
HeldFloes held_from_notices(std::span<const std::uint32_t> own, std::size_t n, std::span<const BandNotice> received,
                            double largest, std::span<double> reach);

// The strips (band_strip of each rank's floes but those that left it)
// widened by the floes that came to each rank: each notice's place and
// half band (half_band_for with the notice's reach) into its new owner's
// strip. The result is each rank's band_strip over its own floes now,
// bit for bit (min and max are exact in any order).
void widen_by_arrivals(std::span<BandStrip> strips, std::span<const LeaveNotice> notices,
                       const contact::CollisionShapes& shapes, double collision_distance);

// The ranks an owner announced its floes to at a detection (band_notices):
// for each floe it owned then, ascending, the ranks whose band held it.
// The halo exchange (docs/parallel.md, "The halo exchange (halo26)") sends
// an owned floe's state to those ranks after the drift, and at the next
// detection knows which of the ranks its band notices go to held the floe
// already (those it announced it to, if it owned the floe then).
struct Announced {
  std::vector<std::uint32_t> floe;  // ascending
  std::vector<std::size_t> offset;  // floe[k]'s ranks: rank[offset[k], offset[k + 1])
  std::vector<int> rank;            // ascending within a floe
  // Whether floe j was announced by this rank (owned at that detection),
  // and if so its ranks in `ranks`.
  bool find(std::uint32_t j, std::span<const int>& ranks) const;
};
// The announced sets of `own` (ascending) from the notices a rank sends
// (band_notices' result, one per rank).
Announced announced_of(std::span<const std::uint32_t> own, std::span<const BandNotice> sent);

// The halo exchange's part at a detection (piece 8 (b)), given to
// announce_held: the floes that enter a rank's held set there get their
// state from their owner with their band notice, and a floe that leaves
// its owner's strip takes its state and step-start copy to its new owner
// with its leave notice (the new owner need not have held it). Every rank
// alike gives one or none.
struct HaloPart {
  // In: this rank's announced sets at the last accepted detection (the
  // floes it owned then); a floe not among them, or one that came to this
  // rank here, has its state sent with every band notice of it.
  const Announced* last = nullptr;
  // In and out: the floes' states (the receiver writes the floes whose
  // state arrives) and step-start copies (the new owner writes the
  // leaving floes' own). Must be the states announce_held reads.
  std::vector<FloeState>* state = nullptr;
  std::vector<FloeState>* start = nullptr;
  // Out: this detection's announced sets, and the floes whose state this
  // rank received (entering its held set, or come to it).
  Announced announced;
  std::vector<std::uint32_t> written;
};

// Collective (every rank, owners assigned for these floes, each rank's own
// floes' reaches in options.reach, n values): every rank's held floes as
// parallel::held_floes gives them with H the ranks' largest h_j, and the
// reaches of its band's floes written into options.reach from their owners'.
// With the owners from the own floes (docs/parallel.md, handover25), the
// owners still those before the places advanced: `leaving`, this rank's
// notices of its floes that left its strip (FloeOwners::leaving, with their
// reaches), and `leaving_counts`, every rank's number of them (known to
// all; empty: none, the owners assigned already), ride on the strips'
// gather; every rank applies them to `owners` and writes the reaches of
// the floes that came to it. Three calls: the strips' and notices'
// allgather, the band's notices' counts and records. Serial: every floe
// held, nothing exchanged.
// With `halo` (the state held by owner), the part (b) of the halo
// exchange rides on the same calls: the leave notices carry the leaving
// floes' states and step-start copies (192 B more a notice), the band
// notices the states of the floes that enter the receiver's held set
// (HaloPart; 96 B a floe and receiver, and 1 B and a header of 8 B).
HeldFloes announce_held(const Communicator& comm, FloeOwners& owners, const Floes& floes,
                        const contact::CollisionShapes& shapes, contact::DetectionOptions& options,
                        std::span<const LeaveNotice> leaving = {}, std::span<const long long> leaving_counts = {},
                        HaloPart* halo = nullptr);

}  // namespace floesim::parallel
