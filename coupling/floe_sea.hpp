#pragma once
// Floe–sea contact by penalty (MODEL.md §4): the vertical motion of the floes
// (heave zeta, bottom slopes a = (pitch, roll)), the pressure they put on the
// sea, and the forces the sea puts back on them, vertical and horizontal.
//
// Floe i's bottom is the plane z_b(x) = zeta_i + z0_i + a_i . (x - G_i), with
// z0_i its height at floating equilibrium (so zeta = 0 at rest). On each area
// piece c of its footprint (coupling/footprint.hpp: cell c of the sea grid,
// area a_c, centroid r_c) the penetration is delta_c = eta_c - z_b(G + r_c)
// and the law (coupling/penalty_law.hpp) gives the force
//     f_c = psi_c a_c (s kappa [delta_c]^+ + (1 - s) c_i delta_c' 1[delta_c > 0]),
// up on the floe, down on the water (pressure f_c / cell area on cell c).
//
// Partly covered cells: psi_c = 1 / (1 + K (1 - Phi_c)), Phi_c the share of
// cell c covered by floes (all pieces in the cell). The sea knows one level
// per cell, eta_c; in a cell covered to the share Phi the water under the
// floe (level w_u) and the free water (w_f) share it, Phi w_u + (1 - Phi) w_f
// = eta_c. Splitting the cell's water into two levels costs the hydrostatic
// energy rho g A Phi (1 - Phi) (w_u - w_f)^2 / 2 beyond that of the mean,
// and the penalty acts on the water under the floe, kappa/2 a [w_u - z_b]^+^2.
// Minimising over the split (it is instantaneous at the grid's scale) leaves
//     V_c = kappa / 2 psi_c a_c [eta_c - z_b]^+^2,  psi = 1 / (1 + K (1 - Phi)),
// the law above. At rest on a calm sea (local static response eta = -p / (rho
// g)) every piece then carries rho g a_c d K / (1 + K) whatever its share of
// the cell, and the cell's level is Phi times the floe's depth: the floating
// depth is d (1 + 1/K) at any resolution, and the static energy of a floe
// does not depend on where it sits in the cells (no cogging; tests in
// tests/coupling/test_subcell.cpp). The energy is C^0 where an edge enters a
// cell (psi(0) = 1 / (1 + K) > 0: the hydrostatic force on a floe's side).
//
// Energy (strong part). With V = s kappa / 2 sum_c psi_c a_c [delta_c]^+^2, the
// vertical forces are exactly -dV/d(zeta, a) and -dV/d eta_c, so floes + sea
// + V + the floes' weight M g zeta is a Hamiltonian that the Strang splitting
// (half kick, exact sea flow and floe drift, half kick) conserves to O(dt^2).
// The horizontal force and torque of the strong part are -dV/dG and
// -dV/dyaw of the same discrete V: a_c, Phi_c and the first moment of piece c
// change with G through the floe's boundary in cell c (Reynolds' transport
// theorem), so with the edge pieces A -> B in the cell, N_c = ∮ n ds,
// Q_c = ∮ r n^T ds, T_c = ∮ r x n ds, S_c = ∮ r (r x n) ds, u = [delta_c]^+,
// U_c = sum over all pieces k in cell c of a_k u_k^2 and psi' = K psi^2,
//     dV/dG   = sum_c s kappa [(psi u^2 + psi' U_c / A) N_c / 2 - psi u (Q_c^T a - (a . r_c) N_c - a_c a)],
//     dV/dyaw = sum_c s kappa [(psi u^2 + psi' U_c / A) T_c / 2 - psi u a . (S_c - r_c T_c)]
// (the bottom slope a is held in the world frame). The damping (weak) part
// has no potential and no horizontal share.
//
// The damper is integrated implicitly per piece over a kick of length h,
// using the inverse mass per unit area of the floe (1 / rho_i h) and of the
// sea under one cell (measured once from the sea's response to a unit
// impulse on one cell):  f_c = a_c psi c delta' / (1 + h psi c (1/m_floe + 1/m_sea)).
// As c -> inf this removes the relative normal velocity in one kick
// (restitution 0) and never destabilises.
//
// Implicit step ([coupling] integrator = "implicit"; docs/coupling.md, "The
// implicit step"). The explicit kicks above are stable only below
// 0.5 / omega_pen, a step set by K. The implicit step instead integrates the
// floes' vertical DOFs x_i = (zeta, a) and the sea's modes together by the
// implicit midpoint rule, with the discrete gradient of the penalty energy in
// place of its force (Gonzalez 1996; Hairer, Lubich & Wanner, Geometric
// Numerical Integration, §V.5):
//     x1 - x0 = h (x0' + x1') / 2,  M (x1' - x0') = h (sum_c Phi_c f_c - M g e_z),
//     the sea: ModalBank::midpoint with the pressure f_c / A on node c,
//     f_c = c_c ([d1]^+^2 - [d0]^+^2) / (2 (d1 - d0)),  c_c = s kappa psi_c a_c
//     (the strong part; the damper's below),
// with d0, d1 the penetrations of piece c at t and t + h (both on the
// footprint at the midpoint of the step's horizontal drift). Since f_c (d1 - d0) is
// exactly the change of c_c / 2 [d]^+^2, the step conserves the floes'
// vertical energy + the weight + the sea's + V exactly, for any h and K
// (up to the solver's tolerance), opening and closing contacts included;
// it is second order where the contact is smooth. Eliminating x1 and the
// sea leaves one equation for d1 on the pieces:
//     R(d1) = d1 - d_free + G f(d0, d1) = 0,
// d_free the penetrations the step reaches with no penalty, G = G_sea + G_floe
// the penetration response to forces held over the step: G_sea applies the
// sea's midpoint response (two FFTs), G_floe = h^2 / 2 Phi M^-1 Phi^T per
// floe. Both are symmetric positive semi-definite and f is non-decreasing
// in d1, so Newton's method, J = I + G diag(f'), converges with a line
// search; each Newton step solves the symmetrised system
// (I + S G S) w = -S R, S = diag(f'^1/2), by conjugate gradients,
// preconditioned per floe by its own rigid response plus the sea's response
// on the piece's own node (Sherman–Morrison–Woodbury on the floe's 1 to 3
// DOFs). The damper (weak) part is in the same step as the impulse of
// Lambda = c [delta]^+ over it, f_c += c psi_c a_c ([d1]^+ - [d0]^+) / h (seed
// eq. 17 on the step: it only absorbs, f (d1 - d0) >= 0, and keeps f
// non-decreasing in d1).
//
// Horizontal loads of the implicit step. At a step long against the
// floe–water contact's own period (0.5 / omega_pen), the midpoint rule leaves
// that stiff mode undamped and turns it by nearly pi per step (d1 ~ -d0 in
// it): the penetrations at the step's ends carry an alternating part as large
// as the static one at K = 1000, and -dV/dG sampled there, squared and cut at
// zero, does not average it out. The step's horizontal impulse
// is instead h F_mean, F_mean = -dV/d(G, yaw) (the formulas above) on the
// step's midpoint footprint, at the midpoint slopes, with each piece's mean
// penetration over the step
//     u_k = ([d1]^+^2 - [d0]^+^2) / (2 (d1 - d0)),
// the spring's discrete gradient per unit stiffness (f_k / c_k), in which the
// alternating part cancels. The drift cannot wait for F_mean: the first half
// kick applies h/2 of the previous step's F_mean, a predictor, which leaves
// the position an error h^2 / 2 (F_mean,n+1/2 - F_mean,n-1/2) = O(h^3); the
// second half kick completes the step's impulse to h F_mean. This is
// [coupling] horizontal_loads = "step_mean"; "step_ends" keeps the loads at
// the step's ends, the exact gradient of the energy there, in the half kicks.
//
// Start (MODEL.md §1): the static problem is solved first. The sea's static
// response to a pressure is local, eta = W - p / (rho_w g) + const, W the
// surface without floes, up to capillarity (relative size sigma k^2 /
// (rho_w g) <= sigma (pi / dx)^2 / (rho_w g), reported), so on each cell
// eta_c (1 + K sum_i w_ci) = W_c + L + K sum_i w_ci z_b,i(r_ci) with
// w_ci = psi_c a_ci / cell area; each
// floe's heave and slopes solve the 3x3 equilibrium of its weight
// (Gauss–Seidel over floes sharing cells), and L is set by the zero mean of
// eta. Solved on the calm sea (W = 0) it gives each floe's reference bottom
// z0_i; solved again with W = the initial waves it puts the floes at rest on
// them: a rigid bottom cannot follow the waves' curvature, so the water under
// it is displaced instead of the floe being lifted by the penetration (which,
// at K = 1000, would hold many times the floe's weight). The sea keeps the
// waves' rates; each floe takes their least-squares plane.

