# SPDX-License-Identifier: BSD-3-Clause
"""Bad-input contract of TissueModelFromCT through pvpython: every property out of range, NaN or
inf; wrong input types; empty, flat, non-finite and degenerate images; images in odd frames. Each
case gives an error naming the problem and empty outputs on all three ports, or, for legal input,
a finite output (with a warning where the input is extreme). argv[1] is the plugin. Exits 77
(skipped) when the plugin was built without CGAL, so the filter is absent."""
import os
import sys

import numpy as np
from paraview.simple import *  # noqa: F401,F403

LoadPlugin(sys.argv[1], ns=globals())
if "TissueModelFromCT" not in globals():
    print("TissueModelFromCT is not in this build (configured without CGAL): skipped")
    sys.exit(77)
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from badinput_util import Cases, Catcher, box_tissue, copy, polydata
from faceplan_test_util import check, fetch, finish, producer
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
from vtkmodules.vtkCommonDataModel import VTK_TETRA, vtkImageData

cases = Cases("TissueModelFromCT")
PORTS = (0, 1, 2)
AIR, TISSUE, BONE = -1000.0, 40.0, 1000.0


def ct_image(dims=(24, 24, 24), spacing=(1.0, 1.0, 1.0), origin=(0.0, 0.0, 0.0), values=None,
             direction=None, components=1, extent_start=(0, 0, 0)):
    """A synthetic CT: a bone ball (r 4) in a soft-tissue ball (r 9) in air, centred in the image."""
    img = vtkImageData()
    lo = np.asarray(extent_start)
    img.SetExtent(lo[0], lo[0] + dims[0] - 1, lo[1], lo[1] + dims[1] - 1, lo[2], lo[2] + dims[2] - 1)
    img.SetSpacing(*spacing)
    img.SetOrigin(*origin)
    if direction is not None:
        img.SetDirectionMatrix(*np.asarray(direction, float).ravel())
    if values is None:
        k, j, i = np.meshgrid(*(np.arange(n) for n in dims[::-1]), indexing="ij")
        r = np.sqrt(sum(((idx - (n - 1) / 2.0) * s) ** 2 for idx, n, s in zip((i, j, k), dims, spacing)))
        values = np.where(r <= 4.0, BONE, np.where(r <= 9.0, TISSUE, AIR)).ravel()
    values = np.ascontiguousarray(np.repeat(np.asarray(values, float)[:, None], components, axis=1)
                                  if components > 1 else values, dtype=float)
    a = numpy_to_vtk(values, deep=1)
    a.SetName("HU")
    if img.GetNumberOfPoints() == len(values):
        img.GetPointData().SetScalars(a)
    return img


CT = ct_image()
HU = vtk_to_numpy(CT.GetPointData().GetScalars()).copy()


def model_on(dataset, **props):
    f = TissueModelFromCT(Input=producer(dataset))
    f.CellSize = 3.0
    f.SurfaceDistance = 1.0
    for k, v in props.items():
        f.SetPropertyWithName(k, v)
    return f, Catcher(f)


def points_of(ds):
    return vtk_to_numpy(ds.GetPoints().GetData()).astype(float)


def rounded_set(pts):
    return set(map(tuple, np.round(pts, 6) + 0.0))


# ---- legal input: the baseline, and frames the filter must honour ------------------------------
f, c = model_on(CT)
base = cases.ok("the synthetic CT (the cases' baseline)", f, c)
check(base.GetNumberOfCells() > 100, "TissueModelFromCT: the baseline has tetrahedra")
check(np.all(vtk_to_numpy(base.GetCellTypesArray()) == VTK_TETRA), "TissueModelFromCT: VTK_TETRA only")
BASE_PTS = points_of(base)

OFFSET = np.array([1e6, -1e6, 1e6])
f, c = model_on(ct_image(origin=OFFSET))
far = cases.ok("origin offset 1e6 (legal)", f, c)
check(far.GetNumberOfCells() == base.GetNumberOfCells() and
      np.allclose(points_of(far) - OFFSET, BASE_PTS, rtol=0, atol=1e-6),
      "TissueModelFromCT [origin offset 1e6]: the baseline's mesh, shifted")

