#!/usr/bin/python3
"""Validation figures of the percussion-fracture model (docs/fracture.md).

usage: /usr/bin/python3 scripts/plot_fracture.py [FLOESIM] [OUT.png]
  FLOESIM  the floesim binary (default build/bin/floesim)
  OUT.png  the figure (default docs/img/fracture_validation.png)

Runs `floesim fracture` on
  (a) the Brazilian disc (D = 20 m, h = 1 m, P = 1 MN) for mesh sizes from
      D/5 to D/80: the tension at the centre against Hertz's 2 P / (pi D h);
  (b) a square floe of side L struck head-on in the middle of a side by a
      vertex of an octagon of diameter L/2 at 1 m/s (restitution 0.4, so the
      impulse is J = 1.4 m1 m2 / (m1 + m2) v), mesh 1 m: the speed at which the
      stress criterion (0.5 MPa) initiates, v_c = v strength / sigma_1, for
      collision durations 0.01, 0.1 and 1 s; and at 1 s with the mesh and the
      load radius scaled with the floe (L/20), the self-similar case.
Prints the numbers as Markdown tables and writes the figure (Debian's
python3-matplotlib).
"""
import math
import os
import subprocess
import sys
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FLOESIM = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "build", "bin", "floesim")
OUT = sys.argv[2] if len(sys.argv) > 2 else os.path.join(ROOT, "docs", "img", "fracture_validation.png")
WORK = tempfile.mkdtemp(prefix="floesim_fracture_")
RHO, H, E_RESTITUTION, STRENGTH = 917.0, 1.0, 0.4, 0.5e6


def fracture(text, *extra):
    path = os.path.join(WORK, "case.toml")
    with open(path, "w") as f:
        f.write(text)
    out = subprocess.run([FLOESIM, "fracture", path, *extra], capture_output=True, text=True, check=True).stdout
    kv = {}
    for line in out.splitlines():
        key, value = line.split(": ", 1)
        kv.setdefault(key, value)
    return kv


def brazilian(mesh, d=20.0, p=1.0e6):
    pts = [[d / 2 * math.cos(-math.pi / 2 + 2 * math.pi * k / 240), d / 2 * math.sin(-math.pi / 2 + 2 * math.pi * k / 240)]
           for k in range(240)]
    text = (f'[sea]\nmodel = "none"\n[[floes.floe]]\nvertices = {pts}\nthickness = {H}\n'
            f'[fracture]\nmesh_size = {mesh}\nstrength = {STRENGTH}\n'
            f'[[fracture.load]]\npoint = [0.0, {d / 2}]\nforce = [0.0, {-p}]\n'
            f'[[fracture.load]]\npoint = [0.0, {-d / 2}]\nforce = [0.0, {p}]\n')
    kv = fracture(text, "--probe", "0", "0")
    exact = 2 * p / (math.pi * d * H)
    centre = float(kv["probe"].split()[2])
    return {"mesh": mesh, "used": float(kv["mesh_size"]), "nodes": int(kv["nodes"]), "centre": centre / exact - 1,
            "max": float(kv["max_principal_stress"]) / exact - 1, "direction": float(kv["direction"]),
            "p_c": p * float(kv["load_factor"]) / (math.pi * d * H * STRENGTH / 2) - 1}


def threshold(side, tau, mesh=1.0, load_radius=0.0):
    r = side / 4
    m1 = RHO * H * side * side
    m2 = RHO * H * 2 * math.sqrt(2) * r * r
    impulse = (1 + E_RESTITUTION) * m1 * m2 / (m1 + m2) * 1.0  # at 1 m/s
    text = (f'[sea]\nmodel = "none"\n[[floes.floe]]\n'
            f'vertices = [[0, 0], [{side}, 0], [{side}, {side}], [0, {side}]]\nthickness = {H}\n'
            f'[fracture]\nmesh_size = {mesh}\nstrength = {STRENGTH}\nduration = {tau}\nload_radius = {load_radius}\n'
            f'[[fracture.load]]\npoint = [0.0, {side / 2}]\nimpulse = [{impulse}, 0.0]\n')
    kv = fracture(text)
    return float(kv["load_factor"]), kv


