"""What the distributed-run checks share (check_ranks.py, check_record_ranks.py,
check_sea_ranks.py, check_slab_moves.py, check_rank_killed.py,
check_writer_ranks.py, check_advance_part.py, check_poison_run.py,
check_whole_seas.py): their arguments (ranks_check), commands run in the work
folder with MPI allowed as root (CI containers) and one thread per rank,
`mpirun --oversubscribe` (with test hooks' variables passed to every rank;
the poison mode's),
`floesim compare`, the run summary as a dict, the small ocean the sea checks
run on, the moving pack's checks' set-up and fracture, a stop with the command's output
when a step that must work fails, and the failures' list a check collects:
a run that must exit 0, a file that must equal another bit for bit (or
must not: a mutation), and the check's end."""
import argparse
import os
import re
import subprocess
import sys

# The fracture the moving pack's checks add (check_writer_ranks.py,
# check_record_ranks.py, check_poison_run.py): a strength its collisions
# exceed, so floes crack and split within a few hundred seconds.
FRACTURE = """
[fracture]
enabled = true
criterion = "stress"
strength = 0.2e6
split = true
mesh_size = 20.0
min_fragment_area = 400.0
"""

ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OMP_NUM_THREADS="1")


class Ranks:
    def __init__(self, floesim, mpiexec, workdir):
        os.makedirs(workdir, exist_ok=True)
        self.floesim, self.mpiexec, self.workdir = floesim, mpiexec, workdir

    def run(self, cmd, timeout=600):
        return subprocess.run(cmd, cwd=self.workdir, capture_output=True, text=True, timeout=timeout, env=ENV)

    def mpirun(self, n, *floesim_args, hooks=None):
        """floesim on n ranks; `hooks` (name -> value) set in the environment
        and passed to every rank (`mpirun -x`): test hooks such as
        FLOESIM_TEST_POISON_UNHELD."""
        if not hooks:
            return self.run([self.mpiexec, "--oversubscribe", "-np", str(n), self.floesim, *floesim_args])
        passed = [a for name in hooks for a in ("-x", name)]
        return subprocess.run([self.mpiexec, "--oversubscribe", "-np", str(n), *passed, self.floesim, *floesim_args],
                              cwd=self.workdir, capture_output=True, text=True, timeout=600,
                              env=dict(ENV, **hooks))

    def poisoned(self, n, poison, *floesim_args):
        """floesim on n ranks in the poison mode: the test hook
        FLOESIM_TEST_POISON_UNHELD set to `poison` (None: unset; docs/parallel.md,
        "The poison mode of the run")."""
        return self.mpirun(n, *floesim_args, hooks={"FLOESIM_TEST_POISON_UNHELD": poison} if poison else None)

    def poison_clean(self, name, config, serial, failures, floes=True, extra=(), ranks=2):
        """The case `name` (its configuration, its serial run file) on `ranks`
        ranks in the poison modes `step` and `step-lure`: each run must exit 0,
        equal the serial run bit for bit, every rank report no phase and, with
        `floes`, poison floes (the exchanges leave unheld copies that no phase
        reads): on every rank, or with floes="any" on one at least (a small
        case whose every floe some rank holds)."""
        for poison in ("step", "step-lure"):
            p = self.poisoned(ranks, poison, "run", config, "-o", f"{name}_{poison}.h5", "-q", *extra)
            poisoned = [int(m.group(1)) for m in re.finditer(r"windows, (\d+) floes poisoned", p.stderr)]
            reported = [int(m.group(1)) for m in re.finditer(r"(\d+) phases reported", p.stderr)]
            what = f"{name} on {ranks} ranks, poison mode {poison}"
            print(f"{what}: exit {p.returncode}, floes poisoned {poisoned}, phases reported {reported}")
            if p.returncode != 0:
                failures.append(f"{what}: exit {p.returncode}\n{p.stderr[-3000:]}")
                continue
            self.same(f"{name}_{poison}.h5", serial, f"{what}, against the serial run", failures)
            none = floes and (max(poisoned, default=0) if floes == "any" else min(poisoned, default=0)) == 0
            if len(poisoned) != ranks or any(reported) or none:
                failures.append(f"{what}: floes poisoned {poisoned}, phases reported {reported} (every rank must "
                                f"report none{' and poison floes' if floes else ''})\n{p.stderr[-3000:]}")

    def restart_2_on_3(self, name, config, serial, failures):
        """The case's first second on 2 ranks, the rest from its checkpoint on 3
        ranks: the run file must equal the serial one bit for bit."""
        need(self.mpirun(2, "run", config, "-o", f"{name}_half.h5", "-q", "--until", "1"),
             f"{name}: the first half on 2 ranks")
        p = self.mpirun(3, "run", "--restart", f"{name}_half.h5", "-o", f"{name}_rest3.h5", "-q")
        if p.returncode != 0:
            failures.append(f"{name}: restart on 3 ranks: exit {p.returncode}\n{p.stderr}")
        else:
            self.same(f"{name}_rest3.h5", serial, f"{name}: half on 2 ranks, continued on 3, against the serial run",
                      failures)

    def compare(self, a, b, rtol):
        """`floesim compare` of two run files within the relative `rtol` (no absolute slack)."""
        return self.run([self.floesim, "compare", a, b, "--rtol", str(rtol), "--atol", "0"])

    def same(self, a, b, what, failures, rtol=0):
        """Whether run files a and b are equal within `rtol` (0: bit for bit),
        said as `what: equal` or `DIFFERENT`; a difference goes to `failures`
        with `floesim compare`'s output."""
        c = self.compare(a, b, rtol)
        print(f"{what}: {'equal' if c.returncode == 0 else 'DIFFERENT'} ({'bit for bit' if rtol == 0 else f'rtol {rtol}'})")
        if c.returncode != 0:
            failures.append(f"{what} differs:\n{c.stdout}")
        return c.returncode == 0

    def differs(self, p, a, b, what, failures):
        """A mutation's run p (it must exit 0) and its file a, which must differ
        from b: said, and a failure when it ran badly or compared equal (the
        check would not see what the mutation breaks)."""
        c = self.compare(a, b, 0)
        ok = p.returncode == 0 and c.returncode != 0
        print(f"{what} (mutation): {'DIFFERENT, as it must be' if ok else 'EQUAL or failed'}")
        if not ok:
            failures.append(f"{what} (mutation): exit {p.returncode}, compared "
                            f"{'equal' if c.returncode == 0 else 'different'}: the check does not see it\n{p.stderr}")
        return ok