f, c = model_on(ct_image(extent_start=(5, -3, 7), origin=(-5.0, 3.0, -7.0)))
shifted = cases.ok("extent not starting at 0 (legal)", f, c)
check(shifted.GetNumberOfCells() == base.GetNumberOfCells() and
      np.allclose(points_of(shifted), BASE_PTS, rtol=0, atol=1e-9),
      "TissueModelFromCT [extent not at 0]: the baseline's mesh in the same place")

ROTATION = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
for name, direction in (("rotation", ROTATION), ("mirror", np.diag([1.0, 1.0, -1.0]))):
    f, c = model_on(ct_image(direction=direction))
    turned = cases.ok("direction matrix, %s (legal)" % name, f, c)
    pts = points_of(turned)
    conn = vtk_to_numpy(turned.GetCells().GetConnectivityArray()).reshape(-1, 4)
    a, b, cc, d = (pts[conn[:, k]] for k in range(4))
    check(np.all(np.einsum("ij,ij->i", np.cross(b - a, cc - a), d - a) > 0),
          "TissueModelFromCT [direction %s]: every tetrahedron positive" % name)
    # The same points (a mirror reorders them: its cells' corners are swapped to stay positive).
    check(turned.GetNumberOfCells() == base.GetNumberOfCells() and
          rounded_set(pts) == rounded_set(BASE_PTS @ direction.T),
          "TissueModelFromCT [direction %s]: the baseline's mesh, turned" % name)

f, c = model_on(CT, SeparateMandible=1)
cases.warning("SeparateMandible on a bone of one piece (legal)", f, c, "SeparateMandible", "one piece")

# ---- properties out of range, NaN, inf ----------------------------------------------------------
nan, inf = float("nan"), float("inf")
for prop, value, words in (
        ("BoneThreshold", nan, ("BoneThreshold", "finite")),
        ("BoneThreshold", inf, ("BoneThreshold", "finite")),
        ("SkinThreshold", nan, ("SkinThreshold", "finite")),
        ("SkinThreshold", -inf, ("SkinThreshold", "finite")),
        ("SkinThreshold", 500.0, ("wrong order",)),
        ("SkinThreshold", 200.0, ("wrong order",)),
        ("CellSize", 0.0, ("CellSize", "positive")),
        ("CellSize", -3.0, ("CellSize", "positive")),
        ("CellSize", nan, ("CellSize", "positive")),
        ("CellSize", inf, ("CellSize", "positive")),
        ("CellSize", 1e-3, ("MaximumCells",)),
        ("SurfaceDistance", 0.0, ("SurfaceDistance", "positive")),
        ("SurfaceDistance", -1.0, ("SurfaceDistance", "positive")),
        ("SurfaceDistance", nan, ("SurfaceDistance", "positive")),
        ("SurfaceDistance", inf, ("SurfaceDistance", "positive")),
        ("QualityBound", -1.0, ("QualityBound",)),
        ("QualityBound", 30.0, ("QualityBound",)),
        ("QualityBound", nan, ("QualityBound",)),
        ("MinimumBoneComponentVolume", -1.0, ("volume", "negative")),
        ("MinimumBoneComponentVolume", nan, ("volume", "negative")),
        ("MinimumBoneComponentVolume", 1e9, ("no voxel at or above BoneThreshold", "smaller")),
        ("MaximumBoneHoleVolume", -5.0, ("volume", "negative")),
        ("MaximumBoneHoleVolume", nan, ("volume", "negative")),
        ("BoneCellSizeFactor", 0.5, ("BoneCellSizeFactor",)),
        ("BoneCellSizeFactor", nan, ("BoneCellSizeFactor",)),
        ("MaximumCells", 0, ("MaximumCells", "positive")),
        ("MaximumCells", -5, ("MaximumCells", "positive")),
        ("MaximumCells", 50, ("exceeds MaximumCells",)),
        ("Optimiser", 7, ("Optimiser", "7")),
        ("Optimiser", -1, ("Optimiser", "-1")),
        ("Seed", -1, ("Seed", "negative"))):
    f, c = model_on(CT, **{prop: value})
    cases.error("%s = %s" % (prop, value), f, c, *words, ports=PORTS)

