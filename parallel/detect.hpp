#pragma once
// Contact detection (contact/detection.hpp) with its narrow phase shared
// among the ranks. Every rank holds every floe (stage one of
// docs/parallel.md: the state is replicated), runs the broad phase, and
// measures one contiguous share of the candidate pairs
// (DetectionOptions::part of parts); the shares are gathered in rank order
// (one message a rank: the counts and the three lists).
// The pairs are sorted by (a, b, shift) before they are shared, so the
// concatenation is the serial pair list, and each pair is measured by the
// same code on the same data: the result is the serial one, bit for bit, on
// any number of ranks.

#include <vector>

#include "contact/detection.hpp"
#include "parallel/comm.hpp"

namespace floesim::parallel {

// Collective: every rank calls it with the same floes and options (part and
// parts are set here).
contact::Detection detect(const Communicator& comm, const Floes& floes, const contact::CollisionShapes& shapes,
                          contact::DetectionOptions options);

// The detections of parts 0, 1, ... of one detection, concatenated: pairs,
// contacts and witnesses in order, each pair's first_contact and
// first_witness moved to where its part's lists start. The reach is the
// first part's (every part has the whole reach).
contact::Detection concatenate(std::vector<contact::Detection> parts);

}  // namespace floesim::parallel