#include <algorithm>
#include <functional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "core/checkpoint.hpp"
#include "core/floes.hpp"
#include "core/params.hpp"
#include "coupling/floe_sea_arrays.hpp"
#include "coupling/footprint.hpp"
#include "coupling/moving_footprint.hpp"
#include "coupling/penalty_step.hpp"
#include "coupling/shared_cells.hpp"
#include "parallel/cell_routes.hpp"

namespace floesim {

namespace fluid { class Sea; }
class IncidentSea;

class FloeSeaContact {
public:
  // Resolves the law (blend from a requested restitution through the
  // calibration table: with the implicit integrator, of the obstacle problem
  // stepped at dt_max on the floes' median draft), measures the sea's local
  // inverse mass, and prepares the floes' vertical inertia. Precondition:
  // footprint "tent" only on a periodic sea (checked at load, core/config.cpp).
  FloeSeaContact(const CouplingParams& params, const SeaParams& sea_params, const Floes& floes, fluid::Sea& sea,
                 double dt_max);

  // Puts the floes at rest on the sea (the static problem above), then adds
  // the sea's present waves; or (start = "given") keeps the floes' heave as given.
  void start(Floes& floes, fluid::Sea& sea, bool given);

  // The loads cache: this class alone knows whether its loads still hold.
  // One evaluation of the contact gives the loads on the floes, the pressure
  // on the sea (and whether the sea was already kicked with it) and the
  // incident waves' velocity under each floe (for drag). An evaluation at
  // the end of a step (evaluate_loads) serves its second half kicks and,
  // unless it went stale, the first half kick of the next step (ready_loads).
  // It goes stale when the floes change (a split: floes_changed), when the
  // kick it served changed the rates it depends on (the explicit damper),
  // or, for the explicit damper, when the kick length changes.
  //
  // With the implicit integrator the vertical law and the weight are left out
  // of the pressure and the vertical loads (advance_vertical applies them);
  // the horizontal forces and the penalty energy are the same.
  //
  // The kick by its holders (docs/parallel.md, "The kick by owner
  // (kick29)"). On several ranks `kicked` marks, per floe, the floes this
  // rank kicks (1; empty: every floe), which are the floes it holds
  // (Simulation::held_now, with the state held by owner). A floe's loads
  // are computed by its coupling owner (MovingFootprints::owners) alone and
  // travel from it to the other ranks that kick the floe only (share_owned).
  // Why every holder kicks, not the drift's owner alone: between the
  // second half kick and the next drift's exchange (which sends each
  // owner's state to the floe's holders) two readers take a held copy's
  // kicked rates on a rank that does not drift the floe:
  //  - the step's start copy (Simulation::choose_dt copies every state
  //    before the first half kick): the collisions of the band read its
  //    rates (contact/step_collisions.cpp, smooth_kick: the arm velocity at
  //    the step's start of both floes of a contact), and no exchange sends
  //    it (the detection's leave notices carry it for the floes changing
  //    owner only);
  //  - the explicit damper's evaluation at the first half kick (s < 1) on
  //    the coupling owner (which need not drift the floe), which reads its
  //    floes' vertical rates.
  // An unheld copy is stale and read by no one (the poison mode's check):
  // it is not kicked, and its loads do not travel. With the implicit step
  // (every rank holds every floe's vertical DOFs; the first half kick's
  // impulse, kicks_.first_half, is read by the second on a rank whose held
  // set the detection between them changed) `kicked` is not used: every
  // floe's loads go to every rank and every rank kicks every floe.
  // `kickers_moved` (the same on every rank): the loads are current but the
  // holders changed since they travelled (a rejected try, whose drift gave
  // its owners floes): they travel again, without a new evaluation.
  void evaluate_loads(const Floes& floes, fluid::Sea& sea, IncidentSea* incident, double h,
                      std::span<const std::uint8_t> kicked = {});
  void ready_loads(const Floes& floes, fluid::Sea& sea, IncidentSea* incident, double h,
                   std::span<const std::uint8_t> kicked = {}, bool kickers_moved = false);
  // Apply the loads over h: to the floes' vertical and horizontal rates (of
  // the floes `kicked` marks, as given to the evaluation or ready_loads
  // that made the loads; empty: every floe); to
  // the sea's modal velocities (a second kick_sea with the same evaluation
  // repeats the sea's last kick, without projecting the pressure again:
  // nothing else may kick the sea in between).
  void kick_floes(Floes& floes, double h, std::span<const std::uint8_t> kicked = {});
  void kick_sea(fluid::Sea& sea, double h);
  // The incident waves' orbital velocity under each floe (m/s, world), the
  // mean over its footprint, at the time of the loads' evaluation. On
  // several ranks, of this rank's floes (MovingFootprints::mine) only, until
  // hand_water_over gives each floe's to the rank that drifts it.
  std::span<const Vec2> water_velocity() const { return evaluated_.water; }
  // On several ranks: the water velocity of each floe whose coupling owner
  // (MovingFootprints::owners) is not drift_owner[i] goes from the first to
  // the second (one all-to-all, none when the owners agree; collective).
  // After it water_velocity() holds the floes this rank drifts. The drift is
  // its only reader (docs/parallel.md, "The coupling by owner"). On a sea
  // not in slabs with dims = 2, drift_owner also becomes the coupling's
  // owners from the next rebuild on (next_owners_).
  void hand_water_over(std::span<const int> drift_owner);
  // On several ranks, for the next evaluation only: the drift's owners by
  // place (parallel::FloeOwners with the sea's slabs first_row), assigned
  // at the floes' present places, every floe's owner and this rank's floes
  // (`mine`). A rebuild of the footprints on those slabs takes them as the
  // coupling's owners (MovingFootprints::takes_owners: the same rule, the
  // row of the centroid, so the same owners) and poses this rank's floes
  // only, instead of posing every floe to find its owner. The spans must
  // stay valid until the evaluation.
  void take_place_owners(std::span<const int> owner, std::span<const std::uint32_t> mine,
                         std::span<const int> first_row) {
    place_owner_ = owner;
    place_mine_ = mine;
    place_rows_ = first_row;
  }

