# SPDX-License-Identifier: BSD-3-Clause
"""Contract tests of CondensedFEMDeform on the Badin face scene (pvpython, headless).

The bone displacement is made with ParaView's own Calculator and WarpByVector on the ROI, so this
test does not depend on Bezier Cut. argv[1] is the plugin, argv[2] the Data folder.
"""
import sys

import numpy as np
from paraview.simple import *
from paraview import servermanager as sm
from vtkmodules.numpy_interface import dataset_adapter as dsa
from vtkmodules.vtkCommonDataModel import vtkStaticCellLocator, vtkGenericCell, vtkUnstructuredGrid
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonCore import reference

from faceplan_test_util import ErrorCatcher, check, fetch, finish, producer

LoadPlugin(sys.argv[1], ns=globals())
data = sys.argv[2]

tissue = XMLUnstructuredGridReader(FileName=[data + "/face/face_tissue.vtu"])
bone = XMLPolyDataReader(FileName=[data + "/face/mandible.vtp"])
roi = ROIExtract(Input=bone)
roi.Region = "Sphere"
roi.Region.Center = [70, 0, 58]
roi.Region.Radius = 25
push = "ROIMask*(1-ROIBoundary)*(0.5*iHat+0.2*jHat+3*kHat)"
calc = Calculator(Input=roi, ResultArrayName="Displacement", Function=push)
moved_bone = WarpByVector(Input=calc, Vectors=["POINTS", "Displacement"])

tissue_before = vtk_to_numpy(fetch(tissue).GetPoints().GetData()).copy()
bone_before = vtk_to_numpy(fetch(moved_bone).GetPoints().GetData()).copy()

fem = CondensedFEMDeform(Model="LinearElastic", Input=tissue, Bone=moved_bone, OutputMode="Volume")
fem.ContactDistance = 1.0
errors = ErrorCatcher(fem)


def field(out, name):
    a = out.GetFieldData().GetAbstractArray(name)
    return a.GetValue(0) if a is not None else None


def displacement(out):
    return vtk_to_numpy(out.GetPointData().GetArray("Displacement")).copy()


fem.UpdatePipeline()
out = fetch(fem)
u = displacement(out)
check(out.GetNumberOfPoints() == tissue_before.shape[0], "Volume output keeps every tissue point")
check(np.all(np.isfinite(u)), "displacements are finite")
check(field(out, "RelativeResidual") < 1e-9, "relative residual below 1e-9")
check(np.allclose(vtk_to_numpy(out.GetPoints().GetData()), tissue_before + u, rtol=0, atol=1e-12),
      "output points are the input points plus Displacement")

# Tied nodes: recompute the contact independently and compare with the output.
undeformed = fetch(moved_bone)
bone_u = vtk_to_numpy(undeformed.GetPointData().GetArray("Displacement"))
mask = vtk_to_numpy(undeformed.GetPointData().GetArray("ROIMask"))
pts = vtk_to_numpy(undeformed.GetPoints().GetData()) - bone_u
from vtkmodules.vtkCommonCore import vtkPoints
from vtkmodules.util.numpy_support import numpy_to_vtk
p0 = vtkPoints()
p0.SetData(numpy_to_vtk(pts.copy()))
undeformed.SetPoints(p0)
locator = vtkStaticCellLocator()
locator.SetDataSet(undeformed)
locator.BuildLocator()
from vtkmodules.vtkFiltersGeometry import vtkDataSetSurfaceFilter
sf = vtkDataSetSurfaceFilter()
sf.SetInputData(fetch(tissue))
sf.PassThroughPointIdsOn()
sf.Update()
boundary = vtk_to_numpy(sf.GetOutput().GetPointData().GetArray("vtkOriginalPointIds"))
cell = vtkGenericCell()
tied_moving, tied_fixed, worst = 0, 0, 0.0
for node in boundary:
    x = tissue_before[node]
    closest = [0.0, 0.0, 0.0]
    cid, sid, d2, inside = reference(0), reference(0), reference(0.0), reference(0)
    if not locator.FindClosestPointWithinRadius(x, 1.0, closest, cell, cid, sid, d2, inside):
        continue
    undeformed.GetCell(int(cid), cell)
    w = [0.0] * cell.GetNumberOfPoints()
    cp, pc, dd = [0.0] * 3, [0.0] * 3, reference(0.0)
    cell.EvaluatePosition(closest, cp, sid, pc, dd, w)
    ids = [cell.GetPointId(k) for k in range(cell.GetNumberOfPoints())]
    expected = sum(wk * bone_u[i] for wk, i in zip(w, ids))
    m = sum(wk * mask[i] for wk, i in zip(w, ids))
    if m <= 1e-12:
        expected = np.zeros(3)
        tied_fixed += 1
    else:
        tied_moving += 1
    worst = max(worst, np.abs(u[node] - expected).max())
