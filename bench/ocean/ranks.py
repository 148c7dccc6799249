#!/usr/bin/env python3
"""bench/ocean/ranks.py: bench/ocean/ocean.toml on 1 and 2 ranks, side by side.

Writes the pack beside ocean.toml (as run.sh does: floesim pack, seed 1),
then for each round runs the ranks of --ranks one after another
(alternating, so load changes on the shared machine hit each), each
`mpirun --oversubscribe -np R floesim run ocean.toml --until T --threads 1
--profile` under /usr/bin/time (R = 0: the binary without mpirun). Per run:
the loop's wall time (summary wall_time), the steps, rank 0's collectives
(bytes received, seconds inside them: transfers and waits for the other
rank), the CPU time of every process (user + system, set-up included) and
rank 0's profile per phase; and whether the run file equals the first
serial run: bit for bit (`floesim compare --rtol 0 --atol 0`), or within
issue 21's relative 1e-6 (`--rtol 1e-6 --atol 0`; the explicit kicks on
several ranks sum the cells shared by ranks grouped by rank: docs/parallel.md,
stage three).

With --half, the uneven case of docs/parallel.md's stage seven: 500 floes
of the same sizes at the same cover packed in the lower half of the box
(`floesim pack --box 1000 500`, seed 1; the periodic contact box stays
[0, 1000]^2), so the floes' by-place work lies in the rows 0 to 255 of the
sea's 512. The columns slab_rows and strip_moves are the summary's
parallel.slab_rows (the slabs' first rows at the end; stage seven) and
parallel.strip_moves.

usage: bench/ocean/ranks.py [--build build] [--until 10] [--ranks 0 1 2] [--rounds 3]
                            [--half] [--csv FILE | -] [--note TEXT]
"""
import argparse
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "scripts", "scenarios"))
import ocean_pack  # noqa: E402
import ranks_bench  # noqa: E402  (the timing shared with bench/mpi_pack.py)

ap = argparse.ArgumentParser()
ap.add_argument("--build", default=os.path.join(ROOT, "build"))
ap.add_argument("--until", type=float, default=10.0)
ap.add_argument("--ranks", type=int, nargs="+", default=[0, 1, 2])
ap.add_argument("--rounds", type=int, default=3)
ap.add_argument("--csv", default="-")
ap.add_argument("--note", default="")
ap.add_argument("--half", action="store_true", help="500 floes in the lower half of the box")
args = ap.parse_args()

floesim = os.path.join(os.path.abspath(args.build), "bin", "floesim")  # the runs start in a scratch folder
work = tempfile.mkdtemp(prefix="floesim_ocean_ranks_")
config = os.path.join(work, "ocean.toml")
if args.half:
    pack = os.path.join(work, "half_pack.h5")
    cmd = [floesim, "pack", "--floes", "500", "--concentration", "0.3", "--box", "1000", "500", "--seed", "1",
           "--min-size", "10", "--max-size", "30", "--thickness", "1", "-o", pack]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"{' '.join(cmd)}: exit {p.returncode}\n{p.stderr}")
else:
    pack = os.path.join(HERE, "ocean_pack.h5")
    ocean_pack.write(floesim, pack)
with open(os.path.join(HERE, "ocean.toml")) as f, open(config, "w") as g:
    for line in f:
        if line.startswith("pack = "):
            g.write(f'pack = "{pack}"\n')
        elif args.half and line.startswith('domain = "periodic"'):
            g.write('domain = "periodic"\nbox = [0.0, 1000.0, 0.0, 1000.0]\n')
        else:
            g.write(line)

reference = None


def one(ranks, label):
    """One run, and whether its file equals the first run: bit for bit, or within 1e-6."""
    global reference
    out_file = os.path.join(work, f"{label}.h5")
    out = ranks_bench.timed(floesim, config, out_file, ranks, work, extra=("--until", str(args.until)))
    out["cpu_s"] = " ".join(f"{c:.2f}" for c in out["cpu"])
    if reference is None:
        reference = out_file
        out["equal"] = "reference"
    else:
        out["equal"] = "NO"
        for rtol, verdict in (("0", "bits"), ("1e-6", "1e-6")):
            c = subprocess.run([floesim, "compare", out_file, reference, "--rtol", rtol, "--atol", "0"],
                               capture_output=True, text=True)
            if c.returncode == 0:
                out["equal"] = verdict
                break
    return out


phases = ["penalty", "sea", "drift", "detect", "advance", "collide", "record"]
rows = []
load_before = ranks_bench.load()
for r in range(args.rounds):
    for ranks in args.ranks:
        s = one(ranks, f"r{ranks}_{r}")
        print(f"round {r}, ranks {ranks}: loop {s['wall_time']} s, cpu {s['cpu_s']}", file=sys.stderr)
        rows.append([str(ranks), str(r), s["wall_time"], s["steps"], s.get("parallel.collectives", "0"),
                     s.get("parallel.bytes_received", "0"), s.get("parallel.collective_seconds", "0"), s["cpu_s"],
                     s["equal"]] + [s.get("profile." + ph, "") for ph in phases] +
                    [s["raw"].get("parallel.slab_rows", ""), s.get("parallel.strip_moves", "")])
ranks_bench.write_table(
    args.csv, f"bench/ocean/ranks.py {' '.join(sys.argv[1:])}", args.note,
    f"bench/ocean/ocean.toml ({'500 floes in the lower half' if args.half else '1000 floes'}, 512^2 spectral sea, K = 100) to {args.until} s; ranks 0 = "
    "the binary without mpirun; one thread per rank; wall_s = the run loop (summary wall_time); collectives, "
    "bytes_received, collective_s: rank 0's over the run (transfers and waits for the other ranks); cpu_s: CPU "
    "time (user + system) of each process, set-up (about 0.3 s) included, waits that yield the core included; "
    "equal: the run file against the first run's (bits: bit for bit; 1e-6: within rtol 1e-6, atol 0); phases: rank 0's profile (s), waits included",
    load_before, ranks_bench.load(),
    "ranks,round,wall_s,steps,collectives,bytes_received,collective_s,cpu_s,equal," +
    ",".join(p + "_s" for p in phases) + ",slab_rows,strip_moves", rows)
