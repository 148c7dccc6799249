#!/usr/bin/python3
"""Fragmentation under refinement (docs/fracture.md, "Convergence").

Runs examples/pack_fracture.toml with mesh_size and dt_max as given and
refined: the mesh size halved, the step halved (LEVELS - 1 times), and a
perturbed twin of the first run (dt_max 3% shorter: a change that refines
nothing, so the distance between the two is the spread of the run itself,
the chaos of the collisions, against which the refinements are judged).
Prints, per run, the floes at t_end, the splits, the fragment sizes
(equivalent diameter d = sqrt(4 A / pi) of the dynamic floes at t_end:
counts in fixed classes and quantiles), then, for each pair of runs that
differ by one halving (and for the twins), the distances between their size
distributions:
  D_N = max over d of |F_a(d) - F_b(d)|, F(d) the fraction of floes with a
        diameter <= d (the two-sample Kolmogorov-Smirnov statistic);
  D_A = the same with F(d) the fraction of the floes' area in floes with a
        diameter <= d (the area-weighted distribution);
  the relative changes of the count and of the quantiles d10, d50, d90 (by
  number) and of the area-weighted median dA50;
  KS95 = 1.358 sqrt((n_a + n_b) / (n_a n_b)), the D_N that two samples of
        n_a and n_b floes drawn from one distribution exceed 5% of the time
        (counting noise).

Usage: validation/fracture/convergence.py BUILD_DIR [--jobs N] [--levels K] [--keep DIR]
       [MESH DT T_END [LOAD_RADIUS]], or scripts/validate fracture [...]
(defaults 20 m, 10 s, 3000 s, and the example's load radius: [fracture]
load_radius, the floes' thickness when unset; --jobs: runs at once, 1;
--levels: step levels DT, DT/2, ..., 2 by default; --keep: keep the run
files there, and reuse those already there). Uses numpy and h5py (Debian
packages). Runs are niced, one thread each.
"""
import os
import subprocess
import sys
import tempfile

import h5py
import numpy as np

build = sys.argv[1]
argv = sys.argv[2:]
jobs, levels, keep = 1, 2, None
while argv[:1] and argv[0].startswith("--"):
    if argv[0] == "--jobs":
        jobs = int(argv[1])
    elif argv[0] == "--levels":
        levels = int(argv[1])
    elif argv[0] == "--keep":
        keep = argv[1]
    else:
        sys.exit(f"convergence.py: unknown option {argv[0]}")
    argv = argv[2:]
mesh, dt, t_end = (float(a) for a in (argv[0:3] if len(argv) >= 3 else (20.0, 10.0, 3000.0)))
load_radius = float(argv[3]) if len(argv) >= 4 else None
src = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
floesim = os.path.join(build, "bin", "floesim")
base = open(os.path.join(src, "examples", "pack_fracture.toml")).read()
pack = os.path.join(src, "examples", "pack_against_wall.h5")
classes = [0.0, 20.0, 30.0, 40.0, 50.0, 60.0, 1e9]  # m, equivalent diameter

work = keep or tempfile.mkdtemp(prefix="fracture_convergence_")
os.makedirs(work, exist_ok=True)
grid = [(m, dt / 2 ** k) for k in range(levels) for m in (mesh, mesh / 2)]
twin = (mesh, round(0.97 * dt, 6))
runs = []
for m, h in grid + [twin]:
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
    name = f"m{m:g}_dt{h:g}_t{t_end:g}_r{load_radius if load_radius is not None else 'h'}"
    cfg = os.path.join(work, name + ".toml")
    open(cfg, "w").write("\n".join(text) + "\n")
    runs.append((m, h, cfg, cfg.replace(".toml", ".h5")))

# Run them, `jobs` at a time (one thread each, niced); a kept run file with
# its summary is reused.
env = dict(os.environ, OMP_NUM_THREADS="1")
outputs = {}
pending = []
for m, h, cfg, out in runs:
    summary = out + ".txt"
    if keep and os.path.exists(summary) and os.path.exists(out):
        outputs[cfg] = open(summary).read()
    else:
        pending.append((m, h, cfg, out))
active = []
while pending or active:
    while pending and len(active) < jobs:
        m, h, cfg, out = pending.pop(0)
        active.append((cfg, out, subprocess.Popen(["nice", floesim, "run", cfg, "-q", "-o", out], stdout=subprocess.PIPE,
                                                  stderr=subprocess.PIPE, text=True, env=env)))
    cfg, out, p = active.pop(0)
    stdout, stderr = p.communicate()
    if p.returncode != 0:
        sys.exit(f"{cfg}: floesim run failed (exit {p.returncode}): {stderr}")
    outputs[cfg] = stdout
    open(out + ".txt", "w").write(stdout)

