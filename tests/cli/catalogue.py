#!/usr/bin/env python3
"""The catalogue of malformed inputs and faults (issue 17, docs/reliability.md).

usage: catalogue.py FLOESIM SOURCE_DIR

One table: each case runs `floesim` as a user would and asserts its exit code
(2: bad input or usage; 1: the run failed, including a full disk or an
unwritable output), the words of its message, and for some what is left on
disk. No case may end in a signal, an abort or a hang (a 60 s timeout each).
Classes: TOML syntax, keys, types and ranges; the forcing CSV; pack HDF5;
FloeDyn HDF5; LCP files; command-line options; a full disk; an unwritable
output; run errors. Exits non-zero listing every case that failed.
"""
import os
import resource
import signal
import struct
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

import h5py
import numpy as np

FLOESIM, SRC = sys.argv[1], sys.argv[2]
WORK = tempfile.mkdtemp(prefix="floesim_catalogue_")
os.chmod(WORK, 0o755)  # the read-only-folder case runs as another user
CASES = []  # dicts: name, cls, args, code, words, check, preexec


def case(cls, name, args, words, code=2, check=None, preexec=None):
    CASES.append(dict(cls=cls, name=name, args=args, words=words, code=code, check=check, preexec=preexec))


def write(name, text):
    path = os.path.join(WORK, name)
    with open(path, "w") as f:
        f.write(text)
    return path


def check(cond, msg):
    # For the fixtures (patch_dims): a broken fixture is a failure of the test itself.
    if not cond:
        sys.exit("FAILED (fixture): " + msg)


def run_ok(*args):
    p = subprocess.run([FLOESIM, *args], cwd=WORK, capture_output=True, text=True, timeout=120)
    check(p.returncode == 0, f"floesim {' '.join(args)}: exit {p.returncode}\n{p.stderr}")
    return p


# A small valid scenario: one floe, no sea, 2 s.
SMALL = ('[run]\nt_end = 2.0\ndt_max = 0.5\noutput_interval = 1.0\n\n[sea]\nmodel = "none"\n\n'
         '[[floes.floe]]\nvertices = [[0, 0], [20, 0], [20, 20], [0, 20]]\n\n[forcing]\nwind = [5.0, 0.0]\n')
HEADER = "t_s,wind_u,wind_v,current_u,current_v\n"

# Malformed forcing series (issue 17: each aborted with a double free, exit 134):
# name, CSV bytes, the line blamed, words of the message.
BAD_SERIES = [
    ("missing_column", HEADER + "0,1,2,3\n", 2, ["expected 5 columns", "got 4"]),
    ("long_row", HEADER + "0,1,2,3,4\n10,1,2,3,4,5\n", 3, ["expected 5 columns", "got 6"]),
    ("short_row", HEADER + "0,1,2,3,4\n10,1\n", 3, ["expected 5 columns", "got 2"]),
    ("decreasing", HEADER + "0,1,2,3,4\n60,1,2,3,4\n30,1,2,3,4\n", 4,
     ["expected times increasing strictly", "t_s = 30 after 60"]),
    ("duplicate", HEADER + "0,1,2,3,4\n60,1,2,3,4\n60,1,2,3,4\n", 4, ["expected times increasing strictly"]),
    ("text", HEADER + "0,1,2,three,4\n", 2, ["column 4 (current_u): expected a number, got 'three'"]),
    ("nan", HEADER + "0,nan,2,3,4\n", 2, ["column 2 (wind_u): expected a finite number, got 'nan'"]),
    ("inf", HEADER + "0,1,2,3,-inf\n", 2, ["column 5 (current_v): expected a finite number"]),
    ("empty", "", 0, ["no data row", "expected the header t_s,wind_u,wind_v,current_u,current_v"]),
    ("header_only", HEADER, 0, ["no data row"]),
    ("wrong_header", "time,u,v,cu,cv\n0,1,2,3,4\n", 1,
     ["expected the header t_s,wind_u,wind_v,current_u,current_v", "got 'time,u,v,cu,cv'"]),
    ("binary", "\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR\x00\xff", 1, ["expected the header", "'?PNG'"]),
]


def bad_pack(name, offsets=None, vertices=None, velocity=None, offsets_dataset=None, thickness=None):
    # A one-square pack file (ours), with one dataset replaced; returns a config loading it.
    square = np.array([[0, 0], [10, 0], [10, 10], [0, 10]], float)
    with h5py.File(os.path.join(WORK, name + ".h5"), "w") as f:
        f.attrs["format"] = "floesim-pack-1"
        g = f.create_group("floes")
        if offsets_dataset is not None:
            g.create_dataset("offsets", **offsets_dataset)
        else:
            g["offsets"] = np.array([0, 4]) if offsets is None else offsets
        g["vertices"] = square if vertices is None else vertices
        g["pose"] = np.array([[5.0, 5.0, 0.0]])
        if velocity is not None:
            g["velocity"] = np.array([velocity], float)
        if thickness is not None:
            g["thickness"] = np.array(thickness, float)
    return write(name + ".toml", f'[run]\nt_end = 0.1\n\n[sea]\nmodel = "none"\n\n[floes]\npack = "{name}.h5"\n')


