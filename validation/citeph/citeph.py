#!/usr/bin/env python3
"""The CITEPH-64-2012 wave-basin tests (data/citeph/README.md) as floesim runs.

The table of tests comes from the data files (single disc, 39% array) and the
79% array's test list; each test becomes one configuration of a basin like
Oceanide: 3.1 m of fresh water, 16 m wide (resolved, periodic across), a
generation zone at x = 0 and an absorbing zone at the far end
([sea.tank], docs/sea.md). Every period T also gets an empty-basin run, which
gives the incident amplitude at the disc and at the probes (the sea is
linear, so one empty run per period serves every wave height: its amplitudes
are scaled by H / H_ref).

Measurements, as the experiment defines them (data/citeph/README.md), by
least-squares fits over the last `window_periods` periods:
  heave RAO  = |heave| / a_inc
  pitch RAO  = |pitch| / (k a_inc)   (pitch = the bottom's slope along x, rad)
  surge RAO  = |x| / a_inc
  transmission = mean over probes of |eta|^2 behind the array, divided by the
                 same mean in the empty basin.
Each disc is held by a soft mooring (Physics.mooring_period); what remains of
the drift under the mean wave force is taken into account by fitting the
motions against the incident wave the disc meets on its way (`response`: the empty basin's complex amplitude along the middle line,
read at the disc's centre), which also takes the Doppler shift of the drift.
Probe amplitudes are fitted as a cos(w t) + b sin(w t) + c0 + c1 t + c2 t^2.

Collisions (79% array): the run records the collision solver's impulses
([run] record_collisions: one row per solve and pair of discs, its normal
impulse, docs/formats.md), taken over the window. A collision of two discs is
a run of rows of their pair no more than two steps apart (an impact and the
contact held after it; `collision_episodes`), its impulse the sum of their
normal impulses. The mean time between collisions is the window times the
number of middle discs over the number of their collisions (a collision of
two middle discs counts for both).

    python3 validation/citeph/citeph.py generate OUTDIR [--resolution NAME]
    python3 validation/citeph/citeph.py run WORKDIR [--jobs 2] [--resolution NAME] [--only REGEX]
    python3 validation/citeph/citeph.py report WORKDIR OUTDIR
"""
import argparse
import csv
import dataclasses
import json
import math
import multiprocessing
import os
import re
import resource
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DATA = os.path.join(ROOT, "data", "citeph")

# The basin and the discs (data/citeph/README.md).
G = 9.81
DEPTH = 3.1          # m
RHO_WATER = 1000.0   # kg/m^3, fresh
SIGMA = 0.0728       # N/m, fresh water
WIDTH = 16.0         # m, Oceanide's width
DIAMETER = 0.99      # m
THICKNESS = 0.033    # m
RHO_DISC = 545.0     # kg/m^3
STRIP = 5.0          # m, the array's length along the waves
DISC_SIDES = 32      # vertices of a disc's outline

# Tests of the 79% array (data/citeph/README.md lists them; no values).
TESTS_79 = [(0.65, 20), (0.8, 20), (0.8, 40), (0.95, 30), (1.1, 40), (1.25, 40), (1.4, 40),
            (1.4, 80), (1.55, 40), (1.7, 40), (1.85, 40), (2.0, 40)]


@dataclasses.dataclass(frozen=True)
class Resolution:
    """The numerical choices of a set of runs (docs/validation.md)."""
    per_wavelength: float = 10.0   # grid cells per incident wavelength, at least
    per_diameter: float = 8.0      # grid cells across a disc, at least
    steps_per_period: int = 20     # dt_max = T / steps_per_period
    window_periods: float = 8.0    # periods fitted at the end of the run
    settle_periods: float = 4.0    # periods after the front has passed the last probe


