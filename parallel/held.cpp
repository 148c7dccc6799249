#include "parallel/held.hpp"

#include <algorithm>
#include <array>
#include <cstdint>

#include "core/error.hpp"
#include "parallel/bytes.hpp"

namespace floesim::parallel {

static_assert(kSentAsBytes<BandStrip> && kSentAsBytes<LeaveNotice>);

std::vector<std::uint32_t> own_floes(const FloeOwners& owners, int rank) {
  if (rank == owners.rank()) return owners.mine();
  std::vector<std::uint32_t> out;  // a simulated rank (tests)
  const std::span<const int> owner = owners.owner();
  for (std::size_t j = 0; j < owner.size(); ++j)
    if (owner[j] == rank) out.push_back(static_cast<std::uint32_t>(j));
  return out;
}

std::vector<BandNotice> band_notices(const FloeOwners& owners, int rank, const Floes& floes,
                                     const contact::CollisionShapes& shapes, const contact::DetectionOptions& options,
                                     std::span<const BandStrip> strips, double largest) {
  FLOESIM_ASSERT(strips.size() == static_cast<std::size_t>(owners.ranks()));
  std::vector<BandNotice> out(strips.size());
  for (const std::uint32_t j : own_floes(owners, rank)) {
    // held_floes' comparison on rank s, with s's strip and the same y_j, h_j.
    const double y = owners.place(floes.state[j]);
    const double band = largest + half_band(owners, floes, shapes, options, j);
    for (std::size_t s = 0; s < strips.size(); ++s) {
      if (static_cast<int>(s) == rank || !(strip_distance(y, strips[s], options.domain) <= band)) continue;
      out[s].floe.push_back(j);
      out[s].reach.push_back(options.reach_of(j));
    }
  }
  return out;
}

HeldFloes held_from_notices(std::span<const std::uint32_t> own, std::size_t n, std::span<const BandNotice> received,
                            double largest, std::span<double> reach) {
  FLOESIM_ASSERT(reach.empty() || reach.size() == n);
  HeldFloes out;
  out.largest = largest;
  out.mask.assign(n, 0);
  for (const std::uint32_t j : own) out.mask[j] = 1;
  for (const BandNotice& notice : received)
    for (std::size_t k = 0; k < notice.floe.size(); ++k) {
      const std::uint32_t j = notice.floe[k];
      FLOESIM_ASSERT(j < n && !out.mask[j]);  // one owner a floe, never the receiver
      out.mask[j] = 1;
      if (!reach.empty()) reach[j] = notice.reach[k];
    }
  for (std::size_t j = 0; j < n; ++j)
    if (out.mask[j]) out.index.push_back(static_cast<std::uint32_t>(j));
  return out;
}

void widen_by_arrivals(std::span<BandStrip> strips, std::span<const LeaveNotice> notices,
                       const contact::CollisionShapes& shapes, double collision_distance) {
  for (const LeaveNotice& k : notices) {
    BandStrip& s = strips[static_cast<std::size_t>(k.owner)];
    s.lo = std::min(s.lo, k.place);
    s.hi = std::max(s.hi, k.place);
    s.largest = std::max(s.largest, half_band_for(k.place, shapes.radius[k.floe], k.reach, collision_distance));
  }
}

bool Announced::find(std::uint32_t j, std::span<const int>& ranks) const {
  const auto it = std::lower_bound(floe.begin(), floe.end(), j);
  if (it == floe.end() || *it != j) return false;
  const auto k = static_cast<std::size_t>(it - floe.begin());
  ranks = std::span<const int>(rank).subspan(offset[k], offset[k + 1] - offset[k]);
  return true;
}

Announced announced_of(std::span<const std::uint32_t> own, std::span<const BandNotice> sent) {
  // Each notice's floes are ascending and among `own`: one pass of a
  // cursor per notice, the ranks of a floe in rank order.
  Announced out;
  out.floe.assign(own.begin(), own.end());
  out.offset.reserve(own.size() + 1);
  out.offset.push_back(0);
  std::vector<std::size_t> at(sent.size(), 0);
  for (const std::uint32_t j : own) {
    for (std::size_t s = 0; s < sent.size(); ++s)
      if (at[s] < sent[s].floe.size() && sent[s].floe[at[s]] == j) {
        out.rank.push_back(static_cast<int>(s));
        ++at[s];
      }
    out.offset.push_back(out.rank.size());
  }
  return out;
}

HeldFloes announce_held(const Communicator& comm, FloeOwners& owners, const Floes& floes,
                        const contact::CollisionShapes& shapes, contact::DetectionOptions& options,
                        std::span<const LeaveNotice> leaving, std::span<const long long> leaving_counts,
                        HaloPart* halo) {
  const std::size_t n = floes.size();
  if (comm.serial()) return every_floe(n);
  const auto ranks = static_cast<std::size_t>(comm.size());
  FLOESIM_ASSERT(owners.owner().size() == n && options.reach.size() == n && owners.rank() == comm.rank() &&
                 (leaving_counts.empty() || leaving_counts.size() == ranks));
  // This rank's floes that left its strip are no longer its own (it knows
  // their new owners); its strip and part of H from the floes it keeps.
  owners.take_leaving(leaving);
  const BandStrip mine = band_strip(owners, comm.rank(), floes, shapes, options);
  // One call: every rank's strip and part of H, then its notices (with the
  // halo exchange, then the leaving floes' states and step-start copies:
  // the old owner holds them current, the new one may not).
  std::vector<std::byte> message;
  append(message, std::span<const BandStrip>(&mine, 1));
  append(message, leaving);
  if (halo)
    for (const LeaveNotice& k : leaving) {
      const std::array<FloeState, 2> both{(*halo->state)[k.floe], (*halo->start)[k.floe]};
      append(message, std::span<const FloeState>(both));
    }
  const std::size_t notice_bytes = sizeof(LeaveNotice) + (halo ? 2 * sizeof(FloeState) : 0);
  std::vector<std::size_t> message_bytes(ranks, sizeof(BandStrip));
  for (std::size_t r = 0; r < leaving_counts.size(); ++r)
    message_bytes[r] += static_cast<std::size_t>(leaving_counts[r]) * notice_bytes;
  const std::vector<std::byte> gathered = comm.allgather_known(message, message_bytes);
  std::vector<BandStrip> strips(ranks);
  std::vector<LeaveNotice> notices;  // every rank's, in rank order
  std::vector<std::uint32_t> came;   // the floes that came to this rank, ascending after the sort below
  const std::byte* at = gathered.data();
  for (std::size_t r = 0; r < ranks; ++r) {
    strips[r] = take<BandStrip>(at, 1)[0];
    const std::size_t count = (message_bytes[r] - sizeof(BandStrip)) / notice_bytes;
    const std::vector<LeaveNotice> part = take<LeaveNotice>(at, count);
    const std::vector<FloeState> states = take<FloeState>(at, halo ? 2 * count : 0);
    // The others' notices change the owner array here (this rank's own did
    // above); a floe that came to this rank takes its reach from its notice,
    // and with the halo exchange its state and step-start copy.
    if (static_cast<int>(r) != comm.rank()) {
      owners.take_leaving(part);
      for (std::size_t k = 0; k < part.size(); ++k) {
        if (part[k].owner != comm.rank()) continue;
        options.reach[part[k].floe] = part[k].reach;
        if (!halo) continue;
        (*halo->state)[part[k].floe] = states[2 * k];
        (*halo->start)[part[k].floe] = states[2 * k + 1];
        halo->written.push_back(part[k].floe);
        came.push_back(part[k].floe);
      }
    }
    notices.insert(notices.end(), part.begin(), part.end());
  }
  std::sort(came.begin(), came.end());
  // Each strip widened by the places and half bands of the floes that came
  // to its rank: band_strip over the rank's own floes now (min and max are
  // exact in any order).
  widen_by_arrivals(strips, notices, shapes, options.collision_distance);
  double largest = 0.0;
  for (const BandStrip& s : strips) largest = std::max(largest, s.largest);
  // The notices as one message a rank: the indices, then the reaches.
  const std::vector<BandNotice> band = band_notices(owners, comm.rank(), floes, shapes, options, strips, largest);
  // With the halo exchange, after them whether each floe's state follows
  // (1 B a floe) and those states, behind a header of the count of floes
  // (the receiver cannot tell the two lengths from the message's size).
  // Rank s held floe j through the step (its copy is current: every
  // holder updates a held floe alike) when this rank owned j at the last
  // detection and announced it to s, and j did not come to it here: then
  // nothing more; else the state goes.
  const auto holds_already = [&](std::uint32_t j, int s) {
    std::span<const int> last;
    if (!halo || !halo->last || std::binary_search(came.begin(), came.end(), j) || !halo->last->find(j, last))
      return false;
    return std::binary_search(last.begin(), last.end(), s);
  };
  std::vector<std::byte> send;
  std::vector<std::size_t> send_counts;
  for (std::size_t s = 0; s < band.size(); ++s) {
    const BandNotice& notice = band[s];
    const std::size_t before = send.size();
    if (halo && !notice.floe.empty()) {
      const std::uint64_t k = notice.floe.size();
      append(send, std::span<const std::uint64_t>(&k, 1));
    }
    append(send, std::span<const std::uint32_t>(notice.floe));
    append(send, std::span<const double>(notice.reach));
    if (halo && !notice.floe.empty()) {
      std::vector<std::uint8_t> carries(notice.floe.size());
      std::vector<FloeState> states;
      for (std::size_t k = 0; k < notice.floe.size(); ++k) {
        carries[k] = holds_already(notice.floe[k], static_cast<int>(s)) ? 0 : 1;
        if (carries[k]) states.push_back((*halo->state)[notice.floe[k]]);
      }
      append(send, std::span<const std::uint8_t>(carries));
      append(send, std::span<const FloeState>(states));
    }
    send_counts.push_back(send.size() - before);
  }
  std::vector<std::byte> got;
  std::vector<std::size_t> got_counts;
  comm.alltoall_bytes(send, send_counts, got, got_counts);
  std::vector<BandNotice> received(got_counts.size());
  at = got.data();
  for (std::size_t s = 0; s < got_counts.size(); ++s) {
    if (!halo) {
      const std::size_t k = got_counts[s] / (sizeof(std::uint32_t) + sizeof(double));
      received[s].floe = take<std::uint32_t>(at, k);
      received[s].reach = take<double>(at, k);
      continue;
    }
    if (got_counts[s] == 0) continue;
    const auto k = static_cast<std::size_t>(take<std::uint64_t>(at, 1)[0]);
    received[s].floe = take<std::uint32_t>(at, k);
    received[s].reach = take<double>(at, k);
    const std::vector<std::uint8_t> carries = take<std::uint8_t>(at, k);
    const std::vector<FloeState> states =
        take<FloeState>(at, static_cast<std::size_t>(std::count(carries.begin(), carries.end(), std::uint8_t{1})));
    for (std::size_t i = 0, m = 0; i < k; ++i)
      if (carries[i]) {
        (*halo->state)[received[s].floe[i]] = states[m++];
        halo->written.push_back(received[s].floe[i]);
      }
  }
  if (halo) halo->announced = announced_of(owners.mine(), band);
  return held_from_notices(owners.mine(), n, received, largest, options.reach);
}

}  // namespace floesim::parallel