def patch_dims(name, dataset_dims, claimed):
    # Corrupts a contiguous dataset's dataspace message in place (version 1, max
    # dims present: 1, rank, 1, 0, 4 reserved bytes, dims, max dims), as a flipped
    # byte on disk would: the file then claims `claimed` entries it does not store.
    path = os.path.join(WORK, name + ".h5")
    b = bytearray(open(path, "rb").read())
    rank = len(dataset_dims)
    pat = bytes([1, rank, 1, 0, 0, 0, 0, 0]) + struct.pack(f"<{2 * rank}Q", *dataset_dims, *dataset_dims)
    check(b.count(pat) == 1, f"{name}: one dataspace message {dataset_dims} to patch")
    i = b.find(pat) + 8
    b[i:i + 16 * rank] = struct.pack(f"<{2 * rank}Q", *claimed, *claimed)
    open(path, "wb").write(b)




# ---------------------------------------------------------------- TOML
def toml_cases():
    small = write("small.toml", SMALL)
    case("toml", "syntax: unclosed table header", ["run", write("syntax.toml", "[run\nt_end = 1\n")],
         ["syntax.toml:1"])
    case("toml", "syntax: value missing", ["run", write("syntax2.toml", "[run]\nt_end =\n")], ["syntax2.toml:2"])
    case("toml", "unknown key", ["run", write("unknown.toml", "[run]\nt_end = 10\n\n[forcing]\nwnd = [1, 2]\n")],
         ["unknown.toml:5", "[forcing] wnd"])
    case("toml", "unknown section", ["run", write("unknown_section.toml", "[rn]\nt_end = 10\n")],
         ["unknown_section.toml:1", "rn"])
    case("toml", "type: string for a number", ["run", write("type.toml", '[run]\nt_end = "ten"\n')],
         ["type.toml:2", "[run] t_end", "string"])
    case("toml", "range: dt_max < 0", ["run", write("range.toml", "[run]\ndt_max = -1.0\n")],
         ["range.toml:2", "[run] dt_max"])
    case("toml", "output_interval 1e-320",
         ["run", write("tiny_interval.toml", SMALL.replace("output_interval = 1.0", "output_interval = 1e-320"))],
         ["tiny_interval.toml:4:", "key '[run] output_interval'", "at most 10000000 records"])
    case("toml", "output_interval 1 s to 1e9 s",
         ["run", write("many_records.toml", SMALL.replace("t_end = 2.0", "t_end = 1.0e9"))],
         ["many_records.toml:4:", "[run] output_interval", ">= 100 s", "1000000002 records"])
    case("toml", "dt_max 1e-300 (a run without end)",
         ["run", write("tiny_dt.toml", SMALL.replace("dt_max = 0.5", "dt_max = 1e-300"))],
         ["tiny_dt.toml:3:", "key '[run] dt_max'", "at most 1000000000 steps", "got 1e-300 s"])
    case("toml", "a folder as CONFIG", ["run", os.path.join(WORK, "a_folder")],
         ["a_folder: is a folder", "expected a configuration file"])
    case("toml", "CONFIG not found", ["run", os.path.join(WORK, "nope.toml")], ["nope.toml", "not found"])
    case("toml", "[sea] size 1e300",
         ["run", write("big_sea.toml", '[sea]\nmodel = "spectral"\nsize = [1e300, 1e300]\ncells = [32, 32]\n'
                       '[sea.waves]\nkind = "regular"\namplitude = 0.1\nwavelength = 50\n')],
         ["big_sea.toml:3", "[sea] size", "<= 1e+09 m", "got [1e+300, 1e+300]"])
    case("toml", "[sea] cells 1e5 x 1e5",
         ["run", write("many_cells.toml", '[sea]\nmodel = "spectral"\ncells = [100000, 100000]\n')],
         ["many_cells.toml:3", "[sea] cells", "at most 16777216 cells", "got 1e+10"])
    bem = '[sea]\nmodel = "bem"\ndims = 1\nsize = [1.0, 0.1]\ncells = [32, 1]\ndepth = 0.5\n'
    case("toml", "bottom above the surface",
         ["run", write("bottom_up.toml", bem + "bottom = [[0.0, -0.1], [0.5, 0.02], [1.0, -0.1]]\n")],
         ["bottom_up.toml:7", "[sea] bottom", "below the surface", "point 1 is (0.5, 0.02) m"])
    case("toml", "bottom short of the basin",
         ["run", write("bottom_short.toml", bem + "bottom = [[0.2, -0.1], [1.0, -0.1]]\n")],
         ["bottom_short.toml:7", "span the basin [0, 1] m"])
    case("toml", "bottom on a spectral sea",
         ["run", write("bottom_spectral.toml", '[sea]\nmodel = "spectral"\nbottom = [[0.0, -1.0], [300.0, -1.0]]\n')],
         ["bottom_spectral.toml:3", "[sea] bottom", "needs model = \"bem\""])
    # A 3D basin's bottom grid in HDF5 (bottom_file): the file and the dataset at fault.
    bem3d = '[sea]\nmodel = "bem"\ndims = 2\nsize = [1.0, 0.5]\ncells = [8, 4]\ndepth = 0.2\n'
    with h5py.File(os.path.join(WORK, "bottom_noz.h5"), "w") as f:
        f["x"] = np.linspace(0.0, 1.0, 3)
        f["y"] = np.linspace(0.0, 0.5, 2)
    case("toml", "HDF5 bottom without /z",
         ["run", write("bottom_noz.toml", bem3d + 'bottom_file = "bottom_noz.h5"\n')],
         ["bottom_noz.toml:7", "[sea] bottom_file", "bottom_noz.h5: dataset '/z' is missing"])
    with h5py.File(os.path.join(WORK, "bottom_dry.h5"), "w") as f:
        f["z"] = np.array([[-0.2, -0.1, -0.2], [-0.2, np.nan, -0.2]])
        f["x"] = np.linspace(0.0, 1.0, 3)
        f["y"] = np.linspace(0.0, 0.5, 2)
    case("toml", "HDF5 bottom with a NaN depth",
         ["run", write("bottom_dry.toml", bem3d + 'bottom_file = "bottom_dry.h5"\n')],
         ["bottom_dry.h5: dataset /z", "finite and below the surface", "at [1, 1]"])
    with h5py.File(os.path.join(WORK, "bottom_grid.h5"), "w") as f:
        f["z"] = -0.2 * np.ones((2, 3))
        f["x"] = np.linspace(0.0, 2.0, 3)
        f["y"] = np.linspace(0.0, 0.5, 2)
    case("toml", "HDF5 bottom grid not spanning the basin",
         ["run", write("bottom_grid.toml", bem3d + 'bottom_file = "bottom_grid.h5"\n')],
         ["bottom_grid.h5: dataset /x", "evenly spaced from 0 to 1 m"])
    case("toml", "tank zones in a bem basin", ["run", write("tank_bem.toml", bem + "[sea.tank]\nenabled = true\n")],
         ["tank_bem.toml:8", "[sea.tank] enabled", "need model = \"spectral\""])
    case("toml", "tank zones without a regular wave",
         ["run", write("tank_calm.toml", '[sea]\nmodel = "spectral"\n[sea.tank]\nenabled = true\n')],
         ["tank_calm.toml:4", "[sea.tank] enabled", "kind = \"regular\""])
    case("toml", "tank zones wider than the sea",
         ["run", write("tank_fit.toml", '[sea]\nmodel = "spectral"\ndims = 1\nsize = [1.0, 0.1]\ncells = [64, 1]\n'
                       '[sea.waves]\nkind = "regular"\namplitude = 0.001\nwavelength = 0.5\n[sea.tank]\nenabled = true\n')],
         ["tank_fit.toml: [sea] size", "zones do not fit in the box of 1 m"])
    case("toml", "a wave the grid cannot resolve",
         ["run", write("unresolved.toml", '[sea]\nmodel = "spectral"\nsize = [200.0, 200.0]\ncells = [16, 16]\n'
                       '[sea.waves]\nkind = "regular"\namplitude = 0.5\nwavelength = 20\n')],
         ["unresolved.toml: [sea.waves] wavelength", "not resolved by the grid spacing 12.5 m"])
    case("toml", "tent footprint in a bem basin",
         ["run", write("tent_bem.toml", bem + '[coupling]\nfootprint = "tent"\n')],
         ["tent_bem.toml:8", "[coupling] footprint", "periodic"])
    case("toml", "footprint reach of a whole cell",
         ["run", write("reach.toml", '[coupling]\nfootprint_reach = 1.0\n')],
         ["reach.toml:2", "[coupling] footprint_reach", "a fraction of a cell in [0, 0.5]"])
    case("toml", "horizontal loads of an unknown kind",
         ["run", write("hloads.toml", '[coupling]\nhorizontal_loads = "ends"\n')],
         ["hloads.toml:2", "[coupling] horizontal_loads", "step_mean"])
    case("toml", "a forcing series whose path is too long for the system",
         ["run", write("long_path.toml", '[forcing]\nseries = "/tmp/' + "x" * 5000 + '"\n')],
         ["long_path.toml:2", "[forcing] series", "file not found"])
    case("toml", "mooring damping without a period",
         ["run", write("moor.toml", '[[floes.floe]]\nvertices = [[0, 0], [20, 0], [20, 20], [0, 20]]\n'
                       'mooring_damping = 0.5\n')],
         ["moor.toml", "mooring_damping", "needs its mooring_period"])
    floe = "[[floes.floe]]\nvertices = {}\n"
    square = "[[0, 0], [20, 0], [20, 20], [0, 20]]"
    case("toml", "self-intersecting floe",
         ["run", write("bowtie.toml", floe.format("[[0, 0], [1, 1], [1, 0], [0, 1]]"))],
         ["bowtie.toml", "intersects itself"])
    case("toml", "floe 1e-164 m thick", ["run", write("thin.toml", floe.format(square) + "thickness = 1.7e-164\n")],
         ["thin.toml", "[[floes.floe]] 0", "thickness = 1.7e-164 m", "expected a thickness in [0.0001, 1e+09] m"])
    case("toml", "floe of density 0", ["run", write("void.toml", floe.format(square) + "density = 0.0\n")],
         ["void.toml:3", "[floes.floe] density", "expected a density > 0"])
    case("toml", "floe of density 1e-3", ["run", write("light.toml", floe.format(square) + "density = 1e-3\n")],
         ["light.toml", "density = 0.001 kg/m^3", "expected a density in [1, 100000] kg/m^3"])
    case("toml", "floe 1e-6 m across",
         ["run", write("speck.toml", floe.format("[[0, 0], [1e-6, 0], [1e-6, 1e-6], [0, 1e-6]]"))],
         ["speck.toml", "m across: expected a floe at least 0.0001 m across"])
    case("toml", "inline 1e300 square",
         ["run", write("inline_huge.toml", floe.format("[[0, 0], [1e300, 0], [1e300, 1e300], [0, 1e300]]"))],
         ["inline_huge.toml", "[[floes.floe]] 0", "coordinates too large"])
    case("toml", "inline absurd speed", ["run", write("inline_fast.toml", floe.format(square) + "velocity = [0.0, -5e3]\n")],
         ["inline_fast.toml", "speed |velocity| = 5000 m/s is not physical"])
    sea = '[sea]\nmodel = "spectral"\nsize = [200.0, 100.0]\ncells = [32, 16]\n'
    case("toml", "floe outside a periodic sea",
         ["run", write("off_sea.toml", sea + floe.format("[[300, 10], [320, 10], [320, 30], [300, 30]]"))],
         ["off_sea.toml", "floe 0", "centroid x = 310 m is outside the sea's periodic box [0, 200] m", "[sea] size"])
    case("toml", "floe wider than a periodic sea",
         ["run", write("wide_floe.toml", sea + floe.format("[[10, 10], [190, 10], [190, 30], [10, 30]]").replace(
             "[[10, 10], [190, 10], [190, 30], [10, 30]]", "[[-5, 40], [205, 40], [205, 60], [-5, 60]]"))],
         ["wide_floe.toml", "floe 0", "is 210 m wide along x, not less than the sea's periodic box of 200 m"])
    case("toml", "floe across a bem basin's wall",
         ["run", write("off_basin.toml", bem + floe.format("[[0.9, 0], [1.1, 0], [1.1, 0.05], [0.9, 0.05]]") +
                       "thickness = 0.01\n")],
         ["off_basin.toml", "floe 0", "spans x in [0.9, 1.1] m, outside the sea's basin [0, 1] m", "bem"])
    box = '[contact]\ndomain = "periodic"\nbox = [0.0, 100.0, 0.0, 100.0]\n'
    case("toml", "floe outside the periodic box",
         ["run", write("off_box.toml", box + floe.format("[[150, 10], [170, 10], [170, 30], [150, 30]]"))],
         ["off_box.toml", "[contact] box", "floe 0: centroid (160, 20) m is outside the periodic box [0, 100] x [0, 100] m"])
    case("toml", "floe larger than the periodic box",
         ["run", write("big_box_floe.toml", box + floe.format("[[-10, 10], [110, 10], [110, 30], [-10, 30]]"))],
         ["big_box_floe.toml", "[contact] box", "not smaller than the periodic box of 100 m x 100 m"])


