#!/usr/bin/env python3
"""bench/ocean/large.py: bench/ocean/ocean.toml scaled up, its memory per rank and its time per step.

Issue 21 asks for a 10^5-floe case on a 4096^2 sea run on 2 ranks, with the
memory each rank needs. This bench builds that case from bench/ocean's: the
same cells (1000 / 512 m), sea, waves, penalty and pack statistics (30%
cover, sizes 10 to 30 m, seed 1), with --cells cells a side and --floes
floes in the box (cells x 1000/512 m a side). The pack is written once into
--work and reused.

For each rank count of --ranks (0: the binary without mpirun) it runs the
case to --until simulated seconds (a few steps: the set-up dominates such a
run) under /usr/bin/time, one thread per rank, and writes one CSV row: the
set-up (each process's elapsed time minus the loop's), the loop's wall time,
steps and ms per step, simulated seconds per wall second, each process's CPU
time and peak resident memory (MiB), and the wall time that 60 simulated
seconds would take at this rate (steps of the run's mean length). Records
are written at the start and the end only (output_interval = the run's end).

usage: bench/ocean/large.py [--build build] [--floes 100000] [--cells 4096] [--until 0.1]
                            [--ranks 0 2] [--integrator explicit|implicit] [--work DIR]
                            [--csv FILE | -] [--note TEXT]
"""
import argparse
import os
import re
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "scripts", "scenarios"))
import ocean_pack  # noqa: E402
import ranks_bench  # noqa: E402  (the timing shared with bench/ocean/ranks.py)

CELL = 1000.0 / 512  # bench/ocean's cell (m)

ap = argparse.ArgumentParser()
ap.add_argument("--build", default=os.path.join(ROOT, "build"))
ap.add_argument("--floes", type=int, default=100000)
ap.add_argument("--cells", type=int, default=4096)
ap.add_argument("--until", type=float, default=0.1)
ap.add_argument("--ranks", type=int, nargs="+", default=[0, 2])
ap.add_argument("--integrator", choices=["explicit", "implicit"], default="explicit")
ap.add_argument("--work", default=os.path.join(ROOT, "build", "bench_ocean_large"))
ap.add_argument("--csv", default="-")
ap.add_argument("--note", default="")
args = ap.parse_args()
if args.floes < 1 or args.cells < 16 or not args.until > 0:
    sys.exit("large.py: --floes >= 1, --cells >= 16 and --until > 0 expected")

floesim = os.path.join(os.path.abspath(args.build), "bin", "floesim")  # the runs start in the work folder
if not os.access(floesim, os.X_OK):
    sys.exit(f"large.py: no {floesim} (build it: cmake --build {args.build} --target floesim)")
os.makedirs(args.work, exist_ok=True)
side = args.cells * CELL
pack = os.path.join(args.work, f"pack_{args.floes}_{args.cells}.h5")
if not os.path.exists(pack):
    print(f"writing {pack} ({args.floes} floes in {side:.0f} m x {side:.0f} m)", file=sys.stderr)
    ocean_pack.write(floesim, pack + ".part", args.floes, side)
    os.replace(pack + ".part", pack)

# bench/ocean/ocean.toml with the box, the cells, the pack, the records and the integrator replaced.
replace = {
    r"^size = .*": f"size = [{side!r}, {side!r}]",
    r"^cells = .*": f"cells = [{args.cells}, {args.cells}]",
    r"^pack = .*": f'pack = "{pack}"',
    r"^output_interval = .*": f"output_interval = {args.until!r}",
}
config = os.path.join(args.work, f"large_{args.floes}_{args.cells}_{args.integrator}.toml")
with open(os.path.join(HERE, "ocean.toml")) as f:
    text = f.read()
for pattern, line in replace.items():
    text, n = re.subn(pattern, line, text, count=1, flags=re.M)
    if n != 1:
        sys.exit(f"large.py: bench/ocean/ocean.toml has no line matching {pattern}")
text = text.replace("[coupling]\n", f'[coupling]\nintegrator = "{args.integrator}"\n', 1)
with open(config, "w") as g:
    g.write(text)

header = ("ranks,simulated_s,loop_s,steps,ms_per_step,setup_s,floes,cells,integrator,sim_s_per_wall_s,"
          "wall_h_for_60s,cpu_s,rss_mb,rss_mb_max")
rows = []
load_before = ranks_bench.load()
for ranks in args.ranks:
    s = ranks_bench.timed(floesim, config, os.path.join(args.work, f"large_r{ranks}.h5"), ranks, args.work,
                          extra=("--until", str(args.until)))
    loop = float(s["wall_time"])
    steps = int(s["steps"])
    simulated = float(s["simulated"])
    setup = max(s["elapsed"]) - loop
    ms = 1000.0 * loop / steps
    rows.append([str(ranks), f"{simulated:.4g}", f"{loop:.2f}", str(steps), f"{ms:.0f}", f"{setup:.1f}",
                 str(args.floes), str(args.cells), args.integrator, f"{simulated / loop:.3g}",
                 f"{60.0 / simulated * loop / 3600.0:.2f}", " ".join(f"{c:.1f}" for c in s["cpu"]),
                 " ".join(f"{m:.0f}" for m in s["rss_mb"]), f"{max(s['rss_mb']):.0f}"])
    print(f"ranks {ranks}: set-up {setup:.1f} s, {steps} steps in {loop:.1f} s ({ms:.0f} ms a step), "
          f"peak memory {' '.join(f'{m:.0f}' for m in s['rss_mb'])} MiB", file=sys.stderr)
ranks_bench.write_table(
    args.csv, f"bench/ocean/large.py {' '.join(sys.argv[1:])}", args.note,
    f"bench/ocean/ocean.toml scaled: {args.floes} floes on a {args.cells}^2 spectral sea ({side:.0f} m a side, "
    f"{CELL:.3f} m cells, K = 100, {args.integrator} penalty step) to {args.until} s; ranks 0 = the binary "
    "without mpirun; one thread per rank; setup_s: the slowest process's elapsed time minus the loop; loop_s: "
    "the run loop (summary wall_time); wall_h_for_60s: 60 simulated s at this loop rate; cpu_s, rss_mb: each "
    "process's CPU time and peak resident memory (MiB), set-up included",
    load_before, ranks_bench.load(), header, rows)
