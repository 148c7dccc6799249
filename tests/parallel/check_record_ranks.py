#!/usr/bin/env python3
"""Runs that keep the impulse record (percussion fracture, [run]
record_collisions) on several ranks against the serial run (docs/parallel.md,
stage seven: the record made by owner and merged in the serial order).

usage: check_record_ranks.py FLOESIM MPIEXEC WORKDIR [--floes N] [--t-end T] [--ranks 2 3]
       check_record_ranks.py --no-mpi    (MPI not built: exits 77, ctest's skip code)

1. The collisions-only periodic pack of scripts/scenarios/moving_pack.py (400
   floes to 500 s by default) with percussion fracture (splits on) and
   record_collisions: on 2 and 3 ranks the run file, its /events/collisions
   (the record's events and loads) and /events/fracture (percussion reads the
   record on every rank) equal the serial run's bit for bit; some floes
   split; and the step-start collisions and the advance ran by owner (not
   redone whole) in most steps: parallel.collide_steps and advance_steps
   count the tries, *_fallbacks those redone whole, *_whole those skipped by
   the back-off. The fracture checks ran by owner: parallel.fracture_checks
   lists each rank's analyses, every one > 0, summing to the serial
   fracture.checks, parallel.fracture_charged their CPU seconds charged to
   the strips (every one > 0), and the summary's fracture.* counts equal the
   serial ones (the splits decided by their floe's owner and again when
   concluding, fracture.splits_redone, included).
   The record is made from each rank's part of the detection (its places
   keyed by pair); the same run on 2 ranks with advance_on_part = false
   (the whole lists gathered at every detection, the advance from the
   whole) is bit for bit too, and its detect phase receives more bytes
   (printed; check_advance_part.py asserts the drop on a larger pack, where
   the lists outweigh the detect phase's fixed reductions).
2. examples/pack_fracture.toml (a jam against a coast, breaking; its jam
   LCPs take the warm store, and clusters of the two ranks meet): bit for
   bit on 2 ranks, with both kinds of step present: kept at the first try,
   and tried again with the meeting clusters joined on one rank (each try
   recording afresh; these steps do not fall back whole:
   `parallel.advance_joined`), or redone whole.
3. In both: the states the splits read are gathered before them
   (`parallel.split_gathers`) in exactly the steps where a floe split
   (the serial run's /events/fracture rows with a piece): a step whose
   cracks are all refused (a sliver, a chord, the neighbours) gathers
   nothing (Percussion::may_split; docs/parallel.md, "A split step by its
   holders").
"""
import os
import shutil
import sys

from ranks_harness import FRACTURE, moving_pack_check, need, phase_bytes, summary

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

args, harness, base = moving_pack_check(
    "floesim was built without MPI (FLOESIM_MPI=OFF): the record on several ranks is not checked", 400, 500.0, [2, 3])
W = args.workdir
run, mpirun = harness.run, harness.mpirun
failures = []

config = os.path.join(W, "record.toml")
with open(base) as f:
    text = f.read()
if "[run]\n" not in text:
    sys.exit("FAILED: the moving pack's configuration has no [run] table")
with open(config, "w") as f:
    f.write(text.replace("[run]\n", "[run]\nrecord_collisions = true\n", 1) + FRACTURE)

s = summary(need(run([args.floesim, "run", config, "-o", "serial.h5", "-q"]), "serial run"))
splits, lcps = int(s.get("fracture.splits", "0")), int(s.get("collisions.lcps", "0"))
print(f"serial: {args.floes} floes to {args.t_end} s, {lcps} collision LCPs, {splits} splits, {s.get('floes')} floes")
if splits == 0 or lcps == 0:
    failures.append(f"the serial run had {lcps} LCPs and {splits} splits: the check would not test the record")


def kept_mostly(p, n, what):
    """The summary's tries by owner of `what` (collide, advance): most kept."""
    k = summary(p)
    steps = int(k.get(f"parallel.{what}_steps", "0"))
    fell = int(k.get(f"parallel.{what}_fallbacks", "0"))
    whole = int(k.get(f"parallel.{what}_whole", "0"))
    print(f"{n} ranks: {what}: {steps} steps tried by owner, {fell} redone whole, {whole} whole by the back-off")
    return steps, fell, whole


def split_steps(path):
    """The steps of a run file in which a floe split: the distinct times of
    its /events/fracture rows with a piece (piece_a >= 0)."""
    import h5py
    with h5py.File(os.path.join(W, path), "r") as f:
        if "events/fracture" not in f:
            return 0
        d = f["events/fracture"]
        columns = [c.decode() if isinstance(c, bytes) else str(c) for c in d.attrs["columns"]]
        rows = d[...]
    if rows.size == 0:
        return 0
    times = {float(r[columns.index("time")]) for r in rows if r[columns.index("piece_a")] >= 0}
    return len(times)


def check_split_gathers(p, serial, what):
    """Item 3: the steps that gathered states before a split (the split's
    readers since split28) are the steps in which a floe split."""
    gathered = int(summary(p).get("parallel.split_gathers", "-1 steps").split()[0])
    steps = split_steps(serial)
    print(f"{what}: the splits' readers' states gathered before the splits in {gathered} steps, "
          f"{steps} steps with a split (serial)")
    if steps == 0 or gathered != steps:
        failures.append(f"{what}: the states gathered for the splits in {gathered} steps, not the {steps} "
                        "steps with a split")


def detect_bytes(p):
    """The bytes the detect phase received (rank 0's)."""
    return phase_bytes(p, "detect")


