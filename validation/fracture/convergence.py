#!/usr/bin/python3
"""Fragmentation under refinement (docs/fracture.md, "Convergence").

Runs examples/pack_fracture.toml with mesh_size and dt_max as given and
halved (each alone and both), and prints, per run, the number of floes at
t_end, the splits, and the fragment-size distribution (equivalent diameter
d = sqrt(4 A / pi) of the dynamic floes at t_end: counts in fixed classes,
and quantiles), with the changes against the first run.

Usage: validation/fracture/convergence.py BUILD_DIR [--jobs N] [MESH DT T_END [LOAD_RADIUS]], or
scripts/validate fracture [--jobs N] [MESH DT T_END [LOAD_RADIUS]]
(defaults 20 m, 10 s, 3000 s, and the example's load radius: [fracture]
load_radius, the floes' thickness when unset; --jobs: runs at once, 1).
Uses numpy and h5py (Debian packages).
"""
import os
import subprocess
import sys
import tempfile

import h5py
import numpy as np

build = sys.argv[1]
argv = sys.argv[2:]
jobs = 1
if argv[:1] == ["--jobs"]:
    jobs = int(argv[1])
    argv = argv[2:]
mesh, dt, t_end = (float(a) for a in (argv[0:3] if len(argv) >= 3 else (20.0, 10.0, 3000.0)))
load_radius = float(argv[3]) if len(argv) >= 4 else None
src = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
floesim = os.path.join(build, "bin", "floesim")
base = open(os.path.join(src, "examples", "pack_fracture.toml")).read()
pack = os.path.join(src, "examples", "pack_against_wall.h5")
classes = [0.0, 20.0, 30.0, 40.0, 50.0, 60.0, 1e9]  # m, equivalent diameter

work = tempfile.mkdtemp(prefix="fracture_convergence_")
runs = []
for m, h in ((mesh, dt), (mesh / 2, dt), (mesh, dt / 2), (mesh / 2, dt / 2)):
    text = []
    for line in base.splitlines():
        key = line.split("=")[0].strip()
        if key == "pack":
            line = f'pack = "{pack}"'
        elif key == "mesh_size":
            line = f"mesh_size = {m}"
        elif key == "dt_max":
            line = f"dt_max = {h}"
        elif key == "t_end":
            line = f"t_end = {t_end}"
        text.append(line)
    if load_radius is not None:  # [fracture] is the example's last table
        text.append(f"load_radius = {load_radius}")
    cfg = os.path.join(work, f"m{m}_dt{h}.toml")
    open(cfg, "w").write("\n".join(text) + "\n")
    runs.append((m, h, cfg, cfg.replace(".toml", ".h5")))

# Run them, `jobs` at a time (one thread each).
outputs = {}
pending = list(runs)
active = []
while pending or active:
    while pending and len(active) < jobs:
        m, h, cfg, out = pending.pop(0)
        active.append((cfg, subprocess.Popen([floesim, "run", cfg, "-q", "-o", out], stdout=subprocess.PIPE,
                                             stderr=subprocess.PIPE, text=True)))
    cfg, p = active.pop(0)
    stdout, stderr = p.communicate()
    if p.returncode != 0:
        sys.exit(f"{cfg}: floesim run failed (exit {p.returncode}): {stderr}")
    outputs[cfg] = stdout

rows = []
for m, h, cfg, out in runs:
    kv = dict(l.split(": ", 1) for l in outputs[cfg].splitlines() if ": " in l)
    with h5py.File(out, "r") as f:
        area = f["floes/area"][:]
        static = f["floes/static"][:].astype(bool)
        x = f["floes/state"][-1, :, 0]
    alive = ~static & ~np.isnan(x)
    d = np.sqrt(4.0 * area[alive] / np.pi)
    counts, _ = np.histogram(d, bins=classes)
    rows.append((m, h, int(alive.sum()), int(kv.get("fracture.splits", 0)), counts, np.quantile(d, [0.1, 0.5, 0.9]),
                 kv.get("fracture.initiations"), float(kv.get("fracture.seconds", 0.0))))

radius = "the example's" if load_radius is None else f"{load_radius:g} m"
print(f"# {os.path.basename(floesim)} on examples/pack_fracture.toml to t = {t_end} s, load radius {radius}; "
      f"classes of d (m): {classes[:-1]}")
print("mesh_m,dt_s,floes,splits,initiations,analysis_s," + ",".join(f"n_d{c:g}" for c in classes[:-1]) +
      ",d10_m,d50_m,d90_m,floes_change")
ref = rows[0]
for m, h, n, s, counts, q, init, secs in rows:
    print(f"{m:g},{h:g},{n},{s},{init},{secs:.2f}," + ",".join(str(c) for c in counts) +
          "," + ",".join(f"{v:.1f}" for v in q) + f",{(n - ref[2]) / ref[2]:+.1%}")