# ---------------------------------------------------------------- forcing CSV
def series_cases():
    def series(name, data):
        with open(os.path.join(WORK, name + ".csv"), "wb") as f:
            f.write(data.encode("latin-1"))
        return write(name + ".toml", SMALL + f'series = "{name}.csv"\n')

    for name, data, line, words in BAD_SERIES:
        csv = os.path.join(WORK, name + ".csv")
        blamed = f"{csv}:{line}: " if line else f"{csv}: "
        case("forcing csv", f"series {name}", ["run", series(name, data), "-o", "out.h5"],
             [f"{name}.toml:", "key '[forcing] series'", blamed] + words)
    # The same reader error through the other commands that load a configuration.
    frac = write("frac_series.toml", '[sea]\nmodel = "none"\n[[floes.floe]]\nvertices = [[0, 0], [20, 0], [20, 20], [0, 20]]\n'
                 '[forcing]\nseries = "decreasing.csv"\n[[fracture.load]]\npoint = [10.0, 20.0]\nforce = [0.0, -1e6]\n')
    case("forcing csv", "fracture series", ["fracture", frac], ["[forcing] series", "decreasing.csv:4:", "increasing"])
    os.makedirs(os.path.join(WORK, "regress_bad"), exist_ok=True)
    with open(os.path.join(WORK, "regress_bad", "c.toml"), "w") as f:
        f.write(SMALL + 'series = "../nan.csv"\n')
    open(os.path.join(WORK, "regress_bad", "c.ref.h5"), "w").close()
    case("forcing csv", "regress series", ["regress", os.path.join(WORK, "regress_bad")],
         ["[forcing] series", "nan.csv:2:", "expected a finite number"])


