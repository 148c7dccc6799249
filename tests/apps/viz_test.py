#!/usr/bin/env python3
"""Tests of `floesim render` and `floesim plot` and of the XDMF beside a run.

usage: viz_test.py FLOESIM SOURCE_DIR CASE
Most cases draw synthetic run files written here with h5py in the run-file
layout of docs/formats.md (so they do not depend on the physics), and check
pixels where the layout says a floe or a wave crest must be. Colours are
checked against the colour-map anchors documented in docs/render.md.
Exit 0 pass, 77 skipped (ctest SKIP_RETURN_CODE), anything else a failure.
"""
import os
import shutil
import struct
import subprocess
import sys
import tempfile
import zlib
import xml.etree.ElementTree as ET

import h5py
import numpy as np

from harness import Cli, check, keyvals

FLOESIM, SRC, CASE = sys.argv[1], sys.argv[2], sys.argv[3]
WORK = os.environ.get("FLOESIM_VIZ_WORK") or tempfile.mkdtemp(prefix="floesim_viz_")
run = Cli(FLOESIM, WORK).run
SKIP = 77

# docs/render.md: anchors of the colour maps, evenly spaced on [0, 1].
SEA = [(0.03, 0.15, 0.36), (0.13, 0.38, 0.64), (0.42, 0.66, 0.84), (0.88, 0.95, 0.98)]
SPEED = [(1.00, 0.96, 0.70), (0.99, 0.70, 0.30), (0.89, 0.30, 0.13), (0.55, 0.03, 0.12)]
HEAVE = [(0.05, 0.45, 0.25), (0.94, 0.94, 0.94), (0.50, 0.12, 0.55)]
STATIC = (0.55, 0.55, 0.55)
OPEN_WATER = (0.80, 0.85, 0.89)
LINES = [(0.12, 0.47, 0.71), (0.90, 0.45, 0.05), (0.17, 0.60, 0.17), (0.80, 0.15, 0.15)]


def cmap(anchors, t):
    t = min(max(t, 0.0), 1.0) * (len(anchors) - 1)
    k = min(int(t), len(anchors) - 2)
    f = t - k
    return tuple(255 * (a + f * (b - a)) for a, b in zip(anchors[k], anchors[k + 1]))


def rgb255(c):
    return tuple(255 * v for v in c)


def read_png(path):
    """An 8-bit RGB or RGBA PNG as an [h, w, 3] uint8 array (our own small decoder)."""
    with open(path, "rb") as f:
        data = f.read()
    check(data[:8] == b"\x89PNG\r\n\x1a\n", f"{path} is a PNG")
    pos, idat, w = 8, b"", 0
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            w, h, depth, colour = struct.unpack(">IIBB", body[:10])
            check(depth == 8 and colour in (2, 6), f"8-bit RGB(A) PNG (depth {depth}, colour type {colour})")
            bpp = 3 if colour == 2 else 4
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    raw = zlib.decompress(idat)
    stride = w * bpp
    rows = []
    prev = np.zeros(stride, dtype=np.int64)
    for r in range(h):
        ftype = raw[r * (stride + 1)]
        line = np.frombuffer(raw, dtype=np.uint8, count=stride, offset=r * (stride + 1) + 1).astype(np.int64)
        if ftype == 0:
            out = line
        elif ftype == 1:  # Sub: a running sum along the row, per channel
            out = np.cumsum(line.reshape(w, bpp), axis=0).ravel() % 256
        elif ftype == 2:  # Up
            out = (line + prev) % 256
        else:  # Average, Paeth: sequential along the row
            cur, up, out = line.tolist(), prev.tolist(), [0] * stride
            for i in range(stride):
                a = out[i - bpp] if i >= bpp else 0
                b = up[i]
                if ftype == 3:
                    pred = (a + b) // 2
                else:
                    c = up[i - bpp] if i >= bpp else 0
                    pa, pb, pc = abs(b - c), abs(a - c), abs(a + b - 2 * c)
                    pred = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
                out[i] = (cur[i] + pred) & 255
            out = np.array(out, dtype=np.int64)
        rows.append(out)
        prev = out
    return np.array(rows).reshape(h, w, bpp)[:, :, :3].astype(np.uint8)


def near(pixel, colour, tol):
    return max(abs(int(p) - c) for p, c in zip(pixel, colour)) <= tol


