#pragma once
// Why the parts of a tried step do not make the whole call's answer: the
// advance's shares (AdvancePart, advance_share.hpp) or the step-start
// collisions' (CollidePart, collide_share.hpp), one a rank, in rank order.
//
// A share says its own conflict (`name_of` gives its name, nullptr for
// none). Two more can be seen only across the parts:
//   - `taken_twice`: two parts changed one floe (a free floe that clusters
//     or groups of two ranks took: the serial call runs them as one);
//   - `stored_twice`: two parts stored one warm pair (a pair is one
//     cluster's or group's, so never expected; refused rather than
//     written twice).
// The parts combine exactly when the list is empty, and the list is what
// the run's summary counts (parallel.advance_conflicts.KIND,
// parallel.collide_conflicts.KIND): one rule for both.

#include <algorithm>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace floesim::parallel {

// Each kind once, sorted.
template <class Part, class NameOf>
std::vector<std::string> refusals(std::span<const Part> parts, NameOf name_of) {
  std::vector<std::string> kinds;
  std::vector<std::uint8_t> taken;
  std::vector<std::uint64_t> stored;
  bool twice = false;
  for (const Part& p : parts) {
    if (const char* name = name_of(p.outcome.conflict)) {
      kinds.emplace_back(name);
      continue;
    }
    for (const std::uint32_t i : p.outcome.moved) {
      if (i >= taken.size()) taken.resize(i + 1, 0);
      twice = twice || taken[i];
      taken[i] = 1;
    }
    for (const auto& w : p.outcome.warm) stored.push_back(w.first);
  }
  if (kinds.empty()) {
    if (twice) kinds.emplace_back("taken_twice");
    std::sort(stored.begin(), stored.end());
    if (std::adjacent_find(stored.begin(), stored.end()) != stored.end()) kinds.emplace_back("stored_twice");
  }
  std::sort(kinds.begin(), kinds.end());
  kinds.erase(std::unique(kinds.begin(), kinds.end()), kinds.end());
  return kinds;
}

}  // namespace floesim::parallel
