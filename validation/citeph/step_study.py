#!/usr/bin/env python3
"""One CITEPH single-disc test run at several steps per wave period: the
surge, heave and pitch amplitudes at the wave's frequency (fitted as in
measure.py, over the last window of the run) and the mean drift over that
window, to see how they depend on the step (docs/coupling.md, "Horizontal
loads of the implicit step").

    PYTHONPATH=build/python python3 validation/citeph/step_study.py T H_MM K STEPS [--explicit]

STEPS: steps per period, comma-separated (e.g. 20,40,80). --explicit runs the
explicit kicks instead (their step is then set by K, not by STEPS).
"""
import argparse
import dataclasses
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import cases  # noqa: E402
import measure  # noqa: E402


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("period", type=float)
    ap.add_argument("height_mm", type=float)
    ap.add_argument("stiffness", type=float)
    ap.add_argument("steps", help="steps per period, comma-separated")
    ap.add_argument("--explicit", action="store_true")
    ap.add_argument("--resolution", default="standard", choices=sorted(cases.RESOLUTIONS))
    a = ap.parse_args(argv)
    found = [t for t in cases.tests() if t["concentration"] == 0 and abs(t["T"] - a.period) < 1e-9
             and abs(t["H_mm"] - a.height_mm) < 1e-9]
    if not found:
        print(f"no single-disc test with T = {a.period} s and H = {a.height_mm} mm in data/citeph", file=sys.stderr)
        return 2
    test = found[0]
    physics = cases.Physics(stiffness=a.stiffness)
    omega = 2 * math.pi / a.period
    for n in (int(s) for s in a.steps.split(",")):
        res = dataclasses.replace(cases.RESOLUTIONS[a.resolution], steps_per_period=n)
        text, layout = cases.configuration(test, res, physics)
        if a.explicit:
            text = text.replace('integrator = "implicit"', 'integrator = "explicit"')
        job = dict(name=test["case"], text=text, layout=layout, test=test, empty=False, physics={},
                   window_periods=res.window_periods)
        out = measure.run_case(job)
        s = out["series"]
        t = np.array(s["t"])
        amp = {q: abs(measure.fit_amplitude(t, np.array(s[q]), omega)) for q in ("x", "heave", "pitch")}
        print(f"{test['case']} K = {a.stiffness:g} {'explicit' if a.explicit else f'T/{n}'}: "
              f"surge {amp['x'] * 1000:.2f} mm, heave {amp['heave'] * 1000:.2f} mm, pitch {amp['pitch']:.5f}, "
              f"drift {out['drift_m']:.3f} m, {out['steps']} steps, {out['cpu_s']:.1f} s CPU", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