def ran(p, what, failures):
    """p, if it exited 0; else None, and its exit and output go to `failures`."""
    if p.returncode != 0:
        failures.append(f"{what}: exit {p.returncode}\n{p.stdout}\n{p.stderr}")
        return None
    return p


def finish(failures):
    """The end of a check: FAILED and every failure (exit 1), or ok."""
    if failures:
        print("FAILED:\n" + "\n".join(failures))
        sys.exit(1)
    print("ok")


def summary(p):
    """The run summary a finished `floesim run` printed, key -> text."""
    return dict(l.split(": ", 1) for l in p.stdout.splitlines() if ": " in l)


def phase_bytes(p, phase):
    """Rank 0's bytes received in a phase (`parallel.phase.PHASE: C calls, B bytes`)."""
    return int(summary(p)[f"parallel.phase.{phase}"].split()[2])


def ocean_toml(pack, t_end, output_interval, contact="", coupling=""):
    """A small ocean like bench/ocean/ocean.toml: the floes of `pack` in a
    200 m x 200 m periodic box on a 128^2 spectral sea (JONSWAP, Hs = 1 m,
    Tp = 6 s, 50 m deep) under wind, riding on it through the strong penalty
    law (K = 100); `contact` and `coupling` are lines added to those tables."""
    return f"""[run]
t_end = {t_end}
dt_max = 0.05
output_interval = {output_interval}
seed = 2
threads = 1

[sea]
model = "spectral"
dims = 2
size = [200.0, 200.0]
cells = [128, 128]
depth = 50.0

[sea.waves]
kind = "jonswap"
hs = 1.0
tp = 6.0

[floes]
pack = "{pack}"

[contact]
domain = "periodic"
{contact}
[forcing]
wind = [15.0, 5.0]

[coupling]
law = "strong"
stiffness = 100.0
{coupling}"""


