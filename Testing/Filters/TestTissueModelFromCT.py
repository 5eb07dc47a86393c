# SPDX-License-Identifier: BSD-3-Clause
"""Contract tests of TissueModelFromCT (pvpython, headless): the bundled head CT through the whole
pipeline CT -> model -> ROIExtract -> BezierCut -> CondensedFEMDeform, and the named errors for bad
inputs. argv[1] is the plugin, argv[2] the Data folder. Exits 77 (skipped) when the plugin was
built without CGAL, so the filter is absent.
"""
import sys

import numpy as np
from paraview.simple import *
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonDataModel import VTK_TETRA, vtkImageData, vtkPolyData
from vtkmodules.vtkCommonCore import vtkPoints, vtkShortArray

from faceplan_test_util import ErrorCatcher, WarningCatcher, check, fetch, finish, producer, triangles

LoadPlugin(sys.argv[1], ns=globals())
data = sys.argv[2]
if "TissueModelFromCT" not in globals():
    print("TissueModelFromCT is not in this build (configured without CGAL): skipped")
    sys.exit(77)


def tet_volumes(grid):
    pts = vtk_to_numpy(grid.GetPoints().GetData())
    cells = vtk_to_numpy(grid.GetCells().GetConnectivityArray()).reshape(-1, 4)
    a, b, c, d = (pts[cells[:, k]] for k in range(4))
    return np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a) / 6.0


# ---- the real CT, whole pipeline ----------------------------------------------------------------
ct = XMLImageDataReader(FileName=[data + "/ct/headsq.vti"])
model = TissueModelFromCT(Input=ct)
model.CellSize = 10.0
model.SurfaceDistance = 2.5
model_warnings = WarningCatcher(model)
model_errors = ErrorCatcher(model)
model.UpdatePipeline()
tissue = fetch(model, 0)
bone = fetch(model, 1)
skin = fetch(model, 2)
check(not model_errors.messages, "no error on the CT: %s" % model_errors.messages)
check(not any("sliver" in m for m in model_warnings.messages),
      "no sliver warning from the model: %s" % model_warnings.messages)
n_tets = tissue.GetNumberOfCells()
check(n_tets > 1000, "the tissue has tetrahedra (%d)" % n_tets)
types = vtk_to_numpy(tissue.GetCellTypesArray())
check(np.all(types == VTK_TETRA), "port 0 holds VTK_TETRA only")
check(tissue.GetCellData().GetArray("Label") is not None, "port 0 has cell data Label")
tissue_pts = vtk_to_numpy(tissue.GetPoints().GetData())
check(np.all(np.isfinite(tissue_pts)), "tissue points are finite")
check(np.all(tet_volumes(tissue) > 0), "every tetrahedron is positive")
ct_bounds = fetch(ct).GetBounds()
# Mesh_3 finds the interface by bisection to 1e-6 of the image's diagonal (about 3e-4 mm here).
overshoot = max(np.max(np.array(ct_bounds[0::2]) - tissue_pts.min(axis=0)),
                np.max(tissue_pts.max(axis=0) - np.array(ct_bounds[1::2])))
check(overshoot <= 1e-3, "the mesh lies in the image's frame (largest overshoot %.2g mm)" % overshoot)
for name, surface in (("bone", bone), ("skin", skin)):
    check(surface.GetNumberOfCells() > 100, "%s surface has triangles" % name)
    tris = triangles(surface)
    ids = vtk_to_numpy(surface.GetPointData().GetArray("TissuePointId"))
    surface_pts = vtk_to_numpy(surface.GetPoints().GetData())
    check(np.array_equal(surface_pts, tissue_pts[ids]), "%s points coincide with tissue points" % name)
check(set(np.unique(vtk_to_numpy(bone.GetCellData().GetArray("Label")))) <= {2, 3}, "bone Label is 2 or 3")
field = tissue.GetFieldData()
worst = field.GetArray("WorstDihedralAngle").GetValue(0)
check(worst >= model.QualityBound, "worst dihedral angle %.2f >= QualityBound" % worst)
distance = field.GetArray("LargestBoundaryDistance").GetValue(0)
check(distance <= model.SurfaceDistance, "boundary within SurfaceDistance (%.3f)" % distance)
# The budget's estimate is calibrated on this CT: it covers the first attempt's cells (every label)
# without overcounting by more than half.
estimate = field.GetArray("EstimatedCells").GetValue(0)
first = field.GetArray("FirstAttemptCells").GetValue(0)
check(first <= estimate <= 1.5 * first, "estimate %d against the first attempt's %d cells" % (estimate, first))

