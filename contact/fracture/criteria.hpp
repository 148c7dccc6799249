#pragma once
// Fracture initiation criteria on a floe's response (MODEL.md §6).
//
// stress: the crack starts where the largest principal stress sigma_1 over
//   the floe and over the response reaches the strength, and runs
//   perpendicular to sigma_1; it is taken straight through the floe (the
//   chord through that point). load_factor = strength / sigma_1 is the
//   factor on the loads at which it would start (the response is linear).
//
// griffith: at the instant of the largest strain energy, with u* the elastic
//   displacement and f = relieve(K u*) its self-equilibrated load, straight
//   candidate cracks are tried through the most stressed region: through
//   each of the (at most `candidates`) nodes of largest sigma_1, at least
//   two mesh sizes apart and with sigma_1 >= `region` x the largest, each
//   perpendicular to its sigma_1 (the direction in which a crack opens; the
//   energy alone would also favour sliding cracks in compression, which
//   do not open). A candidate grows from its node by one mesh size s at
//   each end per increment (from the outline inward when the node is on it);
//   the triangles it meets are cracked (elastic.hpp, crack_factors: they lose
//   their stiffness across and in shear along the crack) by rank-2 downdates
//   of the factor of K + eps M (cholmod_updown, no refactorisation), and the
//   energy released at fixed load is
//      Delta Pi = f^T (u_cracked - u_intact) / 2,   u = (K + eps M)^-1 f.
//   The first increment is the flaw (a crack one mesh size long each side:
//   the shortest the mesh resolves). The crack initiates if the next
//   increment releases at least toughness * h * (its added length) -
//   Griffith's balance G >= G_c in increments - and then grows while every
//   increment does; it stops (arrests) otherwise, or when both ends reach the
//   outline (a through crack). Of the candidates the one with the largest
//   ratio released / needed over that first growth increment is reported.
//   The crack is smeared over a band about one element wide: Delta Pi is a
//   few % to 10% high for a crack 8 elements long and converges as the mesh
//   is refined (docs/fracture.md gives the figures).

#include <span>
#include <vector>

#include "contact/fracture/response.hpp"

namespace floesim::fracture {

enum class Criterion { stress, griffith };

struct CriterionOptions {
  Criterion criterion = Criterion::stress;
  double strength = 0.5e6;  // Pa
  double toughness = 1.5;   // J/m^2
  int candidates = 5;       // griffith: cracks tried, through that many stressed nodes at most
  double region = 0.8;      // griffith: ... whose sigma_1 is at least this fraction of the largest
};

struct Initiation {
  bool initiates = false;
  double stress = 0.0;        // Pa, largest sigma_1 (at the instant judged)
  Vec2 point = Vec2::Zero();  // m, mesh frame: where
  double direction = 0.0;     // rad in [0, pi): the crack's direction from +x
  double time = 0.0;          // s into the response
  Vec2 crack_from = Vec2::Zero(), crack_to = Vec2::Zero();  // m, mesh frame
  bool through = false;       // the crack reaches the outline at both ends
  double load_factor = 0.0;   // stress: strength / sigma_1
  double energy_released = 0.0;  // J (griffith: of the reported crack)
  double energy_needed = 0.0;    // J (griffith: toughness h length of it)
  double growth_released = 0.0;  // J (griffith: by the first growth increment beyond the flaw)
  double growth_needed = 0.0;    // J (griffith: toughness h (its added length))
  int candidates = 0;            // griffith: cracks tried
  int downdates = 0;             // griffith: factor downdates (triangles removed)
};

// `polygon` is the floe's outline in the mesh's frame.
Initiation judge(Responder& responder, const Response& response, std::span<const Vec2> polygon,
                 const CriterionOptions& options);

// Energy released at fixed load f (made self-equilibrated) by cracking the
// listed triangles along `angle`, through a downdate of a copy of the
// responder's static factor. For checks against refactorisation and
// analytic crack energies.
double energy_release(Responder& responder, const Eigen::VectorXd& f, std::span<const int> triangles, double angle);

}  // namespace floesim::fracture
