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
import platform
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "scripts", "scenarios"))
import moving_pack  # noqa: E402  (the pack shared with tests/parallel/check_ranks.py)

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
env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OMP_NUM_THREADS="1")
work = tempfile.mkdtemp(prefix="floesim_mpi_bench_")
config = moving_pack.write(floesim, work, args.floes, args.t_end, seed=1, output_interval=args.t_end)


def load():
    with open("/proc/loadavg") as f:
        return " ".join(f.read().split()[:3])


def one(ranks):
    cmd = ["/usr/bin/time", "-f", "cpu_s: %U %S", floesim, "run", config, "-o", os.path.join(work, f"r{ranks}.h5"),
           "-q", "--threads", "1", "--profile"]
    if ranks > 0:
        cmd = ["mpirun", "--oversubscribe", "-np", str(ranks)] + cmd
    p = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=work)
    if p.returncode != 0:
        sys.exit(f"{' '.join(cmd)}: exit {p.returncode}\n{p.stderr}")
    out = {}
    for line in p.stdout.splitlines():
        if ": " in line:
            k, v = line.split(": ", 1)
            out[k.strip()] = v.split()[0]
    # CPU seconds (user + system) of each process: the mean over the ranks.
    cpu = [sum(map(float, l.split()[1:3])) for l in p.stderr.splitlines() if l.startswith("cpu_s: ")]
    out["cpu_s"] = f"{sum(cpu) / len(cpu):.3f}" if cpu else ""
    return out


phases = ["drift", "collide", "advance", "detect", "record", "choose_dt", "check"]
rows = []
load_before = load()
for r in range(args.rounds):
    for ranks in args.ranks:
        s = one(ranks)
        rows.append([str(ranks), str(r), s["wall_time"], s["steps"], s["collisions.lcps"],
                     s.get("parallel.bytes_received", "0"), s.get("parallel.collective_seconds", "0"),
                     s.get("cpu_s", "")] + [s.get("profile." + ph, "") for ph in phases])
load_after = load()

commit = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
lines = [f"# command: bench/mpi_pack.py {' '.join(sys.argv[1:])}",
         f"# commit: {commit} (Release build); {args.note}",
         f"# machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores (shared); "
         f"load before {load_before}, after {load_after}; {time.strftime('%Y-%m-%d %H:%M', time.gmtime())} UTC",
         f"# scenario: {args.floes} floes, 50 % cover, periodic, to {args.t_end} s; ranks 0 = serial binary without mpirun; "
         "one thread per rank; wall_s = the run loop (summary wall_time); bytes_received and collective_s: "
         "rank 0's collectives over the run (the transfers and the waits for the other ranks); cpu_s: CPU time "
         "(user + system) of a rank's process, mean over the ranks, set-up included; phases: rank 0's profile (s), "
         "waits in collectives included"]
best = {}
for row in rows:
    best[row[0]] = min(best.get(row[0], float("inf")), float(row[2]))
ref = best.get("1") or best.get("0")
for k in sorted(best):
    lines.append(f"# least wall_s on {k} rank(s): {best[k]:.3f} s" +
                 (f" (speed-up over 1 rank: {ref / best[k]:.2f}x)" if ref and k not in ("0", "1") else ""))
lines.append("ranks,round,wall_s,steps,lcps,bytes_received,collective_s,cpu_s," + ",".join(p + "_s" for p in phases))
lines += [",".join(r) for r in rows]
text = "\n".join(lines) + "\n"
if args.csv == "-":
    sys.stdout.write(text)
else:
    with open(args.csv, "w") as f:
        f.write(text)
    sys.stdout.write(text)
