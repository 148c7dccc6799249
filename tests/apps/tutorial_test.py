#!/usr/bin/env python3
"""Runs the commands of docs/tutorial.md, so that the tutorial cannot rot.

usage: tutorial_test.py FLOESIM SOURCE_DIR
Takes the fenced block after the "tutorial-commands" marker, checks it has
five commands, and runs them in a fresh folder laid out like the repository
(build/bin/floesim -> the binary under test, examples/ and scripts/ -> the
source tree's). `scripts/run` (install and build) is not run: the test runs
inside the build it checks; it must exist and be executable. Every other
command must exit 0, and every `-o FILE.png` must be a PNG.
"""
import os
import shlex
import subprocess
import sys
import tempfile

FLOESIM, SRC = sys.argv[1], sys.argv[2]


def fail(msg):
    sys.exit("FAILED: " + msg)


text = open(os.path.join(SRC, "docs", "tutorial.md")).read()
marker = text.find("tutorial-commands")
if marker < 0:
    fail("docs/tutorial.md has no tutorial-commands marker")
start = text.find("```", marker)
end = text.find("```", start + 3)
block = text[text.find("\n", start) + 1:end]
commands = [line.split(" #")[0].strip() for line in block.splitlines()]
commands = [c for c in commands if c and not c.startswith("#")]
if len(commands) != 5:
    fail(f"the tutorial promises five commands, the block has {len(commands)}: {commands}")

work = tempfile.mkdtemp(prefix="floesim_tutorial_")
os.makedirs(os.path.join(work, "build", "bin"))
os.symlink(os.path.abspath(FLOESIM), os.path.join(work, "build", "bin", "floesim"))
for d in ("examples", "scripts"):
    os.symlink(os.path.join(SRC, d), os.path.join(work, d))

for cmd in commands:
    args = shlex.split(cmd)
    if args[0] == "scripts/run":
        path = os.path.join(SRC, "scripts", "run")
        if not (os.path.isfile(path) and os.access(path, os.X_OK)):
            fail("scripts/run is missing or not executable")
        print(f"skipped (install and build): {cmd}")
        continue
    if args[0] != "build/bin/floesim":
        fail(f"a tutorial command that the test does not know how to run: {cmd}")
    p = subprocess.run(args, cwd=work, capture_output=True, text=True, timeout=280)
    if p.returncode != 0:
        fail(f"{cmd}: exit {p.returncode}\nstdout:\n{p.stdout}\nstderr:\n{p.stderr}")
    print(f"ok: {cmd}")
    if "-o" in args:
        out = os.path.join(work, args[args.index("-o") + 1])
        if out.endswith(".png"):
            with open(out, "rb") as f:
                if f.read(8) != b"\x89PNG\r\n\x1a\n":
                    fail(f"{cmd}: {out} is not a PNG")
print("tutorial: ok")
