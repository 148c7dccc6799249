#!/usr/bin/env python3
"""The CITEPH-64-2012 wave-basin tests (data/citeph/README.md) as floesim runs.

The table of tests comes from the data files (single disc, 39% array) and the
79% array's test list; each test becomes one configuration of a basin like
Oceanide: 3.1 m of fresh water, 16 m wide (resolved, periodic across), a
generation zone at x = 0 and an absorbing zone at the far end
([sea.tank], docs/sea.md). Every period T also gets an empty-basin run, which
gives the incident amplitude at the disc and at the probes (the sea is
linear, so one empty run per period serves every wave height: its amplitudes
are scaled by H / H_ref).

Measurements, as the experiment defines them (data/citeph/README.md), by
least-squares fits over the last `window_periods` periods:
  heave RAO  = |heave| / a_inc
  pitch RAO  = |pitch| / (k a_inc)   (pitch = the bottom's slope along x, rad)
  surge RAO  = |x| / a_inc
  transmission = mean over probes of |eta|^2 behind the array, divided by the
                 same mean in the empty basin.
Each disc is held by a soft mooring (Physics.mooring_period); what remains of
the drift under the mean wave force is taken into account by fitting the
motions against the incident wave the disc meets on its way (`response`: the empty basin's complex amplitude along the middle line,
read at the disc's centre), which also takes the Doppler shift of the drift.
Probe amplitudes are fitted as a cos(w t) + b sin(w t) + c0 + c1 t + c2 t^2.

Collisions (79% array): the run records the collision solver's impulses
([run] record_collisions: one row per solve and pair of discs, its normal
impulse, docs/formats.md), taken over the window. A collision of two discs is
a run of rows of their pair no more than two steps apart (an impact and the
contact held after it; `collision_episodes`), its impulse the sum of their
normal impulses. The mean time between collisions is the window times the
number of middle discs over the number of their collisions (a collision of
two middle discs counts for both).

    python3 validation/citeph/citeph.py generate OUTDIR [--resolution NAME]
    python3 validation/citeph/citeph.py run WORKDIR [--jobs 2] [--resolution NAME] [--only REGEX]
    python3 validation/citeph/citeph.py report WORKDIR OUTDIR

The configurations are written by cases.py, the measurements taken by
measure.py; this file runs the set and makes the report.
"""
import argparse
import csv
import json
import math
import multiprocessing
import os
import sys
import time

import numpy as np

from cases import DEPTH, RESOLUTIONS, Physics, jobs, tests, wavenumber
from measure import response, run_case

def _estimated_cost(job):
    nx, ny = job["layout"]["cells"]
    steps = job["layout"]["duration"] / job["layout"]["dt"]
    return steps * nx * ny * (1 + 3 * len(job["layout"]["centres"]) ** 0.5) * (0.2 if job["empty"] else 1)


def _run_and_store(args):
    job, workdir = args
    path = os.path.join(workdir, job["name"] + ".json")
    if os.path.exists(path):
        with open(path) as f:
            old = json.load(f)
        if old.get("config") == job["text"]:
            return old
    with open(os.path.join(workdir, job["name"] + ".toml"), "w") as f:
        f.write(job["text"])
    try:
        result = run_case(job)
    except Exception as e:  # a failed run is reported in results, not hidden
        result = dict(name=job["name"], error=f"{type(e).__name__}: {e}")
    result["config"] = job["text"]
    with open(path, "w") as f:
        json.dump(result, f, indent=1)
    print(f"{time.strftime('%H:%M:%S')} {job['name']}: "
          + (result.get("error") or f"{result['cpu_s']:.0f} s CPU ({result['wall_s']:.0f} s wall), {result['steps']} steps, "
             f"cells {result['cells'][0]}x{result['cells'][1]}"), flush=True)
    return result