rows = {}
for m, h, cfg, out in runs:
    kv = dict(l.split(": ", 1) for l in outputs[cfg].splitlines() if ": " in l)
    with h5py.File(out, "r") as f:
        area = f["floes/area"][:]
        static = f["floes/static"][:].astype(bool)
        x = f["floes/state"][-1, :, 0]
    alive = ~static & ~np.isnan(x)
    rows[(m, h)] = dict(area=area[alive], splits=int(kv.get("fracture.splits", 0)),
                        init=kv.get("fracture.initiations"), secs=float(kv.get("fracture.seconds", 0.0)),
                        wall=float(kv.get("wall_time", "0 s").split()[0]))


def diameters(r):
    return np.sqrt(4.0 * r["area"] / np.pi)


def quantiles(r):
    d = np.sort(diameters(r))
    qa = np.cumsum(r["area"][np.argsort(diameters(r))]) / r["area"].sum()
    return np.quantile(d, [0.1, 0.5, 0.9]), d[np.searchsorted(qa, 0.5)]


def distances(a, b):
    """D_N and D_A between two runs' size distributions (see the header)."""
    da, db = diameters(a), diameters(b)
    grid_d = np.union1d(da, db)
    fn_a = np.searchsorted(np.sort(da), grid_d, side="right") / len(da)
    fn_b = np.searchsorted(np.sort(db), grid_d, side="right") / len(db)
    def area_cdf(d, area):
        order = np.argsort(d)
        cum = np.concatenate([[0.0], np.cumsum(area[order])]) / area.sum()
        return cum[np.searchsorted(d[order], grid_d, side="right")]
    return np.max(np.abs(fn_a - fn_b)), np.max(np.abs(area_cdf(da, a["area"]) - area_cdf(db, b["area"])))


radius = "the example's" if load_radius is None else f"{load_radius:g} m"
print(f"# {os.path.basename(floesim)} on examples/pack_fracture.toml to t = {t_end} s, load radius {radius}; "
      f"classes of d (m): {classes[:-1]}")
print("mesh_m,dt_s,floes,splits,initiations,analysis_s,wall_s," + ",".join(f"n_d{c:g}" for c in classes[:-1]) +
      ",d10_m,d50_m,d90_m,dA50_m,floes_change")
ref = rows[grid[0]]
for m, h in grid + [twin]:
    r = rows[(m, h)]
    counts, _ = np.histogram(diameters(r), bins=classes)
    q, qa = quantiles(r)
    n, n0 = len(r["area"]), len(ref["area"])
    print(f"{m:g},{h:g},{n},{r['splits']},{r['init']},{r['secs']:.2f},{r['wall']:.1f}," + ",".join(str(c) for c in counts) +
          "," + ",".join(f"{v:.1f}" for v in q) + f",{qa:.1f},{(n - n0) / n0:+.1%}")

pairs = [(grid[0], twin, "twin (dt x 0.97)")]
for k in range(levels):
    h = dt / 2 ** k
    pairs.append(((mesh, h), (mesh / 2, h), "mesh halved"))
    if k + 1 < levels:
        pairs.append(((mesh, h), (mesh, h / 2), "step halved"))
        pairs.append(((mesh / 2, h), (mesh / 2, h / 2), "step halved"))
        pairs.append(((mesh, h), (mesh / 2, h / 2), "both halved"))
print("# distances between size distributions (header of validation/fracture/convergence.py)")
print("mesh_a,dt_a,mesh_b,dt_b,change,count_change,D_N,D_A,KS95,d10_change,d50_change,d90_change,dA50_change")
for a, b, what in pairs:
    ra, rb = rows[a], rows[b]
    dn, darea = distances(ra, rb)
    na, nb = len(ra["area"]), len(rb["area"])
    qa_, qaa = quantiles(ra)
    qb_, qba = quantiles(rb)
    ks95 = 1.358 * np.sqrt((na + nb) / (na * nb))
    rel = lambda x, y: f"{(y - x) / x:+.1%}"
    print(f"{a[0]:g},{a[1]:g},{b[0]:g},{b[1]:g},{what},{rel(na, nb)},{dn:.3f},{darea:.3f},{ks95:.3f}," +
          ",".join(rel(x, y) for x, y in zip(qa_, qb_)) + f",{rel(qaa, qba)}")
