"""What the distributed-run checks share (check_ranks.py, check_sea_ranks.py):
commands run in the work folder with MPI allowed as root (CI containers) and
one thread per rank, `mpirun --oversubscribe`, and a stop with the command's
output when a step that must work fails."""
import os
import subprocess
import sys

ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OMP_NUM_THREADS="1")


class Ranks:
    def __init__(self, floesim, mpiexec, workdir):
        os.makedirs(workdir, exist_ok=True)
        self.floesim, self.mpiexec, self.workdir = floesim, mpiexec, workdir

    def run(self, cmd, timeout=600):
        return subprocess.run(cmd, cwd=self.workdir, capture_output=True, text=True, timeout=timeout, env=ENV)

    def mpirun(self, n, *floesim_args):
        return self.run([self.mpiexec, "--oversubscribe", "-np", str(n), self.floesim, *floesim_args])


def need(p, what):
    """p, if it exited 0; else the check stops, saying what failed and its output."""
    if p.returncode != 0:
        sys.exit(f"FAILED: {what}: exit {p.returncode}\n{p.stdout}\n{p.stderr}")
    return p
