#pragma once
// The verdict of a test program run on every rank mpirun started (the
// *_ranks.cpp programs, run by ctest as mpi.*_N): each rank's failures
// printed with its rank, one sum of the failed ranks, and rank 0 saying
// what passed. A check that throws is a failure of its rank, not a rank
// stopping alone (the other ranks would wait in the sum).
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "parallel/comm.hpp"

namespace floesim::test {

using Failures = std::vector<std::string>;

// 0 when no rank failed, else 1 (the same on every rank).
inline int verdict(const parallel::Communicator& comm, const Failures& failures, const std::string& passed) {
  for (const std::string& f : failures) std::printf("rank %d of %d: FAILED: %s\n", comm.rank(), comm.size(), f.c_str());
  const bool all = comm.sum(failures.empty() ? 0LL : 1LL) == 0;
  if (comm.writer())
    std::printf("%s on %d rank(s): %s\n", all ? "passed" : "FAILED", comm.size(), all ? passed.c_str() : "see above");
  return all ? 0 : 1;
}

// Runs each check(comm, failures) in order on every rank, then the verdict.
template <class... Check>
int run_checks(const parallel::Communicator& comm, const std::string& passed, Check&&... check) {
  Failures failures;
  try {
    (check(comm, failures), ...);
  } catch (const std::exception& e) {
    failures.push_back(std::string("threw: ") + e.what());
  }
  return verdict(comm, failures, passed);
}

}  // namespace floesim::test