RESOLUTIONS = {
    "standard": Resolution(),
    "fine": Resolution(per_wavelength=14.0, per_diameter=11.0, steps_per_period=28),
    "smoke": Resolution(per_wavelength=6.0, per_diameter=4.0, steps_per_period=12,
                        window_periods=3.0, settle_periods=1.0),
}


@dataclasses.dataclass(frozen=True)
class Physics:
    """Model choices (docs/validation.md says why)."""
    law: str = "strong"
    blend: float = 1.0             # with law = "blend": s in p = s strong + (1 - s) weak
    stiffness: float = 100.0
    restitution: float = 0.5       # disc-disc (plastic on plastic)
    friction: float = 0.3
    ocean_drag: float = 0.0
    # Each disc on a soft mooring to where it starts ([[floes.floe]] mooring_period,
    # coupling/mooring.hpp), as the experiment held its discs: a period of 20 s,
    # 10 to 30 wave periods, changes the surge at the wave period by 1% or
    # less (an oscillator driven far above its resonance) and keeps the
    # mean wave force from carrying the discs out of the probes' window.
    # 0: no mooring.
    mooring_period: float = 20.0
    mooring_damping: float = 0.7


# -- waves -------------------------------------------------------------------

def wavenumber(period):
    """k of omega^2 = (g k + sigma k^3 / rho) tanh(k h), by Newton from the deep-water guess."""
    omega = 2 * math.pi / period
    k = omega * omega / G
    for _ in range(50):
        t = math.tanh(k * DEPTH)
        f = (G * k + SIGMA * k ** 3 / RHO_WATER) * t - omega * omega
        df = (G + 3 * SIGMA * k * k / RHO_WATER) * t + (G * k + SIGMA * k ** 3 / RHO_WATER) * DEPTH * (1 - t * t)
        step = f / df
        k -= step
        if abs(step) < 1e-14 * k:
            break
    return k


def group_velocity(period):
    k = wavenumber(period)
    omega = 2 * math.pi / period
    kh = k * DEPTH
    return omega / k * 0.5 * (1 + 2 * kh / math.sinh(2 * kh))


# -- the table of tests ------------------------------------------------------

def _read_csv(name):
    with open(os.path.join(DATA, name), newline="") as f:
        return list(csv.DictReader(f))


def tests():
    """Every test as a dict: case, concentration (0, 39, 79), T, H_mm, and the
    measured rows [(quantity, mean, lo, hi)] (empty where not in data/citeph).
    Repeated measurements of one (T, H) are one run with several data rows."""
    by_case = {}

    def add(concentration, period, height, row=None):
        prefix = "disc" if concentration == 0 else f"array{concentration}"
        case = f"{prefix}_T{period:.2f}_H{height:g}"
        entry = by_case.setdefault(case, dict(case=case, concentration=concentration, T=period,
                                              H_mm=height, data=[]))
        if row is not None:
            entry["data"].append(row)

    for r in _read_csv("single_disc_rao.csv"):
        add(0, float(r["T_s"]), float(r["H_mm"]),
            (r["quantity"] + "_rao", float(r["mean"]), float(r["mean_minus_1std"]), float(r["mean_plus_1std"])))
    for r in _read_csv("transmission_39.csv"):
        add(39, float(r["T_s"]), float(r["H_mm"]),
            ("transmission", float(r["energy_transmission"]), float(r["mean_minus_1std"]),
             float(r["mean_plus_1std"])))
    for period, height in TESTS_79:
        add(79, period, float(height))
    return sorted(by_case.values(), key=lambda e: (e["concentration"], e["T"], e["H_mm"]))


# -- the basin ---------------------------------------------------------------

def _nice_cells(n):
    """The smallest count >= n whose prime factors are 2, 3 and 5 (fast FFTs)."""
    n = max(int(math.ceil(n)), 8)
    while True:
        m = n
        for p in (2, 3, 5):
            while m % p == 0:
                m //= p
        if m == 1:
            return n
        n += 1


