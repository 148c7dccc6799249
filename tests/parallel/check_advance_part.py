#!/usr/bin/env python3
"""The advance from each rank's part of the detection ([run] advance_on_part,
docs/parallel.md "The advance from the rank's part") against the serial run.

usage: check_advance_part.py FLOESIM MPIEXEC WORKDIR [--floes N] [--t-end T] [--ranks 2 3]
       check_advance_part.py --no-mpi    (MPI not built: says so and exits 77, ctest's skip code)

The moving pack of check_ranks.py run serially, then on each of --ranks with
advance_on_part = true and = false: every run file must equal the serial one
bit for bit (`floesim compare`, rtol 0, atol 0). With it on the advances ran
from the parts (join candidates gathered), none redone for a floe not held (a
join candidate not gathered), and the detect phase received less than a
tenth of the bytes (the whole lists gathered only when a step needs them);
with it off no candidate was gathered. Then the same pack with
record_collisions (the impulse record, its places keyed by pair, made from
the parts): serially and on 2 ranks, bit for bit (/events/collisions
included), and its detect phase too receives less than a tenth of the bytes
of the run with it off (the same detections: the record changes no state).
"""
from ranks_harness import finish, moving_pack_check, need, phase_bytes, ran, summary

args, harness, config = moving_pack_check(
    "floesim was built without MPI (FLOESIM_MPI=OFF): the advance from the parts is not checked", 1500, 1000.0, [2, 3])
run, mpirun = harness.run, harness.mpirun
failures = []

with open(config) as f:
    text = f.read()
configs = {}
for on in (True, False):
    name = config.replace(".toml", "_on.toml" if on else "_off.toml")
    with open(name, "w") as f:
        f.write(text.replace("[run]\n", f"[run]\nadvance_on_part = {'true' if on else 'false'}\n", 1))
    configs[on] = name

need(run([args.floesim, "run", configs[True], "-o", "serial.h5", "-q"]), "serial run")
whole_detect = None  # the detect phase's bytes on 2 ranks with the whole lists gathered
on_missing = {}  # ranks -> the advances redone for a floe not held, from the parts
for n in args.ranks:
    combined, detect = {}, {}
    for on in (True, False):
        out = f"ranks{n}_{'on' if on else 'off'}.h5"
        p = ran(mpirun(n, "run", configs[on], "-o", out, "-q"), f"{n} ranks, advance_on_part {on}", failures)
        if not p:
            continue
        harness.same(out, "serial.h5", f"{n} ranks, advance_on_part {on}, against the serial run", failures)
        s = summary(p)
        steps, fallbacks = int(s["parallel.advance_steps"]), int(s["parallel.advance_fallbacks"])
        candidates, missing = int(s["parallel.advance_candidates"]), int(s["parallel.advance_missing"])
        combined[on] = steps - fallbacks
        if on:
            on_missing[n] = missing
        detect[on] = phase_bytes(p, "detect")
        print(f"{n} ranks, advance_on_part {on}: {steps} advances tried, {fallbacks} redone ({missing} for a floe "
              f"not held), {s['parallel.advance_whole']} whole, {candidates} join candidates; "
              f"advance {s['parallel.phase.advance']}; detect {s['parallel.phase.detect']}")
        if on and not candidates > 0:
            failures.append(f"{n} ranks: advance_on_part on gathered no join candidate (not from the parts?)")
        if not on and candidates != 0:
            failures.append(f"{n} ranks: advance_on_part off gathered {candidates} join candidates")
    # The whole detection is gathered only when a step needs it (none did
    # here): the detect phase receives far less than the lists (the overlap
    # check's reductions and the start's).
    if len(detect) == 2 and not detect[True] * 10 < detect[False]:
        failures.append(f"{n} ranks: the detect phase received {detect[True]} bytes from the parts, "
                        f"not a tenth of {detect[False]} with the whole lists gathered")
    # Fallbacks for a foreign cluster depend on where the strips' cuts are,
    # which move by measured time (a noisy machine moves them differently
    # from run to run), so the two runs' counts of combined advances are not
    # comparable bit for bit. What the parts alone could lose is a join whose
    # candidate no share gathered (a `missing_pairs` fallback): none may.
    if on_missing.get(n):
        failures.append(f"{n} ranks: from the parts {on_missing[n]} advances fell back for a floe not held "
                        f"(a join candidate not gathered); {combined.get(True)} combined against "
                        f"{combined.get(False)} from the whole detection")
    if n == 2:
        whole_detect = detect.get(False)

# A run that keeps the impulse record: from the parts too.
record = config.replace(".toml", "_record.toml")
with open(record, "w") as f:
    f.write(text.replace("[run]\n", "[run]\nrecord_collisions = true\n", 1))
need(run([args.floesim, "run", record, "-o", "serial_record.h5", "-q"]), "serial record run")
p = ran(mpirun(2, "run", record, "-o", "ranks2_record.h5", "-q"), "2 ranks, record_collisions", failures)
if p:
    harness.same("ranks2_record.h5", "serial_record.h5", "2 ranks, record_collisions, against the serial run", failures)
    s = summary(p)
    detect_record = phase_bytes(p, "detect")
    print(f"2 ranks, record_collisions: collide {s['parallel.collide_steps']} tried, "
          f"{s['parallel.collide_fallbacks']} redone; advance {s['parallel.advance_steps']} tried, "
          f"{s['parallel.advance_fallbacks']} redone; detect {s['parallel.phase.detect']}")
    if int(s["parallel.advance_candidates"]) == 0:
        failures.append("2 ranks, record_collisions: no join candidate gathered (the advance not from the parts?)")
    if whole_detect is None or not detect_record * 10 < whole_detect:
        failures.append(f"2 ranks, record_collisions: the detect phase received {detect_record} bytes, "
                        f"not a tenth of {whole_detect} with the whole lists gathered")

finish(failures)
