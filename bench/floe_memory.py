#!/usr/bin/env python3
"""bench/floe_memory.py: the per-floe structures' bytes on each rank, whole-pack against the held floes'.

Runs each case serially (the binary without mpirun) and under
`mpirun --oversubscribe -np R` for each R of --ranks, one thread a rank, and
reads the summary's `memory.floes.*` lines (Simulation::floe_memory; docs/
parallel.md, "The arrays held by band: measured (mem27)"): per rank its held
floes (its own and its band at the last detection), and per structure the
bytes its arrays hold (capacity) and the bytes the held floes' entries would
take in a layout of those floes alone. Each run on R ranks is compared with
the serial run (`floesim compare --rtol 0 --atol 0`). The cases:

  pack10k:  scripts/scenarios/moving_pack.py, 10 000 floes, seed 1, 100 steps (to 1000 s);
  pack100k: the same pack with 100 000 floes, --until 200 (20 steps);
  ocean:    bench/ocean/ocean.toml (1000 floes, a 512^2 spectral sea), --until 0.1.

One CSV row per case, rank count, rank and structure; the first comment lines
say the command, the commit, the machine and its load. peak_rss_kib is the
maximum resident set of the run (/usr/bin/time -v: of its largest process).

usage: bench/floe_memory.py [--build build] [--ranks 2] [--cases pack10k pack100k ocean] [--csv FILE | -]
                            [--note TEXT]
"""
import argparse
import os
import platform
import re
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "scripts", "scenarios"))
import moving_pack  # noqa: E402

ap = argparse.ArgumentParser()
ap.add_argument("--build", default=os.path.join(ROOT, "build"))
ap.add_argument("--ranks", type=int, nargs="+", default=[2])
ap.add_argument("--cases", nargs="+", default=["pack10k", "pack100k", "ocean"])
ap.add_argument("--csv", default="-")
ap.add_argument("--note", default="")
args = ap.parse_args()

floesim = os.path.join(os.path.abspath(args.build), "bin", "floesim")
work = tempfile.mkdtemp(prefix="floesim_floe_memory_")
env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OMP_NUM_THREADS="1")


def case_config(name):
    """The case's configuration and its `floesim run` options."""
    folder = os.path.join(work, name)
    os.makedirs(folder)
    if name == "pack10k":
        return moving_pack.write(floesim, folder, 10000, 1000.0, seed=1, output_interval=1000.0), []
    if name == "pack100k":
        return moving_pack.write(floesim, folder, 100000, 1000.0, seed=1, output_interval=1000.0), ["--until", "200"]
    if name == "ocean":
        subprocess.run([floesim, "pack", "--floes", "1000", "--concentration", "0.3", "--box", "1000", "1000", "--seed",
                        "1", "--min-size", "10", "--max-size", "30", "--thickness", "1", "-o",
                        os.path.join(folder, "ocean_pack.h5")], check=True, capture_output=True)
        config = os.path.join(folder, "ocean.toml")
        with open(os.path.join(ROOT, "bench", "ocean", "ocean.toml")) as f, open(config, "w") as g:
            g.write(f.read())
        return config, ["--until", "0.1"]
    raise SystemExit(f"unknown case {name}")


def run(config, options, ranks, out):
    command = [floesim, "run", config, "-o", out, "-q", "--threads", "1"] + options
    if ranks > 0:
        command = ["mpirun", "--oversubscribe", "-np", str(ranks)] + command
    p = subprocess.run(["/usr/bin/time", "-v"] + command, capture_output=True, text=True, env=env)
    if p.returncode != 0:
        raise SystemExit(f"{' '.join(command)}: exit {p.returncode}\n{p.stdout}\n{p.stderr}")
    rss = re.search(r"Maximum resident set size \(kbytes\): (\d+)", p.stderr)
    memory = {}
    held = None
    floes = None
    for line in p.stdout.splitlines():
        m = re.match(r"memory\.floes\.held: ([\d ]+) of (\d+)$", line)
        if m:
            held = [int(x) for x in m.group(1).split()]
            floes = int(m.group(2))
            continue
        m = re.match(r"memory\.floes\.(\w+): ([\d ]+) bytes; held ([\d ]+)$", line)
        if m:
            memory[m.group(1)] = ([int(x) for x in m.group(2).split()], [int(x) for x in m.group(3).split()])
    if held is None:
        raise SystemExit(f"{' '.join(command)}: no memory.floes lines in its summary")
    return floes, held, memory, int(rss.group(1)) if rss else 0


def uptime():
    with open("/proc/loadavg") as f:
        return " ".join(f.read().split()[:3])


load_before = uptime()
rows = []
for case in args.cases:
    config, options = case_config(case)
    serial_out = os.path.join(work, case, "s.h5")
    results = [(0, run(config, options, 0, serial_out), "")]
    for r in args.ranks:
        out = os.path.join(work, case, f"p{r}.h5")
        result = run(config, options, r, out)
        c = subprocess.run([floesim, "compare", serial_out, out, "--rtol", "0", "--atol", "0"], capture_output=True,
                           text=True)
        results.append((r, result, "true" if c.returncode == 0 else "false"))
    for ranks, (floes, held, memory, rss), equal in results:
        for rank, h in enumerate(held):
            for name, (whole, held_bytes) in memory.items():
                rows.append(f"{case},{floes},{ranks},{rank},{h},{name},{whole[rank]},{held_bytes[rank]},{rss},{equal}")

commit = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
dirty = subprocess.run(["git", "-C", ROOT, "status", "--porcelain", "--untracked-files=no"], capture_output=True,
                       text=True).stdout.strip()
header = [
    "# command: bench/floe_memory.py " + " ".join(sys.argv[1:]),
    f"# commit: {commit}{' (with uncommitted changes)' if dirty else ''} (Release build {args.build}); {args.note}",
    f"# machine: {platform.machine()}, {os.cpu_count()} cores (shared); load before {load_before}, after {uptime()}; "
    + time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
    "# ranks 0 = serial binary without mpirun; held_floes: the rank's own floes and its band at the last detection "
    "(every floe serially); whole_bytes: the structure's arrays' capacity on that rank; held_bytes: what the held "
    "floes' entries take in a layout of them alone (core/floe_bytes.hpp); peak_rss_kib: the run's largest process; "
    "equal: the run file equals the serial one bit for bit",
    "case,floes,ranks,rank,held_floes,structure,whole_bytes,held_bytes,peak_rss_kib,equal",
]
text = "\n".join(header + rows) + "\n"
if args.csv == "-":
    sys.stdout.write(text)
else:
    with open(args.csv, "w") as f:
        f.write(text)
