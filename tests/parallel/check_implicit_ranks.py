#!/usr/bin/env python3
"""The implicit floe-sea step on several ranks with the halo exchange
(docs/parallel.md, "The halo exchange for the implicit step (implicit28)").

usage: check_implicit_ranks.py FLOESIM MPIEXEC WORKDIR [--ranks 2 3]
       check_implicit_ranks.py --no-mpi    (MPI not built: exits 77, ctest's skip code)

The implicit step ([coupling] integrator = "implicit") on a sea whole on
every rank (BEM, a tank) solves every floe's pieces on every rank; what it
reads of each floe is its vertical DOFs, which every rank holds (the solve
alone writes them), and its yaw, gathered from its owner. On a spectral sea
in slabs (dims = 2, no tank; docs/parallel.md, "The implicit step on the
slabs (slabs30)") each rank solves its own floes' pieces, the products
through the cells' routes and the slab sea, the dots' exact sums over the
ranks, and the vertical DOFs all-gathered after the solve. The floes' whole
states go to the ranks that hold them only (the drift's exchange), and the
drift's owners pose and build their floes' pieces at the step's midpoint.
Five cases, in each of which a rank does not hold some floes on 2 ranks:
  - bem: check_whole_seas.py's BEM basin (150 floes, 12 m x 6 m, walls) with
    the implicit step, to 2 s (100 steps);
  - ocean: ranks_harness's small ocean (120 floes in the lower half of a
    periodic 200 m box, spectral 128^2, in slabs), to 5 s: rank 1's slab
    holds no floe at first, and the slabs move (load balance: checked);
  - slabs: a bench-like periodic ocean in slabs, 300 floes over the whole
    200 m box, to 2 s;
  - moved: slabs to 1 s with footprint_reach = 0.3 (the footprints moved by
    their owners between rebuilds: 40 moves, 1 rebuild);
  - tank: examples/wave_tank_disc.toml (one disc in a tank) to 2 s.
Checked:
  - on 2 and 3 ranks the run file equals the serial one bit for bit
    (`floesim compare --rtol 0 --atol 0`);
  - rank 0's drift phase (parallel.phase.drift) receives less than 0.6 of
    every floe's state (96 B) each step on bem and ocean: with every state
    sent to every rank (the drift's complete_owned, before implicit28) it
    is 1.01 of it on 2 ranks;
  - on 2 ranks in the poison mode (FLOESIM_TEST_POISON_UNHELD=step and
    step-lure: each rank's copies of the horizontal state of the floes it
    does not hold NaN, or wrong but finite, after each exchange; the
    vertical DOFs, which every rank holds, checked in every floe): bit for
    bit, no phase reported, floes poisoned on bem and ocean;
  - ocean, slabs and moved run with the sea in slabs (parallel.slab_rows printed,
    N + 1 cuts), and the ocean's slabs move on 2 ranks (parallel.strip_moves);
  - the bem and slabs cases stopped half-way on 2 ranks and continued from
    their checkpoints on 3 ranks equal the serial run bit for bit.
The mutations that fail it (builds not committed): the tilt inertia from
the rank's own copy of the yaw (FloeSeaContact::gather_tilted_yaw skipped):
the ocean differs on 2 and 3 ranks, the ocean's and the tank's `step` runs
report NaN (bem's floes resist no slope); the midpoint posed by index (every
floe, the drift's owners not given): bem, ocean and tank differ on 3 ranks,
and the restart; the implicit step's zero vertical kick kept (kick_floes,
whose tilt term reads the yaw): the ocean's `step` run fails, the tank's
reports NaN. In slabs (slabs30): the dots' partials summed as doubles in
rank order, the answer route off, and the self-response from each rank's own
slab's first node each make ocean and slabs differ on 2 and 3 ranks (the answer route off:
ocean's runs and slabs' on 3 ranks fail with an error).
"""
import os
import sys
from pathlib import Path

from ranks_harness import finish, half_pack, need, ocean_toml, phase_bytes, ranks_check, summary

sys.path.insert(0, str(Path(__file__).resolve().parent.parent.parent / "scripts" / "scenarios"))
from whole_seas import SEAS, pack_command  # per case: its [sea] and its pack's arguments

args, harness = ranks_check(
    "floesim was built without MPI (FLOESIM_MPI=OFF): the implicit step on several ranks is not checked",
    lambda ap: ap.add_argument("--ranks", type=int, nargs="+", default=[2, 3]))
