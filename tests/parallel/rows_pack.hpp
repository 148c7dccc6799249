#pragma once
// A pack of floes in rows of 6 as a TOML configuration, the set-up shared by
// held_ranks.cpp (a moored pack) and held_arrays_ranks.cpp (a moving pack of
// several shapes): floe k of row r and column c sits in its 60 m x 60 m cell
// at (60 c, 60 r) moved by up to 8 m in x and y, so that with `rows` rows the
// pack spans y from 0 to 60 rows m and every strip of a few ranks holds some;
// its velocity's components are drawn in [-speed, speed] m/s so that the
// floes collide and cross the strips' cuts (open plane, collisions with
// restitution 0.4 and friction 0.5, wind, current and Coriolis at 75 N).
#include <functional>
#include <random>
#include <sstream>
#include <string>

namespace floesim::test {

struct RowsPack {
  unsigned seed = 1;     // of the places' jitter and the velocities
  int rows = 10;         // of 6 floes
  double speed = 0.3;    // m/s, the largest velocity component
  double t_end = 600.0;  // s; dt_max = 10 s, one thread
  std::string wind = "[12.0, 4.0]", current = "[0.05, 0.1]";  // m/s, TOML arrays
};

// One floe's table: its polygon's vertices (TOML pairs without the outer
// brackets) and any more keys (whole lines) after its velocity.
struct RowFloe {
  std::string vertices, keys;
};

// The configuration's text; `floe(k, x, y)` gives floe k's table for its
// cell's corner (x, y) (m).
inline std::string rows_pack(const RowsPack& pack, const std::function<RowFloe(int, double, double)>& floe) {
  std::mt19937_64 rng(pack.seed);
  std::uniform_real_distribution<double> jitter(0.0, 8.0), speed(-pack.speed, pack.speed);
  std::ostringstream t;
  t << "[run]\ndt_max = 10\nt_end = " << pack.t_end << "\nthreads = 1\n"
    << "[contact]\nrestitution = 0.4\nfriction = 0.5\n"
    << "[forcing]\nwind = " << pack.wind << "\ncurrent = " << pack.current << "\nlatitude = 75.0\n";
  int k = 0;
  for (int row = 0; row < pack.rows; ++row)
    for (int col = 0; col < 6; ++col, ++k) {
      const double x = 60.0 * col + jitter(rng), y = 60.0 * row + jitter(rng);
      const RowFloe f = floe(k, x, y);
      const double vx = speed(rng), vy = speed(rng);
      t << "[[floes.floe]]\nvertices = [" << f.vertices << "]\nvelocity = [" << vx << ", " << vy << "]\n" << f.keys;
    }
  return t.str();
}

}  // namespace floesim::test
