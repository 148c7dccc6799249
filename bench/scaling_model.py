#!/usr/bin/env python3
"""bench/scaling_model.py: a weak-scaling model of floesim's distributed step to 1024 ranks.

The model is of the decomposition docs/parallel.md plans (its "next
stages") and, beside it, of the step that runs today (below). The plan:
each rank owns a square of sea and the floes whose centroid it holds, the
sea's transforms are distributed, and a rank exchanges only halos with its
neighbours. Weak scaling: every rank
keeps bench/ocean's share (its pack: 1000 floes on a 1 km, 512^2-cell
square), so P ranks run P km^2, P 10^3 floes, 512^2 P cells. docs/scaling.md
derives the terms; one step on P ranks costs

  T(P) = C + F (log2(n P) / log2 n) + X(P) + H + R(P)

  C      the step's work other than the transforms, per rank (measured: bench/ocean's
         serial step, less its transforms)
  F      the transforms' work on n = 512^2 cells (measured share of the step), growing
         as n log(nP) per rank
  X(P)   the transposes of the distributed transforms: tau transforms a step, each
         moving the rank's half spectrum (8 n bytes) across the ranks: slabs, one
         all-to-all of P ranks; or 2D blocks, two all-to-alls of sqrt(P) ranks
  H      the halo exchange with the 8 neighbours: the states of floes within a
         floe's reach of the square's edges (measured on the pack), then the area
         pieces they put in the neighbour's cells (upper bound: all their pieces)
  R(P)   the step's agreements (time step, failures, stopping): r reductions of
         latency alpha log2 P

The step that runs today (the "today" columns) is the planned one plus what
still grows with the total floe count N = 1000 P on every rank
(docs/scaling.md, "The step that runs today"):

  T_today(P) = T_slabs(P) + W(P) + V (P - 1) 1000 + S(P)

  W(P)   the whole-pack exchanges: w bytes a floe a step of every floe to every
         rank (today's all-gathers, `complete_owned`), in c calls a step, each a
         ring all-gather of its w N / c bytes: (P - 1) alpha + (w N / c) (P - 1) / P / beta
  V      the per-rank passes over every floe (the owners' assignment, the
         advance's set-up, the held masks): seconds a floe a step, on the
         1000 (P - 1) floes a rank does not own (its own 1000 are in C)
  S(P)   with --implicit-whole-sea (the implicit step before slabs30, and on a
         sea not in slabs), its sea whole on every rank: its transforms on
         the whole sea, F P log2(n P) / log2 n, instead of the rank's share and
         its transposes (a lower bound: the solve's other per-cell work, in C,
         is whole on every rank too); since slabs30 the implicit step on a sea
         in slabs transforms its slab (S = 0)

and the floes' whole-pack arrays take m bytes a floe on every rank (memory,
not time). --no-whole sets W, V, S and m to zero: today's columns are then
the planned slabs' step (the check in the commit that added them).

with a message of b bytes taking alpha + b / beta, and beta the rank's share of
its node's network when P fills more than a node. alpha, the node's bandwidth
and the ranks per node are a cluster's, not this machine's (assumed, command
line); every other input is measured on bench/ocean and named in the CSV.

usage: bench/scaling_model.py [--step-ms 22.6] [--fft-share 0.13] [--pieces-per-floe 130]
                              [--alpha-us 2] [--node-gbs 12.5] [--ranks-per-node 32]
                              [--memory-gbs 5] [--whole-bytes-explicit 0.8] [--whole-bytes-implicit ...]
                              [--whole-pass-ns ...] [--floe-memory-bytes 400] [--no-whole] [--implicit-whole-sea]
                              [--build build] [--pack bench/ocean/ocean_pack.h5] [--csv FILE | -]
"""
import argparse
import math
import os
import subprocess
import sys

import h5py
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, os.path.join(ROOT, "scripts", "scenarios"))
import ocean_pack  # noqa: E402  (bench/ocean's pack)

