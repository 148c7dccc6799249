"""floesim.read_run: run files read without h5py agree with h5py's reading.

Run by ctest with Debian's python3 (which has h5py) and PYTHONPATH at the
built package; FLOESIM_SOURCE_DIR is the repository.
"""
import os
import tempfile
import unittest

import h5py
import numpy as np

import floesim

SRC = os.environ["FLOESIM_SOURCE_DIR"]
REF = os.path.join(SRC, "tests", "regression", "floes_on_sea.ref.h5")


class ReadRun(unittest.TestCase):
    def test_same_arrays_as_h5py(self):
        run = floesim.read_run(REF)
        with h5py.File(REF, "r") as f:
            for name, shape in run.datasets.items():
                np.testing.assert_array_equal(run[name], f[name][...].astype(float), err_msg=name)
                self.assertEqual(tuple(shape), f[name].shape)
            np.testing.assert_array_equal(run.time, f["time"][:])
            self.assertEqual(run.state.shape, (len(run.time), 3, 12))
            self.assertEqual(run.columns("/floes/state"), list(floesim.STATE_COLUMNS))
            self.assertEqual(run.energy_columns, [c.decode() if isinstance(c, bytes) else c
                                                  for c in f["diagnostics/energy"].attrs["columns"]])
            self.assertEqual(run.eta.shape, f["sea/eta"].shape)
            self.assertEqual(run.info["config"], f.attrs["config"])
            self.assertEqual(run.status, "complete")
        e = run.energies()
        np.testing.assert_allclose(e["total"], sum(v for k, v in e.items() if k != "total"), rtol=1e-12)

    def test_polygons_match_the_xdmf_vertices(self):
        # Two independent routes to the world outline: body vertices moved by
        # (x, y, yaw) from the state, and the writer's /xdmf/vertices.
        run = floesim.read_run(REF)
        offsets = run["/floes/offsets"].astype(int)
        for k in (0, len(run.time) // 2, -1):
            polys = run.polygons(k)
            world = run["/xdmf/vertices"][k]
            for i, p in enumerate(polys):
                np.testing.assert_allclose(p, world[offsets[i]:offsets[i + 1], :2], atol=1e-9)

    def test_config_attribute_rebuilds_the_run(self):
        run = floesim.read_run(REF)
        cfg = run.config
        self.assertEqual(cfg["sea"]["cells"], (32, 16))
        sim = floesim.Simulation(cfg)
        sim.run_until(run.time[-1])
        np.testing.assert_array_equal(sim.state, run.state[-1])

    def test_errors_name_file_and_dataset(self):
        run = floesim.read_run(REF)
        with self.assertRaises(floesim.InputError) as e:
            run["/floes/nothing"]
        self.assertIn("no dataset '/floes/nothing'", str(e.exception))
        self.assertIn(REF, str(e.exception))
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "not_a_run.h5")
            with h5py.File(path, "w") as f:
                f["x"] = [1.0]
            with self.assertRaises(ValueError) as e:
                floesim.read_run(path)
            self.assertIn("not a floesim run file", str(e.exception))
            with self.assertRaises(floesim.InputError):
                floesim.read_run(os.path.join(d, "missing.h5"))


if __name__ == "__main__":
    unittest.main()