def to_pixel(kv, x, y):
    """World (x, y) to pixel (column, row) from render's `view` and `map_pixels` lines."""
    xmin, xmax, ymin, ymax = map(float, kv["view"].split())
    left, top, w, h = map(float, kv["map_pixels"].split())
    return int(left + (x - xmin) / (xmax - xmin) * w), int(top + h - (y - ymin) / (ymax - ymin) * h)


def square(cx, cy, half):
    return [(-half, -half), (half, -half), (half, half), (-half, half)]


def write_run(path, floes, state, times, sea=None, energy=None):
    """A run file in the floesim-1 layout. floes: list of (body vertices, static);
    state: [T, n, 12]; sea: (x, y, eta) with eta [T, ny, nx] or [T, nx]."""
    with h5py.File(path, "w") as f:
        f.attrs["format"] = "floesim-1"
        f.attrs["status"] = "complete"
        f.attrs["config"] = ""
        f["time"] = np.asarray(times, dtype=float)
        off = np.cumsum([0] + [len(v) for v, _ in floes]).astype(np.int64)
        f["floes/offsets"] = off
        f["floes/vertices"] = np.array([p for v, _ in floes for p in v], dtype=float).reshape(-1, 2)
        n = len(floes)
        f["floes/thickness"] = np.ones(n)
        f["floes/mass"] = np.ones(n)
        f["floes/area"] = np.ones(n)
        f["floes/static"] = np.array([s for _, s in floes], dtype=np.uint8)
        f["floes/state"] = np.asarray(state, dtype=float)
        T = len(times)
        e = np.zeros((T, 3)) if energy is None else energy
        f["diagnostics/energy"] = e
        f["diagnostics/energy"].attrs["columns"] = ["kinetic", "potential", "total"][:e.shape[1]]
        f["diagnostics/lcp"] = np.cumsum(np.ones((T, 4)) * [3, 20, 0, 1], axis=0)
        f["diagnostics/lcp"].attrs["columns"] = ["solves", "pivots", "failures", "fallbacks"]
        if sea is not None:
            f["sea/x"], f["sea/y"], f["sea/eta"] = sea


# The synthetic scene: a 200 m x 100 m sea with one wave along x,
# eta = 0.5 sin(2 pi x / 100) (crest at x = 25, trough at x = 75), and four
# square floes at two records (t = 0, 10 s):
#   0 at (40, 70) at rest, heave -0.3;  1 at (100, 70), v = (2, 0), heave 0.1;
#   2 at (160, 70) at t = 0 only (NaN at t = 10: it no longer exists);
#   3 at (100, 20), static (an obstacle).
def scene(path):
    nx, ny = 100, 50
    x = (np.arange(nx) + 0.5) * 2.0
    y = (np.arange(ny) + 0.5) * 2.0
    eta1 = np.tile(0.5 * np.sin(2 * np.pi * x / 100.0), (ny, 1))
    eta = np.stack([0.2 * eta1, eta1])
    floes = [(square(0, 0, 8), 0)] * 3 + [(square(0, 0, 8), 1)]
    st = np.zeros((2, 4, 12))
    for k in range(2):
        st[k, :, 0:2] = [(40, 70), (100, 70), (160, 70), (100, 20)]
        st[k, 1, 3] = 2.0
        st[k, 0, 6], st[k, 1, 6] = -0.3, 0.1
    st[1, 2, :] = np.nan
    write_run(path, floes, st, [0.0, 10.0], sea=(x, y, eta),
              energy=np.array([[1.0, 2.0, 3.0], [2.0, 1.5, 3.5]]))
    return lambda xw: 0.5 * np.sin(2 * np.pi * xw / 100.0)