# ---------------------------------------------------------------- pack HDF5
def pack_cases():
    def pack(name, cfg, words):
        case("pack hdf5", name, ["run", cfg], words)

    big = 4_000_000_000
    pack("offsets claim 4e9 (chunked, unwritten)",
         bad_pack("huge", offsets_dataset=dict(shape=(big,), dtype="i8", chunks=(4096,))),
         ["huge.h5: dataset '/floes/offsets' has 4000000000 entries", "'/floes/vertices' has only 4 rows"])
    cfg = bad_pack("patched_offsets")
    patch_dims("patched_offsets", [2], [big])
    pack("offsets dataspace patched to 4e9", cfg, ["patched_offsets.h5: dataset '/floes/offsets' has 4000000000 entries"])
    cfg = bad_pack("patched_vertices")
    patch_dims("patched_vertices", [4, 2], [big, 2])
    pack("vertices dataspace patched to 4e9 rows", cfg,
         ["patched_vertices.h5: dataset '/floes/vertices'", "claims [4000000000 x 2] entries", "more than the 268435456"])
    cfg = bad_pack("short_vertices")
    patch_dims("short_vertices", [4, 2], [1000, 2])
    pack("vertices dataspace claims more than stored", cfg,
         ["short_vertices.h5: dataset '/floes/vertices'", "claims [1000 x 2] entries", "the file stores 64 bytes",
          "truncated or corrupted"])
    pack("float offsets", bad_pack("float_offsets", offsets=np.array([0.0, 4.0])),
         ["float_offsets.h5: dataset '/floes/offsets'", "expected integers, got floating-point numbers"])
    pack("string offsets", bad_pack("string_offsets", offsets=np.array([b"0", b"4"])),
         ["string_offsets.h5: dataset '/floes/offsets'", "expected integers, got strings"])
    pack("rank-2 offsets", bad_pack("rank2_offsets", offsets=np.array([[0, 4]])),
         ["rank2_offsets.h5: dataset '/floes/offsets' has shape [1 x 2], expected [any] integers"])
    pack("offsets start at 1", bad_pack("offsets_start", offsets=np.array([1, 4])),
         ["offsets_start.h5: dataset '/floes/offsets' starts at 1, expected 0"])
    pack("offsets decrease", bad_pack("offsets_decrease", offsets=np.array([0, 4, 2])),
         ["offsets_decrease.h5: dataset '/floes/offsets' decreases at floe 1", "expected non-decreasing"])
    pack("offsets past the vertices", bad_pack("offsets_past", offsets=np.array([0, 9])),
         ["offsets_past.h5: dataset '/floes/offsets' entry 1 = 9 (floe 0) points past '/floes/vertices'", "4 rows"])
    pack("offsets end short", bad_pack("offsets_short", offsets=np.array([0, 3])),
         ["offsets_short.h5: dataset '/floes/offsets' ends at 3", "'/floes/vertices' has 4 rows"])
    pack("one offset", bad_pack("one_offset", offsets=np.array([0])),
         ["one_offset.h5: dataset '/floes/offsets' has 1 entries, expected n + 1 >= 2"])
    pack("absurd speed", bad_pack("fast", velocity=[2e130, 0, 0]),
         ["fast.h5: floe 0: speed |velocity| = 2e+130 m/s is not physical", "expected <= 1000 m/s"])
    pack("absurd spin", bad_pack("spin", velocity=[0, 0, 1e9]),
         ["spin.h5: floe 0: angular_velocity = 1e+09 rad/s", "rim speed", "expected <= 1000 m/s"])
    pack("1e300 square", bad_pack("huge_square", vertices=np.array([[0, 0], [1e300, 0], [1e300, 1e300], [0, 1e300]])),
         ["huge_square.h5: floe 0: vertex 1 = (1e+300, 0) m: coordinates too large", "<= 1e+09 m"])
    # One flipped byte of a generated pack (found by flipping bytes): a floe 1.7e-164 m thick.
    pack("thickness 1.7e-164 (a flipped byte)", bad_pack("flipped_thickness", thickness=[1.7365302730352168e-164]),
         ["flipped_thickness.h5: floe 0", "thickness = 1.73653e-164 m", "expected a thickness in [0.0001"])
    with open(os.path.join(WORK, "not_hdf5.h5"), "w") as f:
        f.write("just text\n")
    pack("not an HDF5 file", write("not_hdf5.toml", '[sea]\nmodel = "none"\n[floes]\npack = "not_hdf5.h5"\n'),
         ["not_hdf5.h5: not an HDF5 file"])
    pack("missing pack file", write("no_pack.toml", '[sea]\nmodel = "none"\n[floes]\npack = "absent.h5"\n'),
         ["absent.h5"])


