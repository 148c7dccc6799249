#!/usr/bin/env python3
"""Distributed runs of floes on a spectral sea against the serial run
(docs/parallel.md, stage two).

usage: check_sea_ranks.py FLOESIM MPIEXEC WORKDIR [--ranks 1 2 3] [--t-end T]
       check_sea_ranks.py --no-mpi    (MPI not built: says so and exits 77, ctest's skip code)

A small ocean like bench/ocean/ocean.toml: a 200 m x 200 m periodic box,
128 x 128 cells, a JONSWAP sea (Hs = 1 m, Tp = 6 s), 60 floes of 10 to 30 m
(`floesim pack`, 30 % cover) under wind, colliding in the periodic box,
riding on the sea through the strong penalty law with the tent footprint.
Stage two shares the footprints, the horizontal loads and the water
velocity under the floes among the ranks by floe; each floe's pieces and
loads depend on that floe alone, and the gathered lists are concatenated in
floe order, so every run file must equal the serial one bit for bit
(`floesim compare --rtol 0 --atol 0`), for three variants of the coupling:
footprints rebuilt at every evaluation, footprints moved between rebuilds
(footprint_reach: the pieces are moved by their owner and gathered), and the
implicit integrator (its step-mean horizontal loads). Then floes that split
on a sea (the floe count, and so the shares, change during the run) on 2 and
3 ranks, and a restart across rank counts: the first half on 2 ranks, the rest from its checkpoint on 3
ranks and serially, both equal to the serial run.
"""
import argparse
import os
import sys

from ranks_harness import Ranks, need

if "--no-mpi" in sys.argv:
    print("floesim was built without MPI (FLOESIM_MPI=OFF): the distributed sea runs are not checked")
    sys.exit(77)

ap = argparse.ArgumentParser()
ap.add_argument("floesim")
ap.add_argument("mpiexec")
ap.add_argument("workdir")
ap.add_argument("--ranks", type=int, nargs="+", default=[1, 2, 3])
ap.add_argument("--t-end", type=float, default=2.0)
args = ap.parse_args()

W = args.workdir
failures = []
harness = Ranks(args.floesim, args.mpiexec, W)
run, mpirun = harness.run, harness.mpirun


def same(a, b):
    return run([args.floesim, "compare", a, b, "--rtol", "0", "--atol", "0"])


need(run([args.floesim, "pack", "--floes", "60", "--concentration", "0.3", "--box", "200", "200", "--seed", "3",
          "--min-size", "10", "--max-size", "30", "--thickness", "1", "-o", "sea_pack.h5"]), "floesim pack")

BASE = f"""[run]
t_end = {args.t_end}
dt_max = 0.05
output_interval = {args.t_end / 4}
seed = 2
threads = 1

[sea]
model = "spectral"
dims = 2
size = [200.0, 200.0]
cells = [128, 128]
depth = 50.0

[sea.waves]
kind = "jonswap"
hs = 1.0
tp = 6.0

[floes]
pack = "sea_pack.h5"

[contact]
domain = "periodic"

[forcing]
wind = [15.0, 5.0]

[coupling]
law = "strong"
stiffness = 100.0
"""
VARIANTS = {
    "rebuilt": "",
    "moved": "footprint_reach = 0.3\n",
    "implicit": 'integrator = "implicit"\n',
}

for name, extra in VARIANTS.items():
    config = os.path.join(W, f"sea_{name}.toml")
    with open(config, "w") as f:
        f.write(BASE + extra)
    serial = need(run([args.floesim, "run", config, "-o", f"{name}_serial.h5", "-q"]), f"{name}: serial run")
    summary = dict(l.split(": ", 1) for l in serial.stdout.splitlines() if ": " in l)
    print(f"{name}: serial to {args.t_end} s, {summary.get('steps')} steps, "
          f"{summary.get('footprints.rebuilds')} footprint rebuilds of {summary.get('footprints.placements')} "
          f"placements, {summary.get('collisions.lcps')} collision LCPs")
    if name == "moved" and summary.get("footprints.rebuilds") == summary.get("footprints.placements"):
        failures.append("moved: every placement rebuilt the footprints: the check would not test the moves")
    for n in args.ranks:
        out = f"{name}_{n}.h5"
        p = mpirun(n, "run", config, "-o", out, "-q")
        c = same(out, f"{name}_serial.h5") if p.returncode == 0 else p
        verdict = "equal" if c.returncode == 0 else "DIFFERENT"
        print(f"{name}: {n} ranks {verdict} to the serial run (bit for bit)")
        if c.returncode != 0:
            failures.append(f"{name} on {n} ranks: exit {p.returncode}\n{p.stderr}\n{c.stdout}")

# Floes that split on a sea: the floe count changes during the run, and with
# it every rank's share. tests/regression/floes_on_sea.toml with the first
# floe thrown at 3 m/s into the second, and fracture with splits.
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
with open(os.path.join(ROOT, "tests", "regression", "floes_on_sea.toml")) as f:
    text = f.read()
if "velocity = [0.6, 0.0]" not in text:
    sys.exit("FAILED: tests/regression/floes_on_sea.toml changed: the split case needs its moving floe")
config = os.path.join(W, "sea_splits.toml")
with open(config, "w") as f:
    f.write(text.replace("velocity = [0.6, 0.0]", "velocity = [3.0, 0.0]") +
            "\n[fracture]\nenabled = true\nsplit = true\nstrength = 2.0e4\nmesh_size = 0.5\n")
serial = need(run([args.floesim, "run", config, "-o", "splits_serial.h5", "-q", "--until", "4"]), "splits: serial run")
summary = dict(l.split(": ", 1) for l in serial.stdout.splitlines() if ": " in l)
print(f"splits: serial to 4 s, {summary.get('fracture.splits')} splits, {summary.get('floes')} floes at the end")
if summary.get("fracture.splits", "0") == "0":
    failures.append("splits: no floe split: the check would not test a changing floe count")
for n in (2, 3):
    p = mpirun(n, "run", config, "-o", f"splits_{n}.h5", "-q", "--until", "4")
    c = same(f"splits_{n}.h5", "splits_serial.h5") if p.returncode == 0 else p
    print(f"splits: {n} ranks {'equal' if c.returncode == 0 else 'DIFFERENT'} to the serial run (bit for bit)")
    if c.returncode != 0:
        failures.append(f"splits on {n} ranks: exit {p.returncode}\n{p.stderr}\n{c.stdout}")

# A restart across rank counts: stopped half-way on 2 ranks, continued on 3
# ranks and serially from the checkpoint rank 0 wrote.
config = os.path.join(W, "sea_rebuilt.toml")
half = args.t_end / 2
need(mpirun(2, "run", config, "-o", "half.h5", "-q", "--until", str(half)), "the first half on 2 ranks")
for n, cmd in ((3, lambda: mpirun(3, "run", "--restart", "half.h5", "-o", "rest3.h5", "-q")),
               (1, lambda: run([args.floesim, "run", "--restart", "half.h5", "-o", "rest1.h5", "-q"]))):
    p = cmd()
    c = same(f"rest{n}.h5", "rebuilt_serial.h5") if p.returncode == 0 else p
    where = "serially" if n == 1 else f"on {n} ranks"
    print(f"restart at {half} s from 2 ranks, continued {where}: {'equal' if c.returncode == 0 else 'DIFFERENT'} "
          "to the serial run")
    if c.returncode != 0:
        failures.append(f"restart continued {where}: exit {p.returncode}\n{p.stderr}\n{c.stdout}")

if failures:
    print("FAILED:\n" + "\n".join(failures))
    sys.exit(1)
print("ok")