W = args.workdir
failures = []
run, mpirun = harness.run, harness.mpirun
EXAMPLES = Path(__file__).resolve().parent.parent.parent / "examples"

# check_whole_seas.py's BEM basin and pack (scripts/scenarios/whole_seas.py) with the implicit step.
BEM = """[run]
t_end = 2.0
dt_max = 0.02
output_interval = 0.5
threads = 1
""" + SEAS["bem"][0] + """
[floes]
pack = "bem_pack.h5"

[coupling]
stiffness = 100.0
law = "strong"
integrator = "implicit"
"""
need(run(pack_command(args.floesim, "bem", "bem_pack.h5")), "bem: floesim pack")
half_pack(run, args.floesim)
need(run([args.floesim, "pack", "--floes", "300", "--concentration", "0.6", "--box", "200", "200", "--seed", "5",
          "--min-size", "6", "--max-size", "15", "--thickness", "1", "-o", "slabs_pack.h5"]), "slabs: floesim pack")
IMPLICIT = 'integrator = "implicit"\n'
CASES = {  # name: (configuration, --until, floes whose drift bytes are bounded or None)
    "bem": (BEM, [], 150),
    "ocean": (ocean_toml("half_pack.h5", 5.0, 2.5, coupling=IMPLICIT), [], 120),
    "slabs": (ocean_toml("slabs_pack.h5", 2.0, 0.5, coupling=IMPLICIT), [], 300),
    "moved": (ocean_toml("slabs_pack.h5", 1.0, 0.5, coupling=IMPLICIT + "footprint_reach = 0.3\n"), [], 300),
    "tank": ((EXAMPLES / "wave_tank_disc.toml").read_text(), ["--until", "2"], None),
}
SLABS = ("ocean", "slabs", "moved")  # a spectral sea, dims = 2, no tank: in slabs
for name, (text, until, floes) in CASES.items():
    config = os.path.join(W, f"{name}.toml")
    with open(config, "w") as f:
        f.write(text)
    s = summary(need(run([args.floesim, "run", config, "-o", f"{name}_serial.h5", "-q", *until]), f"{name}: serial"))
    steps = int(s["steps"])
    print(f"{name}: serial, {steps} steps")
    for n in args.ranks:
        p = mpirun(n, "run", config, "-o", f"{name}_{n}.h5", "-q", *until)
        if p.returncode != 0:
            failures.append(f"{name} on {n} ranks: exit {p.returncode}\n{p.stderr}")
            continue
        harness.same(f"{name}_{n}.h5", f"{name}_serial.h5", f"{name}: {n} ranks against the serial run", failures)
        if name in SLABS:
            info = summary(p)
            cuts = info.get("parallel.slab_rows", "").split()
            if len(cuts) != n + 1:
                failures.append(f"{name} on {n} ranks: the sea is not in slabs (parallel.slab_rows: {cuts})")
            if name == "ocean" and n == 2 and int(info.get("parallel.strip_moves", "0")) < 1:
                failures.append(f"{name} on 2 ranks: the slabs did not move (parallel.strip_moves 0)")
            print(f"{name}: {n} ranks, slabs {' '.join(cuts)}, moves {info.get('parallel.strip_moves')}")
        if floes:
            drift, whole = phase_bytes(p, "drift"), 96 * floes * steps
            print(f"{name}: {n} ranks, rank 0's drift phase {summary(p)['parallel.phase.drift']}: "
                  f"{drift / whole:.3f} of every floe's state each step")
            if not drift < 0.6 * whole:
                failures.append(f"{name} on {n} ranks: rank 0's drift phase received {drift} B, not under 0.6 x 96 B "
                                f"x {floes} floes x {steps} steps = {0.6 * whole:.0f} (every state to every rank?)")
    harness.poison_clean(name, config, f"{name}_serial.h5", failures, floes=bool(floes), extra=until)

# A restart across rank counts: the checkpoint holds the step's mean
# horizontal loads and the footprints' reference poses, gathered from the
# owners that posed them.
harness.restart_2_on_3("bem", os.path.join(W, "bem.toml"), "bem_serial.h5", failures)
harness.restart_2_on_3("slabs", os.path.join(W, "slabs.toml"), "slabs_serial.h5", failures)
finish(failures)
