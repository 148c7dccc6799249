"""The collisions-only periodic pack shared by the MPI check (tests/parallel/
check_ranks.py) and the MPI bench (bench/mpi_pack.py): bench/collisions.cpp's
pack_N written as a run configuration.

`floesim pack`: N floes at 50 % cover in a periodic box of side 130.4 sqrt(N) m
(floes of mean diameter about 100 m), thickness 0.5 to 2 m; each floe started
at a speed uniform in [0, 0.1] m/s in a random direction (numpy's generator
with the pack's seed), so that they collide from the first steps; no sea;
restitution 0.4, friction 0.7; wind, a 0.05 m/s current and Coriolis at
80.2 N; dt_max 10 s; one thread.
"""
import os
import subprocess

import h5py
import numpy as np


def box_side(floes):
    return 130.4 * floes ** 0.5


def start_moving(path, seed):
    rng = np.random.default_rng(seed)
    with h5py.File(path, "r+") as f:
        v = f["floes/velocity"][...]
        speed, angle = rng.uniform(0.0, 0.1, len(v)), rng.uniform(0.0, 2 * np.pi, len(v))
        v[:, 0], v[:, 1] = speed * np.cos(angle), speed * np.sin(angle)
        f["floes/velocity"][...] = v


def write(floesim, workdir, floes, t_end, seed, output_interval, wind=(10.0, 0.0), half=False):
    """Writes WORKDIR/pack.h5 and WORKDIR/pack.toml; returns the toml's path.
    half: the floes packed (at 50 % cover) in the lower half of the periodic
    box only, the upper half open water (a case for the ranks' load balance).
    Raises RuntimeError with floesim's message if `floesim pack` fails."""
    side = box_side(floes)
    pack_height = side / 2 if half else side
    box = f"box = [0.0, {side}, 0.0, {side}]\n" if half else ""
    pack = os.path.join(workdir, "pack.h5")
    p = subprocess.run([floesim, "pack", "--floes", str(floes), "--concentration", "0.5", "--box", str(side),
                        str(pack_height), "--thickness-range", "0.5", "2.0", "--seed", str(seed), "-o", pack],
                       capture_output=True, text=True)
    if p.returncode != 0:
        raise RuntimeError(f"floesim pack: exit {p.returncode}\n{p.stdout}\n{p.stderr}")
    start_moving(pack, seed)
    config = os.path.join(workdir, "pack.toml")
    with open(config, "w") as f:
        f.write(f"""[run]
t_end = {t_end}
dt_max = 10.0
output_interval = {output_interval}
threads = 1

[sea]
model = "none"

[contact]
domain = "periodic"
restitution = 0.4
friction = 0.7
{box}
[forcing]
wind = [{wind[0]}, {wind[1]}]
current = [0.0, 0.05]
latitude = 80.2

[floes]
pack = "pack.h5"
""")
    return config
