"""The CITEPH-64-2012 tests as floesim configurations (validation/citeph/citeph.py runs them).

The basin and the discs as the experiment had them (data/citeph/README.md),
the waves' dispersion, the table of tests read from data/citeph, the basin's
layout for a wave period, the arrays' lattices, and each test's TOML text.
"""
import csv
import dataclasses
import math
import os
import re


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
