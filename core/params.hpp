#pragma once
// Run parameters as plain data: one struct per configuration section
// (docs/config.md lists every key, its default and its range). The TOML reader
// in core/config.cpp fills these; solvers and layers take the part they need.
// SI units throughout.

#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace floesim {

struct RunParams {
  double t_end = 100.0;           // s, simulated end time
  double dt_max = 0.05;           // s, upper bound on the step (the loop may take smaller)
  double output_interval = 1.0;   // s, time between records in the run file
  unsigned long seed = 1;         // seed of every random choice of the run
  // Threads for the per-floe and per-piece phases (0: one per core). The
  // results do not depend on it: an execution setting, not written to run files.
  int threads = 0;
  // s, simulated time between checkpoints in the run file (/checkpoint, for
  // `floesim run --restart`); 0: only at the end, on an interruption and on
  // a run error. An execution setting like threads: results do not depend on it.
  double checkpoint_interval = 0.0;
  // Record every collision solve's impulses, per pair of floes, in the run
  // file (/events/collisions; docs/formats.md).
  bool record_collisions = false;
  // On several ranks (docs/parallel.md, "The advance from the rank's part"):
  // each rank advances its clusters from its own part of the detection and
  // the pairs routed to it, rather than from the whole detection gathered to
  // every rank. Like threads, an execution setting: the results are the same
  // bits either way, and it is not written to run files. Off: from the
  // whole detection (advance_by_owner), the path of the runs that keep the
  // impulse record.
  bool advance_on_part = true;
  // The run file written crash-safe (two copies, published whole at each
  // flush: a kill at any instant leaves a whole file) or in place (half the
  // disk and the writes; a kill during a flush may spoil the file);
  // docs/formats.md, "A killed run's file". Like threads, an execution
  // setting: the file's content is the same either way, and it is not
  // written to run files.
  bool crash_safe_output = true;
};

enum class SeaModel { none, spectral, bem };
enum class WaveKind { none, regular, standing, jonswap };

struct WaveParams {
  WaveKind kind = WaveKind::none;
  double amplitude = 0.0;         // m (regular, standing)
  double wavelength = 0.0;        // m (regular, standing); 0 = derived from period
  double period = 0.0;            // s; 0 = derived from wavelength
  double direction = 0.0;         // degrees from +x
  double hs = 0.0;                // m, significant wave height (jonswap)
  double tp = 0.0;                // s, peak period (jonswap)
  double gamma = 3.3;             // peak enhancement (jonswap)
  double spreading = 0.0;         // directional spreading exponent s of cos^2s (0 = none)
};

// Tank-like runs (spectral sea): a zone at x = 0 that relaxes the surface
// toward the target wave of [sea.waves] and an absorbing zone at the far end.
struct TankConfig {
  bool enabled = false;
  double generation_length = 0.0;  // m; 0 = 3 target wavelengths
  double absorption_length = 0.0;  // m; 0 = 2 target wavelengths
  double rate = 0.0;               // 1/s, relaxation rate; 0 = 4 omega of the target
  double ramp_periods = 3.0;       // target amplitude ramp, in wave periods
};

struct SeaParams {
  SeaModel model = SeaModel::none;
  int dims = 2;                                   // 1 long-crested (x only), 2 full plane
  std::array<double, 2> size = {200.0, 200.0};    // m
  std::array<int, 2> cells = {128, 128};
  double depth = std::numeric_limits<double>::infinity();  // m; inf = deep water
  double rho = 1025.0;            // kg/m^3, water density (also for drag)
  double g = 9.81;                // m/s^2
  double sigma = 0.073;           // N/m, surface tension
  std::vector<std::array<double, 2>> bottom;      // bem: bottom polyline (x, z), z < 0
  // bem, dims = 2: a bottom z(x, y) (m, every value < 0) given on a uniform grid
  // of bottom_nx x bottom_ny nodes spanning [0, Lx] x [0, Ly], x fastest,
  // read at load from bottom_file (a CSV; docs/config.md) and bilinear between nodes.
  std::string bottom_file;
  int bottom_nx = 0, bottom_ny = 0;
  std::vector<double> bottom_grid;
  // bem, dims = 2: the modes kept. 0: all of them (the dense eigenproblem);
  // n > 0: the n lowest (Lanczos; fluid/lowest_modes.hpp, docs/sea.md).
  int bem_modes = 0;
  // bem, dims = 2, bem_modes > 0: the dropped modes' static response to the
  // pressure held over a step is part of the surface (fluid/static_correction.hpp;
  // the floes need the implicit integrator for it).
  bool bem_static_correction = false;
  WaveParams waves;
  TankConfig tank;
};

struct ContactParams {
  double collision_distance = 0.01;  // m
  double restitution = 0.4;          // Poisson restitution e in [0, 1]
  double friction = 0.7;             // Coulomb mu >= 0
  double rest_speed = 0.01;          // m/s: contacts approaching no faster rest (contact::ImpulseOptions::rest_speed)
  bool periodic = false;             // a torus made from `box`
  std::array<double, 4> box = {0.0, 0.0, 0.0, 0.0};  // xmin, xmax, ymin, ymax (m); empty: the pack's window
  std::string dump_failed_lcps;      // an existing folder for the LCPs the solver could not solve ("": none)
};