def case_render_colours():
    path = os.path.join(WORK, "scene.h5")
    eta = scene(path)
    p = run("render", path, "--time", "10", "--size", "800x500", "-o", "s.png")
    kv = keyvals(p.stdout)
    check(kv["record"] == "1" and float(kv["time"]) == 10.0, "record nearest to t = 10")
    img = read_png(os.path.join(WORK, "s.png"))
    check(img.shape == (500, 800, 3), f"picture size 800x500, got {img.shape}")
    px = lambda x, y: img[to_pixel(kv, x, y)[1], to_pixel(kv, x, y)[0]]
    # Speed range [0, 2]: floe 0 gets the map's first anchor, floe 1 its last.
    check(near(px(40, 70), cmap(SPEED, 0.0), 3), f"floe at rest: {px(40, 70)} vs {cmap(SPEED, 0.0)}")
    check(near(px(100, 70), cmap(SPEED, 1.0), 3), f"fastest floe: {px(100, 70)} vs {cmap(SPEED, 1.0)}")
    check(near(px(100, 20), rgb255(STATIC), 3), f"static floe grey: {px(100, 20)}")
    # Floe 2 does not exist at t = 10: the sea shows where it was.
    for xw in (155.0, 160.0, 165.0):
        want = cmap(SEA, (eta(xw) + 0.5) / 1.0)
        check(near(px(xw, 70), want, 10), f"sea where the missing floe was, x = {xw}: {px(xw, 70)} vs {want}")
    # The sea: crest light, trough dark, as the map says.
    check(near(px(25, 45), cmap(SEA, 1.0), 10), f"crest colour {px(25, 45)}")
    check(near(px(75, 45), cmap(SEA, 0.0), 10), f"trough colour {px(75, 45)}")
    # A time stamp above the map and two colour legends right of it: dark ink there.
    left, top, w, h = map(float, kv["map_pixels"].split())
    check((img[:int(top), :, :].max(axis=2) < 80).sum() > 50, "time stamp drawn above the map")
    legend = img[:, int(left + w) + 5:, :]
    check(sum(1 for c in (cmap(SPEED, 0.5), cmap(SEA, 0.5))
              if (np.abs(legend.astype(int) - c).max(axis=2) <= 4).sum() > 20) == 2, "both colour bars drawn")
    # At t = 0 floe 2 exists (speed 0: the first anchor).
    kv0 = keyvals(run("render", path, "--time", "0", "--size", "800x500", "-o", "s0.png").stdout)
    img0 = read_png(os.path.join(WORK, "s0.png"))
    c, r = to_pixel(kv0, 160, 70)
    check(near(img0[r, c], cmap(SPEED, 0.0), 3), f"floe 2 drawn at t = 0: {img0[r, c]}")


def case_render_heave():
    path = os.path.join(WORK, "scene.h5")
    scene(path)
    kv = keyvals(run("render", path, "--color", "heave", "--size", "640x400", "-o", "h.png").stdout)
    check(kv["record"] == "1", "default record: the last")
    img = read_png(os.path.join(WORK, "h.png"))
    check(img.shape == (400, 640, 3), "size")
    # Heave range symmetric: [-0.3, 0.3]; floe 0 at -0.3, floe 1 at 0.1.
    lo, hi = map(float, kv["floe_range"].split())
    check(abs(lo + 0.3) < 1e-12 and abs(hi - 0.3) < 1e-12, f"heave range {lo} {hi}")
    c, r = to_pixel(kv, 40, 70)
    check(near(img[r, c], cmap(HEAVE, 0.0), 3), f"floe 0 heave colour {img[r, c]}")
    c, r = to_pixel(kv, 100, 70)
    check(near(img[r, c], cmap(HEAVE, (0.1 + 0.3) / 0.6), 3), f"floe 1 heave colour {img[r, c]}")


def case_render_band():
    # A dims-1 sea (eta [T, nx]) is drawn as a band over its y extent [0, 0.6].
    nx = 120
    x = (np.arange(nx) + 0.5) * 0.1
    eta = np.stack([0.01 * np.cos(2 * np.pi * x / 4.0)] * 2)
    st = np.zeros((2, 1, 12))
    st[:, 0, 0:2] = (6.0, 3.0)
    path = os.path.join(WORK, "band.h5")
    write_run(path, [(square(0, 0, 0.2), 0)], st, [0.0, 0.1], sea=(x, np.array([0.3]), eta))
    kv = keyvals(run("render", path, "--size", "700x400", "-o", "b.png").stdout)
    img = read_png(os.path.join(WORK, "b.png"))
    px = lambda xw, yw: img[to_pixel(kv, xw, yw)[1], to_pixel(kv, xw, yw)[0]]
    check(near(px(8.0, 0.3), cmap(SEA, 1.0), 10), f"band crest at x = 8: {px(8.0, 0.3)}")
    check(near(px(6.0, 0.3), cmap(SEA, 0.0), 10), f"band trough at x = 6: {px(6.0, 0.3)}")
    check(near(px(2.0, 2.0), rgb255(OPEN_WATER), 2), f"outside the band: open water {px(2.0, 2.0)}")
    check(near(px(6.0, 3.0), cmap(SPEED, 0.0), 3), "the floe above the band")