  // Implicit integrator: advances the floes' vertical DOFs and the sea over h
  // (the floes' horizontal positions already at t + h, `start` the floes at
  // t, their vertical DOFs and the sea at t), on the footprint at the
  // midpoint of the horizontal motion. Explicit: the floes' vertical drift
  // and the sea's free flow, of the floes `held` marks (per floe, 1: this
  // rank holds it; empty: every floe; the other copies are left stale).
  // Throws RunError if the Newton iteration does not converge.
  void advance_vertical(Floes& floes, std::span<const FloeState> start, fluid::Sea& sea, double h,
                        std::span<const std::uint8_t> held = {});
  bool implicit() const { return implicit_; }
  // On several ranks: the floes this rank owns for the coupling (whose
  // pieces it built at the footprints' last rebuild and moves), ascending;
  // on a sea not in slabs also those it owns from the next rebuild on
  // (next_owners_), which it must hold (pose, and drift vertically) until
  // then, from the drift's exchange that sends them their states on.
  std::span<const std::uint32_t> own_floes() const {
    const NextOwners& next = next_owners_;
    return next.owner.empty() || !next.current ? footprints_.mine() : std::span<const std::uint32_t>(next.held);
  }
  // On a sea not in slabs, on several ranks: every floe's coupling owner
  // from the next rebuild on (next_owners_; the same on every rank), to
  // which the drift's exchange sends its state (empty: none known yet).
  std::span<const int> next_floe_owners() const { return next_owners_.owner; }
  // On several ranks: every floe's coupling owner (the same on every rank;
  // empty before the first placement).
  std::span<const int> floe_owners() const { return footprints_.owners(); }
  // Threads for the per-floe and per-piece work (results do not depend on it).
  void set_threads(int threads) { threads_ = std::max(threads, 1); }
  // Ranks that share the per-floe work (docs/parallel.md, stages two and
  // three). Each rank builds its floes' footprints (MovingFootprints::mine)
  // and computes their horizontal loads and water velocities; the other
  // ranks receive them.
  // With the explicit kicks each rank also runs the law on its own floes'
  // pieces and sums them into the cells (by_owner()), in the serial run's
  // order of the floes (order_by_owner). When the sea is in slabs
  // (fluid::Sea::slab_rows; stages five and eight) the floes are owned by
  // place (the rank whose slab holds the row of a floe's centroid at the
  // footprints' last rebuild: MovingFootprints::set_slabs), and each cell
  // the pieces of several ranks' floes may share is summed from the pieces
  // themselves, in the serial order (parallel::CellRoutes with the floes'
  // serial keys, serial_key), by every rank that needs it: the ranks whose
  // floes' boxes cover it and the rank whose slab holds its row (without
  // the boxes, by the slab's rank, which sends the coverage and the sums
  // back to the ranks with pieces there); a
  // cell deeper in a slab than any floe of another rank reaches, or under
  // no other rank's floe's box of cells (parallel::CellBox, sent by its
  // owner to the ranks that may share its cells), is summed by the rank whose floes lie there alone,
  // which sends only the pressure's total to the cell's slab's rank. Every cell's sums are then the serial
  // run's to the bit, whichever rank owns which floe. pressure() then holds
  // this rank's slab's rows only, which is what its sea's kick reads. A sea
  // not in slabs (BEM seas, a tank, dims = 1) is whole on every rank, whose
  // kick reads every cell's pressure: its floes are owned by place (the
  // drift's owners; in a flume, shares of its columns: next_owners_), and
  // the same routes make every cell's sums on every rank
  // (parallel::CellRoutes::replicated: a cell under another rank's floe's
  // box as pieces to every rank, any other cell's pressure as its total),
  // the serial sums to the bit too. The implicit step runs by owner on a
  // sea in slabs too (implicit_step: each rank its floes' pieces, the
  // products through cell_product); on a sea whole on every rank it stays
  // replicated on every floe's pieces (gathered), to the bit, its floes
  // posed and built by the drift's owners (next_owners_). Every
  // rank calls every method in the same order (they may exchange data).
  void set_communicator(const parallel::Communicator& comm) {
    comm_ = comm;
    footprints_.set_communicator(comm);
    footprints_.set_gather(!by_owner());
    const bool slabs = by_owner() && !slab_rows_.empty();
    const auto nx = static_cast<std::size_t>(grid_.nx), ny = static_cast<std::size_t>(grid_.ny);
    routes_ = slabs         ? parallel::CellRoutes(slab_rows_, nx)
              : by_owner() ? parallel::CellRoutes::replicated(comm.size(), nx, ny)
                           : parallel::CellRoutes();
    footprints_.set_slabs(slabs ? slab_rows_ : std::vector<int>{});
    owner_.interior_reach = -1;  // the interior cells are those of the new routes
    set_place_owners();
  }
  // The sea's slabs moved (issue 21 stage seven; first_row as
  // fluid::Sea::slab_rows gives it, the same on every rank, at the start of
  // a step, after the last evaluation's pressure was kicked): the cells'
  // routes go to the new slabs' ranks, and the pressure this rank summed for
  // its old slab's cells is cleared (the next evaluation writes its new
  // slab's). The floes' owners follow the slabs from the footprints' next
  // rebuild (MovingFootprints::set_sea_slabs; until then their pieces'
  // reach in rows grows by the move): the sums being the serial ones
  // whatever the owners (stage eight), the answer does not depend on the
  // timings that moved the slabs.
  void set_slabs(std::vector<int> first_row);
  struct ImplicitStats {
    long steps = 0, newton = 0, cg = 0, g_products = 0;  // totals over the run
    double last_residual = 0.0;  // m, the last step's largest piece residual
  };
  const ImplicitStats& implicit_stats() const { return implicit_stats_; }

