#!/usr/bin/env python3
"""Distributed runs against the serial run (docs/parallel.md).

usage: check_ranks.py FLOESIM MPIEXEC WORKDIR [--floes N] [--t-end T] [--ranks 1 2 3] [--rtol R]
                      [--also CONFIG...] [--also-rtol R] [--fallback CONFIG [--fallback-until T]]
                      [--no-errors]
       check_ranks.py --no-mpi    (MPI not built: says so and exits 77, ctest's skip code)

The collisions-only periodic pack of scripts/scenarios/moving_pack.py (N
floes at 50 % cover, started at random velocities up to 0.1 m/s as
bench/collisions.cpp's packs, with wind, current and Coriolis; they collide,
also across the seams) run serially, then by `mpirun -np R`
for each R: every run file must equal the serial one (`floesim compare`,
rtol 0 and atol 0 by default: bit for bit, which stage one's replicated state
and ordered gathers promise); so must a run stopped half-way on 2 ranks and
continued with --restart on 2 ranks. Each --also CONFIG (a run with a sea, say) is
checked on 2 ranks with --also-rtol (0 by default: since stage eight and
notslabs25 a sea with the explicit kicks sums every shared cell in the
serial order, docs/parallel.md). --fallback CONFIG: a run whose step-start collisions
take the warm store (the wall jam) must equal the serial run on 2 and 3 ranks
with no try fallen back for it, and so must it under the test hook
FLOESIM_TEST_COLLIDE_FALLBACK=warm, whose tries fall back (counted) to the
whole solve. Then the errors: bad input and a run file that
rank 0 cannot create must end every rank with exit 2 and 1, and the message
said once.
"""
import argparse
import os
import sys

from ranks_harness import moving_pack_check, need


def options(ap):
    ap.add_argument("--rtol", type=float, default=0.0)
    ap.add_argument("--errors", action=argparse.BooleanOptionalAction, default=True)
    ap.add_argument("--also", nargs="*", default=[], help="other configurations to check on 2 ranks (e.g. with a sea)")
    ap.add_argument("--also-rtol", type=float, default=0.0, help="relative tolerance of the --also runs")
    ap.add_argument("--fallback", help="a run whose step-start collisions take the warm store (a jam forming "
                    "against a wall): on 2 and 3 ranks, plain and with the fallback's test hook, bit for bit")
    ap.add_argument("--fallback-until", type=float, help="the --fallback runs stop at this time")


args, harness, config = moving_pack_check(
    "floesim was built without MPI (FLOESIM_MPI=OFF): the distributed runs are not checked", 1500, 1000.0, [1, 2, 3],
    options)
W = args.workdir
failures = []
run, mpirun = harness.run, harness.mpirun

serial = need(run([args.floesim, "run", config, "-o", "serial.h5", "-q"]), "serial run")
lcps = next(int(l.split()[1]) for l in serial.stdout.splitlines() if l.startswith("collisions.lcps:"))
print(f"serial: {args.floes} floes to {args.t_end} s, {lcps} collision LCPs")
if lcps == 0:
    failures.append("the serial run had no collision: the check would not test the collisions")