def basin(period, resolution):
    """Layout of the basin for waves of this period: zones, strip, probes, grid."""
    wavelength = 2 * math.pi / wavenumber(period)
    generation = max(2.0 * wavelength, 2.0)
    absorption = max(2.0 * wavelength, 3.0)
    gap = max(wavelength, 2.0)                 # free water before and after the strip
    strip0 = generation + gap
    strip1 = strip0 + STRIP
    probes = [strip1 + 1.0 + i * wavelength / 4 for i in range(4)]   # m, probe lines behind
    length = strip1 + 1.0 + max(wavelength, 1.0) + absorption
    dx = min(wavelength / resolution.per_wavelength, DIAMETER / resolution.per_diameter)
    nx = _nice_cells(length / dx)
    ny = _nice_cells(WIDTH / dx)
    duration = (3.0 * period + (probes[-1] - generation) / group_velocity(period)
                + (resolution.settle_periods + resolution.window_periods) * period)
    return dict(wavelength=wavelength, generation=generation, absorption=absorption, length=length,
                strip=(strip0, strip1), disc=(0.5 * (strip0 + strip1), 0.5 * WIDTH), probes=probes,
                cells=(nx, ny), duration=duration, dt=period / resolution.steps_per_period)


def lattice(concentration, strip):
    """Disc centres on a staggered (hexagonal-like) lattice filling the strip
    [strip0, strip1] x [0, WIDTH]: nx columns of ny discs (ny - 1 in the odd
    columns, shifted by half a spacing); the (nx, ny) whose concentration is
    nearest the target with neighbours at least 1 cm apart."""
    area = math.pi * DIAMETER ** 2 / 4
    best = None
    for nx in range(1, 12):
        for ny in range(1, 30):
            sx, sy = STRIP / nx, WIDTH / ny
            closest = min(sy, math.hypot(sx, sy / 2) if nx > 1 else sy, 2 * sx if nx > 1 else sy)
            if closest < DIAMETER + 0.01:
                continue
            c = 100 * (nx * ny - nx // 2) * area / (STRIP * WIDTH)
            if best is None or abs(c - concentration) < abs(best[0] - concentration):
                best = (c, nx, ny)
    c, nx, ny = best
    sx, sy = STRIP / nx, WIDTH / ny
    # the basin is walled: odd columns, shifted, lose the disc that would cross y = WIDTH
    centres = [(strip[0] + (i + 0.5) * sx, (j + 0.5 + 0.5 * (i % 2)) * sy)
               for i in range(nx) for j in range(ny - (i % 2))]
    return centres, 100 * len(centres) * area / (STRIP * WIDTH)


def disc_vertices(cx, cy):
    r = DIAMETER / 2
    return [[round(cx + r * math.cos(2 * math.pi * i / DISC_SIDES), 6),
             round(cy + r * math.sin(2 * math.pi * i / DISC_SIDES), 6)] for i in range(DISC_SIDES)]


def configuration(test, resolution, physics, empty=False):
    """The TOML text of a test (empty: the same basin without discs) and its layout."""
    period, height = test["T"], test["H_mm"]
    b = basin(period, resolution)
    if empty:
        centres, actual = [], 0.0
    elif test["concentration"] == 0:
        centres, actual = [b["disc"]], 0.0
    else:
        centres, actual = lattice(test["concentration"], b["strip"])
    mooring = (f"mooring_period = {physics.mooring_period}\nmooring_damping = {physics.mooring_damping}\n"
               if physics.mooring_period > 0 else "")
    floes = "\n".join(f"[[floes.floe]]\nvertices = {disc_vertices(x, y)}\n{mooring}" for x, y in centres)
    text = f"""# CITEPH-64-2012 {test['case']}{' (empty basin)' if empty else ''}: generated by
# validation/citeph/citeph.py; T = {period} s, H = {height} mm, wavelength {b['wavelength']:.3f} m.
[run]
t_end = {b['duration']:.6f}
dt_max = {b['dt']:.8f}
output_interval = {b['dt']:.8f}
threads = 1
record_collisions = {'true' if len(centres) > 1 else 'false'}

[sea]
model = "spectral"
dims = 2
size = [{b['length']:.6f}, {WIDTH}]
cells = [{b['cells'][0]}, {b['cells'][1]}]
depth = {DEPTH}
rho = {RHO_WATER}
sigma = {SIGMA}

[sea.waves]
kind = "regular"
amplitude = {height / 2000.0}
period = {period}

[sea.tank]
enabled = true
generation_length = {b['generation']:.6f}
absorption_length = {b['absorption']:.6f}

[coupling]
law = "{physics.law}"{f"{chr(10)}blend = {physics.blend}" if physics.law == "blend" else ""}
stiffness = {physics.stiffness}
integrator = "implicit"

[contact]
restitution = {physics.restitution}
friction = {physics.friction}

[forcing]
ocean_drag = {physics.ocean_drag}
air_drag = 0.0

[floes]
density = {RHO_DISC}
thickness = {THICKNESS}

{floes}"""
    layout = dict(b, centres=centres, concentration_actual=actual)
    return text, layout


# -- measurement -------------------------------------------------------------

def fit_amplitude(t, signal, omega):
    """Complex amplitude A (signal ~ Re(A exp(-i w t)) + slow polynomial) by least squares.
    signal may be [n] or [n, m] (one fit per column)."""
    tc = (t - t.mean()) / max(np.ptp(t), 1e-12)
    basis = np.column_stack([np.cos(omega * t), np.sin(omega * t), np.ones_like(t), tc, tc * tc])
    coef, *_ = np.linalg.lstsq(basis, signal, rcond=None)
    return coef[0] + 1j * coef[1]


def middle_discs(centres, strip):
    """Discs of the middle third of the strip along x, away from the periodic seam in y."""
    x0, x1 = strip
    return [i for i, (x, y) in enumerate(centres)
            if x0 + (x1 - x0) / 3 <= x <= x1 - (x1 - x0) / 3 and 0.25 * WIDTH <= y <= 0.75 * WIDTH]


def collision_episodes(rows, discs, gap):
    """Collisions of the discs `discs` from rows of /events/collisions
    (time, floe_a, floe_b, normal, x, y, resting; floe numbers are the discs'
    indices): the rows of a pair whose times are at most `gap` apart are one
    collision (an impact, then the contact held after it, one row per
    step), at the time of its first row, with the sum of their normal
    impulses. A collision of two discs of `discs` counts for both.
    Returns (times, impulses)."""
    discs = set(discs)
    rows = np.asarray(rows, dtype=float).reshape(-1, 7)
    pairs = {}
    for time, a, b, normal, *_ in rows:
        pairs.setdefault((int(a), int(b)), []).append((time, normal))
    times, impulses = [], []
    for (a, b), hits in sorted(pairs.items()):
        weight = (a in discs) + (b in discs)
        if not weight:
            continue
        hits.sort()
        start, total, last = hits[0][0], 0.0, None
        for time, normal in hits:
            if last is not None and time - last > gap:
                times.extend([start] * weight)
                impulses.extend([total] * weight)
                start, total = time, 0.0
            total += normal
            last = time
        times.extend([start] * weight)
        impulses.extend([total] * weight)
    return times, impulses


def response(series, empty, scale, omega):
    """Complex response of each of x, heave, pitch to the incident wave met by
    the drifting disc: a signal s(t) is fitted as Re(R b(t)) + a slow
    quadratic, b(t) = A(x(t)) exp(-i w t) with A the empty basin's complex
    amplitude (times scale) along the middle line, interpolated at the disc's
    centre x(t). |R| is then the response per unit incident amplitude (the
    drift's Doppler shift and the wave's change along the path are in b)."""
    t = np.array(series["t"])
    x = np.array(series["x"])
    row = (np.array(empty["row_re"]) + 1j * np.array(empty["row_im"])) * scale
    centres = (np.arange(len(row)) + 0.5) * empty["row_dx"]
    # modulus and phase interpolated apart: a progressive wave's phase is linear
    # in x, and interpolating re and im would shrink |A| by up to (k dx)^2 / 8
    a = np.interp(x, centres, np.abs(row)) * np.exp(1j * np.interp(x, centres, np.unwrap(np.angle(row))))
    b = a * np.exp(-1j * omega * t)
    tc = (t - t.mean()) / max(np.ptp(t), 1e-12)
    basis = np.column_stack([b.real, b.imag, np.ones_like(t), tc, tc * tc])
    out = {}
    for name in ("x", "heave", "pitch"):
        (c1, c2, *_), *_ = np.linalg.lstsq(basis, np.array(series[name]), rcond=None)
        out[name] = math.hypot(c1, c2)
    out["a_inc"] = float(np.mean(np.abs(a)))
    return out


def run_case(job):
    """Runs one configuration in this process and returns its measurements (a dict)."""
    os.environ["OMP_NUM_THREADS"] = "1"
    import floesim  # noqa: E402 (imported here: the worker processes import it themselves)

    text, layout, test, empty, physics = job["text"], job["layout"], job["test"], job["empty"], job["physics"]
    period = test["T"]
    omega = 2 * math.pi / period
    cfg = floesim.Config(text, name=job["name"])
    sim = floesim.Simulation(cfg)
    grid = sim.sea_grid()
    nx, ny = grid["cells"]
    lx = grid["size"][0]
    dx = lx / nx
    t_end = layout["duration"]
    t_window = t_end - job["window_periods"] * period
    probe_cols = [int(p / dx) for p in layout["probes"]]
    disc_col = int(layout["disc"][0] / dx)
    times, states, probes, at_disc, rows, hits = [], [], [], [], [], []
    dt = layout["dt"]
    start = time.time()
    cpu0 = resource.getrusage(resource.RUSAGE_SELF).ru_utime
    k = 0
    while sim.time < t_end - 1e-9:
        k += 1
        sim.run_until(min(k * dt, t_end))
        collided = sim.take_collision_events()
        if sim.time < t_window - 2 * dt:
            continue
        hits.append(collided[collided[:, 0] >= t_window])
        times.append(sim.time)
        if not empty:
            states.append(np.array(sim.state))
        eta = np.asarray(sim.sea_elevation())
        probes.append(eta[:, probe_cols])
        at_disc.append(eta[:, disc_col].mean())
        if empty:
            rows.append(eta[ny // 2, :])
    wall = time.time() - start
    cpu = resource.getrusage(resource.RUSAGE_SELF).ru_utime - cpu0
    t = np.array(times)
    sel = t >= t_window
    out = dict(name=job["name"], case=test["case"], empty=empty, T=period, H_mm=test["H_mm"],
               wall_s=wall, cpu_s=cpu, steps=sim.steps, cells=[nx, ny], floes=len(layout["centres"]),
               concentration_actual=layout["concentration_actual"])
    p = np.array(probes)[sel]                          # [n, ny, probes]
    a = fit_amplitude(t[sel], p.reshape(p.shape[0], -1), omega)
    out["probe_energy"] = float(np.mean(np.abs(a) ** 2))
    out["disc_amplitude"] = float(abs(fit_amplitude(t[sel], np.array(at_disc)[sel], omega)))
    if empty:   # the incident wave's complex amplitude along the basin's middle line
        row = fit_amplitude(t[sel], np.array(rows)[sel], omega)
        out["row_dx"] = dx
        out["row_re"], out["row_im"] = row.real.tolist(), row.imag.tolist()
    if not empty:
        s = np.array(states)                           # [n_all, floes, 12]
        cols = floesim.STATE_COLUMNS
        ix, ih, ip = cols.index("x"), cols.index("heave"), cols.index("pitch")
        if test["concentration"] == 0:
            out["series"] = dict(t=t[sel].tolist(), x=s[sel, 0, ix].tolist(), heave=s[sel, 0, ih].tolist(),
                                 pitch=s[sel, 0, ip].tolist())
            out["drift_m"] = float(s[sel, 0, ix][-1] - s[sel, 0, ix][0])
            out["window_s"] = float(t[sel][-1] - t[sel][0])
        else:
            centres = np.array(layout["centres"])
            middle = middle_discs(layout["centres"], layout["strip"])
            window = float(t[sel][-1] - t_window)
            _, impulses = collision_episodes(np.vstack(hits), middle, 2 * dt)
            disc_time = window * len(middle)
            out["collisions"] = len(impulses)
            out["disc_time_s"] = disc_time
            out["collision_interval_s"] = disc_time / len(impulses) if impulses else float("nan")
            out["collision_impulse_Ns"] = float(np.mean(impulses)) if impulses else float("nan")
            out["lcp"] = sim.lcp()
            x = s[sel][:, :, ix]
            out["array_drift_m"] = float(np.mean(x[-1] - centres[:, 0]))
            out["array_rear_m"] = float(np.max(x[-1]) + DIAMETER / 2)
            out["first_probe_m"] = float(layout["probes"][0])
    return out


def jobs(resolution, physics, only=None):
    """Every run of the set: the tests, and one empty basin per period."""
    out, periods = [], {}
    for test in tests():
        periods.setdefault(test["T"], test)
        text, layout = configuration(test, resolution, physics)
        out.append(dict(name=test["case"], text=text, layout=layout, test=test, empty=False,
                        physics=dataclasses.asdict(physics), window_periods=resolution.window_periods))
    for period, test in sorted(periods.items()):
        ref = dict(test, case=f"empty_T{period:.2f}", H_mm=40.0, concentration=0)
        text, layout = configuration(ref, resolution, physics, empty=True)
        out.append(dict(name=ref["case"], text=text, layout=layout, test=ref, empty=True,
                        physics=dataclasses.asdict(physics), window_periods=resolution.window_periods))
    if only:
        out = [j for j in out if re.search(only, j["name"])]
    return out


def _estimated_cost(job):
    nx, ny = job["layout"]["cells"]
    steps = job["layout"]["duration"] / job["layout"]["dt"]
    return steps * nx * ny * (1 + 3 * len(job["layout"]["centres"]) ** 0.5) * (0.2 if job["empty"] else 1)


def _run_and_store(args):
    job, workdir = args
    path = os.path.join(workdir, job["name"] + ".json")
    if os.path.exists(path):
        with open(path) as f:
            old = json.load(f)
        if old.get("config") == job["text"]:
            return old
    with open(os.path.join(workdir, job["name"] + ".toml"), "w") as f:
        f.write(job["text"])
    try:
        result = run_case(job)
    except Exception as e:  # a failed run is reported in results, not hidden
        result = dict(name=job["name"], error=f"{type(e).__name__}: {e}")
    result["config"] = job["text"]
    with open(path, "w") as f:
        json.dump(result, f, indent=1)
    print(f"{time.strftime('%H:%M:%S')} {job['name']}: "
          + (result.get("error") or f"{result['cpu_s']:.0f} s CPU ({result['wall_s']:.0f} s wall), {result['steps']} steps, "
             f"cells {result['cells'][0]}x{result['cells'][1]}"), flush=True)
    return result


def run_all(workdir, resolution, physics, processes, only=None):
    os.makedirs(workdir, exist_ok=True)
    todo = sorted(jobs(resolution, physics, only), key=_estimated_cost, reverse=True)
    with multiprocessing.get_context("spawn").Pool(processes) as pool:
        return list(pool.imap_unordered(_run_and_store, [(j, workdir) for j in todo]))


# -- the report --------------------------------------------------------------

def load(workdir):
    out = {}
    for name in os.listdir(workdir):
        if name.endswith(".json"):
            with open(os.path.join(workdir, name)) as f:
                r = json.load(f)
            out[r["name"]] = r
    return out


def results_rows(workdir):
    """Rows case, concentration, T, H_mm, quantity, model, data, lo, hi."""
    runs = load(workdir)
    rows = []
    for test in tests():
        r = runs.get(test["case"])
        empty = runs.get(f"empty_T{test['T']:.2f}")
        model = {}
        if r and empty and "error" not in r and "error" not in empty:
            scale = test["H_mm"] / empty["H_mm"]
            a_inc = empty["disc_amplitude"] * scale
            if test["concentration"] == 0:
                if "series" in r and "row_re" in empty:
                    k = wavenumber(test["T"])
                    rao = response(r["series"], empty, scale, 2 * math.pi / test["T"])
                    model = dict(heave_rao=rao["heave"], pitch_rao=rao["pitch"] / k, surge_rao=rao["x"])
            else:
                model = dict(transmission=r["probe_energy"] / (empty["probe_energy"] * scale * scale))
                if test["concentration"] == 79:
                    model["collision_interval_s"] = r["collision_interval_s"]
                    model["collision_impulse_Ns"] = r["collision_impulse_Ns"]
        quantities = (["heave_rao", "pitch_rao", "surge_rao"] if test["concentration"] == 0 else
                      ["transmission"] + (["collision_interval_s", "collision_impulse_Ns"]
                                          if test["concentration"] == 79 else []))
        for q in quantities:
            data = [d for d in test["data"] if d[0] == q] or [(q, None, None, None)]
            for _, mean, lo, hi in data:
                m = model.get(q)
                rows.append(dict(case=test["case"], concentration=test["concentration"], T=test["T"],
                                 H_mm=test["H_mm"], quantity=q,
                                 model="" if m is None or not math.isfinite(m) else f"{m:.4f}",
                                 data="" if mean is None else f"{mean:.4f}",
                                 lo="" if lo is None else f"{lo:.4f}", hi="" if hi is None else f"{hi:.4f}"))
    return rows


def write_results(workdir, outdir):
    rows = results_rows(workdir)
    os.makedirs(outdir, exist_ok=True)
    path = os.path.join(outdir, "results.csv")
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=["case", "concentration", "T", "H_mm", "quantity", "model", "data",
                                          "lo", "hi"])
        w.writeheader()
        w.writerows(rows)
    return rows


def plot(rows, outdir):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    def panel(ax, quantity, concentration, title, analytic=None):
        sel = [r for r in rows if r["quantity"] == quantity and r["concentration"] == concentration]
        heights = sorted({r["H_mm"] for r in sel})
        markers = dict(zip(heights, "osD^v<>"))
        for h in heights:
            d = [r for r in sel if r["H_mm"] == h and r["data"] != ""]
            if d:
                T = np.array([float(r["T"]) for r in d])
                mean = np.array([float(r["data"]) for r in d])
                lo = np.array([float(r["lo"]) for r in d])
                hi = np.array([float(r["hi"]) for r in d])
                ax.errorbar(T - 0.01, mean, yerr=[mean - lo, hi - mean], fmt=markers[h], color="k",
                            mfc="none", capsize=3, label=f"measured, H = {h:g} mm")
            m = sorted({(float(r["T"]), float(r["model"])) for r in sel if r["H_mm"] == h and r["model"] != ""})
            if m:
                ax.plot([x + 0.01 for x, _ in m], [y for _, y in m], markers[h], color="C3",
                        label=f"model, H = {h:g} mm")
        if analytic is not None:
            T = np.linspace(0.6, 2.05, 100)
            ax.plot(T, [analytic(x) for x in T], "--", color="0.5", lw=1, label="slope-sliding limit")
        ax.set_xlabel("T (s)")
        ax.set_title(title)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)

    fig, axes = plt.subplots(1, 3, figsize=(13, 4))
    panel(axes[0], "heave_rao", 0, "single disc: heave RAO", lambda T: 1.0)
    panel(axes[1], "pitch_rao", 0, "single disc: pitch RAO", lambda T: 1.0)
    panel(axes[2], "surge_rao", 0, "single disc: surge RAO",
          lambda T: 1.0 / math.tanh(wavenumber(T) * DEPTH))
    fig.tight_layout()
    fig.savefig(os.path.join(outdir, "single_disc.png"), dpi=110)
    plt.close(fig)

    fig, axes = plt.subplots(1, 3, figsize=(13, 4))
    panel(axes[0], "transmission", 39, "39% array: energy transmission")
    panel(axes[1], "transmission", 79, "79% array: energy transmission (no data)")
    sel = [r for r in rows if r["concentration"] == 79 and r["model"] != ""]
    ax = axes[2]
    for q, c, lab in (("collision_interval_s", "C0", "mean time between collisions (s)"),
                      ("collision_impulse_Ns", "C1", "mean impulse (N s)")):
        for h, marker in ((40.0, "D"), (20.0, "o"), (30.0, "s"), (80.0, "v")):
            pts = sorted((float(r["T"]), float(r["model"])) for r in sel
                         if r["quantity"] == q and float(r["H_mm"]) == h)
            if pts:
                ax.plot(*zip(*pts), marker + ("-" if h == 40.0 else ""), color=c, label=f"{lab}, H = {h:g} mm")
    ax.set_xlabel("T (s)")
    ax.set_title("79% array: collisions of the middle discs")
    ax.set_yscale("log")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(outdir, "arrays.png"), dpi=110)
    plt.close(fig)


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="command", required=True)
    g = sub.add_parser("generate", help="write the configurations")
    g.add_argument("outdir")
    g.add_argument("--resolution", default="standard", choices=sorted(RESOLUTIONS))
    r = sub.add_parser("run", help="run the tests (results cached per configuration in WORKDIR)")
    r.add_argument("workdir")
    r.add_argument("--resolution", default="standard", choices=sorted(RESOLUTIONS))
    r.add_argument("--jobs", type=int, default=2)
    r.add_argument("--only", help="regular expression on the case names")
    r.add_argument("--law", default=Physics.law)
    r.add_argument("--stiffness", type=float, default=Physics.stiffness)
    r.add_argument("--blend", type=float, default=Physics.blend)
    r.add_argument("--restitution", type=float, default=Physics.restitution)
    r.add_argument("--friction", type=float, default=Physics.friction)
    r.add_argument("--mooring-period", type=float, default=Physics.mooring_period, help="s; 0: no mooring")
    p = sub.add_parser("report", help="results.csv and figures from the runs in WORKDIR")
    p.add_argument("workdir")
    p.add_argument("outdir")
    a = ap.parse_args(argv)
    if a.command == "generate":
        os.makedirs(a.outdir, exist_ok=True)
        for j in jobs(RESOLUTIONS[a.resolution], Physics()):
            with open(os.path.join(a.outdir, j["name"] + ".toml"), "w") as f:
                f.write(j["text"])
        return 0
    if a.command == "run":
        physics = Physics(law=a.law, blend=a.blend, stiffness=a.stiffness, restitution=a.restitution, friction=a.friction,
                          mooring_period=a.mooring_period)
        results = run_all(a.workdir, RESOLUTIONS[a.resolution], physics, a.jobs, a.only)
        failed = [r["name"] for r in results if "error" in r]
        if failed:
            print("failed runs: " + ", ".join(failed), file=sys.stderr)
            return 1
        return 0
    rows = write_results(a.workdir, a.outdir)
    plot(rows, a.outdir)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