  // Stable kick length of the explicit spring part (s > 0): 0.5 / omega_pen,
  // omega_pen^2 = s kappa (1 / m_floe + 1 / m_sea) (a quarter of leapfrog's
  // linear limit 2 / omega; the contact is not linear, see floe_sea.cpp).
  double stable_step() const { return stable_step_; }

  // Energies (J): the penalty spring's at the last evaluate(), and (below)
  // each floe's vertical kinetic and weight (M g zeta) energies at the
  // present state. By owner with the sea in slabs the first call after an evaluation is
  // collective (every rank's terms gathered and summed in the serial order:
  // settle_energy).
  double penalty_energy() const {
    if (energy_pending_) settle_energy();
    return penalty_energy_;
  }
  // Floe i's terms of the floes' vertical kinetic energy (heave, pitch and
  // roll rates) and of their weight energy M g zeta (0 for a floe the sea
  // does not move): the caller sums them exactly over the floes it owns
  // (Simulation::energies), so the sums do not depend on the ranks.
  double vertical_kinetic(const Floes& floes, std::size_t i) const;
  double weight_energy(const Floes& floes, std::size_t i) const;

  // Height of floe i's bottom at its centroid, z_b(G) = zeta + z0 (m).
  double bottom(const Floes& floes, std::size_t i) const { return floes.state[i].heave + constants_.bottom0[i]; }
  // Evaluated by owner (above), this rank's floes' pieces only.
  const Footprints& footprints() const { return footprints_.pieces(); }
  // Placements of the footprints and how many of them were rebuilds
  // (coupling/moving_footprint.hpp; [coupling] footprint_reach).
  long footprint_placements() const { return footprints_.placements(); }
  long footprint_rebuilds() const { return footprints_.rebuilds(); }
  // By owner with the sea in slabs: the slabs (first rows) the floes' owners
  // were set by at the footprints' last rebuild (empty otherwise).
  std::span<const int> owner_slabs() const {
    return in_slabs() ? footprints_.owner_slabs() : std::span<const int>{};
  }
  // On several ranks: the calling thread's CPU time (s, parallel::
  // thread_seconds) in this rank's per-floe work since the last take: its
  // floes' footprints built and moved, the law on their area pieces, their
  // edge pieces' horizontal loads and their incident water velocity. Not
  // the cells' sums and exchanges (per cell, or waits that may spin). The
  // load balance charges it to the floes' owners by place
  // (parallel::FloeOwners::charge_coupling; docs/parallel.md, "The
  // coupling's cost"). With the implicit step (the law replicated) only the
  // footprints are.
  double take_owned_seconds() { return std::exchange(owned_seconds_, 0.0) + footprints_.take_owned_seconds(); }
  // By owner with the sea in slabs, this rank's cells outside its slab's
  // interior since the start, per evaluation summed: those sent as pieces
  // (shared with another rank's floes, or possibly: their boxes meet), and
  // those summed here alone, owned here or by another rank (then sent as
  // the pressure's total). With the boxes (boxed()), the floes' boxes this
  // rank sent and received (order_by_owner: to the ranks that read them).
  struct RoutedCells {
    long shared = 0, pieces = 0, alone_here = 0, alone_sent = 0;
    long boxes_sent = 0, boxes_received = 0;
  };
  const RoutedCells& routed_cells() const { return owner_.routed_counts; }

