#!/usr/bin/env python3
"""Prints [[floes.floe]] tables: irregular convex floes on a jittered grid.

Used to write the inline floes of examples/pack_drift.toml:
    python3 examples/make_floes.py --nx 6 --ny 5 --spacing 40 --seed 3
With --pack PACK.h5 it prints the floes of a pack written by `floesim pack`
instead (world coordinates, rounded to cm; needs Debian's python3-h5py), as for
examples/floes_on_waves.toml.
"""
import argparse
import math
import random

p = argparse.ArgumentParser()
p.add_argument("--nx", type=int, default=6)
p.add_argument("--ny", type=int, default=5)
p.add_argument("--spacing", type=float, default=40.0)
p.add_argument("--seed", type=int, default=3)
p.add_argument("--pack", help="print the floes of this pack file (floesim pack -o) instead")
a = p.parse_args()


def print_floe(pts, h):
    print("[[floes.floe]]")
    print("vertices = [" + ", ".join(f"[{x:.2f}, {y:.2f}]" for x, y in pts) + "]")
    print(f"thickness = {h:.2f}")
    print()


if a.pack:
    import h5py
    with h5py.File(a.pack, "r") as f:
        off, verts = f["floes/offsets"][:], f["floes/vertices"][:]
        pose, thick = f["floes/pose"][:], f["floes/thickness"][:]
    for i in range(len(off) - 1):
        x, y, yaw = pose[i]
        c, s_ = math.cos(yaw), math.sin(yaw)
        pts = [(x + c * u - s_ * v, y + s_ * u + c * v) for u, v in verts[off[i]:off[i + 1]]]
        print_floe(pts, thick[i])
    raise SystemExit(0)
rng = random.Random(a.seed)
for j in range(a.ny):
    for i in range(a.nx):
        cx = (i + 0.5) * a.spacing + rng.uniform(-3, 3)
        cy = (j + 0.5) * a.spacing + rng.uniform(-3, 3)
        r = rng.uniform(0.25, 0.4) * a.spacing
        n = rng.randint(5, 9)
        angles = sorted(rng.uniform(0, 2 * math.pi) for _ in range(n))
        # keep the polygon convex and non-degenerate: radii vary little
        pts = [(cx + r * rng.uniform(0.8, 1.0) * math.cos(t), cy + r * rng.uniform(0.8, 1.0) * math.sin(t))
               for t in angles]
        h = rng.uniform(0.5, 2.0)
        print_floe(pts, h)