enum class PenaltyLaw { strong, weak, blend };
// How floes' footprints are weighed on the sea grid (coupling/footprint.hpp):
// automatic = tent on periodic grids, cell in walled basins.
enum class FootprintChoice { automatic, cell, tent };
// How the penalty spring between floes and sea is integrated in time
// (docs/coupling.md, "The implicit step"): explicit kicks limited to
// 0.5 / omega_pen, or the implicit midpoint with the discrete gradient of the
// penalty energy, whose step is limited by dt_max alone.
enum class CouplingIntegrator { explicit_kicks, implicit };
// Implicit integrator: the horizontal loads of a step (docs/coupling.md,
// "Horizontal loads of the implicit step"): the step's mean (the stiff
// floe–water mode's alternating part cancels in it; the energy is kept to
// O(dt^2)), or the loads at the step's ends (the exact gradient of the
// energy there: the energy is kept closely, but that alternating part drives
// the floes; a thin floe's surge on waves came out twice too large).
enum class HorizontalLoads { step_mean, step_ends };

struct CouplingParams {
  PenaltyLaw law = PenaltyLaw::strong;
  double stiffness = 1000.0;      // K: penalty stiffness kappa = K rho_w g
  double blend = 1.0;             // s in [0, 1] (blend law)
  double restitution = -1.0;      // blend law: target e; < 0 means "use blend"
  // false: the floes start at rest on the sea (the static problem is solved,
  // on the initial waves); true: the floes' heave and heave rate
  // are as given ([[floes.floe]] heave, heave_rate), e.g. for a drop test.
  bool start_given = false;
  FootprintChoice footprint = FootprintChoice::automatic;
  // Cells a floe may move before its footprint is rebuilt; in between it is
  // moved to first order (coupling/moving_footprint.hpp). 0: rebuilt at every
  // evaluation.
  double footprint_reach = 0.0;
  CouplingIntegrator integrator = CouplingIntegrator::explicit_kicks;
  HorizontalLoads horizontal_loads = HorizontalLoads::step_mean;
  // Implicit integrator: the Newton iteration on the end-of-step penetrations
  // stops when every piece's residual is below newton_tolerance times the
  // thickest floe's draft; each Newton step's conjugate gradients stop at a
  // relative residual between cg_tolerance and cg_forcing, looser far from
  // the solution (inexact Newton: coupling/penalty_step.hpp).
  double newton_tolerance = 1e-8;
  double cg_tolerance = 1e-10;
  double cg_forcing = 1e-2;
  int max_newton = 40;
  int max_cg = 500;
};

enum class SeriesInterpolation { linear, previous };

struct ForcingParams {
  std::array<double, 2> current = {0.0, 0.0};  // m/s
  std::array<double, 2> wind = {0.0, 0.0};     // m/s, 10 m wind
  std::string series;             // optional CSV: t_s,wind_u,wind_v,current_u,current_v
  // linear: interpolate between rows; previous: hold each row until the next
  // (FloeDyn's per-minute forcing). Before the first row: the first row; after
  // the last: the last row.
  SeriesInterpolation series_interpolation = SeriesInterpolation::linear;
  double coriolis = 0.0;          // f, 1/s (set from latitude when that is given)
  double ocean_drag = 5.0e-3;     // C_w (a floe's own value overrides it)
  double air_drag = 1.7e-3;       // C_a
  double air_density = 1.341;     // rho_a, kg/m^3
};

enum class FractureCriterion { stress, griffith };
// How floes are meshed (contact/fracture/mesh.hpp): cgal (the default),
// CGAL's refinement for every floe; auto, the lattice mesher for convex floes
// whose lattice mesh meets the size and angle bounds and CGAL's refinement for
// the rest (faster meshing; a lattice has directions, docs/fracture.md).
enum class FractureMesher { automatic, cgal };

struct FractureLoad {
  std::array<double, 2> point = {0.0, 0.0};    // m, world
  std::array<double, 2> force = {0.0, 0.0};    // N (static load)
  std::array<double, 2> impulse = {0.0, 0.0};  // N s (percussion)
  bool is_impulse = false;
};

struct FractureParams {
  bool enabled = false;
  FractureCriterion criterion = FractureCriterion::stress;
  double strength = 0.5e6;        // Pa
  double toughness = 1.5;         // J/m^2 (griffith)
  double young = 6.0e9;           // Pa
  double poisson = 0.3;
  bool split = false;
  double mesh_size = 2.0;         // m
  double duration = 0.01;         // s
  double load_radius = 0.0;       // m, loads spread over this radius; 0: the floe's thickness
  double min_fragment_area = 0.0; // m^2, no split leaves a piece smaller; 0: mesh_size^2
  double elements_across = 0.0;   // a floe's mesh size is at most its diameter / this; 0: mesh_size only
  FractureMesher mesher = FractureMesher::cgal;
  std::vector<FractureLoad> loads;
};

}  // namespace floesim
