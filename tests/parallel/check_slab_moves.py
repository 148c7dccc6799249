#!/usr/bin/env python3
"""The sea's slabs moved by measured cost during a run (docs/parallel.md,
stage seven) against the serial run.

usage: check_slab_moves.py FLOESIM MPIEXEC WORKDIR
       check_slab_moves.py --no-mpi    (MPI not built: exits 77, ctest's skip code)

120 floes of 6 to 15 m packed in the lower half of a 200 m x 200 m periodic
box on a 128^2 spectral sea (JONSWAP, Hs = 1 m, Tp = 6 s) under wind,
footprints moved between rebuilds: the floes' drift and detection cost is
all in rows 0 to 63, the sea's row work is the same in every row, so the
cuts move from the equal shares toward the floes (parallel.slab_rows, every
10 steps by the gathered CPU times). Checked:
  - the slabs moved (parallel.strip_moves > 0 and parallel.slab_rows not the
    equal shares) on 2 and 3 ranks;
  - the run files equal the serial one bit for bit (as
    mpi.sea_ranks_equal_serial: the cells' sums are made in the serial order
    whatever the owners, stage eight);
  - two runs on 2 ranks are equal bit for bit: the slabs' moves follow the
    timings, but the answer does not depend on them (the sea's row blocks
    are transformed by the same plans wherever they lie, and the cells' sums
    do not depend on which rank owns which floe);
  - the coupling's floe owners follow the slabs (stage eight): with the
    footprints rebuilt at every evaluation (footprint_reach = 0, the run
    "rebuilt"), the slabs they were set by at the last rebuild
    (parallel.coupling_slab_rows) are the sea's at the end and not the first,
    equal ones, and that run too equals the serial one bit for bit.
  - the coupling's per-floe work is charged to the slabs' moves (the owners
    doing it follow the slabs): parallel.coupling_seconds > 0 on every rank
    of every run on 2 and 3 ranks. At the start every floe lies in the
    first slab of 2 ranks (rows 0 to 63) and in the first two of 3, so the
    last rank has coupling work only once the slabs moved into the floes.
  - with the blend law (the explicit damper, whose loads are evaluated at
    the first half kick and kicked into the sea after the drift that moves
    the cuts), the runs on 2 and 3 ranks equal the serial one bit for bit.
  - a move of the cuts in a rejected try ("moved in a redo" below): the
    step that moves the slabs is redone after an overlap, and the runs on 2
    and 3 ranks equal the serial one bit for bit, in the poison mode too.
"""
import os
import sys

from ranks_harness import half_pack, need, ocean_toml, ranks_check, squares_on_sea, summary

args, harness = ranks_check("floesim was built without MPI (FLOESIM_MPI=OFF): the moving slabs are not checked")
floesim, W = args.floesim, args.workdir
run, mpirun = harness.run, harness.mpirun
failures = []

half_pack(run, floesim)
config = os.path.join(W, "half.toml")
with open(config, "w") as f:
    f.write(ocean_toml("half_pack.h5", 3.0, 0.5, contact="box = [0.0, 200.0, 0.0, 200.0]\n",
                       coupling="footprint_reach = 0.3\n"))


def compare(a, b, rtol):
    return harness.compare(a, b, rtol)


def check_coupling(n, out, coupling):
    if len(coupling) != n or not all(x > 0.0 for x in coupling):
        failures.append(f"{n} ranks ({out}): the coupling's seconds were not charged on every rank ({coupling})")


need(run([floesim, "run", config, "-o", "serial.h5", "-q"]), "the serial run")
EQUAL = {2: [0, 64, 128], 3: [0, 48, 88, 128]}  # SlabFft2d::equal_rows: 16 blocks of 8 rows
for n, out in ((2, "ranks2.h5"), (3, "ranks3.h5"), (2, "ranks2_again.h5")):
    s = summary(need(mpirun(n, "run", config, "-o", out), f"the run on {n} ranks"))
    rows = [int(x) for x in s.get("parallel.slab_rows", "").split()]
    moves = int(s.get("parallel.strip_moves", "0"))
    coupling = [float(x) for x in s.get("parallel.coupling_seconds", "").split()]
    print(f"{n} ranks ({out}): slabs {rows}, {moves} moves, floes by strip {s.get('parallel.strip_floes')}, "
          f"coupling seconds charged {coupling}")
    check_coupling(n, out, coupling)
    if moves == 0 or rows == EQUAL[n]:
        failures.append(f"{n} ranks: the slabs did not move ({rows}, {moves} moves): the check would not test the moves")
    p = compare(out, "serial.h5", "0")
    print(f"{n} ranks ({out}): {'equal' if p.returncode == 0 else 'DIFFERENT'} to the serial run (bit for bit)")
    if p.returncode != 0:
        failures.append(f"{out} against the serial run:\n{p.stdout}")
