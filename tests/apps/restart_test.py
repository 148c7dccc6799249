#!/usr/bin/env python3
"""`floesim run --restart`: a run continued from its checkpoint equals, bit
for bit, the run that never stopped (docs/formats.md, "Checkpoint and
restart"); and the restarts that cannot continue a run are refused.

usage: restart_test.py FLOESIM SOURCE_DIR CASE
Each continuation case runs a scenario to T (the reference), then to T/2 (or
stops it midway), continues that file to T, and compares every dataset of the
two run files with == (NaN where both are NaN), the XDMF text, and the final
checkpoints (wall-clock counters aside).
"""
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time

import h5py
import numpy as np

from harness import Cli, check, keyvals

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from restart_scenarios import WAVES  # noqa: E402

FLOESIM, SRC, CASE = sys.argv[1], os.path.abspath(sys.argv[2]), sys.argv[3]
WORK = tempfile.mkdtemp(prefix="floesim_restart_")
CLI = Cli(FLOESIM, WORK)
run, write = CLI.run, CLI.write


def datasets(path):
    out = {}
    with h5py.File(path, "r") as f:
        f.visititems(lambda name, obj: out.__setitem__(name, obj[()]) if isinstance(obj, h5py.Dataset) else None)
        columns = list(f["checkpoint/counters"].attrs["columns"]) if "checkpoint/counters" in f else []
        status = f.attrs["status"]
    return out, columns, status


def same_bits(a, b):
    a, b = np.asarray(a), np.asarray(b)
    if a.shape != b.shape or a.dtype != b.dtype:
        return False
    if a.dtype.kind == "f":
        return bool(np.all((a == b) | (np.isnan(a) & np.isnan(b))))
    return bool(np.all(a == b))


def compare_runs(ref, cont, what):
    """Every dataset of the two run files equal with ==, and the XDMF the same."""
    a, cols_a, status_a = datasets(ref)
    b, cols_b, status_b = datasets(cont)
    check(status_a == status_b == "complete", f"{what}: both complete ({status_a}, {status_b})")
    check(sorted(a) == sorted(b), f"{what}: the same datasets\n{sorted(a)}\n{sorted(b)}")
    check(cols_a == cols_b, f"{what}: the same checkpoint counters")
    for name in a:
        x, y = a[name], b[name]
        if name == "checkpoint/counters":
            keep = [k for k, c in enumerate(cols_a) if not c.endswith("seconds")]  # wall time
            x, y = np.asarray(x)[keep], np.asarray(y)[keep]
        if not same_bits(x, y):
            diff = ""
            if np.asarray(x).shape == np.asarray(y).shape and np.asarray(x).dtype.kind == "f":
                d = np.abs(np.asarray(x, float) - np.asarray(y, float))
                diff = f" (max |a - b| = {np.nanmax(d)}, {int(np.sum(d > 0))} elements differ)"
            sys.exit(f"FAILED: {what}: /{name} differs between the uninterrupted and the continued run{diff}")
    xa = open(os.path.splitext(ref)[0] + ".xmf").read().replace(os.path.basename(ref), "RUN")
    xb = open(os.path.splitext(cont)[0] + ".xmf").read().replace(os.path.basename(cont), "RUN")
    check(xa == xb, f"{what}: the XDMF files differ")
    return a


def checkpoint_time(path):
    with h5py.File(os.path.join(WORK, path), "r") as f:
        return float(f["checkpoint"].attrs["time"])


def continuation(config_text, t_full, t_half, name, in_place=False):
    """Full run to t_full; run to t_half; continue it to t_full; compare."""
    cfg = write(name + ".toml", config_text)
    run("run", "-q", cfg, "-o", "full.h5", "--until", str(t_full))
    run("run", "-q", cfg, "-o", "half.h5", "--until", str(t_half))
    check(checkpoint_time("half.h5") == t_half, f"{name}: the first run's checkpoint is at its end")
    if in_place:
        # No CONFIG (the run's own) and no -o: the run file itself goes on.
        p = run("run", "-q", "--restart", "half.h5", "--until", str(t_full))
        cont = "half.h5"
    else:
        p = run("run", "-q", cfg, "--restart", "half.h5", "--until", str(t_full), "-o", "cont.h5")
        cont = "cont.h5"
        check(checkpoint_time("half.h5") == t_half, f"{name}: -o leaves the restarted file as it was")
    check(f"restarted_from: half.h5 at t = {t_half:g} s" in p.stdout, f"{name}: the summary names the restart\n{p.stdout}")
    data = compare_runs(os.path.join(WORK, "full.h5"), os.path.join(WORK, cont), name)
    t = data["time"]
    check(np.any(t > t_half) and np.any(t < t_half), f"{name}: records on both sides of the restart")
    return data


