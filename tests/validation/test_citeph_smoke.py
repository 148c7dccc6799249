"""Smoke test of the CITEPH validation (validation/citeph/citeph.py): one
single-disc test and one 79% array test at the coarse `smoke` resolution,
with their empty-basin runs, through the same runner and report as
`scripts/validate citeph`.

The checks are loose physical bounds, not the validation: at T = 1.85 s the
waves are 5.3 m long, 5.4 disc diameters, and the disc is far below its
heave and pitch resonance (about 0.27 s), so it follows the surface
(analytic long-wave limit: heave and pitch RAO 1, surge RAO 1 / tanh(k h),
the water particle's orbit); an array cannot transmit much more energy than
comes in; neighbours 2 cm apart in 40 mm waves collide (the run's recorded collisions).
The report must write results.csv with the columns of issue 18 and the two PNG figures.
"""
import csv
import math
import os
import sys
import tempfile
import unittest

import numpy as np

sys.path.insert(0, os.path.join(os.environ["FLOESIM_SOURCE_DIR"], "validation", "citeph"))
import cases  # noqa: E402
import citeph  # noqa: E402
import measure  # noqa: E402


class Pieces(unittest.TestCase):
    def test_wavenumber_solves_the_dispersion_relation(self):
        for period in (0.65, 1.25, 2.0):
            k = cases.wavenumber(period)
            omega = 2 * math.pi / period
            lhs = (cases.G * k + cases.SIGMA * k ** 3 / cases.RHO_WATER) * math.tanh(k * cases.DEPTH)
            self.assertAlmostEqual(lhs / omega ** 2, 1.0, places=12)

    def test_fit_recovers_an_amplitude_on_a_drift(self):
        t = np.linspace(10.0, 25.0, 400)
        omega = 2 * math.pi / 1.5
        x = 0.013 * np.cos(omega * t + 0.7) + 0.02 * t - 1e-3 * t * t + 3.0
        self.assertAlmostEqual(abs(measure.fit_amplitude(t, x, omega)), 0.013, delta=1e-4)

    def test_response_of_a_drifting_disc(self):
        # A disc drifting at 0.1 m/s through a progressive wave heaves at 0.8
        # of the wave it meets (a Doppler-shifted frequency): the fit in its
        # frame recovers 0.8, a fit at the wave frequency in the basin's would not.
        period, k, a0 = 1.25, 2.58, 0.02
        omega = 2 * math.pi / period
        dx = 0.1
        centres = (np.arange(200) + 0.5) * dx
        row = a0 * np.exp(1j * k * centres)
        empty = dict(row_dx=dx, row_re=row.real.tolist(), row_im=row.imag.tolist())
        t = np.arange(0.0, 10.0, period / 20)
        x = 8.0 + 0.1 * t
        phase = k * x - omega * t
        series = dict(t=t.tolist(), x=(x + 0.9 * a0 * np.sin(phase)).tolist(),
                      heave=(0.8 * a0 * np.cos(phase + 0.3)).tolist(),
                      pitch=(0.7 * k * a0 * np.sin(phase)).tolist())
        r = measure.response(series, empty, 1.0, omega)
        self.assertAlmostEqual(r["heave"], 0.8, delta=2e-3)
        self.assertAlmostEqual(r["pitch"] / k, 0.7, delta=2e-3)
        self.assertAlmostEqual(r["x"], 0.9, delta=2e-3)
        fixed = abs(measure.fit_amplitude(t, np.array(series["heave"]), omega)) / a0
        self.assertLess(fixed, 0.7)

    def test_collision_episodes_group_the_rows_of_a_contact(self):
        # Rows of /events/collisions (time, floe_a, floe_b, normal, x, y, resting),
        # steps of 0.1 s: discs 3 and 4 (both middle) collide at 1.0 s and stay
        # in contact two more steps, then collide again at 2.0 s; 4 and 9 (9 not
        # middle) once; 7 and 8 (neither) are left out.
        rows = [[1.0, 3, 4, 2.0, 0, 0, 0], [1.1, 3, 4, 0.5, 0, 0, 1], [1.2, 3, 4, 0.5, 0, 0, 1],
                [2.0, 3, 4, 1.0, 0, 0, 0], [1.5, 4, 9, 0.7, 0, 0, 0], [1.5, 7, 8, 9.0, 0, 0, 0]]
        times, impulses = measure.collision_episodes(rows, [3, 4], 0.2)
        self.assertEqual(sorted(zip(times, impulses)),
                         [(1.0, 3.0), (1.0, 3.0), (1.5, 0.7), (2.0, 1.0), (2.0, 1.0)])

    def test_lattices_reach_the_concentrations_without_overlap(self):
        strip = (10.0, 10.0 + cases.STRIP)
        for target in (39, 79):
            centres, c = cases.lattice(target, strip)
            self.assertLess(abs(c - target), 2.0)
            p = np.array(centres)
            d = np.linalg.norm(p[:, None, :] - p[None, :, :], axis=2) + 1e9 * np.eye(len(p))
            self.assertGreater(d.min(), cases.DIAMETER)
            r = cases.DIAMETER / 2
            self.assertTrue(np.all((p[:, 1] > r) & (p[:, 1] < cases.WIDTH - r)))
            self.assertTrue(np.all((p[:, 0] > strip[0]) & (p[:, 0] < strip[1])))