  // The pieces' values through the sea's cells and back: the communication
  // of the implicit step's product G_sea u (docs/parallel.md, "The products'
  // routes (answer30)"), on the footprints of the last evaluation. Each
  // cell's value is sum_k scale u[k] over the pieces k in it, from zero, the
  // floes in the coverage's serial order (order_: by first cell), each
  // floe's pieces in order; respond(first_row, cells, response) then maps
  // the cells' values to the sea's response on the rows this rank holds:
  // `cells` and `response` are rows [first_row, first_row + rows) of the grid
  // (x fastest; `response` to be filled); out[k] = the response at piece
  // k's cell. u and out: one value a piece of footprints().
  // - By owner on a sea in slabs (the implicit step's products and free
  //   elevation; scatter_to_slab alone for its midpoint_step): this rank's pieces;
  //   a cell summed here alone (its pieces all this rank's) adds them
  //   here, one of another slab then sent to its rank as the total; a
  //   shared cell's pieces travel to the ranks the coverage's open named
  //   (CellRoutes::add, 8 bytes a piece), each summing them from zero in key
  //   order (the floes' serial positions): the serial sum. The routes are the
  //   coverage's (opened once an evaluation); the response at the cells
  //   this rank's pieces read in other slabs comes back from their ranks
  //   (CellRoutes::answer, 8 bytes a cell). Two all-to-alls; collective.
  // - Otherwise (serially, or every floe's pieces on every rank): the whole
  //   grid here, first_row = 0. A sea by owner not in slabs: not supported
  //   (its cells have no one owner to respond).
  // Every value out[k] is then the serial run's to the bit: the same sums
  // in the same order, and the response of each cell from its one owner.
  using SlabResponse = std::function<void(int first_row, std::span<const double> cells, std::span<double> response)>;
  void cell_product(std::span<const double> u, double scale, const SlabResponse& respond, std::span<double> out);
  // cell_product's calls since the start and the bytes this rank received
  // from the others in them: the pieces and alone totals to the cells'
  // summing ranks (scatter), the responses back (answer).
  struct CellProductStats {
    long products = 0;
    long long scatter_bytes = 0, answer_bytes = 0;
  };
  const CellProductStats& cell_product_stats() const { return product_.stats; }
  // On several ranks, the loads' travels since the start (share_owned):
  // to the ranks that kick each floe (`asked`: the calls; `asked_floes`:
  // the floes' loads this rank received) and to every rank (`whole`,
  // `whole_floes`: the start, a restore, the implicit step, the advance
  // from the whole detection).
  struct SharedLoads {
    long asked = 0, asked_floes = 0, whole = 0, whole_floes = 0;
  };
  const SharedLoads& shared_loads() const { return shared_loads_; }
  std::span<const FloeSeaLoad> loads() const { return kicks_.loads; }
  std::span<const double> pressure() const { return pressure_; }
  double strong_share() const { return s_; }
  double kappa() const { return kappa_; }
  // Notes for the user (calibrated share, capillarity neglected at the start).
  const std::vector<std::string>& notes() const { return notes_; }
  // Floes whose contact rebuilt data must be redone (after a split). On
  // several ranks after a split, `owner` is every floe's owner by place
  // (parallel::FloeOwners after place_pieces and migrate; the same on every
  // rank), each of which holds its floes' whole states current: on a sea not
  // in slabs and with the implicit step they become the next rebuild's
  // owners (next_owners_, held), so that it poses each rank's floes only
  // (on a sea in slabs the first half kick offers the same owners,
  // take_place_owners). Empty (the start, a restore, serially): the next
  // rebuild finds its owners from every floe's pose.
  void floes_changed(const Floes& floes, std::span<const int> owner = {});

  // What the coupling allocates per floe on this rank, against the held
  // floes' entries (core/floe_bytes.hpp; `held` empty: every floe): its
  // arrays of one entry a floe (its groups, coupling/floe_sea_arrays.hpp:
  // the constants it derives, the kicks' loads, the poses, water velocities
  // and slopes, the implicit step's, the boxes this rank has
  // (owner_.places); and the next owners), and the footprints'
  // (MovingFootprints::memory). Not counted: the per-cell arrays (the sea's
  // grid, not the floes), the per-piece scratch of one evaluation and the
  // lists of floes (order_, owner_.near and known, next_owners_.mine and held).
  struct Memory {
    FloeBytes per_floe;
    MovingFootprints::Memory footprints;
  };
  Memory memory(std::span<const std::uint8_t> held) const;

