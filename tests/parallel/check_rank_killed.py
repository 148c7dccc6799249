#!/usr/bin/env python3
"""A rank killed outright in the middle of a distributed run (docs/parallel.md, "Errors").

usage: check_rank_killed.py FLOESIM MPIEXEC WORKDIR
       check_rank_killed.py --no-mpi    (MPI not built: says so and exits 77, ctest's skip code)

The collisions-only periodic pack of scripts/scenarios/moving_pack.py runs on
2 ranks with checkpoints every 300 s. Once rank 0's progress lines say the
run is past 700 s (so a checkpoint exists), rank 1 is sent SIGKILL: no
handler, no message, the case that `Communicator::together` cannot hear of.
Then:
- every rank stops: mpirun exits non-zero within 60 s and no process of the
  run is left (no deadlock of rank 0 in a collective);
- the run file stays readable: `floesim info` reads it, says the run has no
  end mark and shows a checkpoint, and h5py reads every object and attribute
  of it (rank 0, ended by `mpirun` wherever it was, perhaps inside a write,
  leaves the file as of its last flush: docs/formats.md, "A killed run's
  file");
- the run continues from that checkpoint on 2 ranks (`--restart`) to 1500 s,
  and its file equals a serial run to 1500 s that was never stopped, bit for
  bit (`floesim compare --rtol 0 --atol 0`): nothing the killed run wrote
  after its checkpoint leaks into the continuation.
"""
import os
import re
import signal
import subprocess
import sys
import time

from ranks_harness import ENV, Ranks, need, ranks_check

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))),
                                "scripts", "scenarios"))
import moving_pack  # noqa: E402

args, _ = ranks_check("floesim was built without MPI (FLOESIM_MPI=OFF): the killed rank is not checked")
W = os.path.abspath(args.workdir)
args.floesim = os.path.abspath(args.floesim)
harness = Ranks(args.floesim, args.mpiexec, W)

T_END, CHECKPOINT, KILL_AFTER, CONTINUE_TO = 200000.0, 300.0, 700.0, 1500.0
try:
    config = moving_pack.write(args.floesim, W, 1500, T_END, seed=5, output_interval=100.0, wind=(10.0, 3.0))
except RuntimeError as e:
    sys.exit(f"FAILED: {e}")
with open(config) as f:
    text = f.read()
with open(config, "w") as f:
    f.write(text.replace("[run]\n", f"[run]\ncheckpoint_interval = {CHECKPOINT}\n", 1))


def processes_of_run():
    """{pid: rank} of the floesim processes running this work folder's config."""
    found = {}
    for pid in os.listdir("/proc"):
        if not pid.isdigit():
            continue
        try:
            with open(f"/proc/{pid}/cmdline", "rb") as f:
                cmd = f.read().split(b"\0")
            if not cmd or os.path.basename(cmd[0]) != b"floesim" or config.encode() not in cmd:
                continue
            with open(f"/proc/{pid}/environ", "rb") as f:
                env = dict(e.split(b"=", 1) for e in f.read().split(b"\0") if b"=" in e)
            found[int(pid)] = int(env.get(b"OMPI_COMM_WORLD_RANK", b"-1"))
        except (OSError, ValueError):
            continue  # gone meanwhile, or not ours to read
    return found


killed_file = os.path.join(W, "killed.h5")
for stale in (killed_file, os.path.join(W, "continued.h5"), os.path.join(W, "serial.h5")):
    if os.path.exists(stale):
        os.remove(stale)
job = subprocess.Popen([args.mpiexec, "--oversubscribe", "-np", "2", args.floesim, "run", config, "-o", killed_file,
                        "--log-every", "0.1"], cwd=W, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                       text=True)
log = []
simulated = 0.0
for line in job.stdout:  # rank 0's progress lines: "floesim: [ 0.3%] t = 630 / 200000 s | ..."
    log.append(line)
    m = re.search(r"\bt = ([0-9.e+]+) /", line)
    if m:
        simulated = float(m.group(1))
    if simulated > KILL_AFTER:
        break
else:
    sys.exit("FAILED: the 2-rank run ended before it could be killed:\n" + "".join(log))
ranks = processes_of_run()
victims = [pid for pid, rank in ranks.items() if rank == 1]
if len(victims) != 1:
    job.kill()
    sys.exit(f"FAILED: expected one process of rank 1, found ranks {ranks}")
os.kill(victims[0], signal.SIGKILL)
print(f"rank 1 (pid {victims[0]}) killed at t = {simulated} s")

try:
    rest, _ = job.communicate(timeout=60)
except subprocess.TimeoutExpired:
    job.kill()
    sys.exit(f"FAILED: the ranks did not all stop within 60 s of rank 1's death (left: {processes_of_run()})")
failures = []
if job.returncode == 0:
    failures.append("mpirun exited 0 after a rank was killed")
time.sleep(0.5)
if processes_of_run():
    failures.append(f"processes of the run left after mpirun ended: {processes_of_run()}")

info = harness.run([args.floesim, "info", killed_file])
if info.returncode != 0:
    failures.append(f"floesim info cannot read the killed run's file: exit {info.returncode}\n{info.stdout}{info.stderr}")
elif "no end mark" not in info.stdout or not re.search(r"^checkpoint: t = [0-9.]+ s", info.stdout, re.M):
    failures.append("floesim info should say the killed run has no end mark and show its checkpoint:\n" + info.stdout)
else:
    print(re.search(r"^checkpoint: .*", info.stdout, re.M).group(0))

try:
    import h5py

    def read(name, obj):
        for a in obj.attrs:
            obj.attrs[a]
        if isinstance(obj, h5py.Dataset):
            obj[()]
    with h5py.File(killed_file, "r") as f:
        f.visititems(read)
except Exception as e:  # noqa: BLE001 (h5py raises OSError, KeyError, RuntimeError, ...)
    failures.append(f"h5py cannot read the killed run's file whole: {e}")

if not failures:
    continued = os.path.join(W, "continued.h5")
    need(harness.mpirun(2, "run", "--restart", killed_file, "--until", str(CONTINUE_TO), "-o", continued),
         "the killed run continued from its checkpoint on 2 ranks")
    serial = os.path.join(W, "serial.h5")
    need(harness.run([args.floesim, "run", config, "--until", str(CONTINUE_TO), "-o", serial]), "the serial run")
    same = harness.run([args.floesim, "compare", serial, continued, "--rtol", "0", "--atol", "0"])
    if same.returncode != 0:
        failures.append(f"the continued run differs from the serial run:\n{same.stdout}{same.stderr}")

if failures:
    sys.exit("FAILED:\n" + "\n".join(failures))
print("a killed rank stops every rank, the file stays readable, and the run continues from its checkpoint "
      "to the serial answer bit for bit")
