#!/usr/bin/env python3
"""End-to-end tests of the floesim command line.

usage: cli_test.py FLOESIM SOURCE_DIR CASE [ARGS]
Each case runs the binary as a user would and checks exit codes, messages and
the files it writes. Exits non-zero with a message on the first failure.
"""
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET

import h5py
import numpy as np

from harness import Cli, check, keyvals

FLOESIM, SRC, CASE = sys.argv[1], sys.argv[2], sys.argv[3]
EXAMPLE = os.path.join(SRC, "examples", "pack_drift.toml")
WORK = tempfile.mkdtemp(prefix="floesim_cli_")
CLI = Cli(FLOESIM, WORK)
run, write = CLI.run, CLI.write


def case_run_default():
    # No CONFIG: the default example; the run file goes to the current folder.
    p = run("run", "-q", "--until", "5")
    kv = keyvals(p.stdout)
    check(kv.get("status") == "complete", "status complete")
    out = kv["output"]
    check(os.path.isabs(out) and os.path.exists(out), f"run file printed and present: {out}")
    check(os.path.dirname(out) == os.path.realpath(WORK) or os.path.dirname(out) == WORK, "written here")
    check(os.path.exists(kv["paraview"]), "xdmf beside the run file")
    # Its blend law calibrated for a restitution is a note, not a warning: nothing went wrong.
    check(kv.get("notes") == "1" and "obstacle-problem calibration" in p.stdout.split("\nnotes: ")[1].split("\nwarnings: ")[0],
          f"one note, the blend's calibration: {p.stdout}")
    check(kv.get("warnings") == "0", f"no warning: {p.stdout}")
    with h5py.File(out) as f:
        check(f.attrs["format"] == "floesim-1", "format attribute")
        check("[forcing]" in f.attrs["config"], "resolved config echoed")
        t = f["time"][:]
        check(np.isclose(t[-1], 5.0), "ran until 5 s")
        st = f["floes/state"][:]
        check(st.shape == (len(t), 36, 12), f"state shape {st.shape}")
        # The floes are on waves: every one heaves.
        check(np.all(np.abs(st[1:, :, 6]).max(axis=0) > 1e-3), "every floe heaves")
        check("sea/eta" in f and f["sea/eta"].shape[0] == len(t), "the sea is recorded")
        e = f["diagnostics/energy"]
        check(list(e.attrs["columns"])[-1] == "total", "energy columns end with total")


def case_progress_log():
    # stderr into a file (a batch job's log): a full progress line every --log-every
    # seconds of wall time, none with -q, none in a short run at the default 60 s.
    p = run("run", "--until", "5", "--log-every", "0.1", "-o", "log.h5")
    lines = [l for l in p.stderr.splitlines() if l.startswith("floesim: [")]
    check(len(lines) >= 1, f"progress lines in the log: {p.stderr}")
    times = [float(l.split("t = ")[1].split(" /")[0]) for l in lines]
    check(times == sorted(times) and all(0 < t <= 5 for t in times), f"times advance within the run: {times}")
    check(all("/ 5 s" in l and "steps/s" in l and "ETA" in l for l in lines), f"line format: {lines[0]}")
    check("\r" not in p.stderr, "no carriage returns in a log")
    for quiet in (["-q", "--log-every", "0.1"], []):
        p = run("run", "--until", "5", *quiet, "-o", "log.h5")
        check(not any(l.startswith("floesim: [") for l in p.stderr.splitlines()), f"no progress lines with {quiet}")
    run("run", "--until", "5", "--log-every", "-1", "-o", "log.h5", expect=2)