# Measured (docs/scaling.md, "The step that runs today"; bench/results/whole_pack_s29_epyc-2core.csv).
# The implicit step by owner on the sea in slabs (since slabs30): the vertical DOFs
# (48 B) once and the loads (48 B) twice a step, every floe's to every rank
# (bench/results/whole_pack_s30_epyc-2core.csv). With --implicit-whole-sea, the step
# before slabs30 (and on a sea not in slabs): the area pieces gathered twice, the
# loads twice, the tilted floes' yaw (whole_pack_s29), and the sea whole on every rank.
WHOLE_IMPLICIT_BYTES = 3 * 48.0
WHOLE_IMPLICIT_CALLS = 3.0
WHOLE_SEA_IMPLICIT_BYTES = 2 * 3511.0 + 2 * 48.0 + 8.0
WHOLE_SEA_IMPLICIT_CALLS = 5.0
WHOLE_PASS_NS = 150.0  # rank 0 of 2 less its share of the serial run, per floe (0.08 to 0.19 us; by symbol 0.14)

ap = argparse.ArgumentParser()
# Measured inputs (bench/ocean, docs/scaling.md says where each comes from).
ap.add_argument("--step-ms", type=float, default=22.6,
                help="serial explicit step of bench/ocean, ms (bench/results/ocean_ranks_epyc-2core.csv: 26.03 s / 1154)")
ap.add_argument("--fft-share", type=float, default=0.13, help="the transforms' share of that step (perf, docs/parallel.md)")
ap.add_argument("--implicit-step-ms", type=float, default=352.5,
                help="serial implicit step, dt 0.05 s (bench/results/ocean_implicit_dt_18ef897_epyc-2core.csv)")
ap.add_argument("--implicit-responses", type=float, default=47.48,
                help="sea responses a step of the implicit step (same CSV), each one forward and one backward transform")
ap.add_argument("--pieces-per-floe", type=float, default=130.0,
                help="area pieces a floe (about 1.3e5 for 1000 floes, docs/parallel.md)")
ap.add_argument("--state-bytes", type=int, default=96, help="a floe's state (FloeState)")
ap.add_argument("--piece-bytes", type=int, default=12, help="a piece's (cell, area) for the owner of its cell")
ap.add_argument("--reductions", type=int, default=2, help="agreements a step (time step; failures and stopping)")
# The step that runs today: what grows with the total floe count on every rank (measured on
# bench/ocean's pack at 1000 and 4000 floes on 2 ranks, docs/scaling.md "The step that runs today").
ap.add_argument("--whole-bytes-explicit", type=float, default=0.8,
                help="bytes a floe a step of every floe to every rank, explicit step: the strips' keys (8 B every "
                     "10 steps; the boxes of order_by_owner, 12 B a step, go by holder since boxes30)")
ap.add_argument("--whole-calls-explicit", type=float, default=0.1, help="those all-gathers a step")
ap.add_argument("--whole-bytes-implicit", type=float, default=None,
                help="the same for the implicit step: its vertical DOFs (48 B) once and its loads (48 B) twice "
                     "(144); with --implicit-whole-sea its area pieces (3511 B a floe of bench/ocean's pack) "
                     "twice, its loads twice, the tilted floes' yaw (8 B): 7126")
ap.add_argument("--whole-calls-implicit", type=float, default=None,
                help="those all-gathers a step (3; with --implicit-whole-sea 5)")
ap.add_argument("--implicit-whole-sea", action="store_true",
                help="price the implicit step as it ran before slabs30 (and still runs on a sea not in slabs): "
                     "the sea whole on every rank, every floe's pieces gathered, the solve replicated")
ap.add_argument("--whole-pass-ns", type=float, default=WHOLE_PASS_NS,
                help="the per-rank passes over every floe, ns a floe a step (rank 0 of 2 less half the serial "
                     "step's work, per floe: includes the by-owner code's own work on the rank's floes)")
