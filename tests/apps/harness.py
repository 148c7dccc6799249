"""What the command-line tests share (cli_test.py, restart_test.py,
viz_test.py): floesim run as a user runs it, its exit code checked; a check
that fails ends the test with its message; text files written into the
test's folder; the `key: value` lines floesim prints."""
import os
import subprocess
import sys


def check(cond, msg):
    if not cond:
        sys.exit("FAILED: " + msg)


def keyvals(text):
    out = {}
    for line in text.splitlines():
        if ": " in line and not line.startswith(" "):
            k, v = line.split(": ", 1)
            out[k] = v
    return out


class Cli:
    def __init__(self, floesim, work):
        self.floesim, self.work = floesim, work

    def run(self, *args, expect=0, cwd=None, env=None):
        p = subprocess.run([self.floesim, *args], cwd=cwd or self.work, capture_output=True, text=True,
                           timeout=280, env=env)
        if p.returncode != expect:
            sys.exit(f"floesim {' '.join(args)}: exit {p.returncode}, expected {expect}\n"
                     f"stdout:\n{p.stdout}\nstderr:\n{p.stderr}")
        return p

    def write(self, name, text):
        path = os.path.join(self.work, name)
        with open(path, "w") as f:
            f.write(text)
        return path
