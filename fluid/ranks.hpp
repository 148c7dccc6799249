#pragma once
// The ranks of a distributed run as the sea sees them (docs/parallel.md,
// stage four). fluid/ knows nothing of MPI: the caller (coupling/, through
// parallel::Communicator) gives the two collective exchanges the sea in
// slabs needs. Every rank calls each one, in the same order.

#include <cstddef>
#include <functional>
#include <span>
#include <vector>

namespace floesim::fluid {

struct SeaRanks {
  int rank = 0, ranks = 1;
  // Every rank's bytes to every rank: send holds the parts for ranks
  // 0..N-1 in order, send_counts[s] bytes for rank s; receive gets the parts
  // from ranks 0..N-1 in order, receive_counts[s] bytes from rank s.
  std::function<void(std::span<const std::byte> send, const std::vector<std::size_t>& send_counts,
                     std::span<std::byte> receive, const std::vector<std::size_t>& receive_counts)>
      alltoall;
  // `all` holds the ranks' parts in rank order, counts[r] bytes for rank r;
  // this rank's part is in place on entry, every part on exit.
  std::function<void(std::span<std::byte> all, const std::vector<std::size_t>& counts)> allgather;

  bool distributed() const { return ranks > 1; }
};

}  // namespace floesim::fluid
