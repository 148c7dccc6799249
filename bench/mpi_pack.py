#!/usr/bin/env python3
"""bench/mpi_pack.py: a collisions-only periodic pack on 1 and 2 ranks, side by side.

The pack of scripts/scenarios/moving_pack.py (bench/collisions.cpp's pack_N
as a run configuration), seed 1, wind 10 m/s, to --t-end. For each round, the ranks in --ranks are run one after another
(alternating, so load changes on the shared machine hit both), each
`mpirun --oversubscribe -np R floesim run --threads 1 --profile` (R = 0: the
serial binary without mpirun). Per run: the summary's wall_time (the loop:
steps and records, not the set-up) and its profile per phase. One CSV row per
run; the first comment lines say the command, the commit, the machine and its
load. The speed-up is the least wall time on 1 rank over the least on R.

Several --build directories (e.g. main's and a branch's) are run in each
round one after the other, so that both meet the same load; rows then name
their build (the last column; least times per build). --half packs the floes
in the lower half of the periodic box only (open water above): the case for
the load balance by measured cost (stage six of docs/parallel.md); the rows
give rank 0's strip cuts, the floes in each strip at the end and each rank's
by-place seconds over the last balance window (parallel.strip_* keys).
--percussion adds percussion fracture (splits on, strength 0.2 MPa) and
[run] record_collisions: a run that keeps the impulse record (stage seven:
its collisions by owner, the record merged in the serial order; the
fracture checks by owner, with each rank's checks and seconds in them);
--record-collisions adds record_collisions alone (the record without the
fracture check, which runs whole on every rank).

usage: bench/mpi_pack.py [--build build [build2 ...]] [--floes 10000] [--t-end 1000] [--ranks 0 1 2]
                         [--rounds 3] [--half] [--percussion | --record-collisions] [--csv FILE | -] [--note TEXT]
"""
import argparse
import os
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "scripts", "scenarios"))
import moving_pack  # noqa: E402  (the pack shared with tests/parallel/check_ranks.py)
import ranks_bench  # noqa: E402  (the timing shared with bench/ocean/ranks.py)

ap = argparse.ArgumentParser()
ap.add_argument("--build", nargs="+", default=[os.path.join(ROOT, "build")])
ap.add_argument("--floes", type=int, default=10000)
ap.add_argument("--t-end", type=float, default=1000.0)
ap.add_argument("--ranks", type=int, nargs="+", default=[0, 1, 2])
ap.add_argument("--rounds", type=int, default=3)
ap.add_argument("--csv", default="-")
ap.add_argument("--half", action="store_true", help="floes in the lower half of the box only")
ap.add_argument("--percussion", action="store_true", help="percussion fracture and record_collisions on")
ap.add_argument("--record-collisions", action="store_true", help="record_collisions on (no fracture)")
ap.add_argument("--note", default="")
args = ap.parse_args()

builds = [os.path.abspath(b) for b in args.build]
floesims = [os.path.join(b, "bin", "floesim") for b in builds]
work = tempfile.mkdtemp(prefix="floesim_mpi_bench_")
config = moving_pack.write(floesims[0], work, args.floes, args.t_end, seed=1, output_interval=args.t_end,
                           half=args.half)
if args.percussion or args.record_collisions:
    with open(config) as f:
        text = f.read()
    with open(config, "w") as f:  # as tests/parallel/check_record_ranks.py
        f.write(text.replace("[run]\n", "[run]\nrecord_collisions = true\n", 1) +
                ('\n[fracture]\nenabled = true\ncriterion = "stress"\nstrength = 0.2e6\nsplit = true\n'
                 'mesh_size = 20.0\nmin_fragment_area = 400.0\n' if args.percussion else ""))
phases = ["drift", "collide", "advance", "detect", "record", "choose_dt", "check"] + (["percussion"] if args.percussion else [])
strips = ["strip_cuts", "strip_floes", "strip_seconds", "strip_seconds_total", "advance_steps", "advance_fallbacks",
          "advance_whole",
          "advance_clusters", "collide_steps", "collide_fallbacks", "collide_whole", "collide_groups"] + \
    (["fracture_steps", "fracture_checks", "fracture_seconds", "fracture_charged"] if args.percussion else [])
rows = []
load_before = ranks_bench.load()
for r in range(args.rounds):
    for ranks in args.ranks:
        for build, floesim in zip(builds, floesims):
            s = ranks_bench.timed(floesim, config, os.path.join(work, f"r{ranks}.h5"), ranks, work)
            cpu = f"{sum(s['cpu']) / len(s['cpu']):.3f}" if s["cpu"] else ""  # the mean over the ranks
            rows.append([str(ranks), str(r), s["wall_time"], s["steps"], s["collisions.lcps"],
                         s.get("parallel.bytes_received", "0"), s.get("parallel.collective_seconds", "0"),
                         cpu] + [s.get("profile." + ph, "") for ph in phases] +
                        [s["raw"].get("parallel." + k, "") for k in strips] + [build])
ranks_bench.write_table(
    args.csv, f"bench/mpi_pack.py {' '.join(sys.argv[1:])}", args.note,
    f"{args.floes} floes, 50 % cover{' in the lower half of the box' if args.half else ''}, periodic, "
    f"{'percussion fracture and record_collisions on, ' if args.percussion else ''}"
    f"{'record_collisions on, ' if args.record_collisions else ''}"
    f"to {args.t_end} s; ranks 0 = serial binary without mpirun; "
    "one thread per rank; wall_s = the run loop (summary wall_time); bytes_received and collective_s: "
    "rank 0's collectives over the run (the transfers and the waits for the other ranks); cpu_s: CPU time "
    "(user + system) of a rank's process, mean over the ranks, set-up included; phases: rank 0's profile (s), "
    "waits in collectives included; strip_*: rank 0's parallel.strip_* summary keys (the cuts in y, m; floes "
    "per strip at the end; each rank's by-place CPU seconds over the last balance window and over all windows; "
    "advance_*: the advances by cluster owner, stage seven: tried, redone whole, done whole by the back-off, "
    "clusters run by each rank; collide_*: the step-start collisions by owner, the same way, step groups by rank; "
    "fracture_*: the fracture checks by owner: steps that exchanged them, each rank's analyses and its wall "
    "seconds in them, and its CPU seconds in them charged to the strips, blank before perc10), "
    "blank before stage six (collide_*: before the step-start collisions by owner)",
    load_before, ranks_bench.load(),
    "ranks,round,wall_s,steps,lcps,bytes_received,collective_s,cpu_s," + ",".join(p + "_s" for p in phases) + "," +
    ",".join(strips) + ",build", rows, group=(lambda row: row[-1]) if len(builds) > 1 else None)