# ROI on the anterior mandible, a cut surface across it (z grows towards the chin in this CT).
roi = ROIExtract(Input=OutputPort(model, 1))
roi.Region = "Sphere"
roi.Region.Center = [92.0, 45.0, 125.0]
roi.Region.Radius = 25.0
cut = BezierCut(Input=roi)
CUT_Z = 129.0
cut.CurveU = [70, 30, CUT_Z, 85, 30, CUT_Z, 100, 30, CUT_Z, 115, 30, CUT_Z]
cut.CurveV = [70, 30, CUT_Z, 70, 45, CUT_Z, 70, 60, CUT_Z, 70, 75, CUT_Z]
fem = CondensedFEMDeform(Model="LinearElastic", Input=OutputPort(model, 0), Bone=cut)
fem.ContactDistance = 0.01
fem_warnings = WarningCatcher(fem)
fem_errors = ErrorCatcher(fem)
fem.UpdatePipeline()
cut_out = fetch(cut)
bone_u = vtk_to_numpy(cut_out.GetPointData().GetArray("Displacement"))
check(np.abs(bone_u).max() > 1.0, "the cut moves bone (largest %.2f mm)" % np.abs(bone_u).max())
out = fetch(fem)
u = vtk_to_numpy(out.GetPointData().GetArray("Displacement"))
check(not fem_errors.messages, "no error from CondensedFEMDeform: %s" % fem_errors.messages)
check(np.all(np.isfinite(u)), "tissue displacements are finite")
check(np.abs(u).max() > 0.1, "the tissue moves (largest %.2f mm)" % np.abs(u).max())
check(not any("sliver" in m for m in fem_warnings.messages),
      "no sliver warning from CondensedFEMDeform: %s" % fem_warnings.messages)

# ---- bad inputs ---------------------------------------------------------------------------------
def expect_error(proxy, catcher, text, what):
    catcher.messages = []
    proxy.UpdatePipeline()
    check(any(text in m for m in catcher.messages), "%s: error naming '%s' (got %s)" % (what, text, catcher.messages))
    check(fetch(proxy, 0).GetNumberOfCells() == 0 and fetch(proxy, 1).GetNumberOfCells() == 0,
          "%s: empty outputs" % what)


poly = vtkPolyData()
poly.SetPoints(vtkPoints())
not_image = TissueModelFromCT(Input=producer(poly))
expect_error(not_image, ErrorCatcher(not_image), "not an image", "a polydata input")

bad = TissueModelFromCT(Input=ct)
bad.CellSize = 10.0
bad_errors = ErrorCatcher(bad)
bad.BoneThreshold = 5000.0
expect_error(bad, bad_errors, "no voxel at or above BoneThreshold", "BoneThreshold above every voxel")
bad.BoneThreshold = 200.0
bad.SkinThreshold = 300.0
expect_error(bad, bad_errors, "thresholds in the wrong order", "SkinThreshold above BoneThreshold")
bad.SkinThreshold = -400.0
for size in (0.0, -2.0):
    bad.CellSize = size
    expect_error(bad, bad_errors, "CellSize must be positive", "CellSize %g" % size)
bad.CellSize = 1.0
bad.MaximumCells = 10000
expect_error(bad, bad_errors, "exceeds MaximumCells", "a run over the cell budget")

solid = vtkImageData()
solid.SetDimensions(12, 12, 12)
values = vtkShortArray()
values.SetName("HU")
values.SetNumberOfTuples(12 ** 3)
values.Fill(1000)
solid.GetPointData().SetScalars(values)
all_bone = TissueModelFromCT(Input=producer(solid))
expect_error(all_bone, ErrorCatcher(all_bone), "soft-tissue label is empty", "an image of bone only")

finish("TestTissueModelFromCT")
