"""floesim.Config: loading, reading values in force, checked writes, errors.

Run by ctest with Debian's python3 and PYTHONPATH at the built package
(tests/python/CMakeLists.txt); FLOESIM_SOURCE_DIR is the repository.
"""
import math
import os
import tempfile
import unittest

import numpy as np

import floesim

SRC = os.environ["FLOESIM_SOURCE_DIR"]
EXAMPLE = os.path.join(SRC, "tests", "regression", "pack_wind_periodic.toml")


class LoadAndRead(unittest.TestCase):
    def test_file_values_and_defaults(self):
        cfg = floesim.Config.load(EXAMPLE)
        self.assertEqual(cfg["run"]["t_end"], 1200.0)              # written in the file
        self.assertEqual(cfg["forcing"]["wind"], (18.0, 6.0))      # arrays read as tuples
        self.assertEqual(cfg["contact"]["collision_distance"], 0.01)  # a default (key absent)
        self.assertEqual(cfg["coupling"]["law"], "strong")         # a default ([coupling] absent)
        self.assertEqual(cfg["sea"]["depth"], math.inf)            # default: deep water
        self.assertEqual(len(cfg["floes"]["floe"]), 16)
        self.assertEqual(cfg["floes"]["floe"][1]["thickness"], 0.95)
        # latitude = 75 is resolved into f = 2 Omega sin(75 deg)
        self.assertAlmostEqual(cfg.resolved()["forcing"]["coriolis"],
                               2 * 7.2921e-5 * math.sin(math.radians(75.0)), places=15)

    def test_unknown_key_to_read_is_a_key_error(self):
        cfg = floesim.Config("")
        with self.assertRaises(KeyError) as e:
            cfg["run"]["t_endd"]
        self.assertIn("run.t_endd", str(e.exception))

    def test_missing_file(self):
        with self.assertRaises(FileNotFoundError):
            floesim.Config.load(os.path.join(SRC, "no_such_config.toml"))

    def test_errors_in_text_name_the_line_and_key(self):
        with self.assertRaises(floesim.InputError) as e:
            floesim.Config("[run]\nt_end = -1\n", name="mine.toml")
        self.assertIsInstance(e.exception, ValueError)
        self.assertEqual(str(e.exception), "mine.toml:2: key '[run] t_end': expected a time >= 0 (s), got -1")
        with self.assertRaises(floesim.InputError) as e:
            floesim.Config("[run\n")
        self.assertIn("not valid TOML", str(e.exception))


