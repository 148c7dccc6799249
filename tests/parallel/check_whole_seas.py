#!/usr/bin/env python3
"""Distributed runs on the seas not in slabs against the serial run
(docs/parallel.md, "The seas not in slabs in the serial order").

usage: check_whole_seas.py FLOESIM MPIEXEC WORKDIR [--ranks 2 3] [--part ranks|poison|all]
       check_whole_seas.py --no-mpi    (MPI not built: exits 77, ctest's skip code)

A BEM sea, a spectral tank and a long-crested spectral sea (dims = 1) are
whole on every rank (only a spectral sea with dims = 2 and no tank runs in
slabs); their floes are owned by place for the coupling (docs/parallel.md,
"The seas not in slabs, their floes by place"): the drift's owners (strips
in y) on the bem and tank, shares of the columns in the flume. Each case is
a dense pack (`floesim pack`, 70 % cover) whose floes are smaller than a few
cells, so that many cells hold pieces of three or more floes of several
ranks, with the explicit kicks (the law by owner) to 2 s:
  - bem: 150 floes in a 12 m x 6 m basin with walls (BEM, 24 x 12 cells);
  - tank: 100 floes in a 24 m x 6 m tank (spectral, 96 x 24 cells, wave
    maker and absorber);
  - flume: 40 floes in a 24 m x 2 m flume (spectral, dims = 1, 96 x 1
    cells: every cell spans the flume);
  - wide: 160 floes in a flume 8 m wide (the same grid's cells 8 m across),
    with the blend law (its explicit damper: the loads go stale at each
    kick, so each first half kick evaluates them again). The drift's bands
    (strips in y) do not hold every floe of a rank's share of the columns:
    those come to it by the drift's exchange (docs/parallel.md, "The halo
    exchange on the seas not in slabs (halo27)").
Checked, on 2 and 3 ranks:
  - the run file equals the serial one bit for bit (`floesim compare --rtol
    0 --atol 0`): each cell's coverage, sums and pressure are the serial
    sums, made from every rank's pieces in the serial order on every rank.
    Summing each rank's part and then the parts (stage three's merge, before
    notslabs25) differed on every case here in the floes' states and the
    sea (by ~1e-14 relative), not only in the penalty energy;
  - rank 0 sent cells as pieces (parallel.coupling_cells: `shared` > 0), so
    the pieces' path was taken, and cells summed alone and sent as totals;
  - in the flume, a cell rank 0 sends as pieces (under another rank's
    floe's box) lies within d = ceil(R / dx) + 2 columns of a cut between
    two shares (R the pack's largest floe radius; its pieces and the other
    floe's box each lie within R / dx + 1 columns of their owners' shares,
    the owners being those of the floes' places one evaluation earlier,
    less than a column away): at most 2 d cells a cut, the cuts being ranks
    of them (the seam counted). The first evaluation, by index, may send
    every cell. d = 6 of its 96 cells: on 2 ranks at most 24 cells an
    evaluation; by index (the mutation) its rank 0 sends about 95. The same
    bound in the wide flume, whose first half kicks rebuild the footprints
    with the last rebuild's owners (by index there, every floe posed: 2.2
    times the bound on 2 ranks, 1.4 on 3);
  - the kick by its holders (docs/parallel.md, "The kick by owner
    (kick29)"): on bem, tank and wide rank 0 takes each evaluation's loads
    by request (parallel.coupling_loads: at least one request a step, at
    most one share to every rank, the start's) and receives fewer than 0.6
    of every floe's loads an evaluation;
  - with the halo exchange (every sea with the explicit kicks), rank 0's
    drift phase (parallel.phase.drift) receives less than 0.6 of every
    floe's state (96 B) each step on the bem, tank and wide cases, whose
    bands do not hold every floe (the flume's every rank holds every floe;
    every state to every rank, without the halo exchange, is above 1.0 with
    the water's hand-over).
Then the flume's pack numbered along x (its floes sorted by x: there the
owners by index would be shares of the columns too) on 2 ranks: bit for bit
with its serial run, and rank 0's penalty phase receives at most 1.2 times
the bytes of the pack numbered as made (in two rows along the flume: by
index each rank's floes would lie along the whole flume and every cell
travel as pieces, 3 times the bytes). By place the numbering does not
choose the owners.
Then bem, tank, flume and wide on 2 ranks in the poison mode
(FLOESIM_TEST_POISON_UNHELD=step and step-lure: each rank's copies of the
floes it does not hold, neither in its band nor its own nor its coupling's,
are NaN, or wrong but finite, in the windows; docs/parallel.md, "The poison
mode of the run"): bit for bit with the serial run, no phase reported, floes
poisoned (none in the flume, whose every rank holds every floe). The
coupling's owners are the drift's, or a flume's column shares sent their
floes by the drift's exchange, so a rank builds and reads only floes it
holds. With the columns' shares on the tank too (each rank's coupling
floes along the whole width of the tank, outside its band in y) the run
crashed (SIGSEGV on a NaN place); with the next coupling owner left out of
the drift's exchange the wide flume differs from the serial run, plain and
with the lure, and crashes with NaN.
Then the bem case stopped half-way on 2 ranks and continued from its
checkpoint on 3 ranks must equal the serial run bit for bit.
Then the wide flume with fracture (286 floes at 2 s from 160) on 2 ranks,
from the parts and from the whole detection (advance_on_part = false), bit
for bit with the serial run: a split reads its parent's state on every
rank, whose vertical drift only its holders made (with the split's gather
skipped after the drift's whole exchange, 284 floes on 2 ranks). From the
parts: rank 0's split gathers (parallel.split_gathers) below a quarter of
every floe's state a split step (the split's readers only, the sea's
coupling built by the owners after a split), and the poison modes clean.

`--part ranks` runs the cases on 2 and 3 ranks and the flume numbered along
x; `--part poison` the poison mode, the restart and the splits (each part
makes the packs and serial runs it compares with): ctest runs the two as
two tests, each well under its timeout when oversubscribed ranks share the
cores with other jobs (the whole took 48-54 s alone, 68-119 s in the suite).
"""
import math
import os
import re
import sys