  // Restart (core/checkpoint.hpp): what this class carries from one step to
  // the next beyond the floes and the sea. restore() takes the floes and the
  // sea (and incident waves) already restored, and evaluates the loads cache
  // again from them when it held: the loads depend on positions, the
  // vertical DOFs and the elevation, which the end-of-step kicks leave as
  // they were, so they come out the same to the bit.
  FloeSeaState saved_state() const;
  void restore(const FloeSeaState& state, const Floes& floes, fluid::Sea& sea, IncidentSea* incident);

private:
  double weak_coefficient(const Floes& floes, std::size_t i) const;
  // psi(Phi) = 1 / (1 + K (1 - Phi)): the sub-cell weight of a cell covered
  // to the share Phi (the header's "Partly covered cells").
  double subcell_weight(double coverage) const;
  // Floe i's tilt inertia in the world frame, the floe turned by `yaw`
  // (its present yaw when not given).
  Eigen::Matrix2d tilt_inertia(const Floes& floes, std::size_t i) const {
    return tilt_inertia(floes, i, floes.state[i].yaw);
  }
  Eigen::Matrix2d tilt_inertia(const Floes& floes, std::size_t i, double yaw) const;
  // Clears the cells of the present footprints, places them with floe i at
  // evaluated_.poses[i] (moved if `move`, MovingFootprints::movable's verdict, else
  // rebuilt: coupling/moving_footprint.hpp) and sums the cells' coverage
  // (cells_[c].coverage).
  // With `owners` given by place (take_place_owners), a rebuild takes them.
  void place_footprints(const Floes& floes, bool move, std::span<const int> owners = {});
  // Zeroes pressure_ and cells_ where the present footprints lie.
  void clear_footprint_cells();
  // The contact is evaluated by owner: several ranks, with the explicit
  // kicks on any sea, with the implicit step on a sea in slabs (spectral,
  // dims = 2, no tank: slab_rows_ not empty). The implicit step on a sea
  // whole on every rank (BEM, a tank, dims = 1) solves every floe's pieces
  // on every rank (implicit_whole()).
  bool by_owner() const { return !comm_.serial() && (!implicit_ || !slab_rows_.empty()); }
  bool implicit_whole() const { return implicit_ && !by_owner(); }
  // The footprints' version: it changes whenever the pieces do, at a
  // placement (moved or rebuilt) or a rebuild without one (the start, a
  // restore).
  long footprint_version() const { return footprints_.placements() + footprints_.rebuilds(); }
  // The cells' sums by owner go through routes_ (by owner, always): to the
  // slabs' ranks on a sea in slabs (in_slabs()), to every rank on a sea
  // whole on every rank.
  bool routed() const { return !routes_.empty(); }
  bool in_slabs() const { return routed() && !routes_.replicated(); }
  // Routed, whether the floes' boxes (parallel::CellBox) tell each rank
  // which of its cells no other rank's floe may share: on grids of at most
  // CellBox::kMaxSide rows and columns; else every cell outside the slabs'
  // interiors goes as pieces.
  bool boxed() const {
    return routed() && grid_.nx <= parallel::CellBox::kMaxSide && grid_.ny <= parallel::CellBox::kMaxSide;
  }
  // Whether every rank that needs a shared cell's totals sums its pieces
  // itself (CellRoutes::open_shared, nothing sent back): with the boxes,
  // and always on a sea whole on every rank (every rank needs every cell's
  // pressure); else the slab's rank sums and replies (open, reply).
  bool one_round() const { return routes_.replicated() || boxed(); }
  // By owner (floe_sea_owners.cpp): zeroes pressure_ and cells_ where the
  // last evaluation by owner wrote them.
  void clear_cells_by_owner();
  // By owner (floe_sea_owners.cpp): this rank's pieces' coverage into
  // cells_[c].coverage of this rank's cells (cells_ is zero in the others):
  // every rank's pieces of a shared cell summed in the serial order by each
  // rank that needs it (in slabs without the boxes, by the cell's slab's
  // rank).
  void sum_coverage_by_owner();
  // By owner, after the law (eval_: penetrations u, weights psi, forces):
  // this rank's pieces' a u^2 and pressure in its cells and its part of the
  // penalty energy ks psi a u^2 / 2, in one pass; then, summed over the
  // ranks as the coverage is, into pressure_ (the cells of this rank's
  // slab; every cell not in slabs) and cells_[c].sum (this rank's cells);
  // returns the energy, the ranks' parts summed in rank order (until
  // settle_energy sums the terms in the serial order).
  double sum_cells_by_owner(double ks);
  // By owner: order_ <- this rank's floes in the serial order (serial_key,
  // from its own pieces), and with the boxes (boxed()) each of its floes'
  // box sent to the ranks that may have pieces in its cells (owner_.near on
  // them; docs/parallel.md, "The boxes by holder (boxes30)"): with slabs,
  // the ranks box_readers names; not in slabs, the ranks whose box of all
  // their pieces' cells (gathered, 12 B a rank) it meets. In a flume not in
  // slabs, every floe's share of columns to every rank (next_owners_).
  void order_by_owner(std::size_t floes);
  // next_owners_ for the routes (on replicated routes, in a flume, the
  // columns' shares); the floes' next owners forgotten.
  void set_place_owners();
  // By owner: the penalty energy from every rank's terms
  // (owner_.energy_*), summed in the serial order (one gather).
  void settle_energy() const;
  // evaluated_.poses <- the floes' present poses: every floe's, or those of `which`
  // (the others' entries are left as they were, and not read).
  void pose_at_states(const Floes& floes);
  void pose_at_states(const Floes& floes, std::span<const std::uint32_t> which);
  // The contact at the present state for a kick of length h (see evaluate_loads).
  void evaluate(const Floes& floes, fluid::Sea& sea, double h);
  // kicks_.loads[i].horizontal = -dV/dG, -dV/dyaw (the header's formulas) for the
  // pieces' [delta]^+ u, with eval_.psi, evaluated_.wetted, cells_[c].sum and
  // evaluated_.slope already set for them.
  // On several ranks, for this rank's floes only (share_owned completes them).
  void horizontal_loads(std::span<const double> u);
  // The owners' loads (horizontal and vertical, 48 B a floe) to the ranks
  // that kick each floe (`kicked` on each: the floes it asks its coupling
  // owner for; two all-to-alls: the requests, then the loads), or with
  // `kicked` empty or the implicit step, to every rank (one call). Nothing
  // when serial.
  void share_owned(std::span<const std::uint8_t> kicked = {});
  // Implicit: the step's mean horizontal loads (the header's "Horizontal
  // loads of the implicit step") into kicks_.step_horizontal.
  void step_mean_horizontal(const Floes& floes, std::span<const FloeState> start);
  // Mean over each floe's footprint (weights a_c) of the incident waves'
  // velocity at the sea's time (zero without incident waves).
  // On several ranks, for this rank's floes only (hand_water_over gives
  // them to the ranks that drift them).
  void update_water(const fluid::Sea& sea, IncidentSea* incident);
  void implicit_step(Floes& floes, std::span<const FloeState> start, fluid::Sea& sea, double h);
  // The static start's pressure, held by a sea with a static part (a
  // truncated BEM sea's correction): p = rho g (W - eta), W the waves.
  void hold_static_pressure(fluid::Sea& sea, std::span<const double> waves, std::span<const double> eta);
  // Footprints (and coverage) at the midpoint of each floe's horizontal
  // motion from `start` to its present position. The floes posed are those
  // the placement reads (evaluate()'s rule): the footprints' own floes for
  // a move, the given owners' for a rebuild with owners (given_owners),
  // every floe only for a rebuild by index.
  void place_midpoint_footprints(const Floes& floes, std::span<const FloeState> start);
  // evaluated_.poses[i] <- floe i's pose at the midpoint from start[i] to its present
  // place, for i in `which` (a static floe's: its present place).
  void pose_at_midpoint(const Floes& floes, std::span<const FloeState> start, std::span<const std::uint32_t> which);
  // On several ranks: the present yaw of each floe of order_ that resists a
  // slope (constants_.tilt > 0; its tilt inertia turns with it), from its coupling
  // owner, which holds it (the other ranks' copies of its horizontal state
  // may be stale: the halo exchange), into implicit_floes_.yaw (per floe; the others'
  // entries are not read). One gather, 8 B a tilted floe.
  void gather_tilted_yaw(const Floes& floes);
  // The sea's part of the implicit step's operator: out = G_sea u on the
  // pieces (coupling/penalty_step.hpp).
  void sea_response(fluid::Sea& sea, double h, std::span<const double> u, std::span<double> out);
  // By owner on a sea in slabs, the first half of cell_product: grid_work_
  // <- on this rank's slab rows, each cell's sum_k scale u[k] over every
  // rank's pieces in it (the serial sum); scatter_clear() zeroes what it
  // wrote (grid_work_ is zero between products). Collective.
  void scatter_to_slab(std::span<const double> u, double scale);
  void scatter_clear();
  // By owner, after the solve: every floe's vertical DOFs (heave, pitch,
  // roll and their rates, 48 B a floe) from its coupling owner to every
  // rank, which holds them all as the whole path does (the poison mode's
  // hold_vertical). One all-gather.
  void share_vertical(Floes& floes) const;
  // grid_work_ <- the pressures u_k / cell area of the pieces, each cell's
  // summed from zero in the coverage's serial order (order_, each floe's
  // pieces in their order: the cells' sums of the explicit step), so that
  // a cell's bits do not depend on the floes' indices (docs/parallel.md,
  // "The implicit step's serial rules (impl30)"). grid_work_ is zero on entry.
  void pressure_of_pieces(std::span<const double> u);

