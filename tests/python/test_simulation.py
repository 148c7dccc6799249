"""floesim.Simulation: collisions set up from Python obey the conservation
laws, run_until reproduces `floesim run`, and the floes, energies, LCP
counters and sea come back as arrays that agree with each other.

Run by ctest with Debian's python3 and PYTHONPATH at the built package;
FLOESIM_BINARY is the floesim command, FLOESIM_SOURCE_DIR the repository.
"""
import math
import os
import subprocess
import tempfile
import unittest

import numpy as np

import floesim

SRC = os.environ["FLOESIM_SOURCE_DIR"]
FLOESIM = os.environ["FLOESIM_BINARY"]

# Two floes in free space: no drag, no wind, so only collisions act.
FREE = """
[run]
t_end = 40.0
dt_max = 0.1
output_interval = 1.0

[forcing]
ocean_drag = 0.0
air_drag = 0.0
"""


def momenta(sim):
    """Linear momentum and angular momentum about the origin of the floes (from the state)."""
    s, m, inertia = sim.state, sim.mass, sim.inertia
    p = (m[:, None] * s[:, 3:5]).sum(axis=0)
    l_ = (inertia * s[:, 5] + m * (s[:, 0] * s[:, 4] - s[:, 1] * s[:, 3])).sum()
    return p, l_


def kinetic(sim):
    s, m, inertia = sim.state, sim.mass, sim.inertia
    return 0.5 * (m * (s[:, 3] ** 2 + s[:, 4] ** 2) + inertia * s[:, 5] ** 2).sum()


def polygon_area_centroid(p):
    x, y = p[:, 0], p[:, 1]
    xn, yn = np.roll(x, -1), np.roll(y, -1)
    cross = x * yn - xn * y
    a = cross.sum() / 2
    return a, np.array([((x + xn) * cross).sum(), ((y + yn) * cross).sum()]) / (6 * a)


class Collisions(unittest.TestCase):
    def test_oblique_collision_conserves_momentum(self):
        # Off-centre impact with friction: the floes spin up, but linear and
        # angular momentum (about any point) are conserved, and energy cannot grow.
        cfg = floesim.Config(FREE)
        cfg["contact"]["friction"] = 0.5
        cfg["contact"]["restitution"] = 0.5
        cfg.add_floe([[0, 0], [10, 0], [10, 10], [0, 10]], velocity=[1.0, 0.2], thickness=1.0)
        cfg.add_floe([[15, 4], [24, 3], [26, 12], [16, 14]], velocity=[-0.5, 0.0], thickness=2.0)
        sim = floesim.Simulation(cfg)
        p0, l0 = momenta(sim)
        e0 = kinetic(sim)
        sim.run_until(20.0)
        p1, l1 = momenta(sim)
        self.assertGreater(sim.lcp()["solves"], 0, "the floes collided")
        self.assertGreater(abs(sim.state[0, 5]), 1e-4, "the off-centre impact spun the floes")
        scale = np.abs(sim.mass[:, None] * sim.state[:, 3:5]).sum()
        np.testing.assert_allclose(p1, p0, rtol=0, atol=1e-9 * scale)
        self.assertAlmostEqual(l1, l0, delta=1e-9 * abs(l0) + 1e-6)
        self.assertLess(kinetic(sim), e0 * (1 + 1e-12))
        np.testing.assert_allclose(sim.momentum(), p1, rtol=1e-12, atol=1e-9 * scale)
        self.assertAlmostEqual(sim.energies()["floes_horizontal_kinetic"], kinetic(sim), delta=1e-9 * e0)

    def test_head_on_restitution(self):
        # Frictionless central impact of aligned squares: Newton/Poisson gives
        # the relative normal velocity after = -e times before.
        e = 0.6
        cfg = floesim.Config(FREE)
        cfg["contact"] = {"friction": 0.0, "restitution": e}
        cfg.add_floe([[0, 0], [10, 0], [10, 10], [0, 10]], velocity=[1.0, 0.0])
        cfg.add_floe([[15, 0], [25, 0], [25, 10], [15, 10]], velocity=[-0.5, 0.0], thickness=3.0)
        sim = floesim.Simulation(cfg)
        before = sim.state[0, 3] - sim.state[1, 3]
        sim.run_until(10.0)
        after = sim.state[0, 3] - sim.state[1, 3]
        self.assertAlmostEqual(after / before, -e, delta=1e-3)
        np.testing.assert_allclose(sim.state[:, 4:6], 0.0, atol=1e-9)   # no sideways motion, no spin


