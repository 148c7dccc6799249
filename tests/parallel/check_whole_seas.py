#!/usr/bin/env python3
"""Distributed runs on the seas not in slabs against the serial run
(docs/parallel.md, "The seas not in slabs in the serial order").

usage: check_whole_seas.py FLOESIM MPIEXEC WORKDIR [--ranks 2 3]
       check_whole_seas.py --no-mpi    (MPI not built: exits 77, ctest's skip code)

A BEM sea, a spectral tank and a long-crested spectral sea (dims = 1) are
whole on every rank (only a spectral sea with dims = 2 and no tank runs in
slabs); their floes are owned by index. Each case is a dense pack (`floesim
pack`, 70 % cover) whose floes are smaller than a few cells, so that many
cells hold pieces of three or more floes of several ranks, with the explicit
kicks (the law by owner) to 2 s:
  - bem: 150 floes in a 12 m x 6 m basin with walls (BEM, 24 x 12 cells);
  - tank: 100 floes in a 24 m x 6 m tank (spectral, 96 x 24 cells, wave
    maker and absorber);
  - flume: 40 floes in a 24 m x 2 m flume (spectral, dims = 1, 96 x 1
    cells: every cell spans the flume).
Checked, on 2 and 3 ranks:
  - the run file equals the serial one bit for bit (`floesim compare --rtol
    0 --atol 0`): each cell's coverage, sums and pressure are the serial
    sums, made from every rank's pieces in the serial order on every rank.
    Summing each rank's part and then the parts (stage three's merge, before
    this) differed on every case here in the floes' states and the sea (by
    ~1e-14 relative), not only in the penalty energy;
  - rank 0 sent cells as pieces (parallel.coupling_cells: `shared` > 0), so
    the pieces' path was taken (and, but in the flume, whose few cells are
    nearly all shared, cells summed alone and sent as totals).
Then the bem case stopped half-way on 2 ranks and continued from its
checkpoint on 3 ranks must equal the serial run bit for bit.
"""
import argparse
import os
import re
import sys

from ranks_harness import Ranks, finish, need, summary

if "--no-mpi" in sys.argv:
    print("floesim was built without MPI (FLOESIM_MPI=OFF): the runs on the seas not in slabs are not checked")
    sys.exit(77)

ap = argparse.ArgumentParser()
ap.add_argument("floesim")
ap.add_argument("mpiexec")
ap.add_argument("workdir")
ap.add_argument("--ranks", type=int, nargs="+", default=[2, 3])
args = ap.parse_args()

W = args.workdir
failures = []
harness = Ranks(args.floesim, args.mpiexec, W)
run, mpirun = harness.run, harness.mpirun

RUN = """[run]
t_end = 2.0
dt_max = 0.02
output_interval = 0.5
threads = 1
"""
COUPLING = """
[floes]
pack = "{pack}"

[coupling]
law = "strong"
stiffness = 100.0
"""
SEAS = {
    "bem": ("""
[sea]
model = "bem"
dims = 2
size = [12.0, 6.0]
cells = [24, 12]
depth = 2.0
rho = 1000.0

[sea.waves]
kind = "standing"
amplitude = 0.05
wavelength = 24.0
""", ["--floes", "150", "--box", "12", "6"]),
    "tank": ("""
[sea]
model = "spectral"
dims = 2
size = [24.0, 6.0]
cells = [96, 24]
depth = 1.0
rho = 1000.0

[sea.waves]
kind = "regular"
amplitude = 0.05
wavelength = 6.0

[sea.tank]
enabled = true
generation_length = 6.0
absorption_length = 6.0
""", ["--floes", "100", "--box", "24", "6"]),
    "flume": ("""
[sea]
model = "spectral"
dims = 1
size = [24.0, 2.0]
cells = [96, 1]
depth = 1.0
rho = 1000.0

[sea.waves]
kind = "regular"
amplitude = 0.05
wavelength = 6.0
""", ["--floes", "40", "--box", "24", "2"]),
}

for name, (sea, pack) in SEAS.items():
    need(run([args.floesim, "pack", *pack, "--concentration", "0.7", "--seed", "3", "--thickness", "0.2",
              "-o", f"{name}_pack.h5"]), f"{name}: floesim pack")
    config = os.path.join(W, f"{name}.toml")
    with open(config, "w") as f:
        f.write(RUN + sea + COUPLING.format(pack=f"{name}_pack.h5"))
    s = summary(need(run([args.floesim, "run", config, "-o", f"{name}_serial.h5", "-q"]), f"{name}: serial run"))
    print(f"{name}: serial to 2 s, {s.get('steps')} steps")
    for n in args.ranks:
        p = mpirun(n, "run", config, "-o", f"{name}_{n}.h5", "-q")
        if p.returncode != 0:
            failures.append(f"{name} on {n} ranks: exit {p.returncode}\n{p.stderr}")
            continue
        harness.same(f"{name}_{n}.h5", f"{name}_serial.h5", f"{name}: {n} ranks against the serial run", failures)
        cells = summary(p).get("parallel.coupling_cells")
        print(f"{name}: {n} ranks, rank 0's cells: {cells}")
        m = re.match(r"(\d+) shared \((\d+) pieces\), (\d+) alone owned, (\d+) alone sent", cells or "")
        if not m or int(m.group(1)) == 0 or (name != "flume" and int(m.group(4)) == 0):
            failures.append(f"{name} on {n} ranks: no cell sent as pieces, or none as a total ({cells})")

# A restart across rank counts: the bem case's first half on 2 ranks, the
# rest from its checkpoint on 3 ranks.
need(mpirun(2, "run", os.path.join(W, "bem.toml"), "-o", "bem_half.h5", "-q", "--until", "1"),
     "bem: the first half on 2 ranks")
p = mpirun(3, "run", "--restart", "bem_half.h5", "-o", "bem_rest3.h5", "-q")
if p.returncode != 0:
    failures.append(f"bem: restart on 3 ranks: exit {p.returncode}\n{p.stderr}")
else:
    harness.same("bem_rest3.h5", "bem_serial.h5", "bem: half on 2 ranks, continued on 3, against the serial run",
                 failures)
finish(failures)
