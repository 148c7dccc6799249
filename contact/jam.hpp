#pragma once
// Jams: what makes a contact component a jam, and the tuning of how a jam is
// time-stepped (impulse.hpp "Jams", substep.hpp), in one options struct; and
// the disjoint sets (union–find) the contact layer builds its components with.
//
// A jam is a contact component (dynamic floes joined by contact points) of at
// least `floes` floes. Its contacts rest, its witnesses beyond xi are
// speculative from the first solve, and its cluster in the sub-stepper takes
// time steps (one LCP for the rest of the step) instead of events.

#include <cstddef>
#include <cstdint>
#include <numeric>
#include <vector>

namespace floesim::contact {

struct JamOptions {
  // A contact component of at least this many dynamic floes is a jam.
  std::size_t floes = 20;
  // Where a jam's LCP is solved. false: only in its time step
  // (advance_with_collisions, substep.hpp), which starts from the
  // velocities before any collision of the step; resolve_step_collisions
  // leaves the jam's contacts and speculative points alone, and the
  // sub-stepper time-steps every jam from the step's start. true: also at
  // the start of the step (resolve_step_collisions), after which the time
  // step solves it again from those velocities, a second LCP of the whole
  // jam per step that mostly confirms the first.
  bool at_step_start = false;
  // Dynamic floes whose room to a jam-sized cluster is below pad * xi (10 m
  // at xi = 1 cm) join it at the start of the step: a jam's time steps move
  // its floes 0.5 to 3 m off their straight paths (jam_500), beyond the
  // budgets of nearer pads, and each join during a time step reruns its LCP.
  double pad = 1000.0;
  // A jam's time step solves its LCP again while the turning of its floes
  // closes a contact by more than turning_slack * xi beyond what the contact
  // asked for, at most turning_rounds more times (turning_closing,
  // step_limit.hpp).
  double turning_slack = 0.01;
  int turning_rounds = 3;
  // A jam's time step that overlaps is halved (the linearised gaps miss the
  // floes' turning by a term in h^2); below step_floor * dt the cluster goes
  // back to events for the rest of the step.
  double step_floor = 1.0 / 16.0;
};

// Disjoint sets over the indices 0 .. size() - 1 (union by linking roots,
// path halving); `add` appends a singleton.
struct DisjointSets {
  std::vector<std::uint32_t> parent;

  DisjointSets() = default;
  explicit DisjointSets(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
  std::size_t size() const { return parent.size(); }
  std::uint32_t add() {
    parent.push_back(static_cast<std::uint32_t>(parent.size()));
    return parent.back();
  }
  std::uint32_t find(std::uint32_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  }
  void join(std::uint32_t a, std::uint32_t b) { parent[find(a)] = find(b); }
};

}  // namespace floesim::contact