from ranks_harness import finish, need, phase_bytes, ranks_check, summary

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))), "scripts",
                                "scenarios"))
from whole_seas import SEAS, pack_command  # per case: its [sea] and its pack's arguments

args, harness = ranks_check(
    "floesim was built without MPI (FLOESIM_MPI=OFF): the runs on the seas not in slabs are not checked",
    lambda ap: (ap.add_argument("--ranks", type=int, nargs="+", default=[2, 3]),
                ap.add_argument("--part", choices=("ranks", "poison", "all"), default="all")))
W = args.workdir
failures = []
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
stiffness = 100.0
{law}"""
# Per case: the grid's cells along x and y, its cell size along x and y (m).
GRIDS = {"bem": (24, 12, 0.5, 0.5), "tank": (96, 24, 0.25, 0.25), "flume": (96, 1, 0.25, 2.0),
         "wide": (96, 1, 0.25, 8.0)}
# Per case: the penalty law's lines ([coupling]).
LAWS = {"wide": 'law = "blend"\nblend = 0.5\n'}
FLUMES = ("flume", "wide")  # dims = 1: the coupling's owners are shares of the columns
SOME_HELD = ("bem", "tank", "wide")  # the bands do not hold every floe on 2 ranks


def coupling(name, pack):
    return COUPLING.format(pack=pack, law=LAWS.get(name, 'law = "strong"\n'))

def largest_radius(pack):
    """The largest distance of a floe's vertex from its centroid (m) in a pack file."""
    import h5py  # (only with MPI: --no-mpi needs nothing of it)
    with h5py.File(os.path.join(W, pack), "r") as f:
        offsets, vertices = f["floes/offsets"][:], f["floes/vertices"][:]
    return max(math.hypot(*v) for v in vertices) if len(offsets) > 1 else 0.0


def numbered_along_x(pack, out):
    """The floes of `pack` renumbered by their centroids' x, written to `out`."""
    import h5py
    import numpy as np
    with h5py.File(os.path.join(W, pack), "r") as f, h5py.File(os.path.join(W, out), "w") as g:
        for k, v in f.attrs.items():
            g.attrs[k] = v
        for k in f:
            if k != "floes":
                f.copy(k, g)
        floes = f["floes"]
        order = np.argsort(floes["pose"][:, 0], kind="stable")
        offsets, vertices = floes["offsets"][:], floes["vertices"][:]
        out_floes = g.create_group("floes")
        for k in floes:
            if k not in ("offsets", "vertices"):
                out_floes[k] = floes[k][:][order]
        out_floes["vertices"] = np.concatenate([vertices[offsets[i]:offsets[i + 1]] for i in order])
        out_floes["offsets"] = np.concatenate([[0], np.cumsum([offsets[i + 1] - offsets[i] for i in order])]).astype(
            offsets.dtype)


def penalty_bytes(p):
    return phase_bytes(p, "penalty")