def main():
    rows = [brazilian(m) for m in (4.0, 2.0, 1.0, 0.5, 0.25)]
    print("| mesh_size (m) | used (m) | nodes | centre tension error | largest sigma_1 error | crack direction (deg) | P_c error |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['mesh']} | {r['used']:.3g} | {r['nodes']} | {100 * r['centre']:+.2f}% | {100 * r['max']:+.2f}% | "
              f"{r['direction']:.2f} | {100 * r['p_c']:+.2f}% |")
    sizes = [5.0, 10.0, 20.0, 40.0, 80.0, 160.0]
    taus = [0.01, 0.1, 1.0]
    curves = {}
    print("\n| L (m) | " + " | ".join(f"v_c, tau = {t} s (m/s)" for t in taus) + " |")
    print("|---|" + "---|" * len(taus))
    for side in sizes:
        line = [f"| {side:g} "]
        for tau in taus:
            v, kv = threshold(side, tau)
            curves.setdefault(tau, []).append(v)
            line.append(f"| {v:.3g} ")
        print("".join(line) + "|")
    similar = [threshold(side, 1.0, side / 20, side / 20)[0] for side in sizes]
    print("self-similar (mesh and load radius L/20), tau = 1 s: " + ", ".join(f"{v:.3g}" for v in similar))
    print(f"  log-log slope {math.log(similar[-1] / similar[0]) / math.log(sizes[-1] / sizes[0]):.3f}")
    for tau in taus:
        v = curves[tau]
        s_small = math.log(v[2] / v[0]) / math.log(sizes[2] / sizes[0])
        s_large = math.log(v[-1] / v[-3]) / math.log(sizes[-1] / sizes[-3])
        print(f"tau = {tau} s: log-log slope {s_small:.2f} (L 5-20 m), {s_large:.2f} (L 40-160 m)")

    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.3))
    meshes = [r["used"] for r in rows]
    a.loglog(meshes, [abs(r["centre"]) for r in rows], "o-", label="centre tension $\\sigma_{xx}(0)$")
    a.loglog(meshes, [abs(r["p_c"]) for r in rows], "s--", label="initiation load $P_c$ (largest $\\sigma_1$)")
    a.axhline(0.05, color="grey", lw=0.8, ls=":")
    a.text(meshes[-1], 0.055, "5%", color="grey", ha="left")
    a.set_xlabel("mesh size (m), disc diameter 20 m")
    a.set_ylabel("relative error against $2P/(\\pi D h)$")
    a.set_title("(a) Brazilian disc under refinement")
    a.invert_xaxis()
    a.legend(fontsize=8)
    a.grid(True, which="both", alpha=0.3)
    for tau, marker in zip(taus, "o^s"):
        b.loglog(sizes, curves[tau], marker + "-", label=f"$\\tau$ = {tau} s")
    b.loglog(sizes, similar, "d--", color="grey", label="$\\tau$ = 1 s, mesh and load radius L/20")
    x0 = sizes[0]
    for slope, style in ((-1, ":"), (-2, "--")):
        ref = similar[0] if slope == -1 else curves[0.01][0]
        b.loglog(sizes, [ref * (x / x0) ** slope for x in sizes], "k" + style, lw=0.8, label=f"slope {slope}")
    b.set_xlabel("floe size L (m)")
    b.set_ylabel("initiation speed $v_c$ (m/s)")
    b.set_title("(b) threshold speed (mesh 1 m, load radius h = 1 m)")
    b.legend(fontsize=8)
    b.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(OUT, dpi=110)
    print(f"\nwrote {OUT}")


if __name__ == "__main__":
    main()
