#include "parallel/held.hpp"

#include <algorithm>
#include <cstring>

#include "core/error.hpp"
#include "parallel/bytes.hpp"

namespace floesim::parallel {

static_assert(kSentAsBytes<BandStrip>);

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

HeldFloes announce_held(const Communicator& comm, const FloeOwners& owners, const Floes& floes,
                        const contact::CollisionShapes& shapes, contact::DetectionOptions& options) {
  const std::size_t n = floes.size();
  if (comm.serial()) return every_floe(n);
  FLOESIM_ASSERT(owners.owner().size() == n && options.reach.size() == n && owners.rank() == comm.rank());
  // Every rank's strip and part of H (one call); H their largest.
  const BandStrip mine = band_strip(owners, comm.rank(), floes, shapes, options);
  const std::vector<std::size_t> strip_bytes(static_cast<std::size_t>(comm.size()), sizeof(BandStrip));
  const std::vector<std::byte> gathered = comm.allgather_known(std::as_bytes(std::span<const BandStrip>(&mine, 1)), strip_bytes);
  std::vector<BandStrip> strips(strip_bytes.size());
  std::memcpy(static_cast<void*>(strips.data()), gathered.data(), gathered.size());
  double largest = 0.0;
  for (const BandStrip& s : strips) largest = std::max(largest, s.largest);
  // The notices as one message a rank: the indices, then the reaches.
  const std::vector<BandNotice> notices = band_notices(owners, comm.rank(), floes, shapes, options, strips, largest);
  std::vector<std::byte> send;
  std::vector<std::size_t> send_counts;
  for (const BandNotice& notice : notices) {
    append(send, std::span<const std::uint32_t>(notice.floe));
    append(send, std::span<const double>(notice.reach));
    send_counts.push_back(notice.floe.size() * (sizeof(std::uint32_t) + sizeof(double)));
  }
  std::vector<std::byte> got;
  std::vector<std::size_t> got_counts;
  comm.alltoall_bytes(send, send_counts, got, got_counts);
  std::vector<BandNotice> received(got_counts.size());
  const std::byte* at = got.data();
  for (std::size_t s = 0; s < got_counts.size(); ++s) {
    const std::size_t k = got_counts[s] / (sizeof(std::uint32_t) + sizeof(double));
    received[s].floe = take<std::uint32_t>(at, k);
    received[s].reach = take<double>(at, k);
  }
  return held_from_notices(owners.mine(), n, received, largest, options.reach);
}

}  // namespace floesim::parallel
