// floesim_bench_sea_step: cost of a forced spectral step against the cost of
// the FFTs it performs, on 2-D boxes of 256^2, 512^2 and 1024^2 cells.
//
// A forced step as the coupling loop runs it: kick(p(t), dt/2) [one r2c],
// flow(dt) [modal rotation], elevation() [one c2r, the new surface that the
// next pressure depends on], kick(p(t + dt), dt/2) [one r2c]. Its FFTs alone
// are timed with plans of the same size and flags (FFTW_MEASURE). Each figure
// is the minimum of `repeats` timings after a warm-up. CSV on stdout.
// Columns: fft_* the bare transforms; step_ffts_ms = 2 r2c + 1 c2r; step_ms the
// forced step; ratio = step / its FFTs; flow_ms a flow alone (rotation, staging
// q for the c2r); kick_ms a kick alone (r2c; its modal update is deferred and
// fused into the next flow); in_step_* the four phases timed inside the step
// sequence; ratio_in_step = their sum / (kick1 + elevation + kick2), the step
// against its FFTs as they run inside it (cache-cold, unlike the bare FFTs);
// flow_new_dt_ms a flow whose dt differs from the previous one (one sin/cos per mode).
//
// usage: floesim_bench_sea_step [max_cells = 1024] [repeats = 30]

#include <fftw3.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "fluid/sea.hpp"
#include "fluid/spectral.hpp"

using namespace floesim;
using namespace floesim::fluid;
using clock_type = std::chrono::steady_clock;

namespace {

// Minimum over `repeats` timings after a warm-up: the machine is shared, and the
// minimum is the figure least disturbed by other processes.
template <class F>
double min_ms(int repeats, F&& f) {
  f();  // warm-up
  double best = 1e300;
  for (int r = 0; r < repeats; ++r) {
    const auto a = clock_type::now();
    f();
    best = std::min(best, std::chrono::duration<double, std::milli>(clock_type::now() - a).count());
  }
  return best;
}

}  // namespace

int main(int argc, char** argv) {
  const int max_cells = argc > 1 ? std::atoi(argv[1]) : 1024;
  const int repeats = argc > 2 ? std::atoi(argv[2]) : 30;
  std::printf("cells,modes,fft_r2c_ms,fft_c2r_ms,step_ffts_ms,step_ms,ratio,flow_ms,kick_ms,"
              "in_step_kick1_ms,in_step_flow_ms,in_step_elevation_ms,in_step_kick2_ms,ratio_in_step,"
              "flow_new_dt_ms\n");
  for (int n = 256; n <= max_cells; n *= 2) {
    SeaParams p;
    p.model = SeaModel::spectral;
    p.dims = 2;
    p.size = {200.0, 200.0};
    p.cells = {n, n};
    p.depth = 50.0;
    SeaOptions opt;
    opt.measure_fft_plans = true;
    SpectralSea sea(p, opt);
    const auto& g = sea.grid();
    AlignedVector p0(g.size()), p1(g.size());  // the storage the coupling should use for pressures
    for (std::size_t i = 0; i < g.size(); ++i) {
      p0[i] = 100.0 * std::sin(0.001 * static_cast<double>(i));
      p1[i] = 100.0 * std::cos(0.001 * static_cast<double>(i));
    }
    const double dt = 0.05;

    // The FFTs alone, same sizes and flags.
    const std::size_t nc = static_cast<std::size_t>(n) * (n / 2 + 1);
    double* real = fftw_alloc_real(g.size());
    fftw_complex* spec = fftw_alloc_complex(nc);
    fftw_plan r2c = fftw_plan_dft_r2c_2d(n, n, real, spec, FFTW_MEASURE);
    fftw_plan c2r = fftw_plan_dft_c2r_2d(n, n, spec, real, FFTW_MEASURE);
    std::copy(p0.begin(), p0.end(), real);
    const double t_r2c = min_ms(repeats, [&] { fftw_execute(r2c); });
    const double t_c2r = min_ms(repeats, [&] {
      for (std::size_t c = 0; c < nc; ++c) spec[c][0] = spec[c][1] = 1.0;  // c2r destroys input
      fftw_execute(c2r);
    });
    const double t_fill = min_ms(repeats, [&] {
      for (std::size_t c = 0; c < nc; ++c) spec[c][0] = spec[c][1] = 1.0;
    });
    fftw_destroy_plan(r2c);
    fftw_destroy_plan(c2r);
    fftw_free(real);
    fftw_free(spec);
    const double ffts = 2.0 * t_r2c + (t_c2r - t_fill);

    double sink = 0.0;
    const double t_step = min_ms(repeats, [&] {
      sea.kick(p0, 0.5 * dt);
      sea.flow(dt);
      sink += sea.elevation()[0];
      sea.kick(p1, 0.5 * dt);
    });
    // The same step with each phase timed in sequence (minimum per phase).
    std::array<double, 4> phase{1e300, 1e300, 1e300, 1e300};
    for (int r = 0; r < repeats; ++r) {
      auto t0 = clock_type::now();
      sea.kick(p0, 0.5 * dt);
      auto t1 = clock_type::now();
      sea.flow(dt);
      auto t2 = clock_type::now();
      sink += sea.elevation()[0];
      auto t3 = clock_type::now();
      sea.kick(p1, 0.5 * dt);
      auto t4 = clock_type::now();
      const std::array<double, 4> d = {std::chrono::duration<double, std::milli>(t1 - t0).count(),
                                       std::chrono::duration<double, std::milli>(t2 - t1).count(),
                                       std::chrono::duration<double, std::milli>(t3 - t2).count(),
                                       std::chrono::duration<double, std::milli>(t4 - t3).count()};
      for (int i = 0; i < 4; ++i) phase[i] = std::min(phase[i], d[i]);
    }
    const double t_flow = min_ms(repeats, [&] { sea.flow(dt); });
    double alt = dt;  // a new dt every call: the rotation coefficients are recomputed
    const double t_flow_new_dt = min_ms(repeats, [&] {
      alt = alt == dt ? 0.9 * dt : dt;
      sea.flow(alt);
    });
    const double t_kick = min_ms(repeats, [&] { sea.kick(p0, 0.0); });
    // In the step a kick is its r2c (the modal update is deferred) and the
    // elevation is its c2r (q is staged by the flow): their sum is the step's
    // FFT time as it runs there, with the caches as the step leaves them.
    const double in_step_ffts = phase[0] + phase[2] + phase[3];
    const double in_step = phase[0] + phase[1] + phase[2] + phase[3];
    std::printf("%d,%zu,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f\n", n,
                sea.modes().modes(), t_r2c, t_c2r - t_fill, ffts, t_step, t_step / ffts, t_flow,
                t_kick, phase[0], phase[1], phase[2], phase[3], in_step / in_step_ffts,
                t_flow_new_dt);
    std::fflush(stdout);
    if (sink == 12345.0) std::printf("#\n");
  }
  return 0;
}