# ---- wrong input types --------------------------------------------------------------------------
f, c = model_on(polydata(np.random.default_rng(0).random((10, 3)), polys=[[0, 1, 2]]))
cases.error("polydata input", f, c, "not an image", "vtkPolyData", ports=PORTS)
f, c = model_on(box_tissue())
cases.error("unstructured grid input", f, c, "not an image", "vtkUnstructuredGrid", ports=PORTS)

# ---- degenerate images --------------------------------------------------------------------------
f, c = model_on(vtkImageData())
cases.error("empty image", f, c, "empty", ports=PORTS)
f, c = model_on(ct_image(dims=(1, 1, 1), values=[BONE]))
cases.error("one voxel", f, c, "at least 2 voxels", ports=PORTS)
flat = ct_image(dims=(24, 24, 1), values=np.where(np.arange(24 * 24) % 24 < 12, BONE, TISSUE))
f, c = model_on(flat)
cases.error("2-D image", f, c, "at least 2 voxels", ports=PORTS)
no_scalars = copy(CT)
no_scalars.GetPointData().RemoveArray("HU")
f, c = model_on(no_scalars)
cases.error("no scalars", f, c, "no point scalars", ports=PORTS)
cell_scalars = copy(no_scalars)
cells_hu = numpy_to_vtk(np.full(cell_scalars.GetNumberOfCells(), TISSUE), deep=1)
cells_hu.SetName("HU")
cell_scalars.GetCellData().SetScalars(cells_hu)
f, c = model_on(cell_scalars)
cases.error("scalars on cells, not points", f, c, "no point scalars", ports=PORTS)
f, c = model_on(ct_image(values=HU, components=3))
cases.error("three-component scalars", f, c, "3 components", ports=PORTS)
for name, value in (("NaN", nan), ("inf", inf), ("-inf", -inf)):
    hu = HU.copy()
    hu[1234] = value
    f, c = model_on(ct_image(values=hu))
    cases.error("voxel value %s" % name, f, c, "non-finite", "voxel 1234", ports=PORTS)
f, c = model_on(ct_image(values=np.full(HU.size, AIR)))
cases.error("all air", f, c, "no voxel at or above BoneThreshold", ports=PORTS)
f, c = model_on(ct_image(values=np.full(HU.size, BONE)))
cases.error("all bone", f, c, "soft-tissue label is empty", ports=PORTS)
f, c = model_on(ct_image(values=np.where(HU > 0, TISSUE, AIR)))
cases.error("tissue without bone", f, c, "no voxel at or above BoneThreshold", ports=PORTS)
for spacing in ((1.0, 0.0, 1.0), (1.0, 1.0, -1.0), (nan, 1.0, 1.0), (1.0, inf, 1.0)):
    f, c = model_on(ct_image(spacing=spacing))
    cases.error("spacing %s" % (spacing,), f, c, "spacing", "positive", ports=PORTS)
f, c = model_on(ct_image(origin=(0.0, nan, 0.0)))
cases.error("NaN origin", f, c, "origin", "finite", ports=PORTS)
for name, direction in (("sheared", [[1, 0.5, 0], [0, 1, 0], [0, 0, 1]]), ("scaled", np.eye(3) * 2.0),
                        ("NaN", [[nan, 0, 0], [0, 1, 0], [0, 0, 1]])):
    f, c = model_on(ct_image(direction=direction))
    cases.error("direction matrix %s" % name, f, c, "direction matrix", "orthonormal", ports=PORTS)

check(np.array_equal(vtk_to_numpy(CT.GetPointData().GetScalars()), HU), "TissueModelFromCT: input not modified")
print("TissueModelFromCT bad-input cases: %d" % cases.count)
finish("TestBadInputTissueModelFromCT")