# The whole lists gathered at every detection (advance_on_part = false), on
# 2 ranks: the detect phase's bytes the record run from the parts must stay
# well below.
whole_config = os.path.join(W, "record_whole.toml")
with open(whole_config, "w") as f:
    f.write(text.replace("[run]\n", "[run]\nrecord_collisions = true\nadvance_on_part = false\n", 1) + FRACTURE)
whole_bytes = None
p = mpirun(2, "run", whole_config, "-o", "ranks2_whole.h5", "-q")
c = harness.compare("ranks2_whole.h5", "serial.h5", 0)
print(f"2 ranks, the whole lists gathered: {'equal' if p.returncode == 0 and c.returncode == 0 else 'DIFFERENT'} "
      f"to the serial run; detect {summary(p).get('parallel.phase.detect') if p.returncode == 0 else '-'}")
if p.returncode != 0 or c.returncode != 0:
    failures.append(f"2 ranks, advance_on_part false: exit {p.returncode}\n{p.stderr}\n{c.stdout}")
else:
    whole_bytes = detect_bytes(p)

for n in args.ranks:
    out = f"ranks{n}.h5"
    p = mpirun(n, "run", config, "-o", out, "-q")
    if p.returncode != 0:
        failures.append(f"{n} ranks: exit {p.returncode}\n{p.stdout}\n{p.stderr}")
        continue
    c = harness.compare(out, "serial.h5", 0)
    print(f"{n} ranks: {'equal' if c.returncode == 0 else 'DIFFERENT'} to the serial run (bit for bit); "
          f"detect {summary(p).get('parallel.phase.detect')}")
    if c.returncode != 0:
        failures.append(f"{n} ranks differ from the serial run:\n{c.stdout}")
    if n == 2 and whole_bytes is not None and not detect_bytes(p) < whole_bytes:
        failures.append(f"2 ranks: the record run's detect phase received {detect_bytes(p)} bytes, not fewer than "
                        f"{whole_bytes} with the whole lists gathered")
    check_split_gathers(p, "serial.h5", f"{n} ranks")
    k = summary(p)
    by_rank = [int(x) for x in k.get("parallel.fracture_checks", "").split()]
    print(f"{n} ranks: fracture checks by rank {by_rank} (serial {s.get('fracture.checks')}), "
          f"seconds by rank {k.get('parallel.fracture_seconds')}")
    if len(by_rank) != n or min(by_rank) <= 0 or sum(by_rank) != int(s.get("fracture.checks", "-1")):
        failures.append(f"{n} ranks: the fracture checks by rank {by_rank} are not {n} shares > 0 summing to the "
                        f"serial {s.get('fracture.checks')}")
    # The analyses' CPU seconds charged to the strips' moves, by rank: every
    # rank analysed floes in the closed windows.
    charged = [float(x) for x in k.get("parallel.fracture_charged", "").split()]
    print(f"{n} ranks: fracture seconds charged to the strips by rank {charged}; splits decided by their owner "
          f"and again in conclude: {k.get('fracture.splits_redone')} (serial {s.get('fracture.splits_redone')})")
    if len(charged) != n or min(charged) <= 0.0:
        failures.append(f"{n} ranks: the fracture seconds charged by rank {charged} are not {n} values > 0")
    for key in ("checks", "screened", "bounded", "sustained", "cut_short", "loop_steps", "initiations", "splits",
                "failed_splits", "refused_small", "refused_overlap", "splits_redone"):
        if k.get(f"fracture.{key}") != s.get(f"fracture.{key}"):
            failures.append(f"{n} ranks: fracture.{key} {k.get(f'fracture.{key}')}, serial {s.get(f'fracture.{key}')}")
    for what in ("collide", "advance"):
        steps, fell, whole = kept_mostly(p, n, what)
        total = steps + whole
        if not (total > 0 and steps - fell > total / 2):
            failures.append(f"{n} ranks: the {what} by owner was kept in {steps - fell} of {total} steps")

# The jam against a coast: its LCPs take the warm store, so some steps fall
# back to the whole solve, recorded into the run's record directly.
example = os.path.join(ROOT, "examples", "pack_fracture.toml")
for name in ("pack_fracture.toml", "pack_against_wall.h5"):
    shutil.copy(os.path.join(ROOT, "examples", name), W)
until = ["--until", "900"]
s = summary(need(run([args.floesim, "run", "pack_fracture.toml", "-o", "jam_serial.h5", "-q", *until]),
                 "pack_fracture serial"))
p = mpirun(2, "run", "pack_fracture.toml", "-o", "jam_2.h5", "-q", *until)
c = harness.compare("jam_2.h5", "jam_serial.h5", 0)
equal = p.returncode == 0 and c.returncode == 0
print(f"pack_fracture to 900 s ({s.get('fracture.splits')} splits): 2 ranks {'equal' if equal else 'DIFFERENT'} "
      "to the serial run")
if not equal:
    failures.append(f"pack_fracture on 2 ranks: exit {p.returncode}\n{p.stderr}\n{c.stdout}")
else:
    check_split_gathers(p, "jam_serial.h5", "pack_fracture on 2 ranks")
    steps, fell, whole = kept_mostly(p, 2, "advance")
    joined = int(summary(p).get("parallel.advance_joined", "0"))
    print(f"2 ranks: advance: {joined} tries combined with meeting clusters joined on one rank")
    if not (steps > fell + joined and fell + joined > 0):
        failures.append(f"pack_fracture on 2 ranks: expected advances kept and tried again or redone ({steps} tried, "
                        f"{joined} joined, {fell} redone)")
if s.get("fracture.splits", "0") == "0":
    failures.append("pack_fracture: no split by 900 s")

if failures:
    print("FAILED:\n" + "\n".join(failures))
    sys.exit(1)
print("ok")
