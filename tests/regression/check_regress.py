#!/usr/bin/env python3
"""Tests of `floesim regress` itself (the cases are run by the ctest test regress.cases).

usage: check_regress.py FLOESIM CASES_DIR CHECK
CHECK is one of perturbed, missing_reference, update, bad_input. Each works
on copies in a temporary folder and exits non-zero with a message on failure.
"""
import os
import re
import shutil
import subprocess
import sys
import tempfile

FLOESIM, CASES, CHECK = sys.argv[1], sys.argv[2], sys.argv[3]
WORK = tempfile.mkdtemp(prefix="floesim_regress_test_")

# One small change of physics or forcing per committed case: each must be caught.
PERTURB = {
    "two_floes_collide": ("restitution = 0.4", "restitution = 0.45"),
    "pack_wind_periodic": ("wind = [18.0, 6.0]", "wind = [18.0, 6.05]"),
    "floes_on_sea": ("amplitude = 0.2", "amplitude = 0.201"),
}


def regress(*args, expect):
    p = subprocess.run([FLOESIM, "regress", *args], capture_output=True, text=True, timeout=280)
    if p.returncode != expect:
        fail(f"floesim regress {' '.join(args)}: exit {p.returncode}, expected {expect}\n"
             f"stdout:\n{p.stdout}\nstderr:\n{p.stderr}")
    return p


def fail(msg):
    shutil.rmtree(WORK, ignore_errors=True)
    sys.exit("FAILED: " + msg)


def check(cond, msg):
    if not cond:
        fail(msg)


def copy_case(name, dest, reference=True):
    os.makedirs(dest, exist_ok=True)
    shutil.copy(os.path.join(CASES, name + ".toml"), dest)
    if reference:
        shutil.copy(os.path.join(CASES, name + ".ref.h5"), dest)


def edit(path, old, new):
    with open(path) as f:
        text = f.read()
    check(old in text, f"{path} holds '{old}'")
    with open(path, "w") as f:
        f.write(text.replace(old, new))


def row(stdout, name):
    for line in stdout.splitlines():
        if line.split()[:1] == [name]:
            return line.split()
    fail(f"no table row for {name} in:\n{stdout}")


def case_perturbed():
    cases = sorted(f[:-5] for f in os.listdir(CASES) if f.endswith(".toml"))
    check(sorted(PERTURB) == cases, f"a perturbation for every committed case: {cases}")
    for name, (old, new) in PERTURB.items():
        d = os.path.join(WORK, name)
        copy_case(name, d)
        regress(d, expect=0)                           # the copy as committed passes
        edit(os.path.join(d, name + ".toml"), old, new)
        p = regress(d, expect=1)
        r = row(p.stdout, name)
        check(r[1] == "DIFFERS", f"{name} perturbed: status DIFFERS, got {r}")
        check(float(r[2]) > 0, f"{name}: a max difference > 0: {r}")
        check(re.match(r"/\w+/\w+\[", r[3]) is not None, f"{name}: where names dataset[index]: {r}")
        check(re.search(r"\n  /\S+: values \(\d+ elements out of tolerance", p.stdout) is not None,
              f"{name}: details list the differing datasets:\n{p.stdout}")
        check("0 of 1 case(s) pass" in p.stdout, "summary line")
    # A difference smaller than the tolerance passes: same perturbation, loose rtol.
    d = os.path.join(WORK, "two_floes_collide")
    regress(d, "--rtol", "1", "--atol", "10", expect=0)


def case_missing_reference():
    d = os.path.join(WORK, "cases")
    copy_case("two_floes_collide", d)
    copy_case("floes_on_sea", d, reference=False)
    p = regress(d, expect=2)
    ref = os.path.join(d, "floes_on_sea.ref.h5")
    check(ref in p.stderr, f"the message names the missing reference {ref}: {p.stderr}")
    check(f"floesim regress {d} --update" in p.stderr, f"the message says how to make it: {p.stderr}")
    check(p.stdout == "", "nothing is run")


def case_update():
    for f in os.listdir(CASES):
        if f.endswith(".ref.h5"):
            size = os.path.getsize(os.path.join(CASES, f))
            check(size < 200 * 1024, f"committed reference {f} is small: {size} bytes")
    d = os.path.join(WORK, "cases")
    copy_case("two_floes_collide", d, reference=False)
    p = regress(d, "--update", expect=0)
    check(row(p.stdout, "two_floes_collide")[1] == "new", p.stdout)
    ref = os.path.join(d, "two_floes_collide.ref.h5")
    check(os.path.exists(ref), "--update wrote the reference")
    check(not any(f.endswith(".xmf") for f in os.listdir(d)), "no XDMF beside the references")
    regress(d, expect=0)
    with open(ref, "rb") as f:
        written = f.read()
    p = regress(d, "--update", expect=0)        # nothing changed: the file is left alone
    check(row(p.stdout, "two_floes_collide")[1] == "unchanged", p.stdout)
    with open(ref, "rb") as f:
        check(f.read() == written, "an unchanged reference is not rewritten")
    # the fresh reference equals the committed one (same case, deterministic run)
    c = subprocess.run([FLOESIM, "compare", ref, os.path.join(CASES, "two_floes_collide.ref.h5")],
                       capture_output=True, text=True)
    check(c.returncode == 0, f"a fresh reference equals the committed one:\n{c.stdout}")
    # an intended change: --update marks the case as changed and the new reference passes
    edit(os.path.join(d, "two_floes_collide.toml"), "friction = 0.2", "friction = 0.4")
    regress(d, expect=1)
    p = regress(d, "--update", expect=0)
    check(row(p.stdout, "two_floes_collide")[1] == "updated", p.stdout)
    regress(d, expect=0)
    keep = os.path.join(WORK, "kept")
    regress(d, "--keep", keep, expect=0)
    check(os.path.exists(os.path.join(keep, "two_floes_collide.h5")), "--keep keeps the runs")


def case_bad_input():
    p = regress(os.path.join(WORK, "nowhere"), expect=2)
    check("not a folder" in p.stderr, p.stderr)
    empty = os.path.join(WORK, "empty")
    os.makedirs(empty)
    p = regress(empty, expect=2)
    check("no *.toml cases" in p.stderr, p.stderr)
    d = os.path.join(WORK, "cases")
    copy_case("two_floes_collide", d)
    copy_case("floes_on_sea", d)
    path = os.path.join(d, "two_floes_collide.toml")
    edit(path, "friction = 0.2", "fricton = 0.2")
    p = regress(d, expect=2)
    check("key '[contact] fricton': unknown key" in p.stderr and path in p.stderr,
          f"the bad key and its file are named: {p.stderr}")
    check(p.stdout == "", "no case runs before every configuration is checked")


globals()["case_" + CHECK]()
shutil.rmtree(WORK, ignore_errors=True)
print(f"ok: {CHECK}")