RANKS, POISON = args.part in ("ranks", "all"), args.part in ("poison", "all")
serial_steps = {}  # case -> the serial run's steps
for name, (sea, pack) in SEAS.items():
    need(run(pack_command(args.floesim, name, f"{name}_pack.h5")), f"{name}: floesim pack")
    config = os.path.join(W, f"{name}.toml")
    with open(config, "w") as f:
        f.write(RUN + sea + coupling(name, f"{name}_pack.h5"))
    s = summary(need(run([args.floesim, "run", config, "-o", f"{name}_serial.h5", "-q"]), f"{name}: serial run"))
    print(f"{name}: serial to 2 s, {s.get('steps')} steps")
    serial_steps[name] = int(s["steps"])

penalty = {}  # (case, ranks) -> rank 0's penalty bytes
for name, (sea, pack) in SEAS.items() if RANKS else ():
    config = os.path.join(W, f"{name}.toml")
    steps = serial_steps[name]
    nx, ny, dx, dy = GRIDS[name]
    along_x = ny == 1 or nx >= ny  # the strips' rule (FloeSeaContact::set_strips)
    d = math.ceil(largest_radius(f"{name}_pack.h5") / (dx if along_x else dy)) + 2
    for n in args.ranks:
        p = mpirun(n, "run", config, "-o", f"{name}_{n}.h5", "-q")
        if p.returncode != 0:
            failures.append(f"{name} on {n} ranks: exit {p.returncode}\n{p.stderr}")
            continue
        harness.same(f"{name}_{n}.h5", f"{name}_serial.h5", f"{name}: {n} ranks against the serial run", failures)
        s = summary(p)
        penalty[name, n] = penalty_bytes(p)
        cells = s.get("parallel.coupling_cells")
        evaluations = int(s["footprints.placements"])
        bound = nx * ny + (evaluations - 1) * n * 2 * d * (ny if along_x else nx)
        print(f"{name}: {n} ranks, rank 0's cells: {cells} in {evaluations} evaluations (shared at most {bound}); "
              f"penalty {s['parallel.phase.penalty']}")
        m = re.match(r"(\d+) shared \((\d+) pieces\), (\d+) alone owned, (\d+) alone sent", cells or "")
        if not m or int(m.group(1)) == 0 or int(m.group(4)) == 0:
            failures.append(f"{name} on {n} ranks: no cell sent as pieces, or none as a total ({cells})")
        elif name in FLUMES and int(m.group(1)) > bound:
            failures.append(f"{name} on {n} ranks: rank 0 sent {m.group(1)} cells as pieces, more than the {bound} "
                            f"within {d} cells of the shares' cuts (the floes not owned by place?)")
        # The halo exchange: the drift's states to their holders only.
        drift = phase_bytes(p, "drift")
        whole = 96 * int(pack[1]) * steps  # every floe's state, every step
        print(f"{name}: {n} ranks, rank 0's drift phase {s['parallel.phase.drift']}: {drift / whole:.3f} of every "
              f"floe's state each step")
        if name in SOME_HELD and not drift < 0.6 * whole:
            failures.append(f"{name} on {n} ranks: rank 0's drift phase received {drift} bytes, not under 0.6 x "
                            f"96 B x {pack[1]} floes x {steps} steps = {0.6 * whole:.0f} (every state to every rank?)")
        # The kick by its holders: each evaluation's loads travel from the
        # coupling's owner to the other ranks that hold the floe only (after
        # the start's, which every rank takes).
        loads = s.get("parallel.coupling_loads", "")
        print(f"{name}: {n} ranks, rank 0's loads: {loads}")
        m = re.match(r"(\d+) by request \((\d+) floes\), (\d+) to every rank", loads)
        if name in SOME_HELD and (not m or int(m.group(1)) < steps or int(m.group(3)) > 1 or
                                  not int(m.group(2)) < 0.6 * int(pack[1]) * int(m.group(1))):
            failures.append(f"{name} on {n} ranks: rank 0's loads ({loads or 'none'}) not by request at every "
                            f"evaluation, or not under 0.6 of {pack[1]} floes an evaluation (every floe's to every "
                            f"rank?)")

