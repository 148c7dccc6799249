#!/usr/bin/env python3
"""One writer gathers the records and checkpoints (docs/parallel.md, "One
writer gathers the records and checkpoints"): runs on 2 and 3 ranks in
which each rank's copy of the floes it does not hold (the states of floes
it does not own by place, the heave, pitch and roll of floes it does not
own for the coupling) is poisoned (NaN) before each gather to the writer
(the test hook FLOESIM_TEST_POISON_UNHELD=1, not a user key); the run file
and the checkpoint are right only if the writer reads every floe from its
holder.

usage: check_writer_ranks.py FLOESIM MPIEXEC WORKDIR
       check_writer_ranks.py --no-mpi    (MPI not built: exits 77, ctest's skip code)

1. The collisions-only periodic pack of scripts/scenarios/moving_pack.py
   (400 floes to 500 s) with percussion fracture (floes split, so the floe
   count changes between records) and a checkpoint every 100 s: on 2 and 3
   ranks, poisoned, the run file equals the serial one bit for bit; the
   writer keeping its own poisoned copy (FLOESIM_TEST_POISON_UNHELD=unread,
   the mutation) gives a different file, so the poison reaches what is
   written; stopped at 250 s on 2 ranks, poisoned, and continued from its
   checkpoint serially and on 3 ranks (poisoned), the run equals the serial
   run bit for bit: the checkpoint's states were gathered too.
2. A small ocean (120 floes in half of a 200 m periodic box on a 128^2
   spectral sea in slabs, the footprints moved between rebuilds, the
   floes' vertical DOFs in the states): on 2 and 3 ranks, poisoned, bit for
   bit with the serial run, the mutation different; stopped at 1 s on 2
   ranks and continued serially, bit for bit too.
"""
import os

from ranks_harness import FRACTURE, finish, half_pack, moving_pack_check, need, ocean_toml, ran, summary

args, harness, base = moving_pack_check(
    "floesim was built without MPI (FLOESIM_MPI=OFF): the writer's gather is not checked", 400, 500.0, [2, 3])
W = args.workdir
run = harness.run
failures = []


mpirun = harness.poisoned  # (n, the test hook's value or None, floesim's arguments...)


def same(a, b, what):
    harness.same(a, b, what, failures)


config = os.path.join(W, "writer.toml")
with open(base) as f:
    text = f.read()
with open(config, "w") as f:
    f.write(text.replace("[run]\n", "[run]\ncheckpoint_interval = 100.0\n", 1) + FRACTURE)

s = summary(need(run([args.floesim, "run", config, "-o", "serial.h5", "-q"]), "serial run"))
print(f"serial: {args.floes} floes to {args.t_end} s, {s.get('fracture.splits')} splits, {s.get('floes')} floes")
if s.get("fracture.splits", "0") == "0":
    failures.append("no floe split: the check would not test a changing floe count")
for n in args.ranks:
    p = ran(mpirun(n, "1", "run", config, "-o", f"ranks{n}.h5", "-q"), f"{n} ranks, poisoned", failures)
    if not p:
        continue
    print(f"{n} ranks, poisoned: record phase {summary(p).get('parallel.phase.record')}")
    same(f"ranks{n}.h5", "serial.h5", f"{n} ranks, each rank's unheld floes poisoned, against the serial run")
harness.differs(mpirun(2, "unread", "run", config, "-o", "unread2.h5", "-q"), "unread2.h5", "serial.h5",
                "2 ranks, the writer's poisoned copy written", failures)
half = str(args.t_end / 2)
need(mpirun(2, "1", "run", config, "-o", "half.h5", "-q", "--until", half), "the first half on 2 ranks, poisoned")
need(run([args.floesim, "run", "--restart", "half.h5", "-o", "rest1.h5", "-q"]), "the rest serially")
same("rest1.h5", "serial.h5", f"stopped at {half} s on 2 ranks (poisoned), continued serially, against the serial run")
need(mpirun(3, "1", "run", "--restart", "half.h5", "-o", "rest3.h5", "-q"), "the rest on 3 ranks, poisoned")
same("rest3.h5", "serial.h5", f"stopped at {half} s on 2 ranks, continued on 3 ranks (both poisoned), against the serial run")

# 2. The sea: the vertical DOFs and a sea in slabs.
half_pack(run, args.floesim)
ocean = os.path.join(W, "ocean.toml")
with open(ocean, "w") as f:
    f.write(ocean_toml("half_pack.h5", 2.0, 0.5, contact="box = [0.0, 200.0, 0.0, 200.0]\n",
                       coupling="footprint_reach = 0.3\n"))
need(run([args.floesim, "run", ocean, "-o", "ocean_serial.h5", "-q"]), "the ocean, serial")
for n in args.ranks:
    if ran(mpirun(n, "1", "run", ocean, "-o", f"ocean{n}.h5", "-q"), f"the ocean on {n} ranks, poisoned", failures):
        same(f"ocean{n}.h5", "ocean_serial.h5", f"the ocean on {n} ranks, poisoned, against the serial run")
harness.differs(mpirun(2, "unread", "run", ocean, "-o", "ocean_unread2.h5", "-q"), "ocean_unread2.h5",
                "ocean_serial.h5", "the ocean on 2 ranks, the writer's poisoned copy written", failures)
need(mpirun(2, "1", "run", ocean, "-o", "ocean_half.h5", "-q", "--until", "1.0"), "the ocean's first half on 2 ranks")
need(run([args.floesim, "run", "--restart", "ocean_half.h5", "-o", "ocean_rest1.h5", "-q"]), "the ocean's rest serially")
same("ocean_rest1.h5", "ocean_serial.h5", "the ocean stopped at 1 s on 2 ranks (poisoned), continued serially")

finish(failures)