# A pack with wind against a coast (a static floe): collisions, sub-steps.
PACK = """
[run]
t_end = 60.0
dt_max = 1.0
output_interval = 2.0

[sea]
model = "none"

[forcing]
wind = [20.0, 3.0]

[contact]
restitution = 0.4
friction = 0.5

[[floes.floe]]
vertices = [[0, 0], [10, 0], [10, 10], [0, 10]]
velocity = [1.0, 0.0]
[[floes.floe]]
vertices = [[12, 1], [22, 1], [21, 11], [13, 10]]
velocity = [0.2, 0.05]
angular_velocity = 0.01
[[floes.floe]]
vertices = [[25, -2], [33, -2], [34, 6], [26, 7]]
velocity = [0.6, 0.0]
[[floes.floe]]
vertices = [[38, 0], [47, 1], [46, 9], [39, 10]]
velocity = [0.1, 0.0]
[[floes.floe]]
vertices = [[52, -30], [62, -30], [62, 40], [52, 40]]
static = true
"""

# Floes on a spectral sea with regular waves, wind and collisions.


# A BEM basin (vertical slice) with a floe.
BEM = """
[run]
t_end = 4.0
dt_max = 0.02
output_interval = 0.25

[sea]
model = "bem"
dims = 1
size = [40.0, 2.0]
cells = [48, 1]
depth = 4.0

[sea.waves]
kind = "standing"
amplitude = 0.1
wavelength = 20.0

[[floes.floe]]
vertices = [[15, 0], [21, 0], [21, 2], [15, 2]]
thickness = 0.5
"""

# A 3D BEM basin cut to its lowest modes with the static correction of the
# dropped ones (fluid/static_correction.hpp): the pressure the sea holds is
# part of the state (/checkpoint/sea/held_pressure).
BEM3D_CORRECTED = """
[run]
t_end = 2.0
dt_max = 0.02
output_interval = 0.25
threads = 1

[sea]
model = "bem"
dims = 2
size = [4.0, 2.0]
cells = [16, 8]
depth = 1.0
rho = 1000.0
bem_modes = 40
bem_static_correction = true

[sea.waves]
kind = "standing"
amplitude = 0.02
wavelength = 8.0

[coupling]
law = "strong"
stiffness = 100.0
integrator = "implicit"

[[floes.floe]]
vertices = [[0.8, 0.6], [1.6, 0.6], [1.6, 1.4], [0.8, 1.4]]
thickness = 0.1
"""

# A wave tank (relaxation zones) with a disc-like floe, implicit coupling.
TANK = """
[run]
t_end = 4.0
dt_max = 0.02
output_interval = 0.25

[sea]
model = "spectral"
dims = 1
size = [12.0, 0.6]
cells = [128, 1]
depth = 0.5
rho = 1000.0

[sea.waves]
kind = "regular"
amplitude = 0.01
wavelength = 1.0

[sea.tank]
enabled = true

[coupling]
integrator = "implicit"
law = "blend"
restitution = 0.5

[floes]
thickness = 0.05

[[floes.floe]]
vertices = [[5.5, 0.05], [6.5, 0.05], [6.5, 0.55], [5.5, 0.55]]
"""

