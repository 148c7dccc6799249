// The implicit floe–sea step (FloeSeaContact::implicit_step and what only it
// uses; coupling/floe_sea.hpp, "Implicit step"; docs/coupling.md, "The
// implicit step"): the problem on the midpoint footprint, its solve by
// coupling/penalty_step.hpp, the step of the floes and the sea with the
// forces found, and the step's mean horizontal loads. The explicit kicks and
// the rest of the contact are in floe_sea.cpp.
#include "coupling/floe_sea.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>

#include <Eigen/Dense>

#include "core/error.hpp"
#include "coupling/parallel.hpp"
#include "coupling/penalty_law.hpp"
#include "fluid/sea.hpp"

namespace floesim {

using parallel::for_each_index;

namespace {

// f(i) for the floes of `order` on threads.
template <class F>
void for_each_floe(const std::vector<std::uint32_t>& order, int threads, F&& f) {
  parallel::for_each_of(order, threads, std::forward<F>(f));
}

}  // namespace

void FloeSeaContact::pressure_of_pieces(std::span<const double> u) {
  // Serial: pieces of several floes share cells.
  const Footprints& fp = footprints_.pieces();
  const double inv_cell_area = 1.0 / cell_area_;
  for (const std::uint32_t i : order_)
    for (std::size_t k = fp.offsets[i]; k < fp.offsets[i + 1]; ++k) grid_work_[fp.cell[k]] += u[k] * inv_cell_area;
}

void FloeSeaContact::sea_response(fluid::Sea& sea, double h, std::span<const double> u, std::span<double> out) {
  const Footprints& fp = footprints_.pieces();
  if (by_owner()) {
    // The same sums and response through the cells' routes (cell_product):
    // the slab's rows of grid_work_ hold the cells' serial sums, and the
    // slab sea reads and writes its rows of whole-grid arrays (p, eta), the
    // rows cell_product hands over.
    cell_product(u, 1.0 / cell_area_,
                 [&](int, [[maybe_unused]] std::span<const double> cells, [[maybe_unused]] std::span<double> response) {
                   FLOESIM_ASSERT(cells.empty() || (cells.data() >= grid_work_.data() &&
                                                    response.data() - grid_eta_.data() == cells.data() - grid_work_.data()));
                   sea.midpoint_response(grid_work_, h, grid_eta_);
                 },
                 out);
    for (double& v : out) v = -v;
    return;
  }
  // The pressure of the forces u, held over h, lowers the nodes by the
  // sea's midpoint response (G_sea u is minus that change).
  pressure_of_pieces(u);
  sea.midpoint_response(grid_work_, h, grid_eta_);
  for_each_index(fp.cell.size(), threads_, [&](std::size_t k) { out[k] = -grid_eta_[fp.cell[k]]; });
  for (std::uint32_t c : fp.cell) grid_work_[c] = 0.0;
}

void FloeSeaContact::pose_at_midpoint(const Floes& floes, std::span<const FloeState> start,
                                      std::span<const std::uint32_t> which) {
  // At the step's end the vertical forces would lag the drift by h / 2: a
  // first-order error. A periodic grid's seam is crossed by the shorter way.
  const bool periodic = grid_.edge == fluid::GridEdge::periodic;
  FLOESIM_ASSERT(evaluated_.poses.size() == floes.size());
  for (const std::uint32_t i : which) {
    const FloeState& s = floes.state[i];
    FloePose& p = evaluated_.poses[i];
    p = {s.x, s.y, s.yaw};
    if (!constants_.dynamic[i] || i >= start.size()) continue;
    double dx = p.x - start[i].x, dy = p.y - start[i].y;
    if (periodic) {
      dx -= grid_.lx * std::round(dx / grid_.lx);
      if (grid_.dims == 2) dy -= grid_.ly * std::round(dy / grid_.ly);
    }
    p.x -= 0.5 * dx;
    p.y -= 0.5 * dy;
    p.yaw = 0.5 * (p.yaw + start[i].yaw);
  }
}

void FloeSeaContact::place_midpoint_footprints(const Floes& floes, std::span<const FloeState> start) {
  // The floes a placement reads, as evaluate() poses them: on several ranks
  // with the halo exchange a rank's copies of the floes it does not hold
  // are stale, and the owners that build or move a floe's pieces hold it
  // (its present state and step-start copy: Simulation::held_now).
  pose_at_midpoint(floes, start, footprints_.mine());
  const bool move = footprints_.movable(constants_.dynamic, evaluated_.poses);
  const GivenOwners given = move ? GivenOwners{} : given_owners(floes.size());
  if (!move && !given.owner.empty()) {
    pose_at_midpoint(floes, start, given.mine);
  } else if (!move) {  // by index (the start, a restore, a split: every copy current)
    std::vector<std::uint32_t> every(floes.size());
    for (std::size_t i = 0; i < every.size(); ++i) every[i] = static_cast<std::uint32_t>(i);
    pose_at_midpoint(floes, start, every);
  }
  place_owner_ = {};  // offered for this placement only (evaluate()'s rule)
  place_rows_ = {};
  place_mine_ = {};
  place_footprints(floes, move, given.owner);
}

void FloeSeaContact::gather_tilted_yaw(const Floes& floes) {
  // By owner order_ is this rank's floes, whose present yaw it holds.
  if (comm_.serial() || by_owner()) {
    for (const std::uint32_t i : order_) implicit_floes_.yaw[i] = floes.state[i].yaw;
    return;
  }
  // order_ and constants_.tilt are the same on every rank (every floe's pieces are
  // gathered), and so are the owners: the entries line up.
  const std::span<const int> owner = footprints_.owners();
  std::vector<double> yaw;
  std::vector<int> by;
  for (const std::uint32_t i : order_) {
    if (constants_.tilt[i] == 0) continue;
    yaw.push_back(owner[i] == comm_.rank() ? floes.state[i].yaw : 0.0);
    by.push_back(owner[i]);
  }
  comm_.complete_owned(yaw, by);
  std::size_t j = 0;
  for (const std::uint32_t i : order_)
    if (constants_.tilt[i] != 0) implicit_floes_.yaw[i] = yaw[j++];
}

void FloeSeaContact::implicit_step(Floes& floes, std::span<const FloeState> start, fluid::Sea& sea, double h) {
  fit_floes(implicit_floes_, floes.size());  // the implicit step's per-floe arrays
  // The footprints at the midpoint of the floes' horizontal motion over the step.
  place_midpoint_footprints(floes, start);
  const Footprints& fp = footprints_.pieces();
  const std::size_t n = fp.cell.size();
  // Each floe's vertical inertia on the DOFs it has, at its present yaw.
  // By owner (a sea in slabs) each rank solves over its own floes' pieces,
  // whose states it holds; else the solve is every rank's, over every
  // floe's pieces, and what it reads of each floe is its vertical DOFs,
  // which every rank holds current (the solve alone writes them, alike on
  // every rank: share_vertical by owner; the explicit kicks do not:
  // kick_floes), its constants, and its yaw, from its owner.
  gather_tilted_yaw(floes);
  std::fill(implicit_floes_.inertia.begin(), implicit_floes_.inertia.end(), VerticalInertia{});
  for (std::uint32_t i : order_) {
    VerticalInertia& in = implicit_floes_.inertia[i];
    in.slopes = constants_.tilt[i];
    in.mass(0, 0) = floes.mass[i];
    in.inverse_mass(0, 0) = 1.0 / floes.mass[i];
    if (constants_.tilt[i] == 2) {
      const Eigen::Matrix2d J = tilt_inertia(floes, i, implicit_floes_.yaw[i]);
      in.mass.bottomRightCorner<2, 2>() = J;
      in.inverse_mass.bottomRightCorner<2, 2>() = J.inverse();
    } else if (constants_.tilt[i] == 1) {
      in.mass(1, 1) = tilt_inertia(floes, i, implicit_floes_.yaw[i])(0, 0);
      in.inverse_mass(1, 1) = 1.0 / in.mass(1, 1);
    }
  }
  grid_work_.assign(grid_.size(), 0.0);
  grid_eta_.resize(grid_.size());
  // Per piece: the spring c = s kappa psi a, the damper per step, the
  // penetrations at t (d0) and with no penalty at t + h (d_free), both on
  // this footprint.
  ImplicitPieces& q = pieces_;
  for (auto* v : {&q.spring, &q.damper, &q.start, &q.free_end}) v->assign(n, 0.0);
  std::fill(implicit_floes_.free_bottom.begin(), implicit_floes_.free_bottom.end(), Eigen::Vector3d::Zero());
  const double ks = s_ * kappa_;
  double scale = 0.0;  // the thickest draft: the residual's unit
  for (std::uint32_t i : order_) scale = std::max(scale, floes.draft(i, rho_));
  if (by_owner()) scale = comm_.max(scale);  // over every rank's floes: exact
  // The elevation at t as evaluate() reads it: by place, this rank's pieces
  // lie within reach_rows() of its slab, the halo exchanged there only.
  const bool halo = routed() && footprints_.by_place();
  if (halo) sea.set_field_halo(footprints_.reach_rows());
  const fluid::RowWindow eta0 = sea.field(fluid::Field::elevation);
  if (halo) sea.set_field_halo(-1);
  for_each_floe(order_, threads_, [&](std::uint32_t i) {
    const FloeState& st = floes.state[i];
    const double z = st.heave + constants_.bottom0[i];
    const Vec2 a{st.pitch, st.roll};
    implicit_floes_.free_bottom[i] = {z + h * st.heave_rate - 0.5 * h * h * g_, st.pitch + h * st.pitch_rate,
                       st.roll + h * st.roll_rate};
    const double damper = (1.0 - s_) * weak_coefficient(floes, i) / h;
    for (std::size_t k = fp.offsets[i]; k < fp.offsets[i + 1]; ++k) {
      const double psi_area = subcell_weight(cells_[fp.cell[k]].coverage) * fp.area[k];
      q.spring[k] = ks * psi_area;
      q.damper[k] = damper * psi_area;
      q.start[k] = eta0[fp.cell[k]] - z - a.dot(fp.centroid[k]);
    }
  });
  // The free elevation at t + h at each piece's cell, into free_end. By
  // owner the slab sea computes its rows only, and a piece in another slab
  // reads its cell from that slab's rank by the answer route (the coverage's
  // routes, no pressure scattered: zero values): the field's halo window is
  // the elevation's at t, not this midpoint extrapolation, which exists on
  // its slab's rank alone.
  if (by_owner()) {
    const std::vector<double> none(n, 0.0);
    cell_product(none, 0.0,
                 [&](int, std::span<const double>, [[maybe_unused]] std::span<double> response) {
                   FLOESIM_ASSERT(response.empty() || response.data() >= grid_eta_.data());
                   sea.midpoint_free_elevation(h, grid_eta_);
                 },
                 q.free_end);
  } else {
    sea.midpoint_free_elevation(h, grid_eta_);
    for (const std::uint32_t i : order_)
      for (std::size_t k = fp.offsets[i]; k < fp.offsets[i + 1]; ++k) q.free_end[k] = grid_eta_[fp.cell[k]];
  }
  for_each_floe(order_, threads_, [&](std::uint32_t i) {
    const Eigen::Vector3d& b = implicit_floes_.free_bottom[i];
    for (std::size_t k = fp.offsets[i]; k < fp.offsets[i + 1]; ++k)
      q.free_end[k] = q.free_end[k] - b[0] - b[1] * fp.centroid[k].x() - b[2] * fp.centroid[k].y();
  });
  // The sea's response on a node to its own pressure over h: the diagonal of
  // G_sea, for the preconditioner (a periodic sea's is the same on every node).
  if (self_response_h_ != h) {
    // A walled basin's node in the middle (row ny / 2, column nx / 2), away from its walls.
    const std::size_t middle = static_cast<std::size_t>(grid_.ny / 2) * static_cast<std::size_t>(grid_.nx) +
                               static_cast<std::size_t>(grid_.nx / 2);
    const std::size_t node = grid_.edge == fluid::GridEdge::periodic ? 0 : middle;
    grid_work_[node] = 1.0;
    sea.midpoint_response(grid_work_, h, grid_eta_);  // collective in slabs
    grid_work_[node] = 0.0;
    self_response_ = std::max(-grid_eta_[node], 0.0);
    if (by_owner()) {
      // In slabs only the rank whose slab holds the node's row has it: its
      // value to every rank (8 B), so that every rank's preconditioner is
      // the serial one.
      const int row = static_cast<int>(node / static_cast<std::size_t>(grid_.nx));
      int root = 0;
      while (root + 1 < comm_.size() && slab_rows_[static_cast<std::size_t>(root) + 1] <= row) ++root;
      const std::vector<std::byte> got = comm_.broadcast(std::as_bytes(std::span(&self_response_, 1)), root);
      std::memcpy(&self_response_, got.data(), sizeof(double));
    }
    self_response_h_ = h;
  }

  PenaltyStepProblem problem;
  problem.step = h;
  problem.offsets = fp.offsets;
  problem.bodies = order_;
  problem.inertia = implicit_floes_.inertia;
  problem.lever = fp.centroid;
  problem.spring = q.spring;
  problem.damper = q.damper;
  problem.start = q.start;
  problem.free_end = q.free_end;
  problem.self_response = self_response_ / cell_area_;
  problem.tolerance = newton_tolerance_ * std::max(scale, 1e-300);
  PenaltyStepOptions options = solver_options_;
  options.threads = threads_;
  if (by_owner()) {
    // The bodies are this rank's floes: the dots' exact partial sums added
    // over the ranks as integers, the largest residual over the ranks.
    options.reduction.sum = [this](std::span<ExactSum> sums) { comm_.sum(sums); };
    options.reduction.max = [this](double value) { return comm_.max(value); };
  }
  const PenaltyStepResult result = solver_.solve(
      problem, [&](std::span<const double> u, std::span<double> out) { sea_response(sea, h, u, out); }, options);
  ++implicit_stats_.steps;
  implicit_stats_.newton += result.newton;
  implicit_stats_.cg += result.cg;
  implicit_stats_.g_products += result.responses;
  implicit_stats_.last_residual = result.residual;
  if (result.status != PenaltyStepStatus::converged) {
    std::ostringstream m;
    m << "the implicit floe–sea step did not converge in " << options.max_newton << " Newton iterations (largest residual "
      << result.residual << " m, tolerance " << problem.tolerance << " m; dt = " << h << " s)";
    throw RunError(m.str());
  }

  // The step with the forces f held over it: the floes...
  const std::span<const double> f = solver_.force();
  const double hh = 0.5 * h * h;
  for (std::uint32_t i : order_) {
    FloeState& st = floes.state[i];
    Eigen::Vector3d F(-floes.mass[i] * g_, 0.0, 0.0);
    for (std::size_t k = fp.offsets[i]; k < fp.offsets[i + 1]; ++k)
      F += f[k] * Eigen::Vector3d(1.0, fp.centroid[k].x(), fp.centroid[k].y());
    const Eigen::Vector3d acc = implicit_floes_.inertia[i].inverse_mass * F;
    st.heave += h * st.heave_rate + hh * acc[0];
    st.pitch += h * st.pitch_rate + hh * acc[1];
    st.roll += h * st.roll_rate + hh * acc[2];
    st.heave_rate += h * acc[0];
    st.pitch_rate += h * acc[1];
    st.roll_rate += h * acc[2];
  }
  // Floes with no pieces (outside the sea) drift, as with the explicit kicks
  // (by owner, each by its coupling owner, whose pieces it would be).
  for (std::size_t i = 0; i < floes.size(); ++i) {
    if (!constants_.dynamic[i] || fp.offsets[i] < fp.offsets[i + 1] || (by_owner() && !footprints_.owns(i))) continue;
    FloeState& st = floes.state[i];
    st.heave += h * st.heave_rate;
    st.pitch += h * st.pitch_rate;
    st.roll += h * st.roll_rate;
  }
  if (by_owner()) share_vertical(floes);
  // ... and the sea (by owner, the cells' sums through the routes, as a
  // product's).
  if (by_owner()) {
    scatter_to_slab(f, 1.0 / cell_area_);
    sea.midpoint_step(grid_work_, h);
    scatter_clear();
  } else {
    pressure_of_pieces(f);
    sea.midpoint_step(grid_work_, h);
    for (std::size_t k = 0; k < n; ++k) grid_work_[fp.cell[k]] = 0.0;
  }
  if (step_mean_loads_) step_mean_horizontal(floes, start);
}

void FloeSeaContact::share_vertical(Floes& floes) const {
  struct Vertical {
    double heave, pitch, roll, heave_rate, pitch_rate, roll_rate;
  };
  std::vector<Vertical> v(floes.size(), Vertical{});
  for (std::size_t i = 0; i < floes.size(); ++i)
    if (constants_.dynamic[i] && footprints_.owns(i)) {
      const FloeState& st = floes.state[i];
      v[i] = {st.heave, st.pitch, st.roll, st.heave_rate, st.pitch_rate, st.roll_rate};
    }
  comm_.complete_owned(v, footprints_.owners());
  for (std::size_t i = 0; i < floes.size(); ++i)
    if (constants_.dynamic[i] && !footprints_.owns(i)) {
      FloeState& st = floes.state[i];
      st.heave = v[i].heave;
      st.pitch = v[i].pitch;
      st.roll = v[i].roll;
      st.heave_rate = v[i].heave_rate;
      st.pitch_rate = v[i].pitch_rate;
      st.roll_rate = v[i].roll_rate;
    }
}

void FloeSeaContact::step_mean_horizontal(const Floes& floes, std::span<const FloeState> start) {
  // On the midpoint footprint: each piece's mean [delta]^+ over the step, the
  // spring's discrete gradient per unit stiffness (the header's "Horizontal
  // loads of the implicit step"), and the cells' sums of a_k u_k^2 with it.
  const Footprints& fp = footprints_.pieces();
  const std::span<const double> area0 = footprints_.reference_area();
  const std::span<const double> d1 = solver_.end();
  std::vector<double>& u = eval_.penetration;
  std::vector<double>& psi = eval_.psi;
  u.assign(fp.cell.size(), 0.0);
  psi.resize(fp.cell.size());
  std::fill(evaluated_.wetted.begin(), evaluated_.wetted.end(), 0.0);
  for_each_floe(order_, threads_, [&](std::uint32_t i) {
    // The midpoint slopes, read by the owner's horizontal loads only (its
    // step-start copy is current; another rank's may be stale).
    if (footprints_.owns(i)) {
      const FloeState& st = floes.state[i];
      evaluated_.slope[i] = 0.5 * Vec2{st.pitch + start[i].pitch, st.roll + start[i].roll};
    }
    double wet = 0.0;
    for (std::size_t k = fp.offsets[i]; k < fp.offsets[i + 1]; ++k) {
      psi[k] = subcell_weight(cells_[fp.cell[k]].coverage);
      if (fp.area[k] <= 0.0) continue;
      u[k] = step_force(1.0, 0.0, pieces_.start[k], d1[k]).f;
      wet += psi[k] * area0[k] * u[k];
    }
    evaluated_.wetted[i] = wet;
  });
  if (by_owner()) {
    // The cells' sums of a u^2 through the routes, as an evaluation's (no
    // force: the pressure it writes is zero). Its energy terms are not the
    // penalty energy's: the last evaluation's are kept.
    OwnerCells& o = owner_;
    std::vector<parallel::PieceKey> keys = std::move(o.energy_keys);
    std::vector<std::uint32_t> counts = std::move(o.energy_counts);
    std::vector<double> terms = std::move(o.energy_terms);
    const bool pending = energy_pending_;
    eval_.force.assign(fp.cell.size(), 0.0);
    sum_cells_by_owner(s_ * kappa_);
    o.energy_keys = std::move(keys);
    o.energy_counts = std::move(counts);
    o.energy_terms = std::move(terms);
    energy_pending_ = pending;
  } else {
    for (std::uint32_t i : order_)
      for (std::size_t k = fp.offsets[i]; k < fp.offsets[i + 1]; ++k)
        if (u[k] > 0.0) cells_[fp.cell[k]].sum += fp.area[k] * u[k] * u[k];
  }
  // Zero for a floe without pieces on this footprint; by owner its owner's
  // zero reaches every rank (share_owned).
  for (FloeSeaLoad& load : kicks_.loads) load.horizontal = Eigen::Vector3d::Zero();
  horizontal_loads(u);
  share_owned();
  for (std::size_t i = 0; i < kicks_.loads.size(); ++i) kicks_.step_horizontal[i] = kicks_.loads[i].horizontal;
  step_mean_pending_ = true;
}

}  // namespace floesim