class Smoke(unittest.TestCase):
    def test_disc_and_array(self):
        with tempfile.TemporaryDirectory() as work:
            results = citeph.run_all(work, cases.RESOLUTIONS["smoke"], cases.Physics(), 1,
                                     only="disc_T1.85_H40|array79_T2.00_H40|empty_T1.85|empty_T2.00")
            self.assertEqual(len(results), 4)
            for r in results:
                self.assertNotIn("error", r, r.get("error"))
            # the report as scripts/validate makes it: results.csv and the two figures
            self.assertEqual(citeph.main(["report", work, work]), 0)
            with open(os.path.join(work, "results.csv"), newline="") as f:
                reader = csv.DictReader(f)
                rows = {(r["case"], r["quantity"]): r for r in reader}
                # the columns issue 18 asks for, in its order
                self.assertEqual(reader.fieldnames,
                                 ["case", "concentration", "T", "H_mm", "quantity", "model", "data", "lo", "hi"])
            for figure in ("single_disc.png", "arrays.png"):
                with open(os.path.join(work, figure), "rb") as f:
                    self.assertEqual(f.read(8), b"\x89PNG\r\n\x1a\n", figure)
        quantities = {"heave_rao", "pitch_rao", "surge_rao", "transmission", "collision_interval_s",
                      "collision_impulse_Ns"}
        self.assertEqual({r["quantity"] for r in rows.values()}, quantities)
        self.assertEqual({r["concentration"] for r in rows.values()}, {"0", "39", "79"})
        model = {key: float(r["model"]) for key, r in rows.items() if r["model"]}
        k = cases.wavenumber(1.85)
        self.assertAlmostEqual(model[("disc_T1.85_H40", "heave_rao")], 1.0, delta=0.2)
        self.assertAlmostEqual(model[("disc_T1.85_H40", "pitch_rao")], 1.0, delta=0.3)
        self.assertAlmostEqual(model[("disc_T1.85_H40", "surge_rao")], 1 / math.tanh(k * cases.DEPTH), delta=0.3)
        t = model[("array79_T2.00_H40", "transmission")]
        self.assertGreater(t, 0.0)
        self.assertLess(t, 1.1)
        self.assertGreater(model[("array79_T2.00_H40", "collision_impulse_Ns")], 0.0)
        interval = model[("array79_T2.00_H40", "collision_interval_s")]
        self.assertGreater(interval, 0.0)
        self.assertLess(interval, 30.0)
        # the rows not run here are written with an empty model column
        self.assertEqual(rows[("disc_T0.65_H20", "heave_rao")]["model"], "")
        self.assertEqual(rows[("disc_T0.65_H20", "heave_rao")]["data"], "0.1206")


if __name__ == "__main__":
    unittest.main()