# The owners follow the slabs: footprints rebuilt at every evaluation.
rebuilt = os.path.join(W, "half_rebuilt.toml")
with open(rebuilt, "w") as f:
    f.write(ocean_toml("half_pack.h5", 3.0, 0.5, contact="box = [0.0, 200.0, 0.0, 200.0]\n"))
need(run([floesim, "run", rebuilt, "-o", "rebuilt_serial.h5", "-q"]), "the serial run (rebuilt)")
for n in (2, 3):
    out = f"rebuilt{n}.h5"
    s = summary(need(mpirun(n, "run", rebuilt, "-o", out), f"the rebuilt run on {n} ranks"))
    rows = [int(x) for x in s.get("parallel.slab_rows", "").split()]
    owners = [int(x) for x in s.get("parallel.coupling_slab_rows", "").split()]
    coupling = [float(x) for x in s.get("parallel.coupling_seconds", "").split()]
    print(f"{n} ranks ({out}): slabs {rows}, the coupling's owners by {owners}, coupling seconds charged {coupling}")
    check_coupling(n, out, coupling)
    if rows == EQUAL[n] or owners != rows:
        failures.append(f"{n} ranks rebuilt: the coupling's owners did not follow the slabs ({owners} against {rows})")
    p = compare(out, "rebuilt_serial.h5", "0")
    print(f"{n} ranks ({out}): {'equal' if p.returncode == 0 else 'DIFFERENT'} to the serial run (bit for bit)")
    if p.returncode != 0:
        failures.append(f"{out} against the serial run:\n{p.stdout}")
# The explicit damper (the blend law, s < 1): its loads are evaluated at the
# first half kick, and the sea's kick of that pressure comes after the drift,
# where the cuts move. The sea and the coupling follow the moved slabs only
# after that kick (Simulation::follow_slabs): followed at the drift, the
# rows a rank takes over would be kicked with its old routes' sums, and the
# sea would leave the serial run from the first move on (every cell's eta,
# every floe's vertical rates; floes_on_waves on 2 and 3 ranks,
# scripts/validate_ranks).
damper = os.path.join(W, "half_damper.toml")
with open(damper, "w") as f:
    f.write(ocean_toml("half_pack.h5", 1.0, 0.5, contact="box = [0.0, 200.0, 0.0, 200.0]\n",
                       coupling="footprint_reach = 0.3\nrestitution = 0.3\n").replace('law = "strong"', 'law = "blend"'))
need(run([floesim, "run", damper, "-o", "damper_serial.h5", "-q"]), "the serial run (damper)")
for n in (2, 3):
    out = f"damper{n}.h5"
    s = summary(need(mpirun(n, "run", damper, "-o", out), f"the damper's run on {n} ranks"))
    rows = [int(x) for x in s.get("parallel.slab_rows", "").split()]
    moves = int(s.get("parallel.strip_moves", "0"))
    print(f"{n} ranks ({out}, blend law): slabs {rows}, {moves} moves")
    if moves == 0:
        failures.append(f"{n} ranks, damper: the slabs did not move: the check would not test the moves")
    p = compare(out, "damper_serial.h5", "0")
    print(f"{n} ranks ({out}): {'equal' if p.returncode == 0 else 'DIFFERENT'} to the serial run (bit for bit)")
    if p.returncode != 0:
        failures.append(f"{out} against the serial run:\n{p.stdout}")
