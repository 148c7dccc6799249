"""floesim.Simulation.from_run: the simulation at a run file's checkpoint
steps on exactly as the run would have (docs/formats.md, "Checkpoint and
restart"); states, energies, LCP counters and the sea are equal with ==.

Run by ctest with Debian's python3 and PYTHONPATH at the built package.
"""
import os
import sys
import tempfile
import unittest

import h5py
import numpy as np

import floesim

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
import restart_scenarios  # noqa: E402

# Floes on a spectral sea with waves and wind, colliding (shared with the
# command line's restart test).
WAVES = restart_scenarios.WAVES.format(t_end=4.0, coupling='law = "blend"\nrestitution = 0.3\nstiffness = 100.0')


def snapshot(sim):
    return {"time": sim.time, "state": sim.state.copy(), "energies": sim.energies(), "lcp": sim.lcp(),
            "eta": np.array(sim.sea_elevation(), copy=True), "ids": np.array(sim.ids, copy=True)}


class FromRun(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="floesim_from_run_")
        self.config = floesim.Config(WAVES, name="waves")

    def assert_same(self, a, b, what):
        self.assertEqual(a["time"], b["time"], what)
        np.testing.assert_array_equal(a["state"], b["state"], err_msg=what)
        self.assertEqual(a["energies"], b["energies"], what)
        self.assertEqual(a["lcp"], b["lcp"], what)
        np.testing.assert_array_equal(a["eta"], b["eta"], err_msg=what)
        np.testing.assert_array_equal(a["ids"], b["ids"], err_msg=what)

    def test_steps_on_identically(self):
        path = os.path.join(self.dir, "half.h5")
        floesim.Simulation(self.config).run(path, until=2.0)
        self.assertEqual(floesim.RunFile(path).info["checkpoint_time"], 2.0)
        reference = floesim.Simulation(self.config)
        reference.run_until(2.0)
        sim = floesim.Simulation.from_run(path)
        self.assertEqual(sim.time, 2.0)
        self.assertEqual(sim.steps, reference.steps)
        self.assert_same(snapshot(sim), snapshot(reference), "at the checkpoint")
        # Step by step with the same stops, then on to 4 s.
        for _ in range(7):
            self.assertEqual(sim.step(3.0), reference.step(3.0))
        self.assert_same(snapshot(sim), snapshot(reference), "after 7 steps")
        sim.run_until(4.0)
        reference.run_until(4.0)
        self.assert_same(snapshot(sim), snapshot(reference), "at 4 s")
        self.assertGreater(sim.lcp()["solves"], 0)  # the floes collided

    def test_file_without_checkpoint(self):
        path = os.path.join(self.dir, "old.h5")
        floesim.Simulation(self.config).run(path, until=1.0)
        with h5py.File(path, "a") as f:
            del f["checkpoint"]
        with self.assertRaisesRegex(floesim.InputError, "old.h5: the run has no checkpoint"):
            floesim.Simulation.from_run(path)


if __name__ == "__main__":
    unittest.main()