ap.add_argument("--floe-memory-bytes", type=float, default=400.0,
                help="the floes' arrays still whole-pack on every rank, bytes a floe (docs/scaling.md)")
ap.add_argument("--no-whole", action="store_true",
                help="set every whole-pack term to zero: the today columns are then the planned slabs'")
# A cluster's network (assumed).
ap.add_argument("--alpha-us", type=float, default=2.0, help="latency of a message, us")
ap.add_argument("--node-gbs", type=float, default=12.5, help="a node's network bandwidth, GB/s (100 Gb/s)")
ap.add_argument("--ranks-per-node", type=int, default=32)
ap.add_argument("--memory-gbs", type=float, default=5.0, help="a rank's copy bandwidth within a node, GB/s")
ap.add_argument("--build", default=os.path.join(ROOT, "build"), help="where floesim is, to write the pack if missing")
ap.add_argument("--pack", default=os.path.join(HERE, "ocean", "ocean_pack.h5"),
                help="bench/ocean's pack (written there by the build's floesim if missing)")
ap.add_argument("--csv", default="-")
args = ap.parse_args()
if args.whole_bytes_implicit is None:
    args.whole_bytes_implicit = WHOLE_SEA_IMPLICIT_BYTES if args.implicit_whole_sea else WHOLE_IMPLICIT_BYTES
if args.whole_calls_implicit is None:
    args.whole_calls_implicit = WHOLE_SEA_IMPLICIT_CALLS if args.implicit_whole_sea else WHOLE_IMPLICIT_CALLS

CELLS = 512 * 512          # a rank's cells
SIDE = 1000.0              # a rank's square, m
FLOES = 1000
TRANSFORMS_EXPLICIT = 2    # one forward (the kick), one backward (the elevation) a step: counted, docs/scaling.md


def pack_radii():
    """Centroids, circumradii and window of bench/ocean's pack (one rank's share)."""
    pack = args.pack
    if not os.path.exists(pack):
        floesim = os.path.join(args.build, "bin", "floesim")
        if not os.access(floesim, os.X_OK):
            sys.exit(f"scaling_model.py: no {pack}, and no {floesim} to write it")
        ocean_pack.write(floesim, pack)
    with h5py.File(pack, "r") as f:
        offsets = f["floes/offsets"][:]
        vertices = f["floes/vertices"][:]       # body frame, about the centroid
        c = f["floes/pose"][:, :2]              # centroids
        window = f["window"][:]
    r = np.array([np.max(np.linalg.norm(vertices[a:b], axis=1)) for a, b in zip(offsets[:-1], offsets[1:])])
    return c, r, window


def halo_blocks(c, r, window):
    """A rank's square: the floes whose state a neighbour needs (centroid within
    the largest circumradius and a step's reach, 1 m, of an edge) and the floes
    that put pieces in a neighbour's cells (circumscribed disc across an edge),
    counted on the pack."""
    x0, x1, y0, y1 = window
    edge = np.minimum.reduce([c[:, 0] - x0, x1 - c[:, 0], c[:, 1] - y0, y1 - c[:, 1]])
    return float(np.sum(edge < r.max() + 1.0)), float(np.sum(edge < r))


def halo_slabs(r, thickness):
    """A rank's slab of the given thickness (the same floes, spread along it):
    with centroids uniform across the slab, a floe is within d of one of its two
    long edges with probability min(1, 2 d / thickness)."""
    state = len(r) * min(1.0, 2 * (r.max() + 1.0) / thickness)
    straddle = float(np.sum(np.minimum(1.0, 2 * r / thickness)))
    return state, straddle


def all_to_all(ranks, bytes_, beta):
    """One all-to-all among `ranks` ranks, each holding `bytes_` (sent but its own share)."""
    alpha = args.alpha_us * 1e-6
    return (ranks - 1) * alpha + bytes_ * (ranks - 1) / ranks / beta