def case_render_frames():
    path = os.path.join(WORK, "scene.h5")
    scene(path)
    kv = keyvals(run("render", path, "--frames", "fr", "--size", "320x200").stdout)
    files = sorted(os.listdir(os.path.join(WORK, "fr")))
    check(kv["frames"] == "2" and files == ["frame_00000.png", "frame_00001.png"], f"two frames: {files}")
    for name in files:
        check(read_png(os.path.join(WORK, "fr", name)).shape == (200, 320, 3), "frame size")
    # Fixed scales across frames: the sea range covers both records (0.5).
    check(kv["sea_range"] == "-0.5 0.5", f"sea range over all frames: {kv['sea_range']}")
    # Without ffmpeg on PATH: frames kept, a clear note, exit 0.
    env = dict(os.environ, PATH=os.path.join(WORK, "empty"))
    os.makedirs(env["PATH"], exist_ok=True)
    p = run("render", path, "--frames", "fr2", "--mp4", "--size", "320x200", env=env)
    check("ffmpeg is not installed" in p.stderr and keyvals(p.stdout)["video"].startswith("skipped"),
          f"graceful without ffmpeg: {p.stderr}")
    check(len(os.listdir(os.path.join(WORK, "fr2"))) == 2, "frames kept without ffmpeg")


def case_render_mp4():
    if shutil.which("ffmpeg") is None:
        print("ffmpeg not installed: skipped")
        sys.exit(SKIP)
    path = os.path.join(WORK, "scene.h5")
    scene(path)
    kv = keyvals(run("render", path, "--mp4", "--size", "321x201", "-o", "v.mp4").stdout)
    out = os.path.join(WORK, "v.mp4")
    check(kv["video"] == out or os.path.realpath(kv["video"]) == os.path.realpath(out), "video path printed")
    with open(out, "rb") as f:
        head = f.read(12)
    check(head[4:8] == b"ftyp", "an MP4 container")
    if shutil.which("ffprobe"):
        p = subprocess.run(["ffprobe", "-v", "error", "-count_frames", "-select_streams", "v:0", "-show_entries",
                            "stream=nb_read_frames,width,height", "-of", "csv=p=0", out],
                           capture_output=True, text=True)
        w, h, frames = p.stdout.strip().split(",")
        check((w, h, frames) == ("322", "202", "2"), f"2 frames of 322x202 (odd size padded): {p.stdout}")


def case_render_errors():
    path = os.path.join(WORK, "scene.h5")
    scene(path)
    p = run("render", "nothere.h5", expect=2)
    check("nothere.h5" in p.stderr and "not found" in p.stderr, f"missing file named: {p.stderr}")
    p = run("render", path, "--time", "11", expect=2)
    check("scene.h5" in p.stderr and "outside the run" in p.stderr and "10" in p.stderr, f"time outside: {p.stderr}")
    p = run("render", path, "--color", "vorticity", expect=2)
    check("vorticity" in p.stderr and "speed or heave" in p.stderr, f"unknown colour field: {p.stderr}")
    p = run("render", path, "--size", "12x5", expect=2)
    check("--size" in p.stderr, f"bad size: {p.stderr}")
    p = run("render", path, "--time", "1", "--frames", "d", expect=2)
    # A run file without /floes/state: named.
    with h5py.File(os.path.join(WORK, "broken.h5"), "w") as f:
        f.attrs["format"] = "floesim-1"
        f["time"] = np.zeros(1)
        f["floes/offsets"] = np.zeros(1, dtype=np.int64)
        f["floes/vertices"] = np.zeros((0, 2))
    p = run("render", "broken.h5", expect=2)
    check("broken.h5" in p.stderr and "/floes/state" in p.stderr, f"missing dataset named: {p.stderr}")


