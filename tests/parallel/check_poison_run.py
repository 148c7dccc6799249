#!/usr/bin/env python3
"""The poison mode of the run (docs/parallel.md, "The poison mode of the run
(piece 7; poison18)" and "The halo exchange (halo26)"): with the test hook
FLOESIM_TEST_POISON_UNHELD=step (NaN), step-lure (finite, wrong values) or
step-mutant, each rank poisons its copies of the floes it does not hold (its
own floes, its halo band, its coupling's own floes) right after each part of
the halo exchange (after the drift, at the detection) and restores nothing,
and reports the first NaN it finds in a held floe, and in its sea, after
each phase.

usage: check_poison_run.py FLOESIM MPIEXEC WORKDIR
       check_poison_run.py --no-mpi    (MPI not built: exits 77, ctest's skip code)

On 2 ranks (`mpirun --oversubscribe`):
(a) no reader left: the collisions-only periodic pack of
    scripts/scenarios/moving_pack.py (400 floes to 250 s), NaN and lure, is
    bit for bit the serial run, every rank poisoning floes and reporting no
    phase (unless a step fell back to the whole solve: then said, not
    failed); on 1 rank the mode poisons nothing and the run is the serial one.
(b) known readers are found: the same pack with the advance from the whole
    detection (`advance_on_part = false`, whose set-up and clusters read
    every floe by design; the drift sends every state there) with the lure
    does not give the serial run. (The implicit floe-sea step, a known
    reader here until implicit28, reads only held floes since: its poisoned
    runs are check_implicit_ranks.py's, bit for bit.)
(c) the mutation: each rank poisons one floe it holds too; the run fails,
    and each rank reports it after the drift, the first phase checked.
(d) the whole state on demand (docs/parallel.md, "The whole state on demand
    (ondemand25)"): the steps that read every floe gather it from the owners
    first. The 10 000-floe pack of scripts/scenarios/moving_pack.py (seed 1,
    to 320 s: one pair-list rebuild on a part) on 2 ranks with NaN after the
    drift, and the wall-jam example (examples/pack_against_wall.toml to
    1500 s: the collisions' fallbacks and whole steps, made by the test hook
    FLOESIM_TEST_COLLIDE_FALLBACK=warm, and a rebuild) on 3 ranks with the lure (on 2 ranks every rank holds every
    floe there), are bit for bit the serial run, each having rebuilt or
    fallen back, with no phase reported; the mutation "-stale" (whole_state
    gathers nothing) fails or differs on both (NaN on the pack; the lure on
    the wall jam, where a sub-step on NaN makes no progress).
(e) the halo exchange's bytes: in (d)'s pack run, rank 0's drift phase
    receives less than a tenth of every floe's state each step.
(f) a split's neighbours among the held floes: check_writer_ranks.py's
    fracture pack (to 500 s, floes split) on 3 ranks with the lure is bit
    for bit the serial run.
Only what is stable is pinned.
"""
import os
import re
import sys

from ranks_harness import FRACTURE, moving_pack_check, need, phase_bytes, summary

args, harness, base = moving_pack_check(
    "floesim was built without MPI (FLOESIM_MPI=OFF): the poison mode is not checked", 400, 250.0, [2])
W = args.workdir
run = harness.run
failures = []


def mpirun(n, poison, config, out, *extra, hooks=None):
    """floesim on n ranks in the poison mode `poison`, with other test hooks (name -> value)."""
    return harness.mpirun(n, "run", config, "-o", out, "-q", *extra,
                          hooks=dict(hooks or {}, FLOESIM_TEST_POISON_UNHELD=poison))


def equal(a, b):
    return harness.compare(a, b, 0).returncode == 0


def summaries(p):
    """Each rank's poison summary: rank -> (windows, floes poisoned, phases reported, last check)."""
    out = {}
    for m in re.finditer(r"poison: rank (\d+): (\d+) windows, (\d+) floes poisoned in them, (\d+) phases reported, "
                         r"the last check after (.+)", p.stderr):
        out[int(m.group(1))] = (int(m.group(2)), int(m.group(3)), int(m.group(4)), m.group(5).strip())
    return out


def reports(p):
    """Each report, of a held floe or of the rank's sea (UnheldPoison::check,
    check_sea): (rank, phase, what: "held floe N's FIELD" or "the sea's modal state")."""
    return [(int(m.group(1)), m.group(2), m.group(3)) for m in
            re.finditer(r"poison: rank (\d+): after (.+?): (held floe \d+'s .+|the sea's modal state) is NaN", p.stderr)]