# ---------------------------------------------------------------- FloeDyn HDF5
def floedyn(name, shapes=None, states=None):
    # A FloeDyn input file: /floe_shapes/<i> [V, 2] and /floe_states [T, n, 9].
    square = np.array([[-5, -5], [5, -5], [5, 5], [-5, 5]], float)
    with h5py.File(os.path.join(WORK, name + ".h5"), "w") as f:
        g = f.create_group("floe_shapes")
        for k, s in (shapes if shapes is not None else {"0": square}).items():
            g[k] = s
        f["floe_states"] = states if states is not None else np.array([[[5.0, 5.0, 0, 0, 0, 0, 0, 0, 0]]])
    return write(name + ".toml", f'[sea]\nmodel = "none"\n[floes]\npack = "{name}.h5"\n')


def floedyn_cases():
    def fd(name, cfg, words):
        case("floedyn hdf5", name, ["run", cfg], words)

    fd("no floe shape", floedyn("fd_empty", shapes={}), ["fd_empty.h5: group '/floe_shapes' holds no floe"])
    fd("states of the wrong shape", floedyn("fd_shape", states=np.zeros((1, 2, 9))),
       ["fd_shape.h5: dataset '/floe_states' must be [T, 1, 9 or 11]"])
    fd("NaN in the states", floedyn("fd_nan", states=np.array([[[np.nan, 5.0, 0, 0, 0, 0, 0, 0, 0]]])),
       ["fd_nan.h5: dataset '/floe_states' record 0, floe 0 has a non-finite value in column 0"])
    fd("shape not numbered from 0", floedyn("fd_name", shapes={"a": np.zeros((4, 2))}),
       ["fd_name.h5: dataset '/floe_shapes/0' is missing"])
    fd("NaN in a shape", floedyn("fd_shape_nan", shapes={"0": np.array([[0, 0], [1, np.nan], [1, 1]])}),
       ["fd_shape_nan.h5", "/floe_shapes/0", "non-finite"])
    fd("absurd speed", floedyn("fd_fast", states=np.array([[[5.0, 5.0, 0, 3e3, 0, 0, 0, 0, 0]]])),
       ["fd_fast.h5: floe 0", "speed |velocity| = 3000 m/s is not physical"])


