"""Overlap check of a run file (issue 23's wall jam, docs/contact.md, seventh round).

    /usr/bin/python3 bench/walljam_check.py RUN.h5 [WALL_FACE_X]

At every record, every pair of floes whose bounding boxes meet (static pairs
apart; a wall is a static floe) is tested for overlap by the separating axis
theorem on their convex outlines (/xdmf/vertices): the overlap depth is the
smallest overlap of the two outlines' projections on the edge normals of
either, < 0 when some axis separates them. Prints the largest depth over all
records and pairs, and at a few records the floes with every vertex beyond
x = WALL_FACE_X (default 2100 m, the wall's downwind face)."""
import sys
import h5py
import numpy as np

f = h5py.File(sys.argv[1], "r")
face = float(sys.argv[2]) if len(sys.argv) > 2 else 2100.0
off = f["floes/offsets"][:]
static = f["floes/static"][:]
V = f["xdmf/vertices"]
T = V.shape[0]
n = len(off) - 1
times = f["time"][:] if "time" in f else np.arange(T)

def polys(k):
    v = V[k][:, :2]
    return [v[off[i]:off[i + 1]] for i in range(n)]

def convex(p):
    d = np.roll(p, -1, 0) - p
    c = d[:, 0] * np.roll(d, -1, 0)[:, 1] - d[:, 1] * np.roll(d, -1, 0)[:, 0]
    return (c >= -1e-9).all() or (c <= 1e-9).all()

def depth(a, b):
    """Smallest overlap along the edge normals of a and b (< 0: separated)."""
    best = np.inf
    for p in (a, b):
        e = np.roll(p, -1, 0) - p
        nrm = np.stack([e[:, 1], -e[:, 0]], 1)
        nrm /= np.linalg.norm(nrm, axis=1)[:, None]
        pa, pb = a @ nrm.T, b @ nrm.T
        ov = np.minimum(pa.max(0), pb.max(0)) - np.maximum(pa.min(0), pb.min(0))
        best = min(best, ov.min())
        if best < 0:
            return best
    return best

worst = -np.inf
nonconvex = 0
for k in range(T):
    P = polys(k)
    ok = [i for i in range(n) if not np.isnan(P[i]).any()]
    lo = np.array([P[i].min(0) for i in ok]); hi = np.array([P[i].max(0) for i in ok])
    for a in range(len(ok)):
        cand = np.nonzero((lo[a + 1:] < hi[a]).all(1) & (hi[a + 1:] > lo[a]).all(1))[0] + a + 1
        for b in cand:
            i, j = ok[a], ok[b]
            if static[i] and static[j]:
                continue
            if not (convex(P[i]) and convex(P[j])):
                nonconvex += 1
                continue
            worst = max(worst, depth(P[i], P[j]))
    beyond = sum(1 for i in ok if not static[i] and P[i][:, 0].min() > face)
    if k % max(1, T // 8) == 0 or k == T - 1:
        print(f"record {k} t={times[k] if k < len(times) else k}: floes beyond x={face:g} m: {beyond}")
print(f"records {T}, floes {n}, largest overlap depth over all records and pairs: {worst:.3e} m "
      f"(< 0: none), non-convex pairs skipped: {nonconvex}")
