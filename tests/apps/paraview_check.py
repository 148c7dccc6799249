"""Opens a run's XDMF with ParaView's XDMF3 reader and checks what ParaView sees
against the run file: one time step per record; a floe grid of polygons (one per
floe, with the floe's vertex count) whose cell data x and heave are the state's;
a sea grid with one point per sea cell whose point data eta is /sea/eta.

usage: pvpython paraview_check.py RUN.xmf RUN.h5   (prints "paraview: ok")
"""
import sys

import h5py
import numpy as np
from paraview import servermanager
from paraview import simple
from vtkmodules.numpy_interface import dataset_adapter as dsa
from vtkmodules.vtkCommonDataModel import VTK_POLYGON


def fail(msg):
    print("paraview: FAILED: " + msg)
    sys.exit(1)


import os

# Absolute: the XDMF library resolves the .h5 beside the .xmf from its path.
def leaves(obj):
    """The datasets inside nested multiblock / multipiece datasets."""
    if obj is None:
        return []
    if obj.IsA("vtkMultiPieceDataSet"):
        return [d for k in range(obj.GetNumberOfPieces()) for d in leaves(obj.GetPiece(k))]
    if obj.IsA("vtkMultiBlockDataSet"):
        return [d for k in range(obj.GetNumberOfBlocks()) for d in leaves(obj.GetBlock(k))]
    return [obj]


xmf, h5 = os.path.abspath(sys.argv[1]), sys.argv[2]
reader = simple.Xdmf3ReaderS(registrationName="run", FileName=[xmf])
reader.UpdatePipelineInformation()
with h5py.File(h5) as f:
    t = f["time"][:]
    state = f["floes/state"][:]
    off = f["floes/offsets"][:]
    eta = f["sea/eta"][:] if "sea/eta" in f else None
steps = list(reader.TimestepValues) if len(t) > 1 else [t[0]]
if not np.allclose(steps, t):
    fail(f"time steps {steps} vs /time {list(t)}")
n = len(off) - 1
for k in sorted({0, len(t) // 2, len(t) - 1}):
    reader.UpdatePipeline(t[k])
    data = servermanager.Fetch(reader)
    blocks = leaves(data)
    floes = [b for b in blocks if b is not None and b.GetNumberOfCells() == n and b.GetCellData().GetArray("heave")]
    if not floes:
        fail(f"record {k}: no floe grid with {n} cells and cell data 'heave' among {len(blocks)} blocks")
    g = floes[0]
    for i in range(n):
        if g.GetCellType(i) != VTK_POLYGON or g.GetCell(i).GetNumberOfPoints() != off[i + 1] - off[i]:
            fail(f"record {k}: floe {i} is not a polygon with {off[i + 1] - off[i]} vertices")
    cd = dsa.WrapDataObject(g).CellData
    if not (np.allclose(cd["x"], state[k, :, 0], equal_nan=True) and
            np.allclose(cd["heave"], state[k, :, 6], equal_nan=True)):
        fail(f"record {k}: cell data x / heave differ from /floes/state")
    if eta is not None:
        seas = [b for b in blocks if b is not None and b.GetPointData().GetArray("eta")]
        if not seas:
            fail(f"record {k}: no sea grid with point data 'eta'")
        s = seas[0]
        want = eta[k].ravel()
        got = dsa.WrapDataObject(s).PointData["eta"]
        if s.GetNumberOfPoints() != want.size or not np.allclose(np.asarray(got).ravel(), want):
            fail(f"record {k}: sea has {s.GetNumberOfPoints()} points / eta differs from /sea/eta ({want.size} cells)")
print("paraview: ok")