need(run([args.floesim, "run", base, "-o", "serial.h5", "-q"]), "the pack, serial")

# (a) No reader left on the collisions-only pack.
for poison in ["step", "step-lure"]:
    p = mpirun(2, poison, base, f"{poison}2.h5")
    s = summaries(p)
    what = f"the pack on 2 ranks, {poison}"
    if p.returncode != 0:
        failures.append(f"{what}: exit {p.returncode}\n{p.stderr}")
        continue
    same = equal(f"{poison}2.h5", "serial.h5")
    # The fallbacks (a conflict: the whole step on every rank) read every
    # floe (piece 3, a known reader); whether one happens depends on the
    # cuts, which move by measured time (none in the runs measured).
    whole = {k: summary(p).get(f"parallel.{k}", "0") for k in ["advance_whole", "collide_whole"]}
    print(f"{what}: {'equal' if same else 'DIFFERENT'} to the serial run; {s}; whole steps {whole}")
    if not same and any(v != "0" for v in whole.values()):
        print(f"{what}: a step fell back to the whole solve (a known reader): (a) not tested by this run")
    elif not same:
        failures.append(f"{what} differs from the serial run: a phase reads a floe outside its rank's held set\n{p.stderr}")
    if sorted(s) != [0, 1] or any(w == 0 or f == 0 or r != 0 for w, f, r, _ in s.values()):
        failures.append(f"{what}: every rank must open windows, poison floes and report no phase: {s}\n{p.stderr}")
p = mpirun(1, "step", base, "one.h5")
if p.returncode != 0 or not equal("one.h5", "serial.h5") or summaries(p):
    failures.append(f"1 rank, step: exit {p.returncode}, the mode must poison nothing and equal the serial run\n{p.stderr}")
else:
    print("1 rank, step: nothing poisoned, equal to the serial run")

# (b) Known readers. The advance from the whole detection, with the lure.
whole = os.path.join(W, "whole.toml")
with open(base) as f:
    text = f.read()
with open(whole, "w") as f:
    f.write(text.replace("[run]\n", "[run]\nadvance_on_part = false\n", 1))
need(run([args.floesim, "run", whole, "-o", "whole_serial.h5", "-q"]), "the pack from the whole detection, serial")
p = mpirun(2, "step-lure", whole, "whole_lure2.h5")
found = p.returncode != 0 or not equal("whole_lure2.h5", "whole_serial.h5")
print(f"the pack from the whole detection on 2 ranks, step-lure: exit {p.returncode}, "
      f"{'found (the run failed or differs)' if found else 'NOT FOUND'}")
if not found:
    failures.append(f"the lure did not reach the advance from the whole detection (it reads every floe)\n{p.stderr}")

# (c) The mutation: a held floe poisoned too is reported at the first check.
p = mpirun(2, "step-mutant", base, "mutant2.h5")
r = reports(p)
first = {rank: phase for rank, phase, _ in reversed(r)}
print(f"the mutation on 2 ranks: exit {p.returncode}, first reports {first}")
if p.returncode == 0 or first != {0: "drift", 1: "drift"}:
    failures.append(f"the mutation (a held floe poisoned) must fail the run and be reported after the drift on "
                    f"both ranks: exit {p.returncode}, {first}\n{p.stderr}")

# (d) The whole state on demand: a step that reads every floe (the pair
# list's rebuild on a part, a fallback, a whole step of the back-off)
# gathers the floes a rank does not hold from their owners first.
import moving_pack  # (on the path since moving_pack_check)

rebuild_dir = os.path.join(W, "rebuild")
os.makedirs(rebuild_dir, exist_ok=True)
rebuild = moving_pack.write(args.floesim, rebuild_dir, 10000, 320.0, seed=1, output_interval=320.0)
wall = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))), "examples",
                    "pack_against_wall.toml")
