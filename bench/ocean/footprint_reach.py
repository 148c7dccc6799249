#!/usr/bin/env python3
"""bench/ocean/footprint_reach.py: footprints rebuilt at every step against
footprints moved between rebuilds ([coupling] footprint_reach), on the ocean
case (bench/ocean/ocean.toml), side by side.

For each (integrator, K) case the runs alternate, reach 0 then each reach,
--repeats times, one thread each (OMP_NUM_THREADS=1, --threads 1). Per run:
the CPU time of the loop (the run's user + system time minus that of a
set-up-only run), the footprint placements and rebuilds, the penalty phase's
wall ms per step (--profile), and, against the reach-0 run of the same round,
the largest differences in the floes' heave, heave rate and horizontal
velocity and in the sea's elevation at the last record. One CSV row per run;
the CSV starts with the command, the commit and the machine's load.

usage: bench/ocean/footprint_reach.py [--until T=2] [--repeats R=2] [--reach "0.01 0.04"]
                                      [--build DIR=build] [--csv FILE]
"""
import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time

import h5py
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "scripts", "scenarios"))
import ocean_pack  # noqa: E402

CASES = [("explicit", 100.0), ("implicit", 1000.0)]


def child_cpu():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run(floesim, toml, until, out):
    env = dict(os.environ, OMP_NUM_THREADS="1")
    before = child_cpu()
    p = subprocess.run([floesim, "run", toml, "--until", str(until), "--profile", "-q", "--threads", "1", "-o", out],
                       capture_output=True, text=True, env=env)
    if p.returncode != 0:
        sys.exit(f"footprint_reach.py: floesim run {toml} failed:\n{p.stderr}")
    summary = {}
    for line in p.stdout.splitlines():
        key, _, value = line.partition(": ")
        summary[key.strip()] = value.strip()
    return child_cpu() - before, summary


def last_record(path):
    with h5py.File(path, "r") as f:
        state = np.asarray(f["floes/state"])[-1]
        cols = [c.decode() if isinstance(c, bytes) else str(c) for c in f["floes/state"].attrs["columns"]]
        eta = np.asarray(f["sea/eta"])[-1]
    return {c: state[:, k] for k, c in enumerate(cols)}, eta


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--until", type=float, default=2.0)
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--reach", default="0.01 0.04")
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--csv", default=None)
    a = ap.parse_args()
    floesim = os.path.join(a.build, "bin", "floesim")
    if not os.access(floesim, os.X_OK):
        sys.exit(f"footprint_reach.py: no {floesim} (build it first)")
    reaches = [0.0] + [float(r) for r in a.reach.split()]
    commit = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True).stdout.strip() or "unknown"
    dirty = subprocess.run(["git", "-C", ROOT, "status", "--porcelain", "--untracked-files=no"], capture_output=True,
                           text=True).stdout.strip()
    csv = a.csv or os.path.join(ROOT, "bench", "results", f"ocean_footprint_reach_{commit}_epyc-2core.csv")
    load_before = os.getloadavg()
    rows = []
    with tempfile.TemporaryDirectory() as work:
        pack = os.path.join(work, "ocean_pack.h5")
        ocean_pack.write(floesim, pack)
        base = open(os.path.join(HERE, "ocean.toml")).read().replace('pack = "ocean_pack.h5"', f'pack = "{pack}"')
        for integrator, K in CASES:
            tomls = {}
            for reach in reaches:
                text = base.replace("stiffness = 100.0", f'stiffness = {K}\nintegrator = "{integrator}"\n'
                                    f"footprint_reach = {reach}")
                tomls[reach] = os.path.join(work, f"{integrator}_{reach}.toml")
                open(tomls[reach], "w").write(text)
            setup_cpu, _ = run(floesim, tomls[0.0], 0, os.path.join(work, "setup.h5"))
            for r in range(a.repeats):
                ref = None
                for reach in reaches:  # alternating: reach 0, then each reach, in every round
                    out = os.path.join(work, f"{integrator}_{reach}_{r}.h5")
                    cpu, s = run(floesim, tomls[reach], a.until, out)
                    steps = float(s["steps"])
                    penalty_ms = 1000 * float(s["profile.penalty"].split()[0]) / steps
                    state, eta = last_record(out)
                    if reach == 0.0:
                        ref = (state, eta)
                    d = {c: float(np.abs(state[c] - ref[0][c]).max()) for c in ("heave", "heave_rate", "vx", "vy")}
                    rows.append([integrator, K, reach, r + 1, int(steps), f"{cpu - setup_cpu:.3f}",
                                 s["footprints.placements"], s["footprints.rebuilds"], f"{penalty_ms:.3f}",
                                 f"{d['heave']:.3e}", f"{d['heave_rate']:.3e}", f"{max(d['vx'], d['vy']):.3e}",
                                 f"{float(np.abs(eta - ref[1]).max()):.3e}"])
                    print(",".join(map(str, rows[-1])), file=sys.stderr)
    with open(csv, "w") as f:
        f.write(f"# command: bench/ocean/footprint_reach.py --until {a.until} --repeats {a.repeats} "
                f"--reach \"{a.reach}\"\n")
        f.write(f"# source: commit {commit}{' (with uncommitted changes)' if dirty else ''}; floesim: {floesim}\n")
        f.write(f"# machine: {os.cpu_count()} cores; load average before {load_before[0]:.2f}, "
                f"after {os.getloadavg()[0]:.2f}; {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}\n")
        f.write("# loop_cpu_s: CPU s of the run minus a set-up-only run's; penalty_ms_per_step: wall ms per step of "
                "the penalty phase; d_*: largest |difference| at the last record against the reach-0 run of "
                "the same round (m, m/s, m/s, m)\n")
        f.write("integrator,K,reach,round,steps,loop_cpu_s,placements,rebuilds,penalty_ms_per_step,"
                "d_heave,d_heave_rate,d_velocity,d_eta\n")
        for row in rows:
            f.write(",".join(map(str, row)) + "\n")
    print(csv)


if __name__ == "__main__":
    main()
