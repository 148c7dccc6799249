#!/usr/bin/env python3
"""The poison mode's check of the sea, in a run (docs/parallel.md, "The poison
mode of the run": the sea's check).

usage: check_poison_sea.py FLOESIM MPIEXEC WORKDIR
       check_poison_sea.py --no-mpi    (MPI not built: exits 77, ctest's skip code)

After each phase every rank looks for NaN in the sea it steps
(fluid::Sea::finite_state: the whole sea on a sea not in slabs). The cases
are scripts/validate_ranks' bem_pack and tank_pack (a dense pack over a BEM
basin, over a spectral tank) on 2 ranks to 0.5 s with the mutation
`step-mutant-sea` (each rank's lowest held floe's heave NaN too, its place
finite): that floe's penalty pressure reaches the sea at the next kick, so
every rank must report "the sea's modal state is NaN" after some phase. Without the sea's check no rank says so (the run
is reported by its floes only). The same cases unmutated (`step`, `step-lure`
on 2 and 3 ranks, no sea reported) are validate_ranks' (mpi.validate_ranks_short).
"""
import importlib.machinery
import importlib.util
import os
import re
from pathlib import Path

from ranks_harness import finish, ranks_check

args, harness = ranks_check("floesim was built without MPI (FLOESIM_MPI=OFF): the poison mode's sea check is not run")
SCRIPT = Path(__file__).resolve().parents[2] / "scripts" / "validate_ranks"
loader = importlib.machinery.SourceFileLoader("validate_ranks", str(SCRIPT))
spec = importlib.util.spec_from_loader("validate_ranks", loader)
validate_ranks = importlib.util.module_from_spec(spec)
loader.exec_module(validate_ranks)
validate_ranks.FLOESIM = os.path.abspath(args.floesim)

SEA_REPORT = re.compile(r"poison: rank (\d+): after ([^:]+): the sea's modal state is NaN")
failures = []
for case in ("bem_pack", "tank_pack"):
    folder = Path(args.workdir) / case
    folder.mkdir(parents=True, exist_ok=True)
    config = validate_ranks.pack_config(case, folder)
    p = harness.poisoned(2, "step-mutant-sea", "run", str(config), "-o", str(folder / "mutant.h5"), "-q", "--until", "0.5")
    first = {}
    for rank, phase in SEA_REPORT.findall(p.stderr):
        first.setdefault(int(rank), phase)
    print(f"{case}, step-mutant-sea on 2 ranks: exit {p.returncode}, the sea first reported after {first}")
    if sorted(first) != [0, 1]:
        failures.append(f"{case}: the mutant's NaN floe kicks the sea, but not every rank reported its sea "
                        f"({first})\n{p.stderr[-3000:]}")
finish(failures)