class MatchesTheCommandLine(unittest.TestCase):
    def test_run_until_equals_floesim_run(self):
        # A periodic pack with wind, Coriolis and many collisions: the states
        # after run_until at each output time equal the records of `floesim run`.
        case = os.path.join(SRC, "tests", "regression", "pack_wind_periodic.toml")
        with tempfile.TemporaryDirectory() as d:
            out = os.path.join(d, "out.h5")
            subprocess.run([FLOESIM, "run", case, "-q", "-o", out, "--until", "600"], check=True,
                           capture_output=True)
            run = floesim.read_run(out)
            sim = floesim.Simulation(floesim.Config.load(case))
            self.assertEqual(list(run.time), [0.0, 120.0, 240.0, 360.0, 480.0, 600.0])
            for k, t in enumerate(run.time):
                sim.run_until(t)
                self.assertEqual(sim.time, t)
                np.testing.assert_array_equal(sim.state, run.state[k], err_msg=f"record {k}, t = {t}")
                np.testing.assert_array_equal(list(sim.energies().values()), run.energy[k])
                np.testing.assert_array_equal(list(sim.lcp().values()), run.lcp[k])
            self.assertGreater(run.lcp[-1][0], 100, "the pack collides")
            self.assertEqual(list(sim.energies()), run.energy_columns)

    def test_splitting_floes_follow_their_numbers(self):
        # examples/percussion.toml: both floes crack and split. The simulation's
        # floes map to the run file's floe axis through ids, and the events
        # taken from Python are the run file's /events/fracture.
        case = os.path.join(SRC, "examples", "percussion.toml")
        with tempfile.TemporaryDirectory() as d:
            out = os.path.join(d, "out.h5")
            subprocess.run([FLOESIM, "run", case, "-q", "-o", out], check=True, capture_output=True)
            run = floesim.read_run(out)
            sim = floesim.Simulation(case)
            events = []
            for k, t in enumerate(run.time):
                sim.run_until(t)
                events.append(sim.take_fracture_events())
                np.testing.assert_array_equal(sim.state, run.state[k][sim.ids], err_msg=f"t = {t}")
                alive = ~np.isnan(run.state[k][:, 0])
                self.assertEqual(sorted(sim.ids), list(np.flatnonzero(alive)))
            self.assertEqual(sorted(sim.ids), [2, 3, 4, 5])    # 0 and 1 split into four pieces
            np.testing.assert_array_equal(np.vstack(events), run.fracture_events)
            self.assertEqual(run.fracture_events.shape, (2, len(floesim.FRACTURE_EVENT_COLUMNS)))
            polys = run.polygons(-1)
            self.assertEqual([p is None for p in polys], [True, True, False, False, False, False])

    def test_collisions_in_the_run_file_are_the_solver_impulses(self):
        # tests/regression/two_floes_collide.toml with [run] record_collisions:
        # the run file's /events/collisions are the rows Python takes step by
        # step, and the impacts' impulses are the floes' changes of momentum.
        with open(os.path.join(SRC, "tests", "regression", "two_floes_collide.toml")) as f:
            text = f.read().replace("[run]\n", "[run]\nrecord_collisions = true\n", 1)
        with tempfile.TemporaryDirectory() as d:
            case = os.path.join(d, "case.toml")
            with open(case, "w") as f:
                f.write(text)
            out = os.path.join(d, "out.h5")
            subprocess.run([FLOESIM, "run", case, "-q", "-o", out], check=True, capture_output=True)
            run = floesim.read_run(out)
            sim = floesim.Simulation(case)
            rows = []
            for t in run.time:
                sim.run_until(t)
                rows.append(sim.take_collision_events())
            rows = np.vstack(rows)
            np.testing.assert_array_equal(rows, run.collision_events)
            cols = list(floesim.COLLISION_EVENT_COLUMNS)
            self.assertEqual(cols, ["time", "floe_a", "floe_b", "normal", "x", "y", "resting"])
            impacts = rows[rows[:, cols.index("resting")] == 0]
            self.assertGreaterEqual(len(impacts), 1)
            self.assertTrue(np.all(rows[:, cols.index("normal")] > 0))
            self.assertTrue(np.all(rows[:, 1] == 0) and np.all(rows[:, 2] == 1))
            # The first impact falls between the records where floe 0's velocity
            # jumps most (ocean drag changes it slowly otherwise).
            vx = run.state[:, 0, floesim.STATE_COLUMNS.index("vx")]
            k = int(np.argmax(np.abs(np.diff(vx))))
            self.assertGreater(impacts[0, 0], run.time[k])
            self.assertLessEqual(impacts[0, 0], run.time[k + 1])

    def test_run_writes_a_run_file(self):
        cfg = floesim.Config.load(os.path.join(SRC, "tests", "regression", "two_floes_collide.toml"))
        with tempfile.TemporaryDirectory() as d:
            sim = floesim.Simulation(cfg)
            summary = sim.run(os.path.join(d, "a.h5"))
            self.assertEqual(summary["status"], "complete")
            self.assertEqual(summary["records"], 11)
            run = floesim.read_run(summary["output"])
            np.testing.assert_array_equal(run.state[-1], sim.state)
            ref = os.path.join(SRC, "tests", "regression", "two_floes_collide.ref.h5")
            self.assertTrue(floesim.compare_runs(summary["output"], summary["output"])["equal"])
            # the committed reference holds the same case
            cmp = floesim.compare_runs(summary["output"], ref)
            self.assertTrue(cmp["equal"], cmp["differences"])
            # run() from an advanced simulation: records from there on the same schedule
            sim = floesim.Simulation(cfg)
            sim.run_until(5.0)
            sim.run(os.path.join(d, "b.h5"))
            np.testing.assert_array_equal(floesim.read_run(os.path.join(d, "b.h5")).time,
                                          [5.0, 6.0, 8.0, 10.0, 12.0, 14.0, 16.0, 18.0, 20.0])


