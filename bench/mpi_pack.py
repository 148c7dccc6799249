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

usage: bench/mpi_pack.py [--build build] [--floes 10000] [--t-end 1000] [--ranks 0 1 2]
                         [--rounds 3] [--csv FILE | -] [--note TEXT]
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
ap.add_argument("--build", default=os.path.join(ROOT, "build"))
ap.add_argument("--floes", type=int, default=10000)
ap.add_argument("--t-end", type=float, default=1000.0)
ap.add_argument("--ranks", type=int, nargs="+", default=[0, 1, 2])
ap.add_argument("--rounds", type=int, default=3)
ap.add_argument("--csv", default="-")
ap.add_argument("--note", default="")
args = ap.parse_args()

floesim = os.path.join(args.build, "bin", "floesim")
work = tempfile.mkdtemp(prefix="floesim_mpi_bench_")
config = moving_pack.write(floesim, work, args.floes, args.t_end, seed=1, output_interval=args.t_end)
phases = ["drift", "collide", "advance", "detect", "record", "choose_dt", "check"]
rows = []
load_before = ranks_bench.load()
for r in range(args.rounds):
    for ranks in args.ranks:
        s = ranks_bench.timed(floesim, config, os.path.join(work, f"r{ranks}.h5"), ranks, work)
        cpu = f"{sum(s['cpu']) / len(s['cpu']):.3f}" if s["cpu"] else ""  # the mean over the ranks
        rows.append([str(ranks), str(r), s["wall_time"], s["steps"], s["collisions.lcps"],
                     s.get("parallel.bytes_received", "0"), s.get("parallel.collective_seconds", "0"),
                     cpu] + [s.get("profile." + ph, "") for ph in phases])
ranks_bench.write_table(
    args.csv, f"bench/mpi_pack.py {' '.join(sys.argv[1:])}", args.note,
    f"{args.floes} floes, 50 % cover, periodic, to {args.t_end} s; ranks 0 = serial binary without mpirun; "
    "one thread per rank; wall_s = the run loop (summary wall_time); bytes_received and collective_s: "
    "rank 0's collectives over the run (the transfers and the waits for the other ranks); cpu_s: CPU time "
    "(user + system) of a rank's process, mean over the ranks, set-up included; phases: rank 0's profile (s), "
    "waits in collectives included",
    load_before, ranks_bench.load(),
    "ranks,round,wall_s,steps,lcps,bytes_received,collective_s,cpu_s," + ",".join(p + "_s" for p in phases), rows)