# A struck floe that cracks and splits (examples/percussion.toml, the hexagon
# 0.3 m further away: the impact comes at about 4.6 s).
FRACTURE = """
[run]
t_end = 8.0
dt_max = 0.1
output_interval = 0.25
record_collisions = true

[sea]
model = "none"

[[floes.floe]]
vertices = [[0, 0], [50, 0], [52, 20], [45, 32], [5, 30]]
thickness = 1.0

[[floes.floe]]
vertices = [[-0.32, 12.0], [-4.32, 18.9282], [-12.32, 18.9282], [-16.32, 12.0], [-12.32, 5.0718], [-4.32, 5.0718]]
velocity = [0.5, 0.0]
thickness = 1.0

[contact]
restitution = 0.3
friction = 0.3

[fracture]
enabled = true
criterion = "stress"
strength = 0.5e6
split = true
mesh_size = 1.5
duration = 0.01
"""


def case_pack():
    data = continuation(PACK, 60, 30, "pack")
    lcp = data["diagnostics/lcp"]
    check(lcp[-1, 0] > lcp[15, 0] > 0, "collisions before and after the restart")


def case_moored():
    # Moorings are anchored where the floes start: a restart anchors them there too.
    continuation(PACK.replace("velocity = [1.0, 0.0]", "velocity = [1.0, 0.0]\nmooring_period = 30.0\nmooring_damping = 0.2"),
                 60, 30, "moored")


def case_jam():
    # examples/pack_against_wall.toml: by 1200 s the pack is jamming against
    # the wall, with LCPs of 500 unknowns and more solved by Lemke
    # warm-started from the last step's basis: the warm starts must go on.
    cfg = os.path.join(SRC, "examples", "pack_against_wall.toml")
    run("run", "-q", cfg, "-o", "full.h5", "--until", "1320")
    run("run", "-q", cfg, "-o", "half.h5", "--until", "1260")
    with h5py.File(os.path.join(WORK, "half.h5"), "r") as f:
        check(f["checkpoint/warm_start/keys"].shape[0] > 0, "the checkpoint holds warm starts")
        before = dict(zip(f["checkpoint/counters"].attrs["columns"], f["checkpoint/counters"][()]))
    run("run", "-q", cfg, "--restart", "half.h5", "--until", "1320", "-o", "cont.h5")
    data = compare_runs(os.path.join(WORK, "full.h5"), os.path.join(WORK, "cont.h5"), "jam")
    after = dict(zip(datasets(os.path.join(WORK, "cont.h5"))[1], data["checkpoint/counters"]))
    check(after["collisions.warm"] > before["collisions.warm"] > 0, "warm-started solves before and after the restart")


def case_waves_explicit():
    continuation(WAVES.format(t_end=10.0, coupling='law = "strong"\nstiffness = 100.0'), 4, 2, "waves_explicit")


def case_waves_blend():
    # The explicit damper: its loads are evaluated afresh at every step.
    continuation(WAVES.format(t_end=10.0, coupling='law = "blend"\nrestitution = 0.3\nstiffness = 100.0'), 4, 2, "waves_blend",
                 in_place=True)


def case_waves_implicit():
    continuation(WAVES.format(t_end=10.0, coupling='integrator = "implicit"'), 4, 2, "waves_implicit")


def case_waves_moving():
    # Footprints moved between rebuilds (coupling/moving_footprint.hpp): the
    # checkpoint keeps the poses they were built at.
    continuation(WAVES.format(t_end=10.0, coupling='law = "strong"\nstiffness = 100.0\nfootprint_reach = 0.05'), 4, 2,
                 "waves_moving")
    continuation(WAVES.format(t_end=10.0, coupling='integrator = "implicit"\nfootprint_reach = 0.05'), 4, 2,
                 "waves_moving_implicit")


def case_bem():
    continuation(BEM, 4, 2, "bem")


def case_bem3d_corrected():
    continuation(BEM3D_CORRECTED, 2, 1, "bem3d_corrected")
    with h5py.File(os.path.join(WORK, "half.h5"), "r") as f:
        check("held_pressure" in f["checkpoint/sea"], "the checkpoint keeps the pressure the sea holds")


def case_tank():
    continuation(TANK, 4, 2, "tank")