def halo_time(neighbours, state, straddle, beta):
    """States before detection, pieces after the footprints: two messages to each neighbour."""
    alpha = args.alpha_us * 1e-6
    return 2 * neighbours * alpha + (state * args.state_bytes + straddle * args.pieces_per_floe * args.piece_bytes) / beta


def model(P, step_ms, transforms, r, block_halo):
    """Per rank and step (s): compute, the transforms' work, and for slabs and for
    blocks the transposes and the halo; the reductions."""
    alpha = args.alpha_us * 1e-6
    beta = args.node_gbs * 1e9 / args.ranks_per_node if P > args.ranks_per_node else args.memory_gbs * 1e9
    fft = args.fft_share * args.step_ms * 1e-3 / TRANSFORMS_EXPLICIT * transforms
    compute = step_ms * 1e-3 - fft
    fft_p = fft * math.log2(CELLS * P) / math.log2(CELLS)
    spectrum = 8.0 * CELLS   # a rank's half spectrum, complex doubles, bytes
    if P == 1:
        return compute, fft_p, 0.0, 0.0, 0.0, 0.0, 0.0
    # slabs: one all-to-all of P ranks a transform; a slab 1 km / sqrt(P) thick, 2 neighbours
    slab_x = transforms * all_to_all(P, spectrum, beta)
    slab_h = halo_time(2, *halo_slabs(r, SIDE / math.sqrt(P)), beta)
    # blocks: a transform is two all-to-alls among sqrt(P) ranks; squares, 8 neighbours
    groups = math.sqrt(P)
    block_x = transforms * 2 * all_to_all(groups, spectrum, beta)
    block_h = halo_time(8, *block_halo, beta)
    reductions = args.reductions * alpha * math.ceil(math.log2(P))
    return compute, fft_p, slab_x, slab_h, block_x, block_h, reductions


def today(P, kind, fft_p, slab_x):
    """What the step that runs today adds to the planned slabs' step, per rank and
    step (s): the whole-pack all-gathers, the passes over the floes the rank does
    not own, and (implicit) the whole sea's transforms on every rank instead of the
    rank's share and its transposes; and the floes' whole-pack memory (bytes). All
    zero with --no-whole."""
    if args.no_whole:
        return 0.0, 0.0, 0.0, 0.0, 0.0
    floes = FLOES * P
    memory = args.floe_memory_bytes * floes
    if P == 1:
        return 0.0, 0.0, 0.0, 0.0, memory
    alpha = args.alpha_us * 1e-6
    beta = args.node_gbs * 1e9 / args.ranks_per_node if P > args.ranks_per_node else args.memory_gbs * 1e9
    per_floe = args.whole_bytes_explicit if kind == "explicit" else args.whole_bytes_implicit
    calls = args.whole_calls_explicit if kind == "explicit" else args.whole_calls_implicit
    received = per_floe * floes   # every floe's bytes reach every rank (an all-gather counts its own part too)
    # calls ring all-gathers a step, together of `received` bytes: (P - 1) messages each.
    exchange = calls * (P - 1) * alpha + received * (P - 1) / P / beta
    passes = args.whole_pass_ns * 1e-9 * FLOES * (P - 1)
    # The implicit step keeps the sea whole on every rank: every rank transforms
    # the whole n P cells (n P log(n P) against its share's n log(n P)) and
    # transposes nothing. Its solve's other per-cell work (in C) is whole too and
    # not counted here: for the implicit step this term is a lower bound.
    sea = fft_p * (P - 1) - slab_x if kind == "implicit" and args.implicit_whole_sea else 0.0
    return received, exchange, passes, sea, memory