def case_plot():
    path = os.path.join(WORK, "scene.h5")
    scene(path)
    # heave: by default the moving floes (0, 1 and 2; 3 is static).
    for what, n in (("energy", 3), ("lcp", 4), ("heave", 3)):
        kv = keyvals(run("plot", path, what, "--size", "600x400").stdout)
        out = os.path.join(WORK, f"scene_{what}.png")
        check(kv["output"] == out or os.path.realpath(kv["output"]) == os.path.realpath(out), f"{what}: default name")
        check(int(kv["series"]) == n, f"{what}: {n} series, got {kv['series']}")
        img = read_png(out)
        check(img.shape == (400, 600, 3), f"{what}: size")
        # Each series in its own colour (energy, heave: the legend; lcp: one per panel, colour 0).
        colours = LINES[:n] if what != "lcp" else LINES[:1]
        for c in colours:
            hits = (np.abs(img.astype(int) - rgb255(c)).max(axis=2) <= 12).sum()
            check(hits >= 15, f"{what}: a line of colour {c} ({hits} pixels)")
        # Tick labels and axis labels: dark ink left of and below the axes.
        check((img[:, :60].max(axis=2) < 90).sum() > 40, f"{what}: y labels drawn")
        check((img[-40:, :].max(axis=2) < 90).sum() > 40, f"{what}: x labels drawn")
    run("plot", path, "heave", "--floes", "1", "-o", "one.png")
    p = run("plot", path, "heave", "--floes", "0,7", expect=2)
    check("--floes" in p.stderr and "'7'" in p.stderr, f"floe index out of range: {p.stderr}")
    p = run("plot", path, "spectrum", expect=2)
    check("spectrum" in p.stderr and "energy, lcp, heave or fracture" in p.stderr, f"unknown plot: {p.stderr}")
    p = run("plot", "nothere.h5", "energy", expect=2)
    check("nothere.h5" in p.stderr, "missing file named")
    # fracture: examples/percussion.toml splits both floes (docs/fracture.md):
    # the floe count goes from 2 to 2 + the splits of /events/fracture.
    perc = os.path.join(WORK, "perc.h5")
    run("run", os.path.join(SRC, "examples", "percussion.toml"), "-q", "-o", perc)
    kv = keyvals(run("plot", perc, "fracture", "--size", "600x400").stdout)
    with h5py.File(perc, "r") as f:
        ev = f["events/fracture"][:]
        cols = [c.decode() if isinstance(c, bytes) else c for c in f["events/fracture"].attrs["columns"]]
    splits = int((ev[:, cols.index("piece_a")] >= 0).sum())
    check(splits >= 1, f"percussion example splits ({splits})")
    check(kv["floes"] == f"2 -> {2 + splits}", f"fracture: floe count {kv['floes']} with {splits} splits")
    check(int(kv["series"]) == 6, f"fracture: count + 5 size classes, got {kv['series']}")
    check(read_png(kv["output"]).shape == (400, 600, 3), "fracture: size")


# ------------------------------------------------------------------ real runs

FLOES_ON_SEA = """
[run]
t_end = 3.0
dt_max = 0.1
output_interval = 1.0

[sea]
model = "spectral"
dims = DIMS
size = [200.0, 100.0]
cells = CELLS
depth = 40.0

[sea.waves]
kind = "regular"
amplitude = 0.25
wavelength = 50.0

[[floes.floe]]
vertices = [[40, 40], [60, 40], [60, 60], [40, 60]]
thickness = 1.0

[[floes.floe]]
vertices = [[120, 30], [150, 30], [140, 70]]
thickness = 1.0
"""


def real_run(name, dims):
    cfg = os.path.join(WORK, name + ".toml")
    with open(cfg, "w") as f:
        f.write(FLOES_ON_SEA.replace("DIMS", str(dims)).replace("CELLS", "[64, 32]" if dims == 2 else "[64, 1]"))
    run("run", cfg, "-q", "-o", name + ".h5")
    return os.path.join(WORK, name + ".h5")


def case_render_run():
    # A real run (two floes on a regular wave): the picture shows both floes and a varying sea.
    path = real_run("fw", 2)
    kv = keyvals(run("render", path, "--size", "640x360").stdout)
    img = read_png(os.path.join(WORK, "fw.png"))
    check(img.shape == (360, 640, 3), "size")
    with h5py.File(path) as f:
        st = f["floes/state"][-1]
    for i in range(2):
        c, r = to_pixel(kv, st[i, 0], st[i, 1])
        pix = img[r, c]
        check(int(pix[0]) > int(pix[2]), f"floe {i} drawn in a speed colour (warm), got {pix}")
    c0, r0 = to_pixel(kv, 10, 90)
    row = img[r0, c0:to_pixel(kv, 190, 90)[0]].astype(int)
    check(row.max(axis=0).sum() - row.min(axis=0).sum() > 60, "the sea colour varies along a wave")