for n in args.ranks:
    out = f"ranks{n}.h5"
    p = mpirun(n, "run", config, "-o", out, "-q")
    if p.returncode != 0:
        failures.append(f"{n} ranks: exit {p.returncode}\n{p.stdout}\n{p.stderr}")
        continue
    c = run([args.floesim, "compare", out, "serial.h5", "--rtol", str(args.rtol), "--atol", "0"])
    verdict = "equal" if c.returncode == 0 else "DIFFERENT"
    print(f"{n} ranks: {verdict} to the serial run (rtol {args.rtol}, atol 0)")
    if c.returncode != 0:
        failures.append(f"{n} ranks differ from the serial run:\n{c.stdout}")
    if p.stdout.count("status: complete") != 1:
        failures.append(f"{n} ranks: the summary should be printed once (by rank 0):\n{p.stdout}")
    # Stage six: the strips moved by measured cost during the run, so the
    # equality above holds with the drift and detection split by changing strips.
    moves = [int(l.split()[1]) for l in p.stdout.splitlines() if l.startswith("parallel.strip_moves:")]
    if n > 1 and not (moves and moves[0] > 0):
        failures.append(f"{n} ranks: the strips never moved (parallel.strip_moves: {moves})")
    # Stage seven: the advance ran by cluster owner, so the equality above
    # holds with each rank advancing its own clusters (a step redone whole
    # after a conflict between ranks is the serial advance: not all may be).
    key = lambda k: next((l.split(":", 1)[1].split() for l in p.stdout.splitlines() if l.startswith(k + ":")), [])
    steps, fallbacks, clusters = key("parallel.advance_steps"), key("parallel.advance_fallbacks"), key("parallel.advance_clusters")
    if n > 1:
        print(f"{n} ranks: {steps} advances by cluster owner, {fallbacks} redone whole, clusters by rank {clusters}")
        if not (steps and fallbacks and int(steps[0]) > int(fallbacks[0]) and sum(map(int, clusters)) > 0):
            failures.append(f"{n} ranks: no advance by cluster owner was kept ({steps}, {fallbacks}, {clusters})")
        # Its set-up by owner too: each rank computed the rooms of its own
        # pairs (and the few it read besides), not every pair's.
        rooms, pairs = key("parallel.advance_rooms"), key("parallel.advance_pairs")
        print(f"{n} ranks: pair rooms computed by rank {rooms} of {pairs} pairs in the advances kept")
        if not (rooms and pairs and len(rooms) == n and all(0 < int(r) < int(pairs[0]) for r in rooms)):
            failures.append(f"{n} ranks: the advance's set-up was not shared (rooms {rooms}, pairs {pairs})")
    # The collisions at the step's start by owner too: every try kept here
    # (no warm store at step start in this pack), step groups on every rank.
    tried, fell, groups = key("parallel.collide_steps"), key("parallel.collide_fallbacks"), key("parallel.collide_groups")
    if n > 1:
        print(f"{n} ranks: {tried} step-start collisions by owner, {fell} redone whole, groups by rank {groups}")
        if not (tried and fell and int(tried[0]) > 0 and int(fell[0]) == 0 and len(groups) == n
                and all(int(g) > 0 for g in groups)):
            failures.append(f"{n} ranks: the step-start collisions did not run by owner ({tried}, {fell}, {groups})")
    # The communication by phase: the phases' bytes (and the rest) are rank
    # 0's total, and the drift (the states) and detection (the lists) receive some.
    if n > 1:
        phase = {l.split(":")[0][len("parallel.phase."):]: l.split(":", 1)[1].split()
                 for l in p.stdout.splitlines() if l.startswith("parallel.phase.")}
        total = key("parallel.bytes_received")
        print(f"{n} ranks: bytes received by phase {dict((k, int(v[2])) for k, v in phase.items())}")
        if not (total and sum(int(v[2]) for v in phase.values()) == int(total[0])
                and all(int(phase.get(k, [0, 0, 0])[2]) > 0 for k in ("drift", "detect"))):
            failures.append(f"{n} ranks: the bytes by phase do not add up to {total}: {phase}")

# A restart on 2 ranks: the first half, then --restart from its checkpoint
# (written by rank 0, read by every rank), equals the serial run.
half = args.t_end / 2
p1 = mpirun(2, "run", config, "-o", "half.h5", "-q", "--until", str(half))
p2 = mpirun(2, "run", "--restart", "half.h5", "-o", "restarted.h5", "-q") if p1.returncode == 0 else p1
c = run([args.floesim, "compare", "restarted.h5", "serial.h5", "--rtol", str(args.rtol), "--atol", "0"])
print(f"restart at {half} s on 2 ranks: {'equal' if p2.returncode == 0 and c.returncode == 0 else 'DIFFERENT'} "
      "to the serial run")