def case_progress_after_restart():
    # A restarted run's progress counts its own steps and time: its rate is the
    # rate of the run it continues (same case, same machine), not the steps
    # done before the checkpoint over its own short wall time, and its time
    # left is that of the simulated time left at that rate.
    def lines_of(p):
        return [l for l in p.stderr.splitlines() if l.startswith("floesim: [")]

    def rate(line):
        return float(line.split(" steps | ")[1].split(" steps/s")[0])

    def eta_seconds(line):
        value, unit = line.split("ETA ")[1].split()[:2]
        return float(value) * {"s": 1.0, "min": 60.0, "h": 3600.0}[unit]

    p = run("run", "--until", "10", "--log-every", "0.2", "-o", "first.h5")
    first = lines_of(p)
    at_checkpoint = int(dict(l.split(": ", 1) for l in p.stdout.splitlines() if ": " in l)["steps"])  # its end
    check(len(first) >= 3, f"progress lines of the first run: {first}")
    p = run("run", "--restart", "first.h5", "--until", "20", "--log-every", "0.2", "-o", "next.h5")
    continued = lines_of(p)
    check(len(continued) >= 1, "progress lines of the restarted run")
    # The summary's rate too: steps_per_second times wall_time is this run's
    # steps (the total less the checkpoint's), not the total.
    summary = dict(l.split(": ", 1) for l in p.stdout.splitlines() if ": " in l)
    total = int(summary["steps"])
    own = float(summary["steps_per_second"]) * float(summary["wall_time"].split()[0])
    check(abs(own - (total - at_checkpoint)) <= 0.01 * total + 1,
          f"the summary's rate counts this run's {total - at_checkpoint} steps, not {total}: {own:.1f}")
    fastest = max(rate(l) for l in first)
    check(rate(continued[0]) <= 5 * fastest,
          f"the restart's rate counts its own steps: {continued[0]} against the first run's {fastest:.0f} steps/s")
    check(eta_seconds(continued[0]) >= 1.0, f"the time left is the rest of the run at this run's rate: {continued[0]}")


def case_info_json():
    run("run", EXAMPLE, "-q", "--until", "120", "-o", "a.h5")
    info = json.loads(run("info", "a.h5", "--json").stdout)
    check(info["status"] == "complete", "json status")
    check(info["floes"] == 30 and info["records"] == 3, f"json counts {info['floes']} {info['records']}")
    check(info["datasets"]["/floes/state"] == [3, 30, 12], "json dataset shape")
    text = run("info", "a.h5").stdout
    check("energy.total:" in text, "text info has energy")
    run("info", os.path.join(WORK, "missing.h5"), expect=2)
    run("info", EXAMPLE, expect=2)  # not HDF5


def case_compare():
    run("run", EXAMPLE, "-q", "--until", "120", "-o", "a.h5")
    run("run", EXAMPLE, "-q", "--until", "120", "-o", "b.h5")
    p = run("compare", "a.h5", "b.h5")  # deterministic: identical
    check("equal: true" in p.stdout, "identical runs compare equal")
    cfg = open(EXAMPLE).read().replace("wind = [10.0, 4.0]", "wind = [10.5, 4.0]")
    run("run", write("c.toml", cfg), "-q", "--until", "120", "-o", "c.h5")
    p = run("compare", "a.h5", "c.h5", expect=1)
    check("/floes/state" in p.stdout and "equal: false" in p.stdout, "difference reported")
    run("compare", "a.h5", "c.h5", "--rtol", "1", "--atol", "1e3")


def case_bad_input():
    bad = write("bad.toml", "[run]\nt_end = 10\n\n[forcing]\nwnd = [1, 2]\n")
    p = run("run", bad, "-o", "bad.h5", expect=2)
    check("bad.toml:5" in p.stderr and "[forcing] wnd" in p.stderr, f"names file:line and key: {p.stderr}")
    check(not os.path.exists(os.path.join(WORK, "bad.h5")), "no output file for bad input")
    bad = write("bad2.toml", "[[floes.floe]]\nvertices = [[0,0],[1,1],[1,0],[0,1]]\n")
    p = run("run", bad, "-o", "bad2.h5", expect=2)
    check("intersects itself" in p.stderr and "bad2.toml" in p.stderr, p.stderr)
    p = run("run", os.path.join(WORK, "nope.toml"), expect=2)
    check("not found" in p.stderr, p.stderr)
    run("run", EXAMPLE, "--until", "-3", expect=2)
    run("frobnicate", expect=2)
    run("--help")
    for sub in ("run", "info", "compare"):
        p = run(sub, "--help")
        check("Usage" in p.stdout or "usage" in p.stdout.lower(), f"{sub} --help")