need(run([args.floesim, "run", rebuild, "-o", "rebuild_serial.h5", "-q"]), "the 10 000-floe pack, serial")
need(run([args.floesim, "run", wall, "-o", "wall_serial.h5", "-q", "--until", "1500"]), "the wall jam, serial")
# (what, config, ranks, poison, its mutation (nothing gathered), extra arguments, other test hooks, serial file,
# the counts that say the whole steps happened, the floes whose drift phase's bytes are checked or None)
cases = [("the 10 000-floe pack (its pair list rebuilt on a part)", rebuild, 2, "step@drift", "step-stale@drift", [],
          {}, "rebuild_serial.h5", ["advance_rebuilds"], 10000),
         # The wall jam's advances join their conflicts on one rank
         # (advance_joined: tries that read only the held and routed floes)
         # and its step-start collisions do not fall back on their own: the
         # test hook makes those whose shares use the warm store fall back.
         ("the wall jam (fallbacks by the hook, whole steps, clusters joined on one rank)", wall, 3, "step-lure",
          "step-lure-stale", ["--until", "1500"], {"FLOESIM_TEST_COLLIDE_FALLBACK": "warm"}, "wall_serial.h5",
          ["advance_joined", "collide_fallbacks", "collide_whole"], None)]
for what, config, n, poison, mutant, extra, hooks, serial, counted, floes in cases:
    name = f"{what} on {n} ranks, {poison}"
    p = mpirun(n, poison, config, "on_demand.h5", *extra, hooks=hooks)
    s, counts = summaries(p), {k: summary(p).get(f"parallel.{k}", "0") for k in counted}
    same = p.returncode == 0 and equal("on_demand.h5", serial)
    print(f"{name}: exit {p.returncode}, {'equal' if same else 'DIFFERENT'} to the serial run; {counts}; {s}")
    if floes and p.returncode == 0:
        # (e) The halo exchange: rank 0's drift phase receives the states of
        # the floes it holds and does not own (its band: some hundreds of
        # 10 000), not every floe's (96 B x floes x steps with the drift's
        # complete_owned). The poison mode adds no call (it restores nothing).
        steps = int(summary(p)["steps"])
        drift = phase_bytes(p, "drift")
        whole = 96 * floes * steps
        print(f"{name}: rank 0's drift phase received {drift} B in {steps} steps "
              f"({drift / whole:.3f} of every floe's state each step, {whole} B)")
        if not drift < whole // 10:
            failures.append(f"{name}: the drift phase received {drift} B, not less than a tenth of every floe's "
                            f"state each step ({whole} B): the halo exchange sends more than the held floes")
    if not same:
        failures.append(f"{name}: a step that reads every floe read a floe its rank does not hold\n{p.stderr}")
    if any(v == "0" for v in counts.values()):
        failures.append(f"{name}: the case no longer reads every floe in a step ({counts}): it tests nothing")
    if sorted(s) != list(range(n)) or sum(f for _, f, _, _ in s.values()) == 0 or any(r for _, _, r, _ in s.values()):
        failures.append(f"{name}: the ranks must poison floes and report no phase: {s}\n{p.stderr}")
    # The mutation: nothing gathered.
    m = mpirun(n, mutant, config, "stale.h5", *extra, hooks=hooks)
    found = m.returncode != 0 or not equal("stale.h5", serial)
    print(f"{what} on {n} ranks, {mutant} (mutation): exit {m.returncode}, "
          f"{'found (the run failed or differs)' if found else 'NOT FOUND'}")
    if not found:
        failures.append(f"{what}, {mutant}: with nothing gathered the run must fail or differ\n{m.stderr}")

# (f) A split's neighbours (Percussion::decide_split, on the owner) are
# looked for among the held floes: the lure, which can put an unheld floe
# beside a cracked one, must not change a split. check_writer_ranks.py's
# fracture pack (the pack to 500 s, floes split) on 3 ranks.
splits = os.path.join(W, "splits.toml")
with open(base) as f:
    text = f.read()
with open(splits, "w") as f:
    f.write(re.sub(r"t_end = [^\n]*", "t_end = 500.0", text, count=1) + FRACTURE)
s = summary(need(run([args.floesim, "run", splits, "-o", "splits_serial.h5", "-q"]), "the fracture pack, serial"))
p = mpirun(3, "step-lure", splits, "splits3.h5")
same = p.returncode == 0 and equal("splits3.h5", "splits_serial.h5")
print(f"the fracture pack on 3 ranks, step-lure ({s.get('fracture.splits')} splits): exit {p.returncode}, "
      f"{'equal' if same else 'DIFFERENT'} to the serial run; {summaries(p)}")
if s.get("fracture.splits", "0") == "0":
    failures.append("the fracture pack made no split: (f) tests nothing")
if not same:
    failures.append(f"the fracture pack on 3 ranks with the lure differs: a split read an unheld floe\n{p.stderr}")

if failures:
    print("FAILED:\n" + "\n".join(failures))
    sys.exit(1)
print("ok")
