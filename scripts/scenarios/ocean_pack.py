"""bench/ocean's pack (bench/ocean/ocean.toml): floes 1 m thick covering 30% of
a square, sizes 10 to 30 m, seed 1, written by `floesim pack`. One place for
its statistics, for the benches that build it at its own size or scaled
(bench/ocean/ranks.py, footprint_reach.py, large.py, bench/scaling_model.py).
"""
import subprocess
import sys


def write(floesim, path, floes=1000, side=1000.0):
    """Writes the pack of `floes` floes in a `side` x `side` m box to `path`."""
    cmd = [floesim, "pack", "--floes", str(floes), "--concentration", "0.3", "--box", f"{side:g}", f"{side:g}",
           "--seed", "1", "--min-size", "10", "--max-size", "30", "--thickness", "1", "-o", path]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"{' '.join(cmd)}: exit {p.returncode}\n{p.stderr}")