def run_all(workdir, resolution, physics, processes, only=None):
    os.makedirs(workdir, exist_ok=True)
    todo = sorted(jobs(resolution, physics, only), key=_estimated_cost, reverse=True)
    with multiprocessing.get_context("spawn").Pool(processes) as pool:
        return list(pool.imap_unordered(_run_and_store, [(j, workdir) for j in todo]))


# -- the report --------------------------------------------------------------

def load(workdir):
    out = {}
    for name in os.listdir(workdir):
        if name.endswith(".json"):
            with open(os.path.join(workdir, name)) as f:
                r = json.load(f)
            out[r["name"]] = r
    return out


def results_rows(workdir):
    """Rows case, concentration, T, H_mm, quantity, model, data, lo, hi."""
    runs = load(workdir)
    rows = []
    for test in tests():
        r = runs.get(test["case"])
        empty = runs.get(f"empty_T{test['T']:.2f}")
        model = {}
        if r and empty and "error" not in r and "error" not in empty:
            scale = test["H_mm"] / empty["H_mm"]
            if test["concentration"] == 0:
                if "series" in r and "row_re" in empty:
                    k = wavenumber(test["T"])
                    rao = response(r["series"], empty, scale, 2 * math.pi / test["T"])
                    model = dict(heave_rao=rao["heave"], pitch_rao=rao["pitch"] / k, surge_rao=rao["x"])
            else:
                model = dict(transmission=r["probe_energy"] / (empty["probe_energy"] * scale * scale))
                if test["concentration"] == 79:
                    model["collision_interval_s"] = r["collision_interval_s"]
                    model["collision_impulse_Ns"] = r["collision_impulse_Ns"]
        quantities = (["heave_rao", "pitch_rao", "surge_rao"] if test["concentration"] == 0 else
                      ["transmission"] + (["collision_interval_s", "collision_impulse_Ns"]
                                          if test["concentration"] == 79 else []))
        for q in quantities:
            data = [d for d in test["data"] if d[0] == q] or [(q, None, None, None)]
            for _, mean, lo, hi in data:
                m = model.get(q)
                rows.append(dict(case=test["case"], concentration=test["concentration"], T=test["T"],
                                 H_mm=test["H_mm"], quantity=q,
                                 model="" if m is None or not math.isfinite(m) else f"{m:.4f}",
                                 data="" if mean is None else f"{mean:.4f}",
                                 lo="" if lo is None else f"{lo:.4f}", hi="" if hi is None else f"{hi:.4f}"))
    return rows


def write_results(workdir, outdir):
    rows = results_rows(workdir)
    os.makedirs(outdir, exist_ok=True)
    path = os.path.join(outdir, "results.csv")
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=["case", "concentration", "T", "H_mm", "quantity", "model", "data",
                                          "lo", "hi"])
        w.writeheader()
        w.writerows(rows)
    return rows