# ---------------------------------------------------------------- LCP files
def lcp_cases():
    def lcp(name, text, words):
        case("lcp file", name, ["lcp", write(name.replace(" ", "_") + ".dat", text)], words)

    lcp("not a number", "2\n0\n2 2\n2 2\n1 0\n0 x\n-1 -1\n", ["not_a_number.dat:6", "expected", "found 'x'"])
    lcp("NaN entry", "2\n0\n2 2\n2 2\n1 0\n0 nan\n-1 -1\n", ["NaN_entry.dat:6", "not finite"])
    lcp("size mismatch", "2\n0\n3 3\n", ["size_mismatch.dat:3", "matrix size 3 x 3 does not match n = 2"])
    lcp("truncated", "2\n0\n2 2\n2 2\n1 0\n", ["truncated.dat", "unexpected end of file"])
    lcp("huge n", "4000000000\n0\n", ["huge_n.dat:1", "out of range"])
    case("lcp file", "missing LCP file", ["lcp", os.path.join(WORK, "absent.dat")], ["absent.dat", "cannot open the LCP file"])


# ---------------------------------------------------------------- command-line options
def cli_cases():
    small = write("small_cli.toml", SMALL)
    for value in ("nan", "inf", "-inf", "-3"):
        case("cli option", f"--until {value}", ["run", small, "--until", value, "-o", "out.h5"],
             ["--until", "expected a finite number >= 0", f"got '{value}'"])
    case("cli option", "--until 1e12", ["run", small, "--until", "1e12", "-o", "out.h5"],
         ["--until 1e+12", "expected an output_interval >= 100000 s", "at most 10000000 records", "[run] output_interval"])
    case("cli option", "--until 1e9 at dt_max 0.5 s",
         ["run", write("until_steps.toml", SMALL.replace("output_interval = 1.0", "output_interval = 1e3")),
          "--until", "1e9", "-o", "out.h5"],
         ["--until 1e+09", "at most 1000000000 steps", "[run] dt_max"])
    case("cli option", "--threads -1", ["run", small, "--threads", "-1", "-o", "out.h5"], ["--threads"])
    case("cli option", "-o the configuration itself", ["run", small, "-o", small], ["would overwrite the configuration"])
    for opt in ("--rtol", "--atol"):
        for value in ("nan", "-1", "inf"):
            case("cli option", f"compare {opt} {value}", ["compare", "ref.h5", "ref.h5", opt, value],
                 [f"{opt[2:]} (tolerance): expected a finite number >= 0", f"got {value}"])
    case("cli option", "regress --rtol nan", ["regress", os.path.join(WORK, "regress_bad"), "--rtol", "nan"],
         ["rtol (tolerance): expected a finite number >= 0"])
    pack = ["pack", "--concentration", "0.5", "--box", "100", "100", "-o", "out.h5"]
    case("cli option", "pack --floes -5", pack + ["--floes", "-5"], ["--floes", "expected a whole number >= 0", "'-5'"])
    case("cli option", "pack --floes 2.5", pack + ["--floes", "2.5"], ["--floes", "'2.5'"])
    case("cli option", "pack --floes 0", pack + ["--floes", "0"], ["floes must be at least 1"])
    listed = ["compare", "fracture", "info", "pack", "regress", "render", "run"]
    case("cli option", "unknown subcommand", ["frobnicate", "x.toml"], ["unknown subcommand 'frobnicate'"] + listed)
    case("cli option", "no subcommand", [], ["a subcommand is required"] + listed)
    case("cli option", "unknown option", ["run", small, "--frobnicate"], ["--frobnicate"])
    case("cli option", "info on a text file", ["info", small], ["small_cli.toml", "not an HDF5 file"])


# ---------------------------------------------------------------- full disk, unwritable output
def file_size_limit(limit):
    # A file-size limit makes writes past `limit` bytes fail with EFBIG, as a
    # full disk fails them with ENOSPC (SIGXFSZ ignored: the write returns the error).
    def preexec():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))
    return preexec