class Arrays(unittest.TestCase):
    def setUp(self):
        self.cfg = floesim.Config.load(os.path.join(SRC, "tests", "regression", "floes_on_sea.toml"))

    def test_step(self):
        sim = floesim.Simulation(self.cfg)
        dt = sim.step()
        self.assertEqual(sim.time, dt)
        self.assertLessEqual(dt, self.cfg["run"]["dt_max"])
        steps = 1
        while sim.time < 0.07:             # steps may be shortened (collisions, the floe-sea
            before = sim.time              # penalty's stability limit) but never pass t_stop
            self.assertLessEqual(before + sim.step(0.07), 0.07 + 1e-15)
            steps += 1
        self.assertEqual(sim.time, 0.07)   # and land on it exactly
        self.assertEqual(sim.steps, steps)
        with self.assertRaises(floesim.RunError) as e:
            sim.step(0.07)                 # no time left
        self.assertIsInstance(e.exception, RuntimeError)
        self.assertIn("no time left", str(e.exception))

    def test_polygons_agree_with_state_and_area(self):
        sim = floesim.Simulation(self.cfg)
        sim.run_until(3.0)
        polys = sim.polygons()
        self.assertEqual(len(polys), sim.floe_count)
        for i, p in enumerate(polys):
            a, c = polygon_area_centroid(p)
            self.assertAlmostEqual(a, sim.area[i], delta=1e-9 * a)
            np.testing.assert_allclose(c, sim.state[i, :2], atol=1e-9)

    def test_energies_and_sea(self):
        sim = floesim.Simulation(self.cfg)
        e = sim.energies()
        ref = floesim.read_run(os.path.join(SRC, "tests", "regression", "floes_on_sea.ref.h5"))
        self.assertEqual(list(e), ref.energy_columns)     # the run file's columns, in order
        self.assertTrue({"floes_horizontal_kinetic", "sea_kinetic", "sea_potential"} <= set(e), list(e))
        self.assertEqual(list(e)[-1], "total")
        self.assertAlmostEqual(e["total"], sum(v for k, v in e.items() if k != "total"), delta=1e-9 * e["total"])
        self.assertTrue(sim.has_sea)
        eta = sim.sea_elevation()
        self.assertEqual(eta.shape, (16, 32))       # (ny, nx)
        x, y = sim.sea_coordinates()
        self.assertEqual((len(x), len(y)), (32, 16))
        self.assertAlmostEqual(x[0], 1.0)            # cell centres: 64 m / 32 cells

    def test_regular_wave_rms(self):
        # A regular wave of amplitude A sampled on a grid holding whole
        # wavelengths has mean eta^2 = A^2 / 2 exactly (discrete orthogonality),
        # at every time for the free linear sea (no floes here).
        cfg = floesim.Config("""
[run]
dt_max = 0.05
[sea]
model = "spectral"
size = [64.0, 32.0]
cells = [32, 16]
depth = 20.0
[sea.waves]
kind = "regular"
amplitude = 0.2
wavelength = 16.0
direction = 0.0
""")
        sim = floesim.Simulation(cfg)
        for t in (0.0, 1.3, 4.0):
            sim.run_until(t)
            eta = sim.sea_elevation()
            self.assertAlmostEqual(float(np.mean(eta ** 2)), 0.2 ** 2 / 2, delta=1e-9)
            np.testing.assert_allclose(eta, eta[0:1, :].repeat(16, axis=0), atol=1e-12)  # crests along y

    def test_one_dimensional_sea(self):
        cfg = floesim.Config('[sea]\nmodel = "spectral"\ndims = 1\ncells = [64, 1]\n'
                             '[sea.waves]\nkind = "regular"\namplitude = 0.1\nwavelength = 25.0\n')
        eta = floesim.Simulation(cfg).sea_elevation()
        self.assertEqual(eta.shape, (64,))

    def test_bad_floe_is_an_input_error(self):
        cfg = floesim.Config("")
        cfg.add_floe([[0, 0], [1, 0], [2, 0]])           # collinear: checked when the floes are built
        with self.assertRaises(floesim.InputError) as e:
            floesim.Simulation(cfg)
        self.assertIn("[[floes.floe]] 0", str(e.exception))


if __name__ == "__main__":
    unittest.main()