if p2.returncode != 0 or c.returncode != 0:
    failures.append(f"restart on 2 ranks: exit {p2.returncode}\n{p2.stderr}\n{c.stdout}")

# Other scenarios (a sea: within --also-rtol).
for other in args.also:
    name = os.path.splitext(os.path.basename(other))[0]
    need(run([args.floesim, "run", other, "-o", f"{name}_serial.h5", "-q"]), f"{other}: serial run")
    p = mpirun(2, "run", other, "-o", f"{name}_2.h5", "-q")
    c = run([args.floesim, "compare", f"{name}_2.h5", f"{name}_serial.h5", "--rtol", str(args.also_rtol), "--atol", "0"])
    print(f"{name}: 2 ranks {'equal' if p.returncode == 0 and c.returncode == 0 else 'DIFFERENT'} to the serial run "
          f"(rtol {args.also_rtol}, atol 0)")
    if p.returncode != 0 or c.returncode != 0:
        failures.append(f"{other} on 2 ranks: exit {p.returncode}\n{p.stderr}\n{c.stdout}")

# The wall jam (--fallback): a forming jam's step-start LCPs take the warm
# store. Each share runs on a copy of the store and sends the pairs it
# stored: no try falls back for it (plain runs). The test hook
# FLOESIM_TEST_COLLIDE_FALLBACK=warm makes a share's use of the store a
# conflict, so those tries fall back to the whole solve on every rank (the
# state gathered on demand): still the serial run bit for bit, with
# fallbacks counted by kind and some tries kept.
if args.fallback:
    until = ["--until", str(args.fallback_until)] if args.fallback_until else []
    need(run([args.floesim, "run", args.fallback, "-o", "fallback_serial.h5", "-q", *until]), "fallback: serial run")
    kept_pairs = {}  # ranks -> (parallel.advance_pairs, parallel.advance_rebuilds) when no advance was redone
    for n, hook in ((2, None), (3, None), (2, "warm"), (3, "warm")):
        what = f"fallback run on {n} ranks" + (f" (FLOESIM_TEST_COLLIDE_FALLBACK={hook})" if hook else "")
        p = harness.mpirun(n, "run", args.fallback, "-o", f"fallback_{n}.h5", "-q", *until,
                           hooks={"FLOESIM_TEST_COLLIDE_FALLBACK": hook} if hook else None)
        c = run([args.floesim, "compare", f"fallback_{n}.h5", "fallback_serial.h5", "--rtol", "0", "--atol", "0"])
        key = lambda k: next((l.split(":", 1)[1].split() for l in p.stdout.splitlines() if l.startswith(k + ":")), [])
        tried, fell = key("parallel.collide_steps"), key("parallel.collide_fallbacks")
        equal = p.returncode == 0 and c.returncode == 0
        print(f"{what}: {'equal' if equal else 'DIFFERENT'} to the serial run; "
              f"{tried} step-start collisions by owner, {fell} redone whole")
        if not equal:
            failures.append(f"{what}: exit {p.returncode}\n{p.stderr}\n{c.stdout}")
            continue
        kinds = {l.split(":", 1)[0]: int(l.split(":", 1)[1]) for l in p.stdout.splitlines()
                 if l.startswith(("parallel.advance_conflicts.", "parallel.collide_conflicts."))}
        warm = kinds.get("parallel.collide_conflicts.warm_start", 0)
        if hook:
            # The hook's fallbacks: the whole path, some tries still kept,
            # every fallback the hook's kind.
            if not (tried and fell and int(fell[0]) > 0 and int(tried[0]) > int(fell[0])):
                failures.append(f"{what}: expected fallbacks and kept tries ({tried}, {fell})")
            elif warm != int(fell[0]):
                failures.append(f"{what}: the collisions' fallbacks by kind {kinds} do not sum to {fell}")
        else:
            # Without the hook no try falls back for the warm store.
            if not (tried and fell and int(tried[0]) > 0):
                failures.append(f"{what}: no step-start collisions by owner ({tried}, {fell})")
            elif warm:
                failures.append(f"{what}: a step-start try fell back for the warm store (cured): {kinds}")
            elif sum(v for k, v in kinds.items() if k.startswith("parallel.collide_")) < int(fell[0]):
                failures.append(f"{what}: the collisions' fallbacks {fell} are not all counted by kind {kinds}")
        # The advance's fallbacks by kind: neither the warm store nor clusters
        # of two ranks that meet send an advance to the whole fallback; the
        # meeting clusters are joined on one rank (which this run needs).
        afell = key("parallel.advance_fallbacks")
        print(f"{what}: advance {key('parallel.advance_steps')} tried, {afell} redone, "
              f"{key('parallel.advance_whole')} whole; by kind {kinds}")
        cured = [k for k in ("parallel.advance_conflicts.warm_start", "parallel.advance_conflicts.foreign_cluster",
                             "parallel.advance_conflicts.taken_twice") if k in kinds]
        joined = key("parallel.advance_joined")
        print(f"{what}: {joined} advances combined with meeting clusters joined on one rank")
        if cured:
            failures.append(f"{what}: an advance fell back for a cured kind: {kinds}")
        if not (joined and int(joined[0]) > 0):
            failures.append(f"{what}: no advance joined meeting clusters ({joined}): the case no longer tests it")
        if not (afell and sum(v for k, v in kinds.items() if k.startswith("parallel.advance_")) >= int(afell[0])):
            failures.append(f"{what}: the advance's fallbacks {afell} are not all counted by kind {kinds}")
        # The pairs of the advances kept: with none redone, every step's
        # list counted once whatever the ranks (the parts' lists add up, a
        # list every rank rebuilt counts once: this run rebuilds one).
        if not hook and afell == ["0"]:
            kept_pairs[n] = (key("parallel.advance_pairs"), key("parallel.advance_rebuilds"))
    if len(kept_pairs) == 2:
        (p2, r2), (p3, r3) = kept_pairs[2], kept_pairs[3]
        print(f"fallback runs, every advance kept: {p2} and {p3} pairs on 2 and 3 ranks ({r2} and {r3} rebuilds)")
        if p2 != p3:
            failures.append(f"fallback runs: the advances' pairs differ on 2 and 3 ranks ({p2}, {p3})")