class Write(unittest.TestCase):
    def test_set_value_reaches_the_resolved_configuration(self):
        cfg = floesim.Config.load(EXAMPLE)
        cfg["run"]["t_end"] = 10
        cfg["coupling"]["stiffness"] = 250.0        # a section the file does not have
        self.assertEqual(cfg["run"]["t_end"], 10)
        self.assertEqual(cfg.resolved()["run"]["t_end"], 10.0)
        self.assertEqual(cfg.resolved()["coupling"]["stiffness"], 250.0)
        self.assertIn("stiffness = 250.0", cfg.resolved_toml())
        sim = floesim.Simulation(cfg)
        self.assertIn("t_end = 10.0", sim.resolved_toml())

    def test_bad_key_raises_naming_it_and_changes_nothing(self):
        cfg = floesim.Config.load(EXAMPLE)
        before = cfg.resolved_toml()
        with self.assertRaises(floesim.InputError) as e:
            cfg["run"]["t_endd"] = 3
        msg = str(e.exception)
        self.assertIn("key '[run] t_endd': unknown key", msg)
        self.assertTrue(msg.startswith(EXAMPLE + ": "), msg)    # the file, without a misleading line
        self.assertNotIn("t_endd", cfg.to_dict()["run"])
        self.assertEqual(cfg.resolved_toml(), before)

    def test_bad_value_names_key_and_range(self):
        cfg = floesim.Config("")
        with self.assertRaises(ValueError) as e:
            cfg["contact"]["restitution"] = 1.5
        self.assertIn("key '[contact] restitution': expected a restitution in [0, 1], got 1.5", str(e.exception))
        with self.assertRaises(floesim.InputError) as e:
            cfg["sea"]["cells"] = [64.5, 64]
        self.assertIn("[sea] cells", str(e.exception))
        with self.assertRaises(floesim.InputError) as e:
            cfg["run"]["t_end"] = object()
        self.assertIn("run.t_end", str(e.exception))

    def test_changes_valid_only_together_go_through_update(self):
        cfg = floesim.Config("")
        with self.assertRaises(floesim.InputError):   # a tank needs a spectral sea and a regular wave
            cfg["sea"]["tank"] = {"enabled": True}
        cfg.update({"sea": {"model": "spectral", "tank": {"enabled": True},
                            "waves": {"kind": "regular", "amplitude": 0.1, "wavelength": 20.0}}})
        self.assertTrue(cfg["sea"]["tank"]["enabled"])
        self.assertEqual(cfg["sea"]["waves"]["wavelength"], 20.0)

    def test_floes_from_python(self):
        cfg = floesim.Config("[run]\nt_end = 1\n")
        cfg.add_floe([[0, 0], [10, 0], [10, 10], [0, 10]], velocity=[1, 0])
        cfg.add_floe(np.array([[20.0, 0.0], [30.0, 0.0], [25.0, 8.0]]), thickness=2.0)
        cfg["floes"]["floe"][1]["velocity"] = np.array([-0.5, 0.25])   # NumPy values are accepted
        self.assertEqual(cfg["floes"]["floe"][1]["velocity"], (-0.5, 0.25))
        self.assertEqual(cfg.to_dict()["floes"]["floe"][1]["velocity"], [-0.5, 0.25])
        with self.assertRaises(floesim.InputError) as e:
            cfg["floes"]["floe"][0]["colour"] = "white"
        self.assertIn("[floes.floe] colour", str(e.exception))
        sim = floesim.Simulation(cfg)
        self.assertEqual(sim.floe_count, 2)
        np.testing.assert_allclose(sim.state[1, 3:5], [-0.5, 0.25])
        np.testing.assert_allclose(sim.thickness, [1.0, 2.0])

    def test_delete_goes_back_to_the_default(self):
        cfg = floesim.Config("[contact]\nfriction = 0.1\n")
        del cfg["contact"]["friction"]
        self.assertEqual(cfg["contact"]["friction"], 0.7)

    def test_values_survive_the_round_trip_exactly(self):
        cfg = floesim.Config("[run]\nt_end = 1e-4\n")  # at most 1e9 steps of dt_max = 2^-40 s
        for v in (0.1, 1.0 / 3.0, 2.0 ** -40, 123456.789e10):
            cfg["run"]["dt_max"] = v
            self.assertEqual(cfg.resolved()["run"]["dt_max"], v)
        cfg["sea"]["depth"] = math.inf
        self.assertEqual(cfg.resolved()["sea"]["depth"], math.inf)

    def test_relative_paths_follow_the_file(self):
        with tempfile.TemporaryDirectory() as d:
            with open(os.path.join(d, "f.csv"), "w") as f:
                f.write("t_s,wind_u,wind_v,current_u,current_v\n0,1,0,0,0\n")
            with open(os.path.join(d, "c.toml"), "w") as f:
                f.write('[forcing]\nseries = "f.csv"\n')
            cfg = floesim.Config.load(os.path.join(d, "c.toml"))
            self.assertEqual(cfg["forcing"]["series"], "f.csv")
            self.assertEqual(cfg.resolved()["forcing"]["series"], os.path.join(d, "f.csv"))
            cfg["run"]["t_end"] = 2               # still resolved against the file's folder
            floesim.Simulation(cfg)
            with self.assertRaises(floesim.InputError) as e:
                floesim.Config('[forcing]\nseries = "f.csv"\n', base_dir=SRC)
            self.assertIn("file not found", str(e.exception))


class BadInputAtLoad(unittest.TestCase):
    """Issue 17: a malformed forcing series killed the interpreter (a double free in
    floesim.Simulation); it is an InputError at load now, naming the CSV line."""

    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="floesim_badload_")
        self.csv = os.path.join(self.dir, "wind.csv")
        with open(self.csv, "w") as f:
            f.write("t_s,wind_u,wind_v,current_u,current_v\n0,1,0,0,0\n60,2,0,0,0\n30,3,0,0,0\n")

    def test_bad_series_in_a_file(self):
        path = os.path.join(self.dir, "case.toml")
        with open(path, "w") as f:
            f.write('[forcing]\nseries = "wind.csv"\n')
        with self.assertRaises(floesim.InputError) as e:
            floesim.Config.load(path)
        self.assertIn("key '[forcing] series': " + self.csv + ":4: expected times increasing strictly",
                      str(e.exception))

    def test_bad_series_set_from_python(self):
        cfg = floesim.Config("")
        with self.assertRaises(floesim.InputError) as e:
            cfg["forcing"]["series"] = self.csv
        self.assertIn(self.csv + ":4:", str(e.exception))
        floesim.Simulation(cfg)  # unchanged: constant forcing

    def test_records_bound(self):
        with self.assertRaises(floesim.InputError) as e:
            floesim.Config("[run]\noutput_interval = 1e-320\n")
        self.assertIn("at most 10000000 records", str(e.exception))
        sim = floesim.Simulation(floesim.Config("[run]\nt_end = 1\n"))
        with self.assertRaises(floesim.InputError) as e:
            sim.run(os.path.join(self.dir, "out.h5"), until=1e12)
        self.assertIn("at most 10000000 records", str(e.exception))
        with self.assertRaises(floesim.InputError):
            sim.run(os.path.join(self.dir, "out.h5"), until=math.nan)
        self.assertFalse(os.path.exists(os.path.join(self.dir, "out.h5")))


if __name__ == "__main__":
    unittest.main()
