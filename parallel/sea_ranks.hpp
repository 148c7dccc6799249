#pragma once
// The ranks of a communicator as the sea in slabs sees them (fluid/ranks.hpp:
// fluid/ knows nothing of MPI; this gives it the communicator's two
// collective exchanges). The communicator is copied into the exchanges: it
// must outlive the sea (a Communicator is a handle to the run's ranks).

#include "fluid/ranks.hpp"
#include "parallel/comm.hpp"

namespace floesim::parallel {

inline fluid::SeaRanks sea_ranks(const Communicator& comm) {
  fluid::SeaRanks r;
  r.rank = comm.rank();
  r.ranks = comm.size();
  r.alltoall = [comm](std::span<const std::byte> send, const std::vector<std::size_t>& send_counts,
                      std::span<std::byte> receive, const std::vector<std::size_t>& receive_counts) {
    comm.alltoall(send, send_counts, receive, receive_counts);
  };
  r.allgather = [comm](std::span<std::byte> all, const std::vector<std::size_t>& counts) {
    comm.allgather_in_place(all, counts);
  };
  return r;
}

}  // namespace floesim::parallel