check(tied_moving > 20 and tied_fixed > 20, "the scene ties both moving and fixed nodes (%d, %d)" % (tied_moving, tied_fixed))
check(worst < 1e-9, "tied nodes carry the bone's interpolated displacement (worst %.2e)" % worst)

# Equal to Core's reference solve (no condensation, no cache).
ref = CondensedFEMDeform(Model="LinearElastic", Input=tissue, Bone=moved_bone, Method="FullReference", OutputMode="Volume")
ref.UpdatePipeline()
u_ref = displacement(fetch(ref))
rel = np.abs(u - u_ref).max() / np.abs(u_ref).max()
check(rel < 1e-10, "condensed equals the reference full solve (%.2e)" % rel)
check(field(fetch(ref), "Method") == "FullReference", "reference reports its method")

# An edit of the cut alone re-solves with the factorization reused, equal to a fresh solve.
fem.UpdatePropertyInformation()
count = fem.GetPropertyValue("PrecomputeCount")
calc.Function = push.replace("3*kHat", "4.5*kHat")
fem.UpdatePipeline()
fem.UpdatePropertyInformation()
check(fem.GetPropertyValue("PrecomputeCount") == count, "an edit starts no new precompute")
table = fem.GetClientSideObject().GetOutputDataObject(1)
stages = {table.GetValue(r, 0).ToString(): (table.GetValue(r, 1).ToDouble(), table.GetValue(r, 2).ToInt())
          for r in range(table.GetNumberOfRows())}
check(stages["Factorization"][1] == 1 and stages["Assembly"][1] == 1, "table marks factorization and assembly reused")
check(stages["Solve"][1] == 0, "table marks the solve as fresh")
check(field(fetch(fem), "PrecomputeReused") == 1.0, "field data says the precompute was reused")
fresh = CondensedFEMDeform(Model="LinearElastic", Input=tissue, Bone=moved_bone, OutputMode="Volume")
fresh.UpdatePipeline()
u_edit, u_fresh = displacement(fetch(fem)), displacement(fetch(fresh))
check(np.abs(u_edit - u_fresh).max() <= 1e-12 * np.abs(u_fresh).max(), "edited result equals a fresh solve")
check(np.abs(u_edit - u).max() > 0.1, "the edit changed the result")

# Surface mode: boundary triangles only, same displacement there.
fem.OutputMode = "Surface"
fem.UpdatePipeline()
s = fetch(fem)
ids = vtk_to_numpy(s.GetPointData().GetArray("vtkOriginalPointIds"))
check(s.GetNumberOfPoints() == len(boundary) and s.GetNumberOfCells() == sf.GetOutput().GetNumberOfCells(),
      "Surface output is the tissue boundary")
check(np.abs(displacement(s) - u_edit[ids]).max() <= 1e-10 * np.abs(u_edit).max(), "Surface equals Volume on the boundary")
fem.OutputMode = "Volume"

# Verify reports the difference to a reference solve beside the time.
fem.Verify = 1
fem.UpdatePipeline()
check(field(fetch(fem), "VerifyMaxRelativeError") < 1e-10, "Verify reports agreement with the reference")
check(field(fetch(fem), "SolveTimeMs") > 0, "SolveTimeMs reported")
fem.Verify = 0

