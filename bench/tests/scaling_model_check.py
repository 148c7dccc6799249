#!/usr/bin/env python3
"""The weak-scaling model's two steps agree where they must (docs/scaling.md,
"The step that runs today").

usage: scaling_model_check.py BUILD WORKDIR

bench/scaling_model.py prices the planned step in slabs (slab_*) and the step
that runs today (today_*): the planned one plus what grows with the whole
pack on every rank (W the whole-pack exchanges, V the passes over every
floe, S the implicit step's whole sea, m the whole-pack memory). Checked,
on every row (explicit and implicit, 1 to 1024 ranks):
  - with --no-whole (W, V, S and m zero) today's step and efficiency are the
    planned ones, to the printed digits, and every today_whole_* term is 0;
  - by default every today_whole_* term is >= 0, today's step is no shorter
    than the planned one, and on 1024 ranks strictly longer (the whole-pack
    terms are priced at all: a model that dropped them would pass the first
    check alone).
The pack (bench/ocean's) is written to WORKDIR by BUILD's floesim.
"""
import csv
import io
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
MODEL = os.path.join(os.path.dirname(HERE), "scaling_model.py")


def rows(build, work, *extra):
    cmd = [sys.executable, MODEL, "--build", build, "--pack", os.path.join(work, "ocean_pack.h5"), "--csv", "-", *extra]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"{' '.join(cmd)}: exit {p.returncode}\n{p.stderr}")
    return list(csv.DictReader(io.StringIO("".join(l for l in p.stdout.splitlines(True) if not l.startswith("#")))))


def main():
    build, work = sys.argv[1], sys.argv[2]
    os.makedirs(work, exist_ok=True)
    failures = []
    plain, no_whole = rows(build, work), rows(build, work, "--no-whole")
    if not no_whole or len(plain) != len(no_whole):
        sys.exit(f"scaling_model.py gave {len(plain)} rows by default and {len(no_whole)} with --no-whole")
    for r in no_whole:
        name = f"{r['integrator']} on {r['ranks']} ranks (--no-whole)"
        for a, b in (("today_step_ms", "slab_step_ms"), ("today_efficiency", "slab_efficiency")):
            if r[a] != r[b]:
                failures.append(f"{name}: {a} {r[a]} is not {b} {r[b]}")
        for k, v in r.items():
            if k.startswith("today_whole") and float(v) != 0.0:
                failures.append(f"{name}: {k} = {v}, not 0")
    longer = 0
    for r in plain:
        name = f"{r['integrator']} on {r['ranks']} ranks"
        for k, v in r.items():
            if k.startswith("today_whole") and float(v) < 0.0:
                failures.append(f"{name}: {k} = {v} < 0")
        if float(r["today_step_ms"]) < float(r["slab_step_ms"]):
            failures.append(f"{name}: today's step {r['today_step_ms']} ms shorter than the planned {r['slab_step_ms']}")
        if int(r["ranks"]) == 1024:
            longer += float(r["today_step_ms"]) > float(r["slab_step_ms"])
    if longer == 0:
        failures.append("no row on 1024 ranks where today's step is longer than the planned one: the whole-pack "
                        "terms are not priced")
    print(f"{len(plain)} rows checked, with and without --no-whole")
    for f in failures:
        print("FAILED:", f)
    sys.exit(1 if failures else 0)


main()