if args.errors:
    # Bad input: every rank reads it, every rank stops, exit 2, said once.
    bad = os.path.join(W, "bad.toml")
    with open(bad, "w") as f:
        f.write(open(config).read().replace("dt_max = 10.0", "dt_max = -1.0"))
    p = mpirun(2, "run", bad, "-o", "bad.h5", "-q")
    if p.returncode != 2 or p.stderr.count("dt_max") != 1:
        failures.append(f"bad input on 2 ranks: expected exit 2 and one message naming dt_max, got exit "
                        f"{p.returncode}:\n{p.stderr}")
    # A failure of rank 0 alone (its run file cannot be created: the path is a
    # folder): the other rank hears of it, both stop, exit 1, said once.
    os.makedirs(os.path.join(W, "a_folder.h5"), exist_ok=True)
    p = mpirun(2, "run", config, "-o", "a_folder.h5", "-q")
    if p.returncode != 1 or p.stderr.count("floesim: run failed") != 1 or "a_folder.h5" not in p.stderr:
        failures.append(f"unwritable run file on 2 ranks: expected exit 1 and one message naming the file, got exit "
                        f"{p.returncode}:\n{p.stderr}")
    else:
        print("errors: bad input (exit 2) and rank 0's failure alone (exit 1) stop both ranks, said once")

if failures:
    print("FAILED:\n" + "\n".join(failures))
    sys.exit(1)
print("ok")