# ------------------------------------------------------------------ XDMF

def check_hdf_item(f, item, h5name):
    """An HDF DataItem, "file:/dataset" or, for a hyperslab in the Xdmf3 library's
    notation, "file:/dataset|start:stride:count:dataset dims"."""
    kinds = {"Float": "f", "Int": "i", "UInt": "u"}
    ref, _, sel = item.text.strip().partition("|")
    fname, dset = ref.split(":")
    check(fname == h5name, "file name relative to the .xmf")
    check(dset in f, f"{dset} exists")
    d = f[dset]
    declared = tuple(int(v) for v in item.get("Dimensions").split())
    check(d.dtype.kind == kinds[item.get("NumberType", "Float")], f"{dset}: number type")
    check(d.dtype.itemsize == int(item.get("Precision", "4")), f"{dset}: precision")
    if not sel:
        check(d.shape == declared, f"{dset}: declared {declared}, dataset {d.shape}")
        return
    start, stride, count, full = (np.array(part.split(), dtype=int) for part in sel.split(":"))
    check(tuple(full) == d.shape, f"{dset}: slab of {tuple(full)}, dataset {d.shape}")
    check(len(start) == len(stride) == len(count) == d.ndim, f"{dset}: slab rank")
    check(np.all(start >= 0) and np.all(start + stride * (count - 1) < full), f"{dset}: slab in bounds")
    check(int(np.prod(count)) == int(np.prod(declared)), f"{dset}: slab size = declared dimensions")


# The XDMF 3 subset our writer may use, as a schema: for each element, the
# attributes it may carry (None: any value; a set: one of those values) and the
# children it may have. A misspelt attribute or value is not an error for
# ParaView, which then silently ignores it: here it fails.
XDMF_SCHEMA = {
    "Xdmf": ({"Version": {"3.0"}}, {"Domain"}),
    "Domain": ({}, {"Grid"}),
    "Grid": ({"Name": None, "GridType": {"Collection", "Uniform"}, "CollectionType": {"Temporal"}},
             {"Grid", "Time", "Topology", "Geometry", "Attribute"}),
    "Time": ({"Value": None}, set()),
    "Topology": ({"TopologyType": {"Mixed", "3DCoRectMesh"}, "NumberOfElements": None, "Dimensions": None},
                 {"DataItem"}),
    "Geometry": ({"GeometryType": {"XYZ", "ORIGIN_DXDYDZ"}}, {"DataItem"}),
    "Attribute": ({"Name": None, "AttributeType": {"Scalar"}, "Center": {"Cell", "Node"}}, {"DataItem"}),
    "DataItem": ({"Dimensions": None, "NumberType": {"Float", "Int", "UInt"}, "Precision": {"4", "8"},
                  "Format": {"HDF", "XML"}, "ItemType": {"Uniform"}}, set()),
}


def check_schema(el, path="Xdmf"):
    check(el.tag in XDMF_SCHEMA, f"{path}: unknown element <{el.tag}>")
    attrs, children = XDMF_SCHEMA[el.tag]
    for k, v in el.attrib.items():
        check(k in attrs, f"{path}: <{el.tag}> has no attribute {k}")
        check(attrs[k] is None or v in attrs[k], f"{path}: <{el.tag} {k}=\"{v}\"> not one of {attrs[k]}")
    for c in el:
        check(c.tag in children, f"{path}: <{c.tag}> inside <{el.tag}>")
        check_schema(c, f"{path}/{c.tag}[{c.get('Name', '')}]")
    if el.tag == "DataItem":
        check("Dimensions" in el.attrib and el.text and el.text.strip(), f"{path}: DataItem with dimensions and content")
        dims = [int(v) for v in el.get("Dimensions").split()]
        check(all(d > 0 for d in dims), f"{path}: positive dimensions {dims}")
        if el.get("Format", "XML") == "XML":
            check(len(el.text.split()) == int(np.prod(dims)), f"{path}: {int(np.prod(dims))} inline values")
    if el.tag == "Grid" and el.get("GridType") == "Uniform":
        for tag in ("Time", "Topology", "Geometry"):
            check(len(el.findall(tag)) == 1, f"{path}: one <{tag}>")
    if el.tag == "Grid" and el.get("GridType") == "Collection":
        check(all(c.tag == "Grid" for c in el) and len(el) > 0, f"{path}: a collection holds grids")


