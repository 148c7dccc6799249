#include "coupling/floe_sea.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include <Eigen/Dense>

#include "core/error.hpp"
#include "coupling/incident.hpp"
#include "coupling/parallel.hpp"
#include "coupling/penalty_law.hpp"
#include "fluid/sea.hpp"
#include "parallel/place.hpp"

namespace floesim {

using parallel::for_each_index;
using parallel::kFloesPerThread;

namespace {

// Response eta' at cell `cell` to a pressure impulse (Pa s) from rest: a unit
// impulse on that cell alone, or (checkerboard) +-1 alternating on every
// cell, the grid's shortest wave, which the sea answers fastest. Per unit
// pressure impulse, so an inverse mass per unit area.
double cell_response(fluid::Sea& sea, std::size_t cell, bool checkerboard) {
  fluid::ModalBank& bank = sea.modes();
  const std::vector<double> q(bank.q().begin(), bank.q().end());
  const std::vector<double> v(bank.v().begin(), bank.v().end());
  std::fill(bank.q().begin(), bank.q().end(), 0.0);
  std::fill(bank.v().begin(), bank.v().end(), 0.0);
  const fluid::SurfaceGrid& g = sea.grid();
  std::vector<double> p(g.size(), 0.0);
  if (checkerboard) {
    for (std::size_t c = 0; c < g.size(); ++c)
      p[c] = ((c % static_cast<std::size_t>(g.nx)) + c / static_cast<std::size_t>(g.nx)) % 2 ? -1.0 : 1.0;
  } else {
    p[cell] = 1.0;
  }
  sea.kick(p, 1.0);
  const double r = std::abs(sea.field(fluid::Field::velocity_z)[cell]);
  fluid::ModalBank& back = sea.modes();
  std::copy(q.begin(), q.end(), back.q().begin());
  std::copy(v.begin(), v.end(), back.v().begin());
  return r;
}
}  // namespace

double FloeSeaContact::subcell_weight(double coverage) const {
  return 1.0 / (1.0 + K_ * (1.0 - std::clamp(coverage, 0.0, 1.0)));
}

FloeSeaContact::FloeSeaContact(const CouplingParams& params, const SeaParams& sea_params, const Floes& floes,
                               fluid::Sea& sea, double dt_max)
    : rho_(sea_params.rho), g_(sea_params.g), sigma_(sea_params.sigma), K_(params.stiffness), grid_(sea.grid()),
      implicit_(params.integrator == CouplingIntegrator::implicit),
      step_mean_loads_(implicit_ && params.horizontal_loads == HorizontalLoads::step_mean),
      newton_tolerance_(params.newton_tolerance) {
  solver_options_.cg_tolerance = params.cg_tolerance;
  solver_options_.forcing = params.cg_forcing;
  solver_options_.max_newton = params.max_newton;
  solver_options_.max_cg = params.max_cg;
  kappa_ = K_ * rho_ * g_;
  switch (params.law) {
    case PenaltyLaw::strong: s_ = 1.0; break;
    case PenaltyLaw::weak: s_ = 0.0; break;
    case PenaltyLaw::blend:
      if (params.restitution >= 0.0) {
        // The implicit step's restitution depends on the step in units of
        // the floes' heave time sqrt(d / g): calibrated on the median draft.
        double step = 0.0;
        if (implicit_) {
          std::vector<double> drafts;
          for (std::size_t i = 0; i < floes.size(); ++i)
            if (!floes.is_static[i]) drafts.push_back(floes.draft(i, rho_));
          if (!drafts.empty()) {
            std::nth_element(drafts.begin(), drafts.begin() + drafts.size() / 2, drafts.end());
            step = dt_max / std::sqrt(drafts[drafts.size() / 2] / g_);
          }
        }
        const BlendCalibration cal = calibrate_blend(K_, 61, step);
        s_ = cal.share_for(params.restitution);
        std::ostringstream m;
        m << "[coupling] restitution = " << params.restitution << " at stiffness K = " << K_
          << ": blend s = " << s_ << " (obstacle-problem calibration";
        if (step > 0.0) m << ", stepped as the implicit integrator at dt_max = " << step << " sqrt(d / g)";
        m << ")";
        notes_.push_back(m.str());
      } else {
        s_ = params.blend;
      }
      break;
  }
  const fluid::SurfaceGrid& grid = sea.grid();
  const bool periodic = grid.edge == fluid::GridEdge::periodic;
  // Precondition: no tent on a walled sea (refused at load, core/config.cpp).
  FLOESIM_ASSERT(params.footprint != FootprintChoice::tent || periodic);
  kernel_ = params.footprint == FootprintChoice::cell || !periodic ? FootprintKernel::cell : FootprintKernel::tent;
  footprints_ = MovingFootprints(grid, kernel_, {params.footprint_reach});
  slab_rows_ = sea.slab_rows();
  first_slab_rows_ = slab_rows_;
  cell_area_ = grid.dx() * (grid.dims == 2 ? grid.dy() : grid.ly);
  // The sea under the floes, as fast as it can answer: one cell, or the
  // grid's shortest wave, at a few places (a walled basin answers faster near
  // its walls).
  for (std::size_t c : {std::size_t{0}, grid.size() / 4, grid.size() / 2, grid.size() - 1})
    for (bool checkerboard : {false, true})
      sea_inverse_mass_ = std::max(sea_inverse_mass_, cell_response(sea, c, checkerboard));
  floes_changed(floes);
}

void FloeSeaContact::floes_changed(const Floes& floes, std::span<const int> owner) {
  loads_h_ = -1.0;  // the loads and the water velocity are the old floes'
  footprints_.forget();
  const std::size_t n = floes.size(), old = constants_.bottom0.size();
  // The next rebuild's owners. The last rebuild's (footprints_.owners(),
  // kept by given_owners until new owners hold their floes) and the next
  // owners known before a split are sized for the old floes. After a split
  // the owners by place hold every floe's whole state current: their own
  // floes (the unsplit ones since the step's detection, the notices of
  // migrate carrying the states of those that changed owner) and the
  // pieces (built on every rank alike from their parents' states, which
  // the split gathered). So they may pose and build the next rebuild at
  // once, as next owners that have held their floes through a vertical
  // drift (`drifted`) and a drift's exchange (`current`). In a flume they
  // stand for the columns' shares until order_by_owner finds those at that
  // rebuild (any owners that hold their floes give the serial sums). Not on
  // a sea in slabs, whose owners follow its rows (takes_owners): the first
  // half kick offers the drift's (Simulation::offer_place_owners). Without
  // owners, the next rebuild is by index (every floe posed), or on the
  // slabs by every floe's place: every copy must then be current (the
  // start, a restore).
  if (!owner.empty() && (routes_.replicated() || implicit_whole())) {
    FLOESIM_ASSERT(owner.size() == n);
    set_next_owners(owner);
    next_owners_.current = true;
    next_owners_.drifted = true;
  } else {
    next_owners_.owner.clear();
    next_owners_.drifted = false;
  }
  // The groups of one entry a floe sized with the floes (the header's
  // members; the implicit step's at the step, the serial places at
  // order_by_owner). Every constant is set below but a staying floe's
  // bottom0; the kicks' loads are the old floes'.
  fit_floes(constants_, n);
  fit_floes(kicks_, n);
  fit_floes(evaluated_, n);
  std::fill(kicks_.loads.begin(), kicks_.loads.end(), FloeSeaLoad{});
  std::fill(kicks_.first_half.begin(), kicks_.first_half.end(), Eigen::Vector3d::Zero());
  std::fill(kicks_.step_horizontal.begin(), kicks_.step_horizontal.end(), Eigen::Vector3d::Zero());
  step_mean_pending_ = false;
  double min_mass_per_area = INFINITY;
  for (std::size_t i = 0; i < n; ++i) {
    constants_.dynamic[i] = floes.is_static[i] ? 0 : 1;
    const PolygonMoments m = polygon_moments(floes.vertices(i));
    const double rh = floes.density[i] * floes.thickness[i];
    constants_.body_moments[i] << rh * m.sxx, rh * m.sxy, rh * m.sxy, rh * m.syy;
    // A slope is resisted when the floe spans about two cells along it: its
    // smallest radius of gyration is at least half a cell. A long-crested sea
    // (dims = 1) is uniform across, so it never resists roll.
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(constants_.body_moments[i] /
                                                             std::max(floes.mass[i], 1e-300));
    const double gyration = std::sqrt(std::max(eig.eigenvalues()[0], 0.0));
    const bool resists = gyration >= 0.5 * std::max(grid_.dx(), grid_.dims == 2 ? grid_.dy() : 0.0);
    constants_.tilt[i] = !resists ? 0 : grid_.dims == 2 ? 2 : 1;
    // A new floe (a piece of a split) floats at its draft (and compliance)
    // below the calm sea's free level, as its parent did.
    if (i >= old) constants_.bottom0[i] = free_level_ - floes.draft(i, rho_) * (1.0 + 1.0 / K_);
    if (constants_.dynamic[i]) min_mass_per_area = std::min(min_mass_per_area, rh);
  }
  // Leapfrog's linear limit is 2 / omega_pen. The contact is not linear (it
  // opens and closes, and the coverage changes as edges cross cells): at
  // K = 1000, 1 / omega_pen let a floe in a steady wind pump grid-scale waves
  // and drift at 1.5 times the free drift after 1000 s, while 0.5 / omega_pen
  // and below agree with each other (docs/coupling.md, Known problems). We
  // take a quarter of the linear limit.
  stable_step_ = INFINITY;
  if (!implicit_ && s_ > 0.0 && std::isfinite(min_mass_per_area))
    stable_step_ = 0.5 / std::sqrt(s_ * kappa_ * (1.0 / min_mass_per_area + sea_inverse_mass_));
}

FloeSeaState FloeSeaContact::saved_state() const {
  FloeSeaState s{true, constants_.bottom0, loads_h_, penalty_energy(), {}, {}};
  // Every floe's reference pose (from the floes' owners when the last
  // rebuild posed each rank's own floes only: collective, as save() is).
  for (const FloePose& p : footprints_.whole_reference()) s.footprint_reference.push_back({p.x, p.y, p.yaw});
  // The implicit step's mean horizontal loads cannot be evaluated again from the state.
  if (step_mean_loads_ && loads_h_ >= 0.0)
    for (const FloeSeaLoad& load : kicks_.loads)
      s.mean_horizontal.push_back({load.horizontal[0], load.horizontal[1], load.horizontal[2]});
  return s;
}

void FloeSeaContact::restore(const FloeSeaState& state, const Floes& floes, fluid::Sea& sea, IncidentSea* incident) {
  floes_changed(floes);
  constants_.bottom0 = state.bottom0;
  // The footprints move from where they were last built: built there again,
  // they move to the same bits.
  if (!state.footprint_reference.empty()) {
    FLOESIM_ASSERT(state.footprint_reference.size() == evaluated_.poses.size());
    for (std::size_t i = 0; i < evaluated_.poses.size(); ++i) {
      const auto& p = state.footprint_reference[i];
      evaluated_.poses[i] = {p[0], p[1], p[2]};
    }
    clear_footprint_cells();
    footprints_.rebuild_at(floes, constants_.dynamic, evaluated_.poses, threads_);
  }
  if (state.loads_h >= 0.0) evaluate_loads(floes, sea, incident, state.loads_h);
  if (state.mean_horizontal.size() == kicks_.loads.size())
    for (std::size_t i = 0; i < kicks_.loads.size(); ++i) {
      const auto& mean = state.mean_horizontal[i];
      kicks_.loads[i].horizontal = {mean[0], mean[1], mean[2]};
      kicks_.step_horizontal[i] = kicks_.loads[i].horizontal;
    }
  penalty_energy_ = state.penalty_energy;
  energy_pending_ = false;
}

double FloeSeaContact::weak_coefficient(const Floes& floes, std::size_t i) const {
  return K_ * rho_ * std::sqrt(g_ * floes.draft(i, rho_));
}

Eigen::Matrix2d FloeSeaContact::tilt_inertia(const Floes& floes, std::size_t i, double yaw) const {
  const double c = std::cos(yaw), s = std::sin(yaw);
  Eigen::Matrix2d R;
  R << c, -s, s, c;
  const double h = floes.thickness[i];
  return R * constants_.body_moments[i] * R.transpose() + floes.mass[i] * h * h / 12.0 * Eigen::Matrix2d::Identity();
}

void FloeSeaContact::pose_at_states(const Floes& floes, std::span<const std::uint32_t> which) {
  FLOESIM_ASSERT(evaluated_.poses.size() == floes.size());
  for (const std::uint32_t i : which) evaluated_.poses[i] = {floes.state[i].x, floes.state[i].y, floes.state[i].yaw};
}

void FloeSeaContact::pose_at_states(const Floes& floes) {
  FLOESIM_ASSERT(evaluated_.poses.size() == floes.size());
  for (std::size_t i = 0; i < floes.size(); ++i)
    evaluated_.poses[i] = {floes.state[i].x, floes.state[i].y, floes.state[i].yaw};
}

void FloeSeaContact::clear_footprint_cells() {
  // The pressure is zero outside the footprints: clear the cells of the last
  // ones rather than the whole grid (and the cells' coverage and sums).
  if (pressure_.size() != grid_.size()) {
    pressure_.assign(grid_.size(), 0.0);
    cells_.assign(grid_.size(), {});
  } else if (by_owner()) {
    clear_cells_by_owner();
  } else {
    for (std::uint32_t c : footprints_.pieces().cell) {
      pressure_[c] = 0.0;
      cells_[c] = {};
    }
  }
}

void FloeSeaContact::place_footprints(const Floes& floes, bool move, std::span<const int> owners) {
  clear_footprint_cells();
  footprints_.place(floes, constants_.dynamic, evaluated_.poses, threads_, move, owners);
  // By owner, this rank's floes only, in the serial order (the others'
  // pieces are not here).
  if (by_owner()) {
    order_by_owner(floes.size());
    return sum_coverage_by_owner();
  }
  const Footprints& fp = footprints_.pieces();
  // Floes in the order of their first cell, so that floes next to each
  // other on the grid come one after the other (the grid's arrays are
  // read and written where each floe lies: this keeps them in cache); ties
  // by floe index (serial_key: the order by owner is this one).
  order_.clear();
  for (std::size_t i = 0; i < floes.size(); ++i)
    if (constants_.dynamic[i] && fp.offsets[i] < fp.offsets[i + 1]) order_.push_back(static_cast<std::uint32_t>(i));
  std::sort(order_.begin(), order_.end(), [&](std::uint32_t x, std::uint32_t y) { return serial_key(x) < serial_key(y); });
  const double inv_cell_area = 1.0 / cell_area_;
  for (std::uint32_t i : order_)
    for (std::size_t k = fp.offsets[i]; k < fp.offsets[i + 1]; ++k) cells_[fp.cell[k]].coverage += fp.area[k] * inv_cell_area;
}

void FloeSeaContact::evaluate(const Floes& floes, fluid::Sea& sea, double h) {
  pressure_kicked_ = false;
  energy_pending_ = false;
  loads_h_ = h;
  // The poses a placement reads: a move and the window's test that allows
  // it, this rank's floes' (MovingFootprints::mine, whose pieces it moves;
  // the verdict agreed over the ranks); a rebuild with owners given
  // (given_owners: the drift's by place on the slabs, take_place_owners, or
  // by place on a sea not in slabs), this rank's floes' by them (the
  // pieces it builds); any other rebuild, every floe's (set_owners finds
  // the owners by place from them).
  pose_at_states(floes, footprints_.mine());
  const bool move = footprints_.movable(constants_.dynamic, evaluated_.poses);
  const GivenOwners given = move ? GivenOwners{} : given_owners(floes.size());
  if (!move && !given.owner.empty()) pose_at_states(floes, given.mine);
  else if (!move) pose_at_states(floes);
  place_owner_ = {};
  place_rows_ = {};
  place_mine_ = {};
  place_footprints(floes, move, given.owner);
  const Footprints& fp = footprints_.pieces();
  const std::span<const double> area0 = footprints_.reference_area();
  // Routed with the floes owned by place, this rank's pieces lie within
  // reach_rows() of its slab: the sea's fields are exchanged there only.
  const bool halo = routed() && footprints_.by_place();
  if (halo) sea.set_field_halo(footprints_.reach_rows());
  // Windows of the rows held (by place: the slab and that halo; else whole),
  // read by global cell.
  const fluid::RowWindow eta = sea.field(fluid::Field::elevation);
  fluid::RowWindow w;
  if (s_ < 1.0) w = sea.field(fluid::Field::velocity_z);
  if (halo) sea.set_field_halo(-1);
  const double ks = s_ * kappa_, inv_cell_area = 1.0 / cell_area_;
  // The implicit integrator applies the vertical law and the weight itself.
  const double spring_kick = implicit_ ? 0.0 : 1.0, weight = implicit_ ? 0.0 : g_;
  const double damper_kick = implicit_ ? 0.0 : 1.0 - s_;
  // Scratch shared by the threads (each writes its own floes' entries).
  std::vector<double>& u = eval_.penetration;
  std::vector<double>& psi = eval_.psi;
  std::vector<double>& force = eval_.force;
  std::vector<double>& wetted = evaluated_.wetted;
  u.assign(fp.cell.size(), 0.0);
  psi.resize(fp.cell.size());
  force.assign(fp.cell.size(), 0.0);
  std::fill(wetted.begin(), wetted.end(), 0.0);
  for (FloeSeaLoad& load : kicks_.loads) load = {};
  const double law_start = owned_clock();
  // Vertical: the law on each area piece, floe by floe (on threads); then
  // the pieces' sums into the cells, in order (the same sums whatever the
  // thread count).
  const std::ptrdiff_t floes_in_order = static_cast<std::ptrdiff_t>(order_.size());
#pragma omp parallel for num_threads(threads_) schedule(dynamic, 16) if (floes_in_order > kFloesPerThread)
  for (std::ptrdiff_t j = 0; j < floes_in_order; ++j) {
    const std::uint32_t i = order_[static_cast<std::size_t>(j)];
    FloeSeaLoad& load = kicks_.loads[i];
    const FloeState& st = floes.state[i];
    const double z = st.heave + constants_.bottom0[i];
    const Vec2 a{st.pitch, st.roll}, ar{st.pitch_rate, st.roll_rate};
    const double c = damper_kick * weak_coefficient(floes, i);
    const double inv_mass = 1.0 / (floes.density[i] * floes.thickness[i]) + sea_inverse_mass_;
    double fz = 0.0, wet = 0.0;
    Vec2 moment = Vec2::Zero();
    for (std::size_t k = fp.offsets[i]; k < fp.offsets[i + 1]; ++k) {
      const Vec2& r = fp.centroid[k];
      const std::uint32_t cell = fp.cell[k];
      const double delta = eta[cell] - z - a.dot(r);
      const double ps = subcell_weight(cells_[cell].coverage);
      psi[k] = ps;
      const double area = fp.area[k];
      if (delta <= 0.0 || area <= 0.0) continue;
      u[k] = delta;
      double f = spring_kick * ks * ps * area * delta;
      wet += ps * area0[k] * delta;  // d m_c / dG = Q_c - a_c(P0) I (moving_footprint.hpp)
      if (c > 0.0) {
        const double rate = w[cell] - st.heave_rate - ar.dot(r);
        f += area * ps * c / (1.0 + h * ps * c * inv_mass) * rate;
      }
      force[k] = f;
      fz += f;
      moment += f * r;
    }
    wetted[i] = wet;
    load.vertical = {fz - floes.mass[i] * weight, moment.x(), moment.y()};
  }
  charge_owned(law_start);
  double energy = 0.0;
  if (by_owner()) {
    energy = sum_cells_by_owner(ks);
  } else {
    for (std::uint32_t i : order_)
      for (std::size_t k = fp.offsets[i]; k < fp.offsets[i + 1]; ++k) {
        if (u[k] <= 0.0) continue;
        const double area = fp.area[k], delta = u[k];
        energy += 0.5 * ks * psi[k] * area * delta * delta;
        cells_[fp.cell[k]].sum += area * delta * delta;
        pressure_[fp.cell[k]] += force[k] * inv_cell_area;
      }
  }
  // Strong part, horizontal: -dV/dG and -dV/dyaw at the present slopes.
  for (std::uint32_t i : order_) evaluated_.slope[i] = {floes.state[i].pitch, floes.state[i].roll};
  horizontal_loads(u);
  penalty_energy_ = energy;
}

void FloeSeaContact::horizontal_loads(std::span<const double> u) {
  // Through the edge pieces. The coverage Phi_c moves with every floe's edge
  // in cell c, so an edge also carries psi'(Phi_c) / (2 A) sum_k a_k u_k^2 of
  // the cell's pieces.
  const Footprints& fp = footprints_.pieces();
  const std::vector<double>& psi = eval_.psi;
  const std::vector<double>& wetted = evaluated_.wetted;
  const double ks = s_ * kappa_, inv_cell_area = 1.0 / cell_area_;
  if (ks <= 0.0) return;
  // Each rank its own floes (their edge pieces are only there); the caller
  // shares the loads (share_owned).
  const std::ptrdiff_t floes_in_order = static_cast<std::ptrdiff_t>(order_.size());
  const double start = owned_clock();
#pragma omp parallel for num_threads(threads_) schedule(dynamic, 16) if (floes_in_order > kFloesPerThread)
  for (std::ptrdiff_t j = 0; j < floes_in_order; ++j) {
    const std::uint32_t i = order_[static_cast<std::size_t>(j)];
    if (!footprints_.owns(i)) continue;
    const Vec2 a = evaluated_.slope[i];
    Vec2 fh = Vec2::Zero();
    double torque = 0.0;
    for (std::size_t k = fp.edge_offsets[i]; k < fp.edge_offsets[i + 1]; ++k) {
      const std::ptrdiff_t piece = fp.edge_piece[k];
      if (piece < 0 || fp.area[piece] <= 0.0) continue;  // none, or a node the floe has left
      const double up = u[piece], sum = cells_[fp.edge_cell[k]].sum;
      if (up <= 0.0 && sum <= 0.0) continue;
      const double ps = psi[piece];
      const double dpsi = K_ * ps * ps;  // d psi / d Phi
      const Vec2& N = fp.edge_normal[k];  // d w_c / dG
      const double T = fp.edge_twist[k];  // d w_c / dyaw
      const Vec2 Qa = fp.edge_first[k].transpose() * a;  // ∮ B (r . a) n ds
      const Vec2& S = fp.edge_swept[k];
      const Vec2& rc = fp.centroid[piece];
      const double area_term = 0.5 * ks * (ps * up * up + dpsi * sum * inv_cell_area);  // dV / d a_c
      const double kf = ks * ps;
      const Vec2 dVdG = area_term * N - kf * up * (Qa - a.dot(rc) * N);
      const double dVdyaw = area_term * T - kf * up * a.dot(S - rc * T);
      fh -= dVdG;
      torque -= dVdyaw;
    }
    // The explicit-G term of dV/dG: -psi_c a_c(P0) u a, summed over the area pieces.
    fh -= ks * wetted[i] * a;
    kicks_.loads[i].horizontal = {fh.x(), fh.y(), torque};
  }
  charge_owned(start);
}

void FloeSeaContact::evaluate_loads(const Floes& floes, fluid::Sea& sea, IncidentSea* incident, double h,
                                    std::span<const std::uint8_t> kicked) {
  evaluate(floes, sea, h);
  update_water(sea, incident);
  share_owned(kicked);
  // After an implicit step the horizontal loads are that step's mean (zero
  // on a floe that had no pieces on the step's midpoint footprint).
  if (step_mean_pending_)
    for (std::size_t i = 0; i < kicks_.loads.size(); ++i) kicks_.loads[i].horizontal = kicks_.step_horizontal[i];
}

void FloeSeaContact::ready_loads(const Floes& floes, fluid::Sea& sea, IncidentSea* incident, double h,
                                 std::span<const std::uint8_t> kicked, bool kickers_moved) {
  // Only the explicit damper's loads depend on the kick length.
  const bool explicit_damper = !implicit_ && s_ < 1.0;
  if (loads_h_ < 0.0 || (explicit_damper && loads_h_ != h)) evaluate_loads(floes, sea, incident, h, kicked);
  else if (kickers_moved) share_owned(kicked);
}

void FloeSeaContact::update_water(const fluid::Sea& sea, IncidentSea* incident) {
  std::fill(evaluated_.water.begin(), evaluated_.water.end(), Vec2::Zero());
  water_by_owner_ = false;  // zero on every rank
  if (!incident) return;
  water_by_owner_ = !comm_.serial();
  // Routed with the floes owned by place, this rank's floes' pieces lie
  // within reach_rows_from(first_slab_rows_) of the first slabs (the
  // owners follow the sea's slabs, which may have moved from them), which
  // are the incident sea's slabs (it keeps its first, equal, shares): the
  // snapshots are windows of that slab and halo.
  const int halo = routed() && footprints_.by_place() ? footprints_.reach_rows_from(first_slab_rows_) : -1;
  incident->advance_to(sea.time(), halo);
  const double w = incident->weight(sea.time());
  const fluid::RowWindow u0 = incident->u0(), v0 = incident->v0(), u1 = incident->u1(), v1 = incident->v1();
  const Footprints& fp = footprints_.pieces();
  // Each rank its own floes; the drift's owners get them (hand_water_over).
  const std::span<const std::uint32_t> mine = footprints_.mine();
  const std::ptrdiff_t count = static_cast<std::ptrdiff_t>(mine.size());
  const double start = owned_clock();
#pragma omp parallel for num_threads(threads_) schedule(static) if (count > kFloesPerThread)
  for (std::ptrdiff_t j = 0; j < count; ++j) {
    const std::size_t i = mine[static_cast<std::size_t>(j)];
    if (i >= fp.floes()) continue;
    double area = 0.0;
    Vec2 sum0 = Vec2::Zero(), sum1 = Vec2::Zero();
    for (std::size_t k = fp.offsets[i]; k < fp.offsets[i + 1]; ++k) {
      const std::uint32_t c = fp.cell[k];
      area += fp.area[k];
      sum0 += fp.area[k] * Vec2{u0[c], v0[c]};
      sum1 += fp.area[k] * Vec2{u1[c], v1[c]};
    }
    if (area > 0.0) evaluated_.water[i] = ((1.0 - w) * sum0 + w * sum1) / area;
  }
  charge_owned(start);
}

// Timed by owner only: with the implicit step every rank runs the law on
// every floe, work that is the same on every rank whatever the owners.
double FloeSeaContact::owned_clock() const { return by_owner() ? parallel::thread_seconds() : 0.0; }

void FloeSeaContact::charge_owned(double start) {
  // The calling thread's time only: with OpenMP threads the others' share of
  // the loop is not counted (as for the drift's charge, parallel/place.hpp).
  if (by_owner()) owned_seconds_ += parallel::thread_seconds() - start;
}

void FloeSeaContact::kick_sea(fluid::Sea& sea, double h) {
  if (implicit_) return;  // the implicit step applies the whole vertical law
  if (pressure_kicked_) {
    sea.repeat_kick(h);
  } else {
    sea.kick(pressure_, h);
    pressure_kicked_ = true;
  }
}

void FloeSeaContact::kick_floes(Floes& floes, double h, std::span<const std::uint8_t> kicked) {
  // The explicit damper's loads depend on the rates this kick changes.
  if (!implicit_ && s_ < 1.0) loads_h_ = -1.0;
  // The floes this rank holds, whose loads share_owned brought (the
  // header's "The kick by its holders"); the implicit step kicks every floe.
  const bool every = kicked.empty() || implicit_;
  FLOESIM_ASSERT(every || kicked.size() == floes.size());
  for (std::size_t i = 0; i < floes.size(); ++i) {
    if (!constants_.dynamic[i] || (!every && !kicked[i])) continue;
    FloeState& st = floes.state[i];
    const FloeSeaLoad& load = kicks_.loads[i];
    // The implicit step applies the vertical law and the weight itself (the
    // loads' vertical part is zero): no vertical kick. Every rank's copy of
    // every floe's vertical DOFs is then the implicit step's alone, which
    // it reads; the kick would turn a stale copy's yaw into them.
    if (!implicit_) {
      st.heave_rate += h * load.vertical[0] / floes.mass[i];
      if (constants_.tilt[i] == 2) {
        const Eigen::Vector2d da = tilt_inertia(floes, i).ldlt().solve(load.vertical.tail<2>());
        st.pitch_rate += h * da[0];
        st.roll_rate += h * da[1];
      } else if (constants_.tilt[i] == 1) {
        st.pitch_rate += h * load.vertical[1] / tilt_inertia(floes, i)(0, 0);
      }
    }
    // Implicit: the first half kick of a step applies the last step's mean
    // load (the drift's predictor), the second completes the step's impulse
    // to 2 h F_mean (the header's "Horizontal loads of the implicit step").
    Eigen::Vector3d impulse = h * load.horizontal;
    if (step_mean_loads_) {
      if (step_mean_pending_) impulse = 2.0 * h * kicks_.step_horizontal[i] - kicks_.first_half[i];
      else kicks_.first_half[i] = impulse;
    }
    st.vx += impulse[0] / floes.mass[i];
    st.vy += impulse[1] / floes.mass[i];
    st.yaw_rate += impulse[2] / floes.inertia_z[i];
  }
  step_mean_pending_ = false;
}

void FloeSeaContact::advance_vertical(Floes& floes, std::span<const FloeState> start, fluid::Sea& sea, double h,
                                      std::span<const std::uint8_t> held) {
  if (implicit_) return implicit_step(floes, start, sea, h);
  // Each floe's vertical drift is its own (three multiply-adds from its own
  // rates), so every rank that holds a floe drifts it alike, to the same
  // bits, and no exchange is needed. The other copies stay stale until the
  // drift's exchange brings their owners'. (Simulation::held_now says which
  // floes a rank holds: its band, its own floes and its own floes for the
  // coupling, whose heave, pitch and roll the next evaluation's law reads.)
  FLOESIM_ASSERT(held.empty() || held.size() == floes.size());
  next_owners_.drifted = true;  // the next owners held their floes through it
  for (std::size_t i = 0; i < floes.size(); ++i) {
    if (floes.is_static[i] || (!held.empty() && !held[i])) continue;
    FloeState& st = floes.state[i];
    st.heave += h * st.heave_rate;
    st.pitch += h * st.pitch_rate;
    st.roll += h * st.roll_rate;
  }
  sea.flow(h);
}

double FloeSeaContact::vertical_kinetic(const Floes& floes, std::size_t i) const {
  if (!constants_.dynamic[i]) return 0.0;
  const FloeState& st = floes.state[i];
  const Eigen::Vector2d ar(st.pitch_rate, st.roll_rate);
  return 0.5 * floes.mass[i] * st.heave_rate * st.heave_rate + 0.5 * ar.dot(tilt_inertia(floes, i) * ar);
}

double FloeSeaContact::weight_energy(const Floes& floes, std::size_t i) const {
  return constants_.dynamic[i] ? floes.mass[i] * g_ * floes.state[i].heave : 0.0;
}

FloeSeaContact::Memory FloeSeaContact::memory(std::span<const std::uint8_t> held) const {
  const std::size_t k = held_count(held, constants_.dynamic.size());
  Memory m;
  FloeBytes& f = m.per_floe;
  f += floe_group_bytes(constants_, k);
  f += floe_group_bytes(kicks_, k);
  f += floe_group_bytes(evaluated_, k);
  f += floe_group_bytes(implicit_floes_, k);
  f += floe_group_bytes(owner_.places, k);
  // Not a group: empty until the owners by place are known (set_next_owners).
  f += per_floe_bytes(next_owners_.owner, k);
  m.footprints = footprints_.memory(held);
  return m;
}

}  // namespace floesim