def squares_on_sea(path, floes, t_end, amplitude, wind, law):
    """Writes a 64 m periodic box on a 32^2 spectral sea (regular waves of
    16 m, depth 20 m) with 2 m square floes 0.5 m thick, each (x, y, vy): its
    lower-left corner and its velocity along y; `law` is the [coupling]
    section's lines. The redone-step cases of check_sea_ranks.py and
    check_slab_moves.py."""
    def square(x, y):
        return f"[[{x}, {y}], [{x + 2}, {y}], [{x + 2}, {y + 2}], [{x}, {y + 2}]]"
    with open(path, "w") as f:
        f.write(f'[run]\nt_end = {t_end}\ndt_max = 0.25\noutput_interval = 0.5\nthreads = 1\n\n'
                '[sea]\nmodel = "spectral"\ndims = 2\nsize = [64.0, 64.0]\ncells = [32, 32]\ndepth = 20.0\n\n'
                f'[sea.waves]\nkind = "regular"\namplitude = {amplitude}\nwavelength = 16.0\n\n'
                '[contact]\ndomain = "periodic"\nbox = [0.0, 64.0, 0.0, 64.0]\nrestitution = 1.0\n\n'
                f'[forcing]\nwind = [{wind[0]}, {wind[1]}]\n\n[coupling]\n{law}\n')
        for x, y, vy in floes:
            f.write(f"\n[[floes.floe]]\nvertices = {square(x, y)}\nvelocity = [0.0, {vy}]\nthickness = 0.5\n")


def need(p, what):
    """p, if it exited 0; else the check stops, saying what failed and its output."""
    if p.returncode != 0:
        sys.exit(f"FAILED: {what}: exit {p.returncode}\n{p.stdout}\n{p.stderr}")
    return p


def half_pack(run, floesim, out="half_pack.h5"):
    """The small ocean's floes (for ocean_toml): 120 floes of 6 to 15 m, 1 m
    thick, at 50 % cover in the lower half of a 200 m x 200 m box (`floesim
    pack`, seed 3), written to `out` by run([...]) in the check's folder."""
    need(run([floesim, "pack", "--floes", "120", "--concentration", "0.5", "--box", "200", "100", "--seed", "3",
              "--min-size", "6", "--max-size", "15", "--thickness", "1", "-o", out]), "floesim pack")
    return out


def ranks_check(no_mpi, options=None):
    """The set-up every distributed-run check shares. With --no-mpi (MPI not
    built): says `no_mpi` and exits 77 (ctest's skip code). Else the
    arguments FLOESIM MPIEXEC WORKDIR and those `options(parser)` adds.
    Returns the arguments and a Ranks for WORKDIR."""
    if "--no-mpi" in sys.argv:
        print(no_mpi)
        sys.exit(77)
    ap = argparse.ArgumentParser()
    ap.add_argument("floesim")
    ap.add_argument("mpiexec")
    ap.add_argument("workdir")
    if options:
        options(ap)
    args = ap.parse_args()
    return args, Ranks(args.floesim, args.mpiexec, args.workdir)


def moving_pack_check(no_mpi, floes, t_end, ranks, options=None):
    """The set-up of the checks on the moving pack (check_ranks.py,
    check_record_ranks.py). With --no-mpi (MPI not built): says `no_mpi` and
    exits 77 (ctest's skip code). Else the arguments FLOESIM MPIEXEC WORKDIR
    [--floes N] [--t-end T] [--ranks R...] (the defaults given here), and
    those `options(parser)` adds; then the collisions-only periodic pack of
    scripts/scenarios/moving_pack.py (seed 5, wind (10, 3) m/s, records every
    quarter of the run) written to WORKDIR. Returns the arguments, a Ranks
    for WORKDIR and the configuration's path."""
    def pack_options(ap):
        ap.add_argument("--floes", type=int, default=floes)
        ap.add_argument("--t-end", type=float, default=t_end)
        ap.add_argument("--ranks", type=int, nargs="+", default=ranks)
        if options:
            options(ap)

    args, harness = ranks_check(no_mpi, pack_options)
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))),
                                    "scripts", "scenarios"))
    import moving_pack  # (the pack shared with bench/mpi_pack.py; it needs h5py, which --no-mpi does not)
    try:
        config = moving_pack.write(args.floesim, args.workdir, args.floes, args.t_end, seed=5,
                                   output_interval=args.t_end / 4, wind=(10.0, 3.0))
    except RuntimeError as e:
        sys.exit(f"FAILED: {e}")
    return args, harness, config