def case_fracture():
    # Restart after the split (pieces carried in the checkpoint) ...
    data = continuation(FRACTURE, 8, 6, "fracture_after")
    check(data["events/fracture"].shape[0] >= 1 and np.all(data["events/fracture"][:, 0] < 6)
          and data["floes/thickness"].shape[0] > 2,
          "the floes cracked and split")
    with h5py.File(os.path.join(WORK, "half.h5"), "r") as f:
        check(f["checkpoint/floes/thickness"].shape[0] > 2, "the checkpoint holds the pieces")
    # ... and before the impact: the events come after the restart.
    data = continuation(FRACTURE, 8, 2, "fracture_before")
    check(np.all(data["events/fracture"][:, 0] > 2), "the fracture after the restart")
    check(data["events/collisions"].shape[0] >= 1 and np.all(data["events/collisions"][:, 0] > 2),
          "the collisions after the restart (/events/collisions, [run] record_collisions)")
    # A run that went on past its last checkpoint (as a killed run does):
    # the full run's file with the checkpoint of 2 s. The restart drops the
    # records, the fracture and collision events and the pieces' numbers after 2 s, and
    # writes them again, equal.
    shutil.copy(os.path.join(WORK, "full.h5"), os.path.join(WORK, "spliced.h5"))
    with h5py.File(os.path.join(WORK, "spliced.h5"), "a") as f, h5py.File(os.path.join(WORK, "half.h5"), "r") as h:
        del f["checkpoint"]
        h.copy(h["checkpoint"], f, "checkpoint")
        check(f["floes/thickness"].shape[0] > h["floes/thickness"].shape[0], "pieces after the checkpoint")
    run("run", "-q", "--restart", "spliced.h5", "--until", "8")
    compare_runs(os.path.join(WORK, "full.h5"), os.path.join(WORK, "spliced.h5"), "fracture, truncated")


