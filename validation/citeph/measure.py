"""The CITEPH measurements taken from a floesim run (validation/citeph/citeph.py).

Amplitudes by least squares, the discs' responses to the incident wave they
meet, and the collisions of the 79% array's middle discs; `run_case` runs one
configuration through the Python module and returns them.
"""
import math
import os
import resource
import time

import numpy as np

from cases import DIAMETER, WIDTH

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
    for when, a, b, normal, *_ in rows:
        pairs.setdefault((int(a), int(b)), []).append((when, normal))
    times, impulses = [], []
    for (a, b), hits in sorted(pairs.items()):
        weight = (a in discs) + (b in discs)
        if not weight:
            continue
        hits.sort()
        start, total, last = hits[0][0], 0.0, None
        for when, normal in hits:
            if last is not None and when - last > gap:
                times.extend([start] * weight)
                impulses.extend([total] * weight)
                start, total = when, 0.0
            total += normal
            last = when
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

    text, layout, test, empty = job["text"], job["layout"], job["test"], job["empty"]
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