def read_hdf_item(f, item):
    """The values an HDF DataItem selects (the whole dataset or its hyperslab)."""
    ref, _, sel = item.text.strip().partition("|")
    data = f[ref.split(":")[1]]
    if not sel:
        return data[()]
    start, stride, count, _ = (np.array(part.split(), dtype=int) for part in sel.split(":"))
    return data[tuple(slice(a, a + b * (c - 1) + 1, b) for a, b, c in zip(start, stride, count))]


def check_mixed_topology(f, topo, geo, name):
    """A Mixed topology lists polygons as (3, n, n node indices): exactly
    NumberOfElements of them, filling the item, every index a node of the
    geometry, every node used."""
    tp = read_hdf_item(f, topo.find("DataItem")).ravel()
    check(geo.get("GeometryType") == "XYZ", f"{name}: XYZ geometry")
    gdims = [int(v) for v in geo.find("DataItem").get("Dimensions").split()]
    check(len(gdims) == 2 and gdims[1] == 3, f"{name}: geometry of (nodes, 3), got {gdims}")
    k, polys, used = 0, 0, np.zeros(gdims[0], dtype=bool)
    while k < len(tp):
        check(tp[k] == 3 and k + 1 < len(tp) and tp[k + 1] >= 3, f"{name}: polygon record at {k}")
        n = int(tp[k + 1])
        idx = tp[k + 2:k + 2 + n]
        check(len(idx) == n and np.all((idx >= 0) & (idx < gdims[0])), f"{name}: polygon {polys} node indices")
        used[idx] = True
        k += 2 + n
        polys += 1
    check(polys == int(topo.get("NumberOfElements")), f"{name}: {polys} polygons, declared {topo.get('NumberOfElements')}")
    check(bool(used.all()), f"{name}: every geometry node belongs to a polygon")


def validate_xdmf(h5path):
    """The XML against XDMF_SCHEMA; every HDF DataItem names an existing dataset
    with the declared dimensions, number type and precision; every hyperslab is in
    bounds and as large as declared; times strictly increase and every collection
    has the run file's records; a Mixed topology's polygons index its geometry;
    every attribute has one value per cell or node of its grid."""
    xmf = os.path.splitext(h5path)[0] + ".xmf"
    root = ET.parse(xmf).getroot()
    check_schema(root)
    check(root.tag == "Xdmf" and root.get("Version") == "3.0", "Xdmf 3")
    grids = 0
    with h5py.File(h5path) as f:
        T = f["time"].shape[0]
        for coll in root.findall("./Domain/Grid"):
            check(coll.get("GridType") == "Collection" and coll.get("CollectionType") == "Temporal", "temporal")
            steps = coll.findall("Grid")
            check(len(steps) == T, f"{coll.get('Name')}: one grid per record ({len(steps)} vs {T})")
            times = np.array([float(g.find("Time").get("Value")) for g in steps])
            check(bool(np.all(np.diff(times) > 0)), f"{coll.get('Name')}: times strictly increase")
            for k, g in enumerate(steps):
                grids += 1
                check(abs(float(g.find("Time").get("Value")) - f["time"][k]) <= 1e-9 * max(1, abs(f["time"][k])),
                      "grid time = record time")
                for item in g.iter("DataItem"):
                    check(item.get("ItemType") in (None, "Uniform"), "no XDMF2 HyperSlab items (ParaView skips them)")
                    if item.get("Format") != "HDF":
                        continue
                    check_hdf_item(f, item, os.path.basename(h5path))
                topo, geo = g.find("Topology"), g.find("Geometry")
                if topo.get("TopologyType") == "Mixed":
                    check_mixed_topology(f, topo, geo, g.get("Name"))
                    cells = int(topo.get("NumberOfElements"))
                    check(cells == f["floes/thickness"].shape[0], "one polygon per floe")
                    nodes = f["floes/vertices"].shape[0]
                else:
                    # A flat 3D grid, one layer (z, y, x order).
                    check(topo.get("TopologyType") == "3DCoRectMesh", "sea grid")
                    nz, ny, nx = (int(v) for v in topo.get("Dimensions").split())
                    check(nz == 1 and nx == f["sea/x"].shape[0], "sea: one layer of nx points")
                    check(geo.get("GeometryType") == "ORIGIN_DXDYDZ", "sea origin and spacing")
                    o = [float(v) for v in geo.findall("DataItem")[0].text.split()]
                    dxy = [float(v) for v in geo.findall("DataItem")[1].text.split()]
                    check(abs(o[2] - f["sea/x"][0]) < 1e-9 and abs(o[2] + (nx - 1) * dxy[2] - f["sea/x"][-1]) < 1e-6,
                          "sea x origin and spacing = /sea/x")
                    if f["sea/eta"].ndim == 3:
                        check(ny == f["sea/y"].shape[0] and abs(o[1] - f["sea/y"][0]) < 1e-9, "sea y = /sea/y")
                    else:
                        check(ny == 1, "a dims-1 sea is one row")
                    cells, nodes = max(nx - 1, 1) * max(ny - 1, 1), nx * ny
                for a in g.findall("Attribute"):
                    size = int(np.prod([int(v) for v in a.find("DataItem").get("Dimensions").split()]))
                    want = cells if a.get("Center") == "Cell" else nodes
                    check(size == want, f"attribute {a.get('Name')}: {size} values for {want} {a.get('Center')}s")
    return grids