c, r, window = pack_radii()
state, straddle = halo_blocks(c, r, window)
rows = []
for kind, step_ms, transforms in (("explicit", args.step_ms, TRANSFORMS_EXPLICIT),
                                  ("implicit", args.implicit_step_ms, 2 * args.implicit_responses)):
    base = None
    for P in (1, 4, 16, 64, 256, 1024):
        compute, fft_p, slab_x, slab_h, block_x, block_h, red = model(P, step_ms, transforms, r, (state, straddle))
        slab = compute + fft_p + slab_x + slab_h + red
        block = compute + fft_p + block_x + block_h + red
        base = base or slab
        received, exchange, passes, sea, memory = today(P, kind, fft_p, slab_x)
        now = slab + exchange + passes + sea
        side = 512 * math.isqrt(P)
        rows.append([kind, P, P * FLOES, f"{side}x{side}", f"{compute * 1e3:.2f}", f"{fft_p * 1e3:.2f}",
                     f"{slab_x * 1e3:.3f}", f"{slab_h * 1e3:.3f}", f"{slab * 1e3:.2f}", f"{base / slab:.3f}",
                     f"{block_x * 1e3:.3f}", f"{block_h * 1e3:.3f}", f"{block * 1e3:.2f}", f"{base / block:.3f}",
                     f"{red * 1e3:.4f}", f"{received / 1e6:.3f}", f"{exchange * 1e3:.3f}", f"{passes * 1e3:.3f}",
                     f"{sea * 1e3:.2f}", f"{now * 1e3:.2f}", f"{base / now:.3f}", f"{memory / 1e6:.1f}"])

commit = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
lines = [
    f"# command: bench/scaling_model.py {' '.join(sys.argv[1:])}",
    f"# commit: {commit}; a model (docs/scaling.md), not a run",
    f"# measured inputs: explicit step {args.step_ms} ms (transforms {args.fft_share:.0%} of it, {TRANSFORMS_EXPLICIT} a step); "
    f"implicit step {args.implicit_step_ms} ms ({args.implicit_responses} sea responses a step); "
    f"{args.pieces_per_floe:g} area pieces a floe; bench/ocean's pack: {state:.0f} of {FLOES} floes within "
    f"{r.max():.1f} + 1 m of its square's edges, {straddle:.0f} across them",
    f"# assumed network: latency {args.alpha_us} us, {args.node_gbs} GB/s a node shared by {args.ranks_per_node} ranks, "
    f"{args.memory_gbs} GB/s a rank within a node",
    "# per rank and step, ms: compute = the step less its transforms; fft = the transforms' work on the rank's share "
    "of the whole sea; for slabs and for square blocks: the transposes, the halo, the step and the efficiency "
    "T(1) / T(P); reductions (both)",
    f"# today (the step that runs, slabs): the planned slabs' step plus the whole-pack all-gathers "
    f"({'zero: --no-whole' if args.no_whole else f'{args.whole_bytes_explicit:g} B a floe a step explicit, {args.whole_bytes_implicit:g} implicit, every floe to every rank'}; "
    f"MB received a step and ms), the passes over every floe ({0 if args.no_whole else args.whole_pass_ns:g} ns a floe a step), "
    f"the implicit step's whole sea (its transforms on every rank); the step, its efficiency against T(1) and the floes' "
    f"whole-pack arrays per rank ({0 if args.no_whole else args.floe_memory_bytes:g} B a floe, MB)",
    "integrator,ranks,floes,cells,compute_ms,fft_ms,slab_transpose_ms,slab_halo_ms,slab_step_ms,slab_efficiency,"
    "block_transpose_ms,block_halo_ms,block_step_ms,block_efficiency,reductions_ms,"
    "today_whole_mb,today_whole_exchange_ms,today_whole_passes_ms,today_whole_sea_ms,today_step_ms,today_efficiency,"
    "today_floe_memory_mb",
] + [",".join(str(x) for x in r) for r in rows]
text = "\n".join(lines) + "\n"
if args.csv != "-":
    with open(args.csv, "w") as f:
        f.write(text)
sys.stdout.write(text)