# The flume's floes numbered along x: the same owners by place, so the same
# traffic within the runs' own drift (the two packs' serial runs differ in
# their floes' order, so in round-off).
def flume_along_x():
    numbered_along_x("flume_pack.h5", "flume_x_pack.h5")
    config = os.path.join(W, "flume_x.toml")
    with open(config, "w") as f:
        f.write(RUN + SEAS["flume"][0] + coupling("flume", "flume_x_pack.h5"))
    need(run([args.floesim, "run", config, "-o", "flume_x_serial.h5", "-q"]), "flume numbered along x: serial run")
    p = mpirun(2, "run", config, "-o", "flume_x_2.h5", "-q")
    if p.returncode != 0:
        failures.append(f"flume numbered along x on 2 ranks: exit {p.returncode}\n{p.stderr}")
    elif ("flume", 2) in penalty:
        harness.same("flume_x_2.h5", "flume_x_serial.h5", "flume numbered along x: 2 ranks against the serial run",
                     failures)
        along, made = penalty_bytes(p), penalty["flume", 2]
        print(f"flume on 2 ranks, rank 0's penalty bytes: {made} (numbered as made), {along} (numbered along x)")
        if not made <= 1.2 * along:
            failures.append(f"flume on 2 ranks: rank 0's penalty phase received {made} bytes with the pack numbered as "
                            f"made, more than 1.2 times the {along} with it numbered along x (owners by index?)")


if RANKS:
    flume_along_x()

FRACTURE = """
[fracture]
enabled = true
criterion = "stress"
strength = 2.0e3
split = true
mesh_size = 0.2
min_fragment_area = 0.05
"""


def poison_restart_splits():
    # The poison mode: the coupling, the seas and the step read only floes
    # their rank holds (none poisoned in the 2 m flume: every band holds every floe).
    for name in SEAS:
        harness.poison_clean(name, os.path.join(W, f"{name}.toml"), f"{name}_serial.h5", failures, floes=name != "flume")

    # A restart across rank counts: the bem case's first half on 2 ranks, the
    # rest from its checkpoint on 3 ranks.
    harness.restart_2_on_3("bem", os.path.join(W, "bem.toml"), "bem_serial.h5", failures)
    # Splits on a sea not in slabs: the wide flume with fracture (its floes
    # crack and split within the 2 s), on 2 ranks from the parts (the default,
    # the halo exchange) and from the whole detection (`advance_on_part =
    # false`: the drift sends every state). A split reads its parent's state on
    # every rank; the vertical drift before it moves only the floes each rank
    # holds, so the other copies' heave, pitch and roll are stale whatever the
    # drift's exchange, and whole_state must gather them.
    for label, run_table in (("from the parts", RUN), ("from the whole detection", RUN + "advance_on_part = false\n")):
        config = os.path.join(W, "wide_split.toml" if run_table == RUN else "wide_split_whole.toml")
        with open(config, "w") as f:
            f.write(run_table + SEAS["wide"][0] + coupling("wide", "wide_pack.h5") + FRACTURE)
        serial = config.replace(".toml", "_serial.h5")
        s = summary(need(run([args.floesim, "run", config, "-o", serial, "-q"]), f"wide with splits {label}: serial run"))
        print(f"wide with splits {label}: serial to 2 s, {s.get('floes')} floes from 160")
        if int(s.get("floes", 0)) <= 160:
            failures.append(f"wide with splits {label}: no floe split in the serial run ({s.get('floes')} floes)")
        p = mpirun(2, "run", config, "-o", config.replace(".toml", "_2.h5"), "-q")
        if p.returncode != 0:
            failures.append(f"wide with splits {label} on 2 ranks: exit {p.returncode}\n{p.stderr}")
            continue
        harness.same(config.replace(".toml", "_2.h5"), serial, f"wide with splits {label}: 2 ranks against the "
                     f"serial run", failures)
        if run_table != RUN:
            continue
        # A split step gathers only the states its conclusion reads (the split's
        # readers: the parents and their neighbours, 100 B a floe), with the sea
        # as without: rank 0's bytes in those gathers are below a quarter of the
        # 160 floes' states (96 B) a step, which every floe's state (the whole
        # gather, about 6 times that bound here) exceeds. And in the poison mode
        # the coupling's rebuild after a split poses only floes its rank holds
        # (the owners just placed, FloeSeaContact::floes_changed): with the
        # rebuild by index (every floe posed) the run ended with signal 11.
        m = re.match(r"(\d+) steps, (\d+) bytes", summary(p).get("parallel.split_gathers", ""))
        bound = None if not m else int(m.group(1)) * 160 * 96 / 4
        print(f"wide with splits {label}: rank 0's split gathers {m.group(0) if m else None} (bound {bound} bytes)")
        if not m or int(m.group(1)) == 0 or int(m.group(2)) >= bound:
            failures.append(f"wide with splits {label}: rank 0's split gathers "
                            f"({summary(p).get('parallel.split_gathers')}) not below a quarter of every floe's state")
        harness.poison_clean("wide_split", config, serial, failures)


if POISON:
    poison_restart_splits()
finish(failures)