def rejected(path, old, new, what):
    """validate_xdmf fails on the XDMF of `path` with its first `old` replaced by `new`."""
    xmf = os.path.splitext(path)[0] + ".xmf"
    text = open(xmf).read()
    check(old in text, f"mutation '{what}': {old!r} in the XDMF")
    folder = tempfile.mkdtemp(dir=WORK)
    shutil.copy(path, folder)
    copy = os.path.join(folder, os.path.basename(path))
    with open(os.path.splitext(copy)[0] + ".xmf", "w") as out:
        out.write(text.replace(old, new, 1))
    try:
        validate_xdmf(copy)
    except SystemExit as e:
        check(str(e.code).startswith("FAILED"), f"mutation '{what}': failed through a check, got {e.code}")
        return
    check(False, f"the XDMF check accepts a file with {what}")


def case_xdmf_sea():
    for dims in (2, 1):
        path = real_run(f"x{dims}", dims)
        grids = validate_xdmf(path)
        with h5py.File(path) as f:
            check(grids == 2 * f["time"].shape[0], f"dims {dims}: floes and sea grids at every record")
            T = f["time"].shape[0]
            nodes = f["floes/vertices"].shape[0]
            n = f["floes/thickness"].shape[0]
    # The check is strict: each of these faults, one at a time, fails it.
    check(T >= 3, "at least three records")
    rejected(path, 'AttributeType="Scalar"', 'AttributeType="Scaler"', "a misspelt attribute value")
    rejected(path, 'Center="Cell"', 'Centre="Cell"', "a misspelt attribute name")
    rejected(path, '<Grid Name="floes_1" GridType="Uniform"><Time Value="',
             '<Grid Name="floes_1" GridType="Uniform"><Time Value="-1', "times not increasing")
    rejected(path, f'NumberOfElements="{n}"', f'NumberOfElements="{n + 1}"', "one polygon too many declared")
    rejected(path, f'Dimensions="{nodes} 3"', f'Dimensions="{nodes + 1} 3"', "a geometry larger than its slab")
    rejected(path, ":/floes/state|", ":/floes/states|", "a dataset that does not exist")
    rejected(path, "<Time ", "<Times ", "an unknown element")


def case_paraview():
    # ParaView's own XDMF3 reader (Debian python3-paraview), when installed.
    pv = shutil.which("pvpython")
    if pv is None:
        print("pvpython (Debian python3-paraview) not installed: skipped")
        sys.exit(SKIP)
    for dims in (2, 1):
        path = real_run(f"p{dims}", dims)
        script = os.path.join(SRC, "tests", "apps", "paraview_check.py")
        p = subprocess.run([pv, "--force-offscreen-rendering", script, os.path.splitext(path)[0] + ".xmf", path],
                           capture_output=True, text=True, timeout=280)
        check(p.returncode == 0 and "paraview: ok" in p.stdout,
              f"ParaView reads the XDMF (dims {dims}):\nstdout:\n{p.stdout}\nstderr:\n{p.stderr}")


if __name__ == "__main__":
    globals()["case_" + CASE]()
    print(f"{CASE}: ok")