def xdmf_matches(name):
    # NAME.xmf describes exactly the records of NAME.h5: one grid per record,
    # every referenced dataset with the declared full dimensions.
    root = ET.parse(os.path.join(WORK, name + ".xmf")).getroot()
    with h5py.File(os.path.join(WORK, name + ".h5"), "r") as f:
        for collection in root.findall("./Domain/Grid"):  # "floes" (when there are floes), "sea"
            steps = len(collection.findall("Grid"))
            if f["floes/offsets"].shape[0] == 1 and collection.get("Name") == "floes":
                continue
            if steps != f["time"].shape[0]:
                return f"{steps} XDMF grids of {collection.get('Name')} for {f['time'].shape[0]} records"
        for item in root.iter("DataItem"):
            if item.get("Format") != "HDF":
                continue
            ref, _, sel = item.text.strip().partition("|")
            dset = ref.split(":")[1]
            dims = tuple(int(d) for d in (sel.split(":")[3] if sel else item.get("Dimensions")).split())
            if f[dset].shape != dims:
                return f"{dset}: XDMF says {dims}, the file holds {f[dset].shape}"
    return None


def kept_records(name, at_least):
    # The run file opens, says failed, and holds whole, finite records.
    def check_file():
        path = os.path.join(WORK, name + ".h5")
        with h5py.File(path, "r") as f:
            status = f.attrs["status"]
            t = f["time"][:]
            st = f["floes/state"][:]
            n = int(f.attrs["records"])
            eta = f["sea/eta"][:] if "sea/eta" in f else np.zeros((len(t), 1))
        if eta.shape[0] != len(t) or not np.all(np.isfinite(eta)):
            return f"sea records: {eta.shape} for {len(t)} times, finite {np.all(np.isfinite(eta))}"
        if not status.startswith("failed: "):
            return f"status {status!r}"
        if len(t) < at_least or n != len(t) or st.shape[0] != len(t) or not np.all(np.isfinite(st)):
            return f"records: time {t.shape}, state {st.shape}, attribute {n}, finite {np.all(np.isfinite(st))}"
        if not np.all(np.diff(t) > 0):
            return "times not increasing"
        return xdmf_matches(name)
    return check_file


def absent(*names):
    return lambda: next((f"{n} was left behind" for n in names if os.path.exists(os.path.join(WORK, n))), None)


def disk_cases():
    long = write("long.toml", open(os.path.join(SRC, "examples", "pack_drift.toml")).read().replace(
        "output_interval = 60.0", "output_interval = 5.0"))
    case("full disk", "disk fills mid-run (file-size limit 900 kB)", ["run", long, "-q", "-o", "full.h5"],
         ["run failed", "full.h5: cannot reserve", "File too large", "the run file keeps the", "records written before"],
         code=1, check=kept_records("full", 10), preexec=file_size_limit(900_000))
    waves = write("waves.toml", '[run]\nt_end = 20\ndt_max = 0.1\noutput_interval = 0.1\n[sea]\nmodel = "spectral"\n'
                  'size = [200.0, 200.0]\ncells = [128, 128]\n[sea.waves]\nkind = "regular"\namplitude = 0.5\n'
                  'wavelength = 50\n')
    case("full disk", "disk fills during a wave-only run (128 kB sea records)", ["run", waves, "-q", "-o", "waves.h5"],
         ["waves.h5: cannot reserve", "records written before"], code=1, check=kept_records("waves", 10),
         preexec=file_size_limit(3_000_000))
    write("full0.xmf", "<Xdmf/>\n")  # left by an earlier run: removed with the file that could not start
    case("full disk", "disk full from the start (file-size limit 100 kB)", ["run", long, "-q", "-o", "full0.h5"],
         ["full0.h5: cannot reserve", "no record was written", "(the run file could not be started: removed)"],
         code=1, check=absent("full0.h5", "full0.xmf"), preexec=file_size_limit(100_000))
    case("full disk", "-o /dev/full", ["run", long, "-q", "-o", "/dev/full"],
         ["/dev/full: cannot create the file (No space left on device)"], code=1)
    case("unwritable output", "a folder that does not exist", ["run", long, "-q", "-o", "no/such/dir/x.h5"],
         ["no/such/dir/x.h5: cannot write the run file in", "No such file or directory"], code=1)
    case("unwritable output", "the output is a folder", ["run", long, "-q", "-o", os.path.join(WORK, "a_folder")],
         ["a_folder: cannot create the file"], code=1)
    ro = os.path.join(WORK, "read_only")
    os.makedirs(ro, exist_ok=True)
    os.chmod(ro, 0o555)
    # root writes anywhere: the case then runs as nobody, if nobody may run the
    # binary (its folders may be closed to others); else sysfs, which refuses
    # new files even to root.
    as_nobody = (lambda: (os.setgid(65534), os.setuid(65534))) if os.geteuid() == 0 else None
    try:
        usable = subprocess.run([FLOESIM, "--version"], cwd=WORK, capture_output=True, preexec_fn=as_nobody,
                                timeout=30).returncode == 0
    except (OSError, subprocess.SubprocessError):
        usable = False
    if usable:
        case("unwritable output", "a read-only folder", ["run", long, "-q", "-o", os.path.join(ro, "x.h5")],
             ["read_only/x.h5: cannot write the run file in", "Permission denied"], code=1, preexec=as_nobody,
             check=absent("read_only/x.h5"))
    else:
        case("unwritable output", "a folder that refuses new files (/sys)", ["run", long, "-q", "-o", "/sys/x.h5"],
             ["/sys/x.h5: cannot create the file (Permission denied"], code=1)