def plot(rows, outdir):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    def panel(ax, quantity, concentration, title, analytic=None):
        sel = [r for r in rows if r["quantity"] == quantity and r["concentration"] == concentration]
        heights = sorted({r["H_mm"] for r in sel})
        markers = dict(zip(heights, "osD^v<>"))
        for h in heights:
            d = [r for r in sel if r["H_mm"] == h and r["data"] != ""]
            if d:
                T = np.array([float(r["T"]) for r in d])
                mean = np.array([float(r["data"]) for r in d])
                lo = np.array([float(r["lo"]) for r in d])
                hi = np.array([float(r["hi"]) for r in d])
                ax.errorbar(T - 0.01, mean, yerr=[mean - lo, hi - mean], fmt=markers[h], color="k",
                            mfc="none", capsize=3, label=f"measured, H = {h:g} mm")
            m = sorted({(float(r["T"]), float(r["model"])) for r in sel if r["H_mm"] == h and r["model"] != ""})
            if m:
                ax.plot([x + 0.01 for x, _ in m], [y for _, y in m], markers[h], color="C3",
                        label=f"model, H = {h:g} mm")
        if analytic is not None:
            T = np.linspace(0.6, 2.05, 100)
            ax.plot(T, [analytic(x) for x in T], "--", color="0.5", lw=1, label="slope-sliding limit")
        ax.set_xlabel("T (s)")
        ax.set_title(title)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)

    fig, axes = plt.subplots(1, 3, figsize=(13, 4))
    panel(axes[0], "heave_rao", 0, "single disc: heave RAO", lambda T: 1.0)
    panel(axes[1], "pitch_rao", 0, "single disc: pitch RAO", lambda T: 1.0)
    panel(axes[2], "surge_rao", 0, "single disc: surge RAO",
          lambda T: 1.0 / math.tanh(wavenumber(T) * DEPTH))
    fig.tight_layout()
    fig.savefig(os.path.join(outdir, "single_disc.png"), dpi=110)
    plt.close(fig)

    fig, axes = plt.subplots(1, 3, figsize=(13, 4))
    panel(axes[0], "transmission", 39, "39% array: energy transmission")
    panel(axes[1], "transmission", 79, "79% array: energy transmission (no data)")
    sel = [r for r in rows if r["concentration"] == 79 and r["model"] != ""]
    ax = axes[2]
    for q, c, lab in (("collision_interval_s", "C0", "mean time between collisions (s)"),
                      ("collision_impulse_Ns", "C1", "mean impulse (N s)")):
        for h, marker in ((40.0, "D"), (20.0, "o"), (30.0, "s"), (80.0, "v")):
            pts = sorted((float(r["T"]), float(r["model"])) for r in sel
                         if r["quantity"] == q and float(r["H_mm"]) == h)
            if pts:
                ax.plot(*zip(*pts), marker + ("-" if h == 40.0 else ""), color=c, label=f"{lab}, H = {h:g} mm")
    ax.set_xlabel("T (s)")
    ax.set_title("79% array: collisions of the middle discs")
    ax.set_yscale("log")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(outdir, "arrays.png"), dpi=110)
    plt.close(fig)


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="command", required=True)
    g = sub.add_parser("generate", help="write the configurations")
    g.add_argument("outdir")
    g.add_argument("--resolution", default="standard", choices=sorted(RESOLUTIONS))
    r = sub.add_parser("run", help="run the tests (results cached per configuration in WORKDIR)")
    r.add_argument("workdir")
    r.add_argument("--resolution", default="standard", choices=sorted(RESOLUTIONS))
    r.add_argument("--jobs", type=int, default=2)
    r.add_argument("--only", help="regular expression on the case names")
    r.add_argument("--law", default=Physics.law)
    r.add_argument("--stiffness", type=float, default=Physics.stiffness)
    r.add_argument("--blend", type=float, default=Physics.blend)
    r.add_argument("--restitution", type=float, default=Physics.restitution)
    r.add_argument("--friction", type=float, default=Physics.friction)
    r.add_argument("--mooring-period", type=float, default=Physics.mooring_period, help="s; 0: no mooring")
    p = sub.add_parser("report", help="results.csv and figures from the runs in WORKDIR")
    p.add_argument("workdir")
    p.add_argument("outdir")
    a = ap.parse_args(argv)
    if a.command == "generate":
        os.makedirs(a.outdir, exist_ok=True)
        for j in jobs(RESOLUTIONS[a.resolution], Physics()):
            with open(os.path.join(a.outdir, j["name"] + ".toml"), "w") as f:
                f.write(j["text"])
        return 0
    if a.command == "run":
        physics = Physics(law=a.law, blend=a.blend, stiffness=a.stiffness, restitution=a.restitution, friction=a.friction,
                          mooring_period=a.mooring_period)
        results = run_all(a.workdir, RESOLUTIONS[a.resolution], physics, a.jobs, a.only)
        failed = [r["name"] for r in results if "error" in r]
        if failed:
            print("failed runs: " + ", ".join(failed), file=sys.stderr)
            return 1
        return 0
    rows = write_results(a.workdir, a.outdir)
    plot(rows, a.outdir)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