def stop_midway(cfg, out, sig, ready):
    """Starts a run to t = 1000 s (too long to end first) and sends it `sig`
    once ready(file) says so; returns the process's exit code and stderr."""
    if os.path.exists(out):
        os.remove(out)
    p = subprocess.Popen([FLOESIM, "run", "-q", cfg, "-o", out, "--until", "1000"], cwd=WORK,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 60
    while time.time() < deadline and p.poll() is None:
        time.sleep(0.05)
        try:
            with h5py.File(out, "r") as f:
                if ready(f):
                    break
        except (OSError, KeyError):
            pass  # not created yet, or being written
    p.send_signal(sig)
    _, stderr = p.communicate(timeout=120)
    return p.returncode, stderr


def continue_and_compare(cfg, stopped, what):
    # The steps up to any record time do not depend on where the run ends
    # (records land on multiples of output_interval), so the reference is a
    # run to a record time past the stop.
    with h5py.File(os.path.join(WORK, stopped), "r") as f:
        t_end = float(np.floor(f["time"][-1] / 0.5) * 0.5 + 1.0)
    run("run", "-q", cfg, "-o", "full.h5", "--until", str(t_end))
    run("run", "-q", cfg, "--restart", stopped, "--until", str(t_end), "-o", "cont.h5")
    compare_runs(os.path.join(WORK, "full.h5"), os.path.join(WORK, "cont.h5"), what)


def case_sigint():
    # Ctrl-C (SIGINT) or SIGTERM in the middle of a step: the step finishes,
    # a checkpoint is written, exit 130; the restart equals the full run.
    cfg = write("waves.toml", WAVES.format(t_end=10.0, coupling='law = "strong"\nstiffness = 100.0'))
    for sig in (signal.SIGINT, signal.SIGTERM):
        out = os.path.join(WORK, "stopped.h5")
        code, stderr = stop_midway(cfg, out, sig, lambda f: f["time"].shape[0] >= 5)
        check(code == 130, f"{sig.name}: exit 130, got {code}\n{stderr}")
        check("floesim run --restart " + out in stderr, f"{sig.name}: says how to continue\n{stderr}")
        t_stop = checkpoint_time(out)
        check(0 < t_stop < 1000, f"{sig.name}: stopped midway (t = {t_stop})")
        with h5py.File(out, "r") as f:
            check(f.attrs["status"].startswith("interrupted"), f"{sig.name}: status interrupted")
        continue_and_compare(cfg, "stopped.h5", sig.name)


def case_kill():
    # SIGKILL (no clean-up at all) with [run] checkpoint_interval: the run
    # goes on from its last periodic checkpoint, which is between records
    # (0.7 s against records every 0.5 s); the records written after it are
    # dropped and written again, equal.
    text = WAVES.format(t_end=10.0, coupling='law = "strong"\nstiffness = 100.0').replace(
        "output_interval = 0.5", "output_interval = 0.5\ncheckpoint_interval = 0.7")
    cfg = write("waves.toml", text)
    out = os.path.join(WORK, "killed.h5")
    # Once: the file a kill leaves is the file as of its last flush, whole
    # (core/detail/h5_published.hpp), whatever the kill interrupted.
    code, _ = stop_midway(cfg, out, signal.SIGKILL,
                          lambda f: "checkpoint" in f and f["checkpoint"].attrs["time"] >= 1.4)
    check(code == -signal.SIGKILL, f"killed (exit {code})")
    t_ck = checkpoint_time(out)
    check(1.4 <= t_ck < 1000, f"killed after periodic checkpoints (the last at {t_ck} s)")
    with h5py.File(out, "r") as f:
        check(f.attrs["status"] == "running", "a killed run says running")
    continue_and_compare(cfg, "killed.h5", "killed")


def case_kill_anywhere():
    # SIGKILL at 20 instants spread over 1 s of a run that records, and
    # checkpoints, at every step (the writer is in an HDF5 write most of the
    # time): every file the kills leave opens, every object and attribute of
    # it reads, and its run continues from its last checkpoint. A file
    # updated in place by HDF5 fails this: a kill inside a flush leaves its
    # metadata half written (docs/formats.md, "A killed run's file").
    text = WAVES.format(t_end=1000.0, coupling='law = "strong"\nstiffness = 100.0').replace(
        "output_interval = 0.5", "output_interval = 0.05\ncheckpoint_interval = 0.05")
    cfg = write("every_step.toml", text)
    out = os.path.join(WORK, "anywhere.h5")
    failures = []
    kills, early = 20, 0
    for k in range(kills):
        delay = 0.05 * k + 0.007 * (k % 7)  # spread, and off any period of the writes
        for stale in (out, out + ".writing", out + ".previous"):
            if os.path.exists(stale):
                os.remove(stale)
        p = subprocess.Popen([FLOESIM, "run", "-q", cfg, "-o", out], cwd=WORK,
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        deadline = time.time() + 60
        while not os.path.exists(out) and time.time() < deadline and p.poll() is None:
            time.sleep(0.005)
        time.sleep(delay)
        p.kill()
        p.wait()
        try:
            with h5py.File(out, "r") as f:
                def read(name, obj):
                    for a in obj.attrs:
                        obj.attrs[a]
                    if isinstance(obj, h5py.Dataset):
                        obj[()]
                f.visititems(read)
                check(f.attrs["status"] == "running", "a killed run says running")
                if "checkpoint" not in f:
                    # Killed before its first checkpoint (0.05 s, written
                    # after the record at 0.05 s): nothing to continue, and
                    # nothing recorded past it.
                    t = f["time"][()]
                    check(t.size == 0 or t[-1] <= 0.05, f"kill {k}: records to {t[-1] if t.size else 0} s but no checkpoint")
                    early += 1
                    continue
                t_ck = float(f["checkpoint"].attrs["time"])
        except Exception as e:  # noqa: BLE001 (h5py raises OSError, KeyError, RuntimeError, ...)
            failures.append(f"kill {k} ({delay:.3f} s after the file appeared): the file does not read: {e}")
            continue
        c = subprocess.run([FLOESIM, "run", "-q", "--restart", out, "--until", str(t_ck + 0.1),
                            "-o", os.path.join(WORK, "anywhere_cont.h5")], cwd=WORK, capture_output=True, text=True)
        if c.returncode != 0:
            failures.append(f"kill {k} ({delay:.3f} s): the restart from t = {t_ck} s failed: {c.stderr.strip()}")
    check(not failures, f"{len(failures)} of {kills} killed runs left a file that does not restore:\n" +
          "\n".join(failures))
    check(early <= 2, f"{early} of {kills} kills came before the first checkpoint: too early to test restores")
    print(f"{kills} kills: every file read whole; {kills - early} continued from their checkpoint, "
          f"{early} killed before their first one")


def case_in_place():
    # [run] crash_safe_output = false: the run file is written in place
    # (docs/formats.md, "A killed run's file"). While the run writes, no
    # helper copy lies beside it (the default run has its working copy
    # there); its content equals the default run's, bit for bit; and such a
    # run, interrupted and continued, equals the uninterrupted one.
    text = WAVES.format(t_end=4.0, coupling='law = "strong"\nstiffness = 100.0')
    cfgs = {"crash_safe": write("safe.toml", text),
            "in_place": write("in_place.toml", text.replace("[run]\n", "[run]\ncrash_safe_output = false\n", 1))}
    for how, cfg in cfgs.items():
        out = os.path.join(WORK, how + "_stopped.h5")
        helper = []

        def ready(f):
            if f["time"].shape[0] < 3:
                return False
            helper.append(os.path.exists(out + ".writing") or os.path.exists(out + ".previous"))
            return True
        code, stderr = stop_midway(cfg, out, signal.SIGINT, ready)
        check(code == 130, f"{how}: interrupted, exit 130, got {code}\n{stderr}")
        check(helper == [how == "crash_safe"],
              f"{how}: a helper copy beside the file while it is written: {helper} (expected {how == 'crash_safe'})")
        check(not os.path.exists(out + ".writing") and not os.path.exists(out + ".previous"),
              f"{how}: no helper copy left after the run")
        run("run", "-q", cfg, "-o", how + ".h5")
    run("compare", "crash_safe.h5", "in_place.h5", "--rtol", "0", "--atol", "0")
    compare_runs(os.path.join(WORK, "crash_safe.h5"), os.path.join(WORK, "in_place.h5"), "in place against crash-safe")
    # Continued in place, written in place: equals the uninterrupted run.
    t_end = checkpoint_time("in_place_stopped.h5") + 1.0
    run("run", "-q", cfgs["crash_safe"], "-o", "full.h5", "--until", str(t_end))
    run("run", "-q", cfgs["in_place"], "--restart", "in_place_stopped.h5", "--until", str(t_end), "-o", "cont.h5")
    check(not os.path.exists(os.path.join(WORK, "cont.h5.writing")), "the continued run left no helper copy")
    compare_runs(os.path.join(WORK, "full.h5"), os.path.join(WORK, "cont.h5"), "continued in place")


def case_run_error():
    # A run that fails (exit 1: a wind of 1e200 m/s from t = 10.5 s overflows
    # the drag) keeps, as its checkpoint, the state at its last record: the
    # same checkpoint, bit for bit, as a run that ended there.
    write("wind.csv", "t_s,wind_u,wind_v,current_u,current_v\n0,10,0,0,0\n10,10,0,0,0\n10.5,1e200,0,0,0\n")
    cfg = write("fail.toml", PACK.replace("wind = [20.0, 3.0]", 'series = "wind.csv"'))
    p = run("run", "-q", cfg, "-o", "failed.h5", "--until", "20", expect=1)
    check("a checkpoint at the last record" in p.stderr, f"the failure message mentions the checkpoint\n{p.stderr}")
    with h5py.File(os.path.join(WORK, "failed.h5"), "r") as f:
        check(f.attrs["status"].startswith("failed:"), "status failed")
        check(f["time"][-1] == 10.0, f"the last record at 10 s ({f['time'][-1]})")
    check(checkpoint_time("failed.h5") == 10.0, "the checkpoint at the last record")
    run("run", "-q", cfg, "-o", "ten.h5", "--until", "10")
    a, cols, _ = datasets(os.path.join(WORK, "failed.h5"))
    b, _, _ = datasets(os.path.join(WORK, "ten.h5"))
    for name in a:
        if name.startswith("checkpoint/") or name in ("time", "floes/state", "diagnostics/lcp"):
            check(same_bits(a[name], b[name]), f"/{name} of the failed run equals the run to 10 s")


def case_refusals():
    cfg = write("pack.toml", PACK)
    run("run", "-q", cfg, "-o", "half.h5", "--until", "30")
    p = run("info", "half.h5")
    check("checkpoint: t = 30 s (floesim run --restart half.h5)" in p.stdout, f"info shows the checkpoint\n{p.stdout}")
    # No checkpoint (a file from before checkpoints existed).
    shutil.copy(os.path.join(WORK, "half.h5"), os.path.join(WORK, "old.h5"))
    with h5py.File(os.path.join(WORK, "old.h5"), "a") as f:
        del f["checkpoint"]
    check("checkpoint: none" in run("info", "old.h5").stdout, "info: no checkpoint")
    p = run("run", cfg, "--restart", "old.h5", expect=2)
    check("old.h5: the run has no checkpoint" in p.stderr, f"no checkpoint: message\n{p.stderr}")
    # A checkpoint of another format version, or a damaged one.
    shutil.copy(os.path.join(WORK, "half.h5"), os.path.join(WORK, "v2.h5"))
    with h5py.File(os.path.join(WORK, "v2.h5"), "a") as f:
        f["checkpoint"].attrs["version"] = 2.0
    p = run("run", cfg, "--restart", "v2.h5", expect=2)
    check("v2.h5: /checkpoint: version 2, this floesim reads version 1" in p.stderr, f"version: message\n{p.stderr}")
    shutil.copy(os.path.join(WORK, "half.h5"), os.path.join(WORK, "bad.h5"))
    with h5py.File(os.path.join(WORK, "bad.h5"), "a") as f:
        del f["checkpoint/floes/state"]
        f["checkpoint/floes/state"] = np.zeros((4, 12))
    p = run("run", cfg, "--restart", "bad.h5", expect=2)
    check("bad.h5: /checkpoint/floes/state: expected 60 numbers, got 48" in p.stderr, f"damaged: message\n{p.stderr}")
    # A configuration that changes the results: each key that differs is named.
    changed = write("changed.toml", PACK.replace("restitution = 0.4", "restitution = 0.5").replace(
        "wind = [20.0, 3.0]", "wind = [20.0, 4.0]"))
    p = run("run", changed, "--restart", "half.h5", expect=2)
    check("differs from the run's" in p.stderr and "[contact] restitution: 0.4 -> 0.5" in p.stderr
          and "[forcing] wind: [20, 3] -> [20, 4]" in p.stderr, f"changed config: message\n{p.stderr}")
    moved = write("moved.toml", PACK.replace("velocity = [0.6, 0.0]", "velocity = [0.7, 0.0]"))
    p = run("run", moved, "--restart", "half.h5", expect=2)
    check("[floes.floe 2] velocity: [0.6, 0] -> [0.7, 0]" in p.stderr, f"changed floe: message\n{p.stderr}")
    check(checkpoint_time("half.h5") == 30.0, "a refused restart leaves the file as it was")
    # What does not change the results may change: t_end, checkpoint_interval, threads.
    free = write("free.toml", PACK.replace("t_end = 60.0", "t_end = 34.0").replace(
        "output_interval = 2.0", "output_interval = 2.0\ncheckpoint_interval = 3.0"))
    run("run", "-q", free, "--restart", "half.h5", "--threads", "1", "-o", "free.h5")
    check(checkpoint_time("free.h5") == 34.0, "restart to the new t_end")
    # An end before the checkpoint.
    p = run("run", cfg, "--restart", "half.h5", "--until", "20", expect=2)
    check("the checkpoint is at t = 30 s" in p.stderr and "expected an end >= 30" in p.stderr,
          f"--until before the checkpoint: message\n{p.stderr}")
    # Not a run file; a missing one.
    p = run("run", cfg, "--restart", cfg, "-o", "x.h5", expect=2)
    check("not an HDF5 file" in p.stderr or "not a floesim run file" in p.stderr, f"not a run file\n{p.stderr}")
    p = run("run", cfg, "--restart", "nothing.h5", expect=2)
    check("nothing.h5: run file not found" in p.stderr, f"missing run file\n{p.stderr}")


CASES = {name[5:]: fn for name, fn in globals().items() if name.startswith("case_")}
if CASE not in CASES:
    sys.exit(f"unknown case {CASE}; cases: {', '.join(CASES)}")
CASES[CASE]()
print(f"restart.{CASE}: OK")