# The slabs moved in a try that is then rejected (docs/parallel.md, "The
# kick by owner (kick29)"): the move's drift hands floes its old bands did
# not hold to their new owners (hand_over_moved), the try is redone from the
# step's start with half the dt, and the redo's first half kick kicks those
# floes on their new holders with the loads of the step's start, which must
# travel again (ready_loads' kickers_moved; the strong law: no damper, so
# the loads are not evaluated again). Without that second share the run
# leaves the serial one at the redo (on 2 and 3 ranks).
# The cuts may move only every StripOptions::rebalance_steps (10) steps, so
# the overlap is timed for the 11th step: no wind, waves of 1 cm, the
# penalty spring soft enough (stiffness 0.05) for dt = dt_max = 0.25 s, and a
# 2 m square A at 4 m/s (slowed by the drag) meets B, at rest 7.3 m ahead,
# just after t = 2.5 s; B, thrown past its reach (set at rest), overlaps C
# 0.2 m ahead: the try is rejected. Every floe lies below y = 30 m, in rank
# 0's strip of the equal slabs (cut at row 16, y = 32 m), so the first
# window moves the cut toward them (to row 8, y = 16 m, on 2 ranks): the
# floes above it, A, B and C among them, far out of rank 1's old band, go to
# rank 1 at that try.
# Both in the same step, from the summary: to t = 2.5 s, 10 steps, none
# redone, no move; to 2.75 s, one move and one step redone, in 12 steps (the
# 11th's first try of 0.25 s rejected, its redo and the next step 0.125 s).
redo_floes = [(30.0, 20.0 - 2.0 - 7.3, 4.0), (30.0, 20.0, 0.0), (30.0, 22.2, 0.0)]
redo_floes += [(2.0 + 4.0 * i, 2.0 + 5.0 * j, 0.0) for i in range(6) for j in range(6)]
redo = os.path.join(W, "moved_redo.toml")
squares_on_sea(redo, redo_floes, 3.0, 0.01, (0.0, 0.0), 'law = "strong"\nstiffness = 0.05')
need(run([floesim, "run", redo, "-o", "redo_serial.h5", "-q"]), "moved in a redo: the serial run")
for n in (2, 3):
    counts = {}
    for until in ("2.5", "2.75", None):
        out = f"redo{n}_{until or 'end'}.h5"
        p = need(mpirun(n, "run", redo, "-o", out, *(("--until", until) if until else ())),
                 f"moved in a redo: the run on {n} ranks to {until or 'the end'}")
        s = summary(p)
        counts[until] = (int(s.get("steps", "0")), int(s.get("steps_redone", "0")),
                         int(s.get("parallel.strip_moves", "0")))
        rows = s.get("parallel.slab_rows")
    print(f"moved in a redo on {n} ranks: (steps, redone, moves) to 2.5 s {counts['2.5']}, to 2.75 s "
          f"{counts['2.75']}, to the end {counts[None]}; slabs at the end {rows}")
    if counts["2.5"] != (10, 0, 0) or counts["2.75"] != (12, 1, 1):
        failures.append(f"moved in a redo on {n} ranks: the move and the redo were not in the 11th step "
                        f"(to 2.5 s {counts['2.5']}, to 2.75 s {counts['2.75']}; want (10, 0, 0) and (12, 1, 1)): "
                        "the case would not test a move in a rejected try")
    p = compare(f"redo{n}_end.h5", "redo_serial.h5", "0")
    print(f"moved in a redo on {n} ranks: {'equal' if p.returncode == 0 else 'DIFFERENT'} to the serial run "
          "(bit for bit)")
    if p.returncode != 0:
        failures.append(f"moved in a redo on {n} ranks against the serial run:\n{p.stdout}")
    # The poison mode (unheld copies NaN): the redo reads no floe its rank does not hold.
    harness.poison_clean(f"redo{n}", redo, "redo_serial.h5", failures, ranks=n)
p = compare("ranks2.h5", "ranks2_again.h5", "0")
print(f"two runs on 2 ranks: {'equal' if p.returncode == 0 else 'DIFFERENT'} (bit for bit)")
if p.returncode != 0:
    failures.append(f"two runs on 2 ranks:\n{p.stdout}")

if failures:
    print("FAILED:\n" + "\n".join(failures))
    sys.exit(1)
