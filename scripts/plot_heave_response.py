#!/usr/bin/env python3
"""Heave response of a 10 m floe in regular long-crested waves (issue #6).

Runs `floesim run` on a flume (dims = 1, 320 m, 1 m cells, 100 m deep, the
floe 10 m long and 0.5 m thick spanning the flume's 10 m width, strong law,
K = 100) for a range of wavelengths, takes the heave's Fourier component at
the wave frequency over wave periods 2..6, and plots heave / wave amplitude
against wavelength / floe length, with the quasi-static rigid-floe curve
|sin(kL/2) / (kL/2)| for reference. Each wavelength is run twice: with the
explicit kicks at dt_max = 0.01 s, and with the implicit step
([coupling] integrator = "implicit") at dt_max = T / 20.

    /usr/bin/python3 scripts/plot_heave_response.py [build/bin/floesim]

Writes docs/img/heave_response.png and prints the table (CSV).
"""
import math
import os
import subprocess
import sys
import tempfile

import h5py
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FLOESIM = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "build", "bin", "floesim")
L, A, H = 10.0, 0.05, 100.0


def response(wavelength, work, implicit=False):
    k = 2 * math.pi / wavelength
    omega = math.sqrt(9.81 * k * math.tanh(k * H))
    period = 2 * math.pi / omega
    dt = period / 20 if implicit else 0.01
    cfg = f"""[run]
t_end = {6 * period}
dt_max = {dt}
output_interval = {dt if implicit else 0.02}
[sea]
model = "spectral"
dims = 1
size = [320.0, 10.0]
cells = [320, 1]
depth = {H}
[sea.waves]
kind = "regular"
amplitude = {A}
wavelength = {wavelength}
[coupling]
law = "strong"
stiffness = 100.0
integrator = "{'implicit' if implicit else 'explicit'}"
[forcing]
ocean_drag = 0.0
air_drag = 0.0
[[floes.floe]]
vertices = [[155.0, 0.0], [165.0, 0.0], [165.0, 10.0], [155.0, 10.0]]
thickness = 0.5
"""
    path = os.path.join(work, "rao.toml")
    with open(path, "w") as f:
        f.write(cfg)
    out = os.path.join(work, "rao.h5")
    subprocess.run([FLOESIM, "run", path, "-q", "-o", out], check=True, stdout=subprocess.DEVNULL)
    with h5py.File(out) as f:
        t = f["time"][:]
        z = f["floes/state"][:, 0, 6]
    m = t >= 2 * period
    w = np.exp(-1j * omega * t[m])
    dt = np.gradient(t[m])
    return abs(np.sum(z[m] * w * dt)) * 2 / (t[m][-1] - t[m][0]) / A


with tempfile.TemporaryDirectory() as work:
    lams = [5, 7.5, 10, 12.5, 15, 20, 30, 40, 60, 80, 120, 160]
    rows = [(lam, response(lam, work), response(lam, work, implicit=True)) for lam in lams]
print("wavelength_m,wavelength_over_L,heave_over_amplitude_explicit,heave_over_amplitude_implicit_T_over_20")
for lam, r, ri in rows:
    print(f"{lam},{lam / L:.3f},{r:.4f},{ri:.4f}")
x = np.array([lam / L for lam, _, _ in rows])
y = np.array([r for _, r, _ in rows])
yi = np.array([ri for _, _, ri in rows])
xs = np.linspace(0.4, 17, 400)
ks = 2 * np.pi / (xs * L)
plt.figure(figsize=(6, 4))
plt.semilogx(xs, np.abs(np.sin(ks * L / 2) / (ks * L / 2)), "k--", lw=1, label="quasi-static rigid floe |sin(kL/2)/(kL/2)|")
plt.semilogx(x, y, "o-", label="floesim, explicit kicks, dt = 0.01 s (strong law, K = 100)")
plt.semilogx(x, yi, "s--", label="floesim, implicit step, dt = T / 20")
plt.xlabel("wavelength / floe length")
plt.ylabel("heave amplitude / wave amplitude")
plt.title("Heave of a 10 m floe in regular waves")
plt.grid(True, which="both", alpha=0.3)
plt.legend()
plt.tight_layout()
plt.savefig(os.path.join(ROOT, "docs", "img", "heave_response.png"), dpi=120)