# Gravity changes the answer; the residual stays small.
fem.UseGravity = 1
fem.UpdatePipeline()
check(np.abs(displacement(fetch(fem)) - u_edit).max() > 1e-6, "gravity load moves the tissue")
check(field(fetch(fem), "RelativeResidual") < 1e-9, "gravity solve residual below 1e-9")
fem.UseGravity = 0

# CUDA requested on a machine without it: a warning and the CPU (the table says so).
fem.Backend = "CUDA"
warnings = []
fem.GetClientSideObject().AddObserver("WarningEvent", lambda o, e: warnings.append(e))
fem.UpdatePipeline()
backend = field(fetch(fem), "Backend")
check(backend in ("CPU", "CUDA"), "Backend reported (%s)" % backend)
if backend == "CPU":
    check(len(warnings) > 0, "CUDA unavailable gives a warning")
fem.Backend = "Auto"

# Inputs never modified (the bone compared at the displacement it had at the start).
calc.Function = push
fem.UpdatePipeline()
check(np.array_equal(vtk_to_numpy(fetch(tissue).GetPoints().GetData()), tissue_before), "tissue input unchanged")
check(np.array_equal(vtk_to_numpy(fetch(moved_bone).GetPoints().GetData()), bone_before), "bone input unchanged")

# Bad input: clear errors, empty output.
from vtkmodules.vtkFiltersCore import vtkAppendFilter
hexes = fetch(XMLUnstructuredGridReader(FileName=[data + "/face/face_tissue.vtu"]))
bad = vtkUnstructuredGrid()
bad.DeepCopy(hexes)
from vtkmodules.vtkCommonDataModel import vtkHexahedron
bad.InsertNextCell(12, 8, [0, 1, 2, 3, 4, 5, 6, 7])
bad_fem = CondensedFEMDeform(Model="LinearElastic", Input=producer(bad), Bone=moved_bone)
bad_errors = ErrorCatcher(bad_fem)
bad_fem.UpdatePipeline()
check(bad_errors.contains("Tetrahedralize"), "non-tetrahedral input names Tetrahedralize")
check(fetch(bad_fem).GetNumberOfPoints() == 0, "non-tetrahedral input gives an empty output")

inverted = vtkUnstructuredGrid()
inverted.DeepCopy(hexes)
pts_ids = inverted.GetCells().GetConnectivityArray()
a, b = pts_ids.GetValue(4 * 5), pts_ids.GetValue(4 * 5 + 1)
pts_ids.SetValue(4 * 5, b)
pts_ids.SetValue(4 * 5 + 1, a)
inv_fem = CondensedFEMDeform(Model="LinearElastic", Input=producer(inverted), Bone=moved_bone)
inv_errors = ErrorCatcher(inv_fem)
inv_fem.UpdatePipeline()
check(inv_errors.contains("inverted cells 5"), "inverted tetrahedron named by id")
check(fetch(inv_fem).GetNumberOfPoints() == 0, "inverted tetrahedron gives an empty output")

far = CondensedFEMDeform(Model="LinearElastic", Input=tissue, Bone=moved_bone, ContactDistance=1e-9)
far_errors = ErrorCatcher(far)
far.UpdatePipeline()
check(far_errors.contains("no tissue boundary node"), "no contact gives a clear error")

no_disp = CondensedFEMDeform(Model="LinearElastic", Input=tissue, Bone=bone)
nd_errors = ErrorCatcher(no_disp)
no_disp.UpdatePipeline()
check(not nd_errors.messages, "a bone without Displacement is a fixed bone, not an error: %s" % nd_errors.messages)
nd_u = vtk_to_numpy(fetch(no_disp).GetPointData().GetArray("Displacement"))
check(len(nd_u) > 0 and np.all(nd_u == 0.0), "a fixed bone leaves the tissue where it is")

finish("TestCondensedFEMDeform")