  FootprintKernel kernel_ = FootprintKernel::cell;
  double rho_ = 1025.0, g_ = 9.81, sigma_ = 0.0, K_ = 1000.0, s_ = 1.0, kappa_ = 0.0;
  fluid::SurfaceGrid grid_;
  double sea_inverse_mass_ = 0.0;  // 1 / m_sea: eta' per unit pressure impulse on one cell (m^2 s / kg... per Pa s)
  double stable_step_ = 0.0;
  double cell_area_ = 1.0;
  // The arrays of one entry a floe, in groups of one life (coupling/
  // floe_sea_arrays.hpp: each group sized and counted as one). Sized with
  // the floes (floes_changed): the floes' constants; the loads the kicks
  // apply (zeroed there); what an evaluation poses and finds per floe.
  // Sized at each implicit step: the implicit step's (empty with the
  // explicit kicks). By owner, the serial places: owner_.places.
  FloeSeaConstants constants_;
  FloeSeaKicks kicks_;
  FloeSeaEvaluated evaluated_;
  FloeSeaImplicit implicit_floes_;
  double free_level_ = 0.0;                 // the calm sea's free level (m; eta has zero mean)
  MovingFootprints footprints_;
  // take_place_owners' owners, for the next evaluation (empty: none given).
  std::span<const int> place_owner_, place_rows_;
  std::span<const std::uint32_t> place_mine_;
  std::vector<double> pressure_;
  struct CellSums {
    double coverage = 0.0;  // Phi_c: the share of cell c under floes
    double sum = 0.0;       // sum over the pieces in cell c of a_k [delta_k]^+^2
  };
  std::vector<CellSums> cells_;
  // The contact by owner: the cells of this rank's pieces that travel as
  // pieces. The next evaluation clears pressure_ where the routes put it
  // and in this rank's pieces' cells, cells_ in the latter.
  struct OwnerCells {
    std::vector<std::uint32_t> slot;   // per grid cell: 1 + its index in `cells`, 0: none of this rank's pieces
    std::vector<std::uint32_t> cells;  // this rank's cells sent as pieces, in the order its pieces meet them
    std::vector<double> coverage, sum;  // per cell of `cells`: the totals sent back (in slabs without the boxes)
    // Per grid cell, what kind (CellKind): deep in its slab (every
    // row within `interior_reach` rows is the slab's), where only the slab's
    // rank has pieces; else, during sum_coverage_by_owner, whether another
    // rank's floe's box covers it (shared: its pieces are routed), and
    // whether it is in `alone`. A cell with this rank's pieces that is not
    // shared is summed into cells_ and pressure_ directly (`cells` and
    // routed_pieces hold the others); `alone` lists those of them
    // another rank owns, whose pressure goes to the owner as a total
    // (alone_totals); and the parts sent, per cell of `cells`.
    enum CellKind : std::uint8_t { kRoutedRow = 0, kInteriorRow = 1, kShared = 2, kAloneListed = 3 };
    std::vector<std::uint8_t> kind, interior_row;
    int interior_reach = -1;
    std::vector<double> parts;
    std::vector<std::uint32_t> alone;
    // marks.painted: the cells whose kind is not their row's. With the boxes
    // (boxed()), during sum_coverage_by_owner: marks.shared_at, per grid
    // cell 1 + its index among the shared cells (0: not shared), and
    // marks.shared_ranks, per shared cell the ranks whose floes' boxes cover
    // it (`rank_words` 64-bit words of bits; coupling/shared_cells.hpp); per
    // cell of `cells`, the ranks that sum it (receivers_first into
    // receivers: those ranks, the cell's slab's rank and this one).
    SharedMarks marks;
    std::vector<std::uint32_t> receivers_first;
    std::vector<int> receivers;
    std::vector<double> alone_totals;
    // The boxes this rank has (order_by_owner): per floe the box of its
    // pieces' cells (a group of one entry a floe), set for this rank's
    // floes of order_ and the floes in `near`, whose boxes their owners
    // sent here because they may cover a cell of this rank's pieces (the
    // others' entries empty); `known`, the floes whose entries are set.
    // With slabs, row_owner: per row, its rank in the owners' slabs
    // (footprints_.owner_slabs(), kept in owner_slabs); not in slabs,
    // rank_box: per rank, the box of all its pieces' cells.
    FloeSeaSerialPlaces places;
    std::vector<std::uint32_t> near, known;
    std::vector<int> row_owner, owner_slabs;
    std::vector<parallel::CellBox> rank_box;
    // Routed: the pieces of the cells of `cells` grouped by cell (cell j's
    // are [first[j], first[j + 1])), each with its floe's serial key (keys)
    // and its coverage (values).
    std::vector<std::uint32_t> first;
    std::vector<parallel::PieceKey> keys;
    std::vector<double> values;
    // Routed: the pieces of the cells of `cells` in order_'s order (the
    // pieces' loops meet them so), each with its index among the
    // footprints' pieces, its floe's serial key, its cell's index in `cells`
    // and its place among the pieces grouped by cell.
    struct RoutedPiece {
      parallel::PieceKey key;
      std::uint32_t piece, cell, at;
    };
    std::vector<RoutedPiece> routed_pieces;
    // Routed: this rank's terms of the penalty energy, per floe with terms
    // (its serial key and count), in order_.
    std::vector<parallel::PieceKey> energy_keys;
    std::vector<std::uint32_t> energy_counts;
    std::vector<double> energy_terms;
    RoutedCells routed_counts;  // since the start, this rank's
    // The footprints' placements and rebuilds when the routes were opened
    // (any new pieces change the count; footprint_version()).
    long routes_footprints = -1;
  } owner_;
  // cell_product's scratch (the routed pieces' values, the alone cells'
  // totals, the answers per cell of owner_.cells and owner_.alone) and counts.
  struct ProductScratch {
    std::vector<double> parts, alone_totals, cells_answer, alone_answer;
    CellProductStats stats;
  } product_;
  static constexpr std::uint32_t kNoCell = parallel::CellBox::kNone;
  // The coupling's owners by place on a sea not in slabs (routes_.
  // replicated(); docs/parallel.md, "The seas not in slabs, their floes by
  // place"), so that a cell holds pieces of several ranks' floes only near
  // the parts' boundaries, not wherever the floes are dense (by index):
  // - dims = 2 (a BEM sea, a tank): the drift's owners (parallel::
  //   FloeOwners, strips in y), which Simulation gives every step
  //   (hand_water_over). A new owner then holds the floe (its band or its
  //   own: Simulation::held_now), and the water's hand-over has only the
  //   floes that changed owner since to hand.
  // - dims = 1 (a flume): the drift's strips in y would give each rank
  //   floes along the whole sea, whose cells span its width; instead the
  //   grid's columns are cut in `ranks` equal shares (parallel::share) and
  //   rank r owns the floes whose centroid's column (periodic: wrapped;
  //   walled: clamped) lies in its share. Each owner finds the share of its
  //   own floes at every evaluation (from their poses, which it reads
  //   anyway) and sends it with the boxes' gather (order_by_owner: 4 bytes
  //   a floe more). A rank holds the floes of its share (own_floes(), in
  //   held_now) from the next drift's exchange on, which sends each floe's
  //   state to its next owner (next_floe_owners: its band need not hold
  //   them in a flume wider than the floes' reach).
  // - the implicit step (every sea: it is whole on every rank): the
  //   drift's owners too, whatever the sea's dims. Its footprints are
  //   gathered to every rank and its solve replicated, so the owners
  //   choose only who poses and builds each floe's pieces: a rank that
  //   holds the floe.
  // The next rebuild after a vertical drift (advance_vertical) takes them:
  // a new owner's copy of a floe is current after the drift's exchange and
  // the vertical drift of the floes it holds (with the implicit step after
  // the drift's exchange: every rank's copy of every floe's vertical DOFs
  // is current, kick_floes); an evaluation before it (a
  // first half kick) keeps the last rebuild's owners (given_owners). Until
  // the first (the start, a restart, a split), the owners are by index.
  struct NextOwners {
    std::vector<int> column;  // dims = 1: per grid column, its share's rank (empty: the drift's owners)
    std::vector<int> owner;   // per floe: the next rebuild's owner (empty: none yet)
    std::vector<std::uint32_t> mine;  // this rank's floes in `owner`, ascending
    std::vector<std::uint32_t> held;  // own_floes() once `current`: the footprints' mine() and `mine`
    // A drift's exchange since `owner` was set, which sent each floe's state
    // to its next owner (hand_water_over, before it): until then a new
    // owner's copy is stale and own_floes() is the footprints' mine() alone.
    bool current = false;
    bool drifted = false;     // a vertical drift since `owner` was set
  } next_owners_;
  // next_owners_ from every floe's next owner.
  void set_next_owners(std::span<const int> owner);
  // dims = 1: the rank of the share of columns that holds a floe at pose p.
  int column_owner(const FloePose& p) const;
  // The owners a rebuild of this evaluation takes, and this rank's floes
  // among them (empty: none given, the footprints find them). The spans
  // stay valid until the rebuild. Called only before a rebuild: when they
  // are the last rebuild's, it tells the footprints to keep them
  // (MovingFootprints::keep_owners) and returns their own arrays.
  struct GivenOwners {
    std::span<const int> owner;
    std::span<const std::uint32_t> mine;
  };
  GivenOwners given_owners(std::size_t floes);
  // The sea's slabs (fluid::Sea::slab_rows; empty: whole on every rank), and
  // by owner on them, the routes of the cells' sums to the slabs' ranks;
  // the next evaluation clears pressure_ in routes_.owned() (the cells the
  // last one received pieces of: its slab's, where it wrote the pressure,
  // and with the boxes other slabs' shared cells, where pressure_ is zero)
  // and cells_ in owner_.cells.
  std::vector<int> slab_rows_;
  std::vector<int> first_slab_rows_;  // the slabs at set-up (the incident sea's, which do not move)
  parallel::CellRoutes routes_;
  std::vector<std::uint32_t> order_;  // dynamic floes with pieces (by owner: this rank's), by serial_key
  // The serial order of the floes in the cells' sums: by the first cell of
  // their pieces, ties broken by floe index (a total order, so a key each
  // floe's owner computes alone, from its own pieces: no rank needs the
  // other floes' first cells to place its own among them). As one number,
  // first cell x floes + index (below cells x floes: 4 bytes on the wire
  // when that is at most 2^32, CellRoutes::set_largest_key). Floe i has
  // pieces.
  parallel::PieceKey serial_key(std::uint32_t i) const {
    const Footprints& fp = footprints_.pieces();
    return parallel::PieceKey{fp.cell[fp.offsets[i]]} * constants_.dynamic.size() + i;
  }
  bool pressure_kicked_ = false;  // the sea's last kick was with pressure_ as it is
  SharedLoads shared_loads_;
  double loads_h_ = -1.0;         // the kick length of the last evaluation (< 0: stale)
  bool water_by_owner_ = false;   // evaluated_.water holds this rank's floes' only (several ranks, incident waves)
  // Implicit integrator: the mean in kicks_.step_horizontal is this step's
  // and its second half kick is to come.
  bool step_mean_pending_ = false;
  bool implicit_ = false;
  bool step_mean_loads_ = false;  // implicit, [coupling] horizontal_loads = "step_mean"
  int threads_ = 1;
  parallel::Communicator comm_;
  double newton_tolerance_ = 1e-8;  // times the thickest draft
  PenaltyStepOptions solver_options_;
  PenaltyStepSolver solver_;
  ImplicitStats implicit_stats_;
  double self_response_h_ = -1.0, self_response_ = 0.0;  // sea's node response to its own pressure over h
  std::vector<double> grid_work_, grid_eta_;  // grid-sized scratch of the implicit step
  struct ImplicitPieces {                     // per piece, the implicit step's problem
    std::vector<double> spring, damper, start, free_end;
  } pieces_;
  struct EvaluationScratch {           // per area piece, one evaluation's
    std::vector<double> penetration;  // [delta]^+ of each area piece
    std::vector<double> psi;          // psi of each area piece's cell
    std::vector<double> force;        // of each area piece on the sea (N)
  } eval_;
  mutable double penalty_energy_ = 0.0;
  double owned_seconds_ = 0.0;  // take_owned_seconds()
  // Adds the calling thread's CPU time since `start` (from owned_clock()) to
  // owned_seconds_, when the law runs by owner (by_owner()).
  double owned_clock() const;
  void charge_owned(double start);
  mutable bool energy_pending_ = false;  // penalty_energy_ is this rank's part, to be settled
  std::vector<std::string> notes_;
};

}  // namespace floesim