def case_killed_run():
    # A long run killed midway leaves a readable file with the records so far.
    cfg = open(EXAMPLE).read().replace("t_end = 3600.0", "t_end = 1.0e7").replace(
        "output_interval = 60.0", "output_interval = 5.0").replace("dt_max = 5.0", "dt_max = 0.5")
    path = write("long.toml", cfg)
    p = subprocess.Popen([FLOESIM, "run", path, "-q", "-o", "long.h5"], cwd=WORK,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    out = os.path.join(WORK, "long.h5")
    deadline = time.time() + 60
    records = 0
    while time.time() < deadline and records < 20:
        time.sleep(0.3)
        try:
            with h5py.File(out, "r") as f:
                records = f["time"].shape[0]
        except Exception:
            pass
    p.send_signal(signal.SIGKILL)
    p.wait()
    check(records >= 20, f"records appeared while running ({records})")
    with h5py.File(out, "r") as f:
        t = f["time"][:]
        st = f["floes/state"][:]
        check(f.attrs["status"] == "running", "no end mark after a kill")
        check(st.shape[0] >= records and np.all(np.isfinite(st)), "state readable")
        check(np.all(np.diff(t) > 0), "times increasing")
    info = run("info", "long.h5").stdout
    check("killed" in info, "info says the run has no end mark")


def check_xdmf(name):
    # Validate NAME.xmf against NAME.h5: every HDF reference exists, has the
    # declared dimensions, and every hyperslab selection is in bounds.
    tree = ET.parse(os.path.join(WORK, name + ".xmf"))
    root = tree.getroot()
    check(root.tag == "Xdmf", "root element")
    grids = root.findall("./Domain/Grid")
    check(len(grids) >= 1 and grids[0].get("CollectionType") == "Temporal", "temporal collection")
    steps = grids[0].findall("Grid")
    with h5py.File(os.path.join(WORK, name + ".h5")) as f:
        check(len(steps) == f["time"].shape[0], "one grid per record")
        for g in steps:
            for item in g.iter("DataItem"):
                if item.get("Format") != "HDF":
                    continue
                # "file:/dataset", or a hyperslab "file:/dataset|start:stride:count:dims" (Xdmf3 notation)
                ref, _, sel = item.text.strip().partition("|")
                fname, dset = ref.split(":")
                check(fname == name + ".h5", "relative file name")
                dims = tuple(int(d) for d in (sel.split(":")[3] if sel else item.get("Dimensions")).split())
                check(dset in f and f[dset].shape == dims, f"{dset}: {dims} vs {f[dset].shape if dset in f else None}")
                if sel:
                    s = np.array([p.split() for p in sel.split(":")[:3]], dtype=int)
                    end = s[0] + s[1] * (s[2] - 1)
                    check(np.all(end < dims), "hyperslab in bounds")
                    check(int(np.prod(s[2])) == int(np.prod([int(d) for d in item.get("Dimensions").split()])),
                          "hyperslab size = declared")
    return steps


def case_xdmf():
    # Validate the XDMF against the run file: every HDF reference exists, has
    # the declared dimensions, and every hyperslab selection is in bounds.
    run("run", EXAMPLE, "-q", "--until", "300", "-o", "x.h5")
    steps = check_xdmf("x")
    with h5py.File(os.path.join(WORK, "x.h5")) as f:
        for g in steps:
            topo = g.find("Topology")
            check(topo.get("TopologyType") == "Mixed" and int(topo.get("NumberOfElements")) == 30, "topology")
        # The mixed topology lists 30 polygons (type 3) covering every vertex.
        tp = f["xdmf/topology"][:]
        k, polys = 0, 0
        while k < len(tp):
            check(tp[k] == 3, "polygon type")
            k += 2 + tp[k + 1]
            polys += 1
        check(polys == 30, "30 polygons")
        # World vertices are the body vertices moved by the state.
        st = f["floes/state"][-1]
        off = f["floes/offsets"][:]
        body = f["floes/vertices"][:]
        world = f["xdmf/vertices"][-1]
        i = 7
        c, s_ = np.cos(st[i, 2]), np.sin(st[i, 2])
        b = body[off[i]:off[i + 1]]
        w = np.stack([st[i, 0] + c * b[:, 0] - s_ * b[:, 1], st[i, 1] + s_ * b[:, 0] + c * b[:, 1]], axis=1)
        check(np.allclose(w, world[off[i]:off[i + 1], :2]), "world vertices from state")


def case_example():
    cfg = sys.argv[4]
    p = run("run", cfg, "-q", "--until", "60", "-o", "example.h5")
    kv = keyvals(p.stdout)
    check(kv.get("status") == "complete", f"{cfg} runs")
    # An example shows the code working: no failed or approximate LCP, no refused split, no floor step.
    check(kv.get("warnings") == "0", f"{cfg} runs without warnings: {p.stdout}")


def case_pack():
    # floesim pack: key: value lines, a floesim-pack-1 file that `floesim run`
    # loads, the same file for the same seed, exit 2 for bad arguments.
    args = ["pack", "--floes", "60", "--concentration", "0.6", "--box", "400", "300", "--seed", "5",
            "--size-distribution", "power:2.5", "--min-size", "5", "--max-size", "50",
            "--thickness-range", "0.5", "1.5", "--walls", "10"]
    kv = keyvals(run(*args, "-o", "pack.h5").stdout)
    check(kv["floes"] == "60" and kv["walls"] == "4", f"counts {kv}")
    check(abs(float(kv["concentration"]) - 0.6) < 0.012, f"concentration {kv['concentration']}")
    check(float(kv["min_gap"].split()[0]) >= float(kv["required_gap"].split()[0]) > 0, "gap")
    check(float(kv["time_ms"]) >= 0 and os.path.samefile(kv["output"], os.path.join(WORK, "pack.h5")), "output")
    with h5py.File(os.path.join(WORK, "pack.h5")) as f:
        check(f.attrs["format"] == "floesim-pack-1", "pack format")
        check(f["floes/offsets"].shape == (65,) and f["floes/pose"].shape == (64, 3), "64 floes")
        check(list(f["floes/static"][:]) == [0] * 60 + [1] * 4, "walls last, static")
        check(np.allclose(f["window"][:], [0, 400, 0, 300]), "window is the box")
        h = f["floes/thickness"][:60]
        check(h.min() >= 0.5 and h.max() <= 1.5 and h.max() > h.min(), "thickness range")
        pose = f["floes/pose"][:60]
        check(np.all((pose[:, 0] > 0) & (pose[:, 0] < 400) & (pose[:, 1] > 0) & (pose[:, 1] < 300)), "in box")
        first = f["floes/vertices"][:]
    run(*args, "-o", "pack2.h5")
    with h5py.File(os.path.join(WORK, "pack2.h5")) as f:
        check(np.array_equal(f["floes/vertices"][:], first), "same seed, same pack")
    cfg = write("pack_run.toml", '[run]\nt_end = 60.0\ndt_max = 5.0\noutput_interval = 30.0\n\n'
                '[sea]\nmodel = "none"\n\n[floes]\npack = "pack.h5"\n\n[forcing]\nwind = [5.0, 0.0]\n')
    p = run("run", cfg, "-q", "-o", "pack_run.h5")
    check(keyvals(p.stdout).get("status") == "complete", "a run from the pack completes")
    with h5py.File(os.path.join(WORK, "pack_run.h5")) as f:
        check(f["floes/state"].shape[1] == 64, "the run has the pack's floes")
        check(list(f["floes/static"][:]) == [0] * 60 + [1] * 4, "walls static in the run")
    base = ["pack", "--floes", "10", "--box", "100", "100", "-o", "bad.h5"]
    for bad, word in [(["--concentration", "0"], "concentration"), (["--concentration", "0.99"], "concentration"),
                      (["--concentration", "0.5", "--size-distribution", "powr:2"], "size-distribution"),
                      (["--concentration", "0.5", "--size-distribution", "power:-1"], "exponent"),
                      (["--concentration", "0.5", "--min-size", "5", "--max-size", "1"], "max_size"),
                      (["--concentration", "0.5", "--thickness-range", "2", "1"], "thickness"),
                      (["--concentration", "0.5", "--thickness", "1", "--thickness-range", "1", "2"], "excludes")]:
        p = run(*base, *bad, expect=2)
        check(word in p.stderr, f"{bad}: message names {word}: {p.stderr}")
        check(not os.path.exists(os.path.join(WORK, "bad.h5")), "no file for bad arguments")
    run("pack", "--floes", "10", "--concentration", "0.5", "-o", "bad.h5", expect=2)  # no --box
    run("pack", "--help")


def disc_config(name, p, extra=""):
    # A disc of diameter 20 m squeezed by P along its vertical diameter (the Brazilian test).
    pts = [[round(10 * np.cos(-np.pi / 2 + 2 * np.pi * k / 120), 9), round(10 * np.sin(-np.pi / 2 + 2 * np.pi * k / 120), 9)]
           for k in range(120)]
    return write(name, f"""[sea]\nmodel = "none"\n[[floes.floe]]\nvertices = {pts}\nthickness = 1.0\n{extra}
[fracture]\nmesh_size = 1.0\nstrength = 0.5e6
[[fracture.load]]\npoint = [0.0, 10.0]\nforce = [0.0, {-p}]
[[fracture.load]]\npoint = [0.0, -10.0]\nforce = [0.0, {p}]\n""")


def case_fracture():
    # floesim fracture: the key: value lines of ARCHITECTURE.md on a Brazilian
    # disc (tension 2 P / (pi D h) across the loaded diameter, Hertz), the crack
    # along that diameter just above the load the tool predicts; exit 2 for bad input.
    p_load = 1.0e6
    kv = keyvals(run("fracture", disc_config("disc.toml", p_load), "--probe", "0", "0").stdout)
    for key in ("max_principal_stress", "at", "direction", "initiates", "load_factor", "time_ms"):
        check(key in kv, f"key {key} printed: {kv}")
    exact = 2 * p_load / (np.pi * 20.0)
    check(abs(float(kv["max_principal_stress"]) / exact - 1) < 0.05, f"tension {kv['max_principal_stress']} vs {exact}")
    check(abs(float(kv["direction"]) - 90) < 5, f"direction {kv['direction']}")
    check(abs(float(kv["at"].split()[0])) < 2.0, f"on the loaded diameter: {kv['at']}")
    check(kv["initiates"] == "false" and "crack_from" not in kv, "no initiation below the threshold")
    sxx = float(kv["probe"].split()[2])
    check(abs(sxx / exact - 1) < 0.02, f"centre sxx {sxx} vs {exact}")
    p_c = p_load * float(kv["load_factor"])
    check(abs(p_c / (np.pi * 20 * 0.5e6 / 2) - 1) < 0.05, f"predicted initiation load {p_c}")
    kv = keyvals(run("fracture", disc_config("disc2.toml", 1.02 * p_c)).stdout)
    check(kv["initiates"] == "true", f"initiates above the threshold: {kv}")
    a, b = (np.array(kv[k].split(), dtype=float) for k in ("crack_from", "crack_to"))
    check(abs(a[0]) < 2 and abs(b[0]) < 2 and abs(a[1] - b[1]) > 19, f"crack across the loaded diameter: {a} {b}")
    # An impulse: the dynamic response is integrated.
    imp = write("imp.toml", open(os.path.join(WORK, "disc.toml")).read().replace("force = [0.0, -1000000.0]",
                "impulse = [0.0, -1.0e4]").replace("force = [0.0, 1000000.0]", "impulse = [0.0, 1.0e4]"))
    kv = keyvals(run("fracture", imp).stdout)
    check(int(kv["steps"]) > 10 and float(kv["time"]) > 0, f"dynamic response: {kv}")
    # Griffith: its energies are printed.
    g = write("g.toml", open(os.path.join(WORK, "disc.toml")).read().replace("[fracture]", "[fracture]\ncriterion = \"griffith\""))
    kv = keyvals(run("fracture", g).stdout)
    check("energy_released" in kv and kv["criterion"] == "griffith", f"griffith: {kv}")
    # Bad input: two floes, a load off the floe, no load.
    two = disc_config("two.toml", p_load, "[[floes.floe]]\nvertices = [[30, 0], [40, 0], [40, 10]]\n")
    p = run("fracture", two, expect=2)
    check("one floe" in p.stderr, p.stderr)
    off = write("off.toml", open(os.path.join(WORK, "disc.toml")).read().replace("point = [0.0, 10.0]", "point = [0.0, 30.0]"))
    p = run("fracture", off, expect=2)
    check("not on the floe" in p.stderr and "off.toml" in p.stderr, p.stderr)
    none = write("none.toml", open(os.path.join(WORK, "disc.toml")).read().split("[[fracture.load]]")[0])
    p = run("fracture", none, expect=2)
    check("[[fracture.load]]" in p.stderr, p.stderr)
    run("fracture", "--help")


def case_fracture_run():
    # examples/percussion.toml: a collision cracks and splits floes; the run file
    # has the events and the pieces (NaN rows where a floe does not exist).
    kv = keyvals(run("run", os.path.join(SRC, "examples", "percussion.toml"), "-q", "-o", "perc.h5").stdout)
    check(kv["status"] == "complete" and int(kv["fracture.splits"]) >= 1, f"splits: {kv}")
    with h5py.File(os.path.join(WORK, "perc.h5")) as f:
        ev = f["events/fracture"]
        cols = list(ev.attrs["columns"])
        check(cols[:6] == ["time", "floe", "x", "y", "direction", "load"], f"columns {cols}")
        ev = ev[:]
        check(len(ev) >= 1, "events recorded")
        n = f["floes/offsets"].shape[0] - 1
        st = f["floes/state"][:]
        m = f["floes/mass"][:]
        check(st.shape[1] == n and n == 2 + 2 * int(kv["fracture.splits"]), f"floes {n}, state {st.shape}")
        t = f["time"][:]
        for e in ev:
            parent, a, b = int(e[cols.index("floe")]), int(e[cols.index("piece_a")]), int(e[cols.index("piece_b")])
            check(abs(m[a] + m[b] - m[parent]) < 1e-9 * m[parent], "pieces keep the mass")
            after = t > e[0] + 1e-9
            check(np.all(np.isnan(st[after, parent, 0])), "the parent ends")
            check(np.all(np.isnan(st[t < e[0], a, 0])) and np.all(np.isfinite(st[after, a, 0])), "pieces appear")
    # The XDMF still describes every record: before the split 2 floes, after it 6 numbers.
    steps = check_xdmf("perc")
    counts = [int(g.find("Topology").get("NumberOfElements")) for g in steps]
    check(counts[0] == 2 and counts[-1] == 6, f"floes per record {counts[0]} -> {counts[-1]}")
    info = json.loads(run("info", "perc.h5", "--json").stdout)
    check(info["status"] == "complete", "info reads it")


globals()["case_" + CASE]()
print(f"cli.{CASE}: 1 passed, 0 failed")
