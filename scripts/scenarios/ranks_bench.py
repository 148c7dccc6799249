"""Timing floesim serially and on several ranks, for the benches that compare
them (bench/mpi_pack.py, bench/ocean/ranks.py).

`timed(...)` runs `floesim run CONFIG ... --threads 1 --profile`, under
`mpirun --oversubscribe -np R` when R > 0 (R = 0: the binary alone), each
process under /usr/bin/time, and returns the run's summary lines as a dict
(wall_time, steps, profile.*, parallel.*) with "cpu" the CPU seconds (user +
system) of each process, "elapsed" their wall seconds (set-up included) and
"rss_mb" their peak resident memory (MiB). `write_table(...)` writes a bench's CSV: comment
lines (command, commit, machine and its load, the scenario), the least wall
time per rank count with the speed-up over one rank, then the rows.
"""
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
# mpirun as root (CI containers) must be allowed explicitly; one thread per rank.
ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OMP_NUM_THREADS="1")


def load():
    """The machine's load averages (1, 5, 15 min) as text."""
    with open("/proc/loadavg") as f:
        return " ".join(f.read().split()[:3])


def timed(floesim, config, out_file, ranks, cwd, extra=()):
    # Each process writes its /usr/bin/time line to a file of its own (named
    # by its rank): lines on stderr forwarded by mpirun can be lost at exit.
    times = tempfile.mkdtemp(prefix="times_", dir=cwd)
    run = [floesim, "run", config, *extra, "-o", out_file, "-q", "--threads", "1", "--profile"]
    cmd = ["sh", "-c", '/usr/bin/time -o "$0/time.${OMPI_COMM_WORLD_RANK:-0}" -f "cpu_s: %U %S %e %M" "$@"',
           times, *run]
    if ranks > 0:
        cmd = ["mpirun", "--oversubscribe", "-np", str(ranks)] + cmd
    p = subprocess.run(cmd, capture_output=True, text=True, env=ENV, cwd=cwd)
    if p.returncode != 0:
        sys.exit(f"{' '.join(run)} on {ranks} rank(s): exit {p.returncode}\n{p.stderr}")
    out, raw = {}, {}
    for line in p.stdout.splitlines():
        if ": " in line:
            k, v = line.split(": ", 1)
            out[k.strip()] = v.split()[0] if v.split() else ""
            raw[k.strip()] = v.strip()
    out["raw"] = raw  # whole values (keys with several, e.g. parallel.strip_cuts)
    processes = []
    for name in sorted(os.listdir(times), key=lambda n: int(n.split(".")[1])):
        with open(os.path.join(times, name)) as f:
            processes += [l.split()[1:] for l in f if l.startswith("cpu_s: ")]
    shutil.rmtree(times)
    if len(processes) != max(ranks, 1):
        sys.exit(f"{' '.join(run)} on {ranks} rank(s): {len(processes)} timings of its processes")
    out["cpu"] = [float(u) + float(s) for u, s, _, _ in processes]
    out["elapsed"] = [float(e) for _, _, e, _ in processes]
    out["rss_mb"] = [int(m) / 1024.0 for _, _, _, m in processes]
    return out


def write_table(path, command, note, scenario, load_before, load_after, header, rows, group=None):
    """The CSV text (also printed); rows' first column is the rank count, the third the wall time.
    group(row), if given, names the build a row ran (least times and speed-ups are per group)."""
    commit = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True).stdout.strip()
    lines = [f"# command: {command}",
             f"# commit: {commit} (Release build){'; ' + note if note else ''}",
             f"# machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores (shared); "
             f"load before {load_before}, after {load_after}; {time.strftime('%Y-%m-%d %H:%M', time.gmtime())} UTC",
             f"# scenario: {scenario}"]
    group = group or (lambda row: "")
    best = {}
    for row in rows:
        key = (group(row), row[0])
        best[key] = min(best.get(key, float("inf")), float(row[2]))
    for g, k in sorted(best):
        ref = best.get((g, "1")) or best.get((g, "0"))
        lines.append(f"# least wall_s{' of ' + g if g else ''} on {k} rank(s): {best[(g, k)]:.3f} s" +
                     (f" (speed-up over 1 rank: {ref / best[(g, k)]:.2f}x)" if ref and k not in ("0", "1") else ""))
    lines.append(header)
    lines += [",".join(r) for r in rows]
    text = "\n".join(lines) + "\n"
    if path != "-":
        with open(path, "w") as f:
            f.write(text)
    sys.stdout.write(text)
    return text