# ---------------------------------------------------------------- run errors
def run_error_cases():
    # Valid input whose numerics overflow (a 1e200 m/s wind; floes faster than
    # 1000 m/s are refused at load, a wind is not): a run error, exit 1, the run
    # file marked failed with the reason and its first record kept.
    overflow = SMALL.replace("wind = [5.0, 0.0]", "wind = [1e200, 0.0]")
    case("run error", "a non-finite state mid-run", ["run", write("overflow.toml", overflow), "-q", "-o", "overflow.h5"],
         ["run failed", "is not finite after the step", "the run file overflow.h5 keeps the 1 records written before"],
         code=1, check=kept_records("overflow", 1))
    two = overflow + "\n[[floes.floe]]\nvertices = [[20.005, 0], [40, 0], [40, 20], [20.005, 20]]\n"
    case("run error", "a non-finite state with floes in contact", ["run", write("overflow2.toml", two), "-q", "-o",
                                                                   "overflow2.h5"],
         ["run failed", "not finite", "keeps the 1 records written before"], code=1, check=kept_records("overflow2", 1))


def byte_flips(count=60):
    # Seeded random bytes of a generated pack overwritten (1 to 16 of them):
    # every run answers within 20 s (no hang, no growing memory) with exit 0,
    # 1 or 2. A few such files crash HDF5 1.10.8 itself (a corrupted global heap
    # or object header read by H5Aread / H5Aexists): read_pack reads a pack in a
    # child process first and refuses a file that kills it (exit 2).
    run_ok("pack", "--floes", "20", "--concentration", "0.5", "--box", "200", "200", "--seed", "3", "-o", "flip_src.h5")
    data = open(os.path.join(WORK, "flip_src.h5"), "rb").read()
    cfg = write("flip.toml", '[run]\nt_end = 5.0\ndt_max = 0.5\noutput_interval = 5.0\n[sea]\nmodel = "none"\n'
                '[floes]\npack = "flipped.h5"\n[forcing]\nwind = [5.0, 0.0]\n')
    rng = np.random.default_rng(17)
    failures, codes = [], {}
    for k in range(count):
        b = bytearray(data)
        for _ in range(int(rng.choice([1, 2, 4, 8, 16]))):
            b[int(rng.integers(len(b)))] = int(rng.integers(256))
        open(os.path.join(WORK, "flipped.h5"), "wb").write(b)
        try:
            p = subprocess.run([FLOESIM, "run", cfg, "-q", "-o", "flip_out.h5"], cwd=WORK, capture_output=True,
                               text=True, errors="replace", timeout=20)
        except subprocess.TimeoutExpired:
            failures.append(f"[byte flips] flip {k}: no answer within 20 s")
            continue
        codes[p.returncode] = codes.get(p.returncode, 0) + 1
        if p.returncode not in (0, 1, 2):
            failures.append(f"[byte flips] flip {k}: exit {p.returncode}\n    {p.stderr.strip()}")
    print(f"byte-flipped packs: {count} runs, exit codes {codes}")
    return failures


CLASSES = ["toml", "forcing csv", "pack hdf5", "floedyn hdf5", "lcp file", "cli option", "full disk",
           "unwritable output", "run error"]


def main():
    os.makedirs(os.path.join(WORK, "a_folder"), exist_ok=True)
    run_ok("run", write("ref.toml", SMALL), "-q", "-o", "ref.h5")
    toml_cases()
    series_cases()
    pack_cases()
    floedyn_cases()
    lcp_cases()
    cli_cases()
    disk_cases()
    run_error_cases()

    failures = []
    for c in CASES:
        out = os.path.join(WORK, "out.h5")
        try:
            p = subprocess.run([FLOESIM, *c["args"]], cwd=WORK, capture_output=True, text=True, errors="replace",
                               timeout=60, preexec_fn=c["preexec"])
        except subprocess.TimeoutExpired:
            failures.append(f"[{c['cls']}] {c['name']}: no answer within 60 s")
            continue
        text = p.stdout + p.stderr
        missing = [w for w in c["words"] if w not in text]
        problem = None
        if p.returncode != c["code"] or missing:
            problem = f"exit {p.returncode} (expected {c['code']}), missing {missing}"
        elif c["code"] == 2 and os.path.exists(out):
            problem = "wrote out.h5 for bad input"
        elif c["check"]:
            try:
                problem = c["check"]()
            except Exception as e:  # an unreadable file is a failure, not a crash of the test
                problem = f"check raised {type(e).__name__}: {e}"
        if os.path.exists(out):
            os.remove(out)
        if problem:
            failures.append(f"[{c['cls']}] {c['name']}: {problem}\n    {text.strip()}")
    failures += byte_flips()
    counts = {k: sum(1 for c in CASES if c["cls"] == k) for k in CLASSES}
    print("cases per class: " + ", ".join(f"{k} {v}" for k, v in counts.items()))
    if len(CASES) < 60 or min(counts.values()) == 0 or len(counts) != len(CLASSES):
        failures.append(f"the catalogue must hold >= 60 cases covering every class, has {len(CASES)}: {counts}")
    if failures:
        sys.exit(f"FAILED: {len(failures)} of {len(CASES)} cases:\n" + "\n".join(failures))
    print(f"cli.catalogue: {len(CASES)} cases passed")


main()
