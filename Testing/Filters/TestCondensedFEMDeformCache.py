# SPDX-License-Identifier: BSD-3-Clause
"""CondensedFEMDeform's per-edit caches (pvpython, headless): an edit of the cut re-solves without a
new precompute and equals a fresh filter's result; a tissue with the same content under a new
modification time keeps the precompute; a changed mesh (new data set, or moved in place with
Modified()), ROI, material property or material cell array always gets a new precompute.
argv[1] is the plugin, argv[2] the Data folder.
"""
import sys

import numpy as np
from paraview.simple import *
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
from vtkmodules.vtkCommonDataModel import vtkUnstructuredGrid

from faceplan_test_util import check, fetch, finish, producer

LoadPlugin(sys.argv[1], ns=globals())
data = sys.argv[2]

reader = XMLUnstructuredGridReader(FileName=[data + "/face/face_tissue.vtu"])
original = vtkUnstructuredGrid()
original.DeepCopy(fetch(reader))
grid = vtkUnstructuredGrid()
grid.DeepCopy(original)
tissue = producer(grid)
mandible = XMLPolyDataReader(FileName=[data + "/face/mandible.vtp"])
roi = ROIExtract(Input=mandible)
roi.Region = "Sphere"
roi.Region.Center = [70.0, 0.0, 58.0]
roi.Region.Radius = 22.0
cut = BezierCut(Input=roi)
Z = 60.0


def curves(dz):
    z = Z + dz
    return ([40, -30, z, 60, -30, z - 0.5, 80, -30, z - 0.5, 100, -30, z],
            [40, -30, z, 40, -10, z + 0.5, 40, 10, z + 0.5, 40, 30, z])


cut.CurveU, cut.CurveV = curves(0.0)
cut.FlipNormal = 1
fem = CondensedFEMDeform(Model="LinearElastic", Input=tissue, Bone=cut)
fem.OutputMode = "Surface"
fem.Backend = "CPU"


def count():
    fem.UpdatePropertyInformation()
    return fem.GetPropertyValue("PrecomputeCount")


def displacement(proxy):
    return vtk_to_numpy(fetch(proxy).GetPointData().GetArray("Displacement")).copy()


def stages():
    table = fem.GetClientSideObject().GetOutputDataObject(1)
    # (this update's TimeMs, Reused, CachedTimeMs: what a reused stage took when it was computed)
    return {table.GetValue(r, 0).ToString(): (table.GetValue(r, 1).ToDouble(), table.GetValue(r, 2).ToInt(),
                                              table.GetValue(r, 4).ToDouble())
            for r in range(table.GetNumberOfRows())}


def updated_count():
    fem.UpdatePipeline()
    return count()


n0 = updated_count()
check(n0 == 1, "the first update precomputes once (%d)" % n0)
u0 = displacement(fem)
first = stages()
precompute_rows = sum(first[s][0] for s in ("Reordering", "ElementStiffness", "Assembly", "Separation",
                                            "Condensation", "Factorization"))
check(first["PrecomputeTotal"][1] == 0 and first["PrecomputeTotal"][0] >= precompute_rows * 0.99,
      "PrecomputeTotal is the fresh precompute's total")
check(first["Total"][0] >= first["PrecomputeTotal"][0] + first["Solve"][0] - 1e-9,
      "the first update's Total holds the precompute and the solve")

# Edits of the cut: no new precompute, and the result equals a fresh filter on the same inputs.
for k, dz in enumerate((0.3, -0.2, 0.5)):
    cut.CurveU, cut.CurveV = curves(dz)
    check(updated_count() == n0, "edit %d starts no new precompute" % k)
edit = stages()
check(edit["PrecomputeTotal"][1] == 1 and abs(edit["PrecomputeTotal"][2] - first["PrecomputeTotal"][0]) < 1e-9,
      "an edit's PrecomputeTotal is the reused precompute's (CachedTimeMs)")
check(all(row[0] == 0.0 for row in edit.values() if row[1] == 1),
      "a reused stage takes no time in this update (TimeMs 0; its old time is CachedTimeMs)")
check(edit["Total"][0] < edit["PrecomputeTotal"][2], "an edit's Total is the solve alone")
u_edit = displacement(fem)
check(np.abs(u_edit - u0).max() > 1e-3, "the edits changed the result")
fresh = CondensedFEMDeform(Model="LinearElastic", Input=tissue, Bone=cut, OutputMode="Surface", Backend="CPU")
fresh.UpdatePipeline()
u_fresh = displacement(fresh)
check(u_fresh.shape == u_edit.shape and np.abs(u_edit - u_fresh).max() <= 1e-10 * np.abs(u_fresh).max(),
      "the edited result equals a fresh filter's")
Delete(fresh)

# The same content under a new modification time (a re-executed source): no new precompute.
same = vtkUnstructuredGrid()
same.DeepCopy(original)
tissue.GetClientSideObject().SetOutput(same)
tissue.MarkModified(tissue)
check(updated_count() == n0, "a copy of the same tissue starts no new precompute")
check(np.abs(displacement(fem) - u_edit).max() <= 1e-12 * np.abs(u_edit).max(),
      "a copy of the same tissue gives the same result")

# A changed mesh, as a new data set: a new precompute.
moved = vtkUnstructuredGrid()
moved.DeepCopy(original)
pts = vtk_to_numpy(moved.GetPoints().GetData())
far = np.argmax(pts[:, 2])  # a point far from the chin
pts[far, 2] += 0.5
moved.GetPoints().GetData().Modified()
tissue.GetClientSideObject().SetOutput(moved)
tissue.MarkModified(tissue)
n1 = updated_count()
check(n1 == n0 + 1, "a moved tissue point (new data set) starts a new precompute (%d -> %d)" % (n0, n1))

# A changed mesh in place, the same data object with its points marked modified: a new precompute.
pts = vtk_to_numpy(moved.GetPoints().GetData())
pts[far, 2] -= 0.25
moved.GetPoints().GetData().Modified()
tissue.MarkModified(tissue)
n2 = updated_count()
check(n2 == n1 + 1, "a tissue point moved in place starts a new precompute (%d -> %d)" % (n1, n2))

# A changed ROI: new contact (movable nodes), a new precompute.
roi.Region.Radius = 18.0
n3 = updated_count()
check(n3 == n2 + 1, "a smaller ROI starts a new precompute (%d -> %d)" % (n2, n3))

# A changed material property: a new precompute.
fem.YoungsModulus = 20000.0
n4 = updated_count()
check(n4 == n3 + 1, "a new YoungsModulus starts a new precompute (%d -> %d)" % (n3, n4))

# A per-cell material array changed in place and marked modified: a new precompute.
modulus = np.full(moved.GetNumberOfCells(), 15000.0)
array = numpy_to_vtk(modulus, deep=1)
array.SetName("YoungsModulus")
moved.GetCellData().AddArray(array)
tissue.MarkModified(tissue)
n5 = updated_count()
check(n5 == n4 + 1, "a YoungsModulus cell array starts a new precompute (%d -> %d)" % (n4, n5))
values = vtk_to_numpy(array)
values[: len(values) // 2] = 30000.0
array.Modified()
tissue.MarkModified(tissue)
n6 = updated_count()
check(n6 == n5 + 1, "YoungsModulus values changed in place start a new precompute (%d -> %d)" % (n5, n6))
u_stiff = displacement(fem)
fresh = CondensedFEMDeform(Model="LinearElastic", Input=tissue, Bone=cut, OutputMode="Surface", Backend="CPU")
fresh.UpdatePipeline()
check(np.abs(u_stiff - displacement(fresh)).max() <= 1e-10 * np.abs(u_stiff).max(),
      "after the changes the result equals a fresh filter's")

# After a changed input an edit again reuses the new precompute.
cut.CurveU, cut.CurveV = curves(0.1)
check(updated_count() == n6, "an edit after the changes starts no new precompute")

# A bone handed over with new structure arrays (as Osteotomy or Append Geometry do on every edit):
# the same values keep the precompute, different values start a new one and equal a fresh filter's,
# and an array of the wrong shape is refused although the cells did not change.
from vtkmodules.vtkCommonDataModel import vtkPolyData

bone = vtkPolyData()
bone.DeepCopy(fetch(cut))
bone_source = producer(bone)
fem.Bone = bone_source
n7 = updated_count()
u_bone = displacement(fem)
mask = vtk_to_numpy(bone.GetPointData().GetArray("ROIMask")).copy()


def replace_array(name, values):
    array = numpy_to_vtk(values, deep=1)
    array.SetName(name)
    bone.GetPointData().RemoveArray(name)
    bone.GetPointData().AddArray(array)
    bone_source.MarkModified(bone_source)


replace_array("ROIMask", mask)
check(updated_count() == n7 and np.abs(displacement(fem) - u_bone).max() == 0.0,
      "a new ROIMask array with the same values keeps the precompute and the result")
smaller = mask.copy()
smaller[np.flatnonzero(smaller)[::2]] = 0
replace_array("ROIMask", smaller)
n8 = updated_count()
check(n8 == n7 + 1, "a new ROIMask array with other values starts a new precompute (%d -> %d)" % (n7, n8))
fresh = CondensedFEMDeform(Model="LinearElastic", Input=tissue, Bone=bone_source, OutputMode="Surface", Backend="CPU")
fresh.UpdatePipeline()
check(np.abs(displacement(fem) - displacement(fresh)).max() <= 1e-10 * np.abs(displacement(fresh)).max(),
      "after the new ROIMask the result equals a fresh filter's")
Delete(fresh)


def contact_builds():
    fem.UpdatePropertyInformation()
    return fem.GetPropertyValue("ContactBuildCount")


# Released flags: new arrays with the same bytes keep the contact and the precompute; other flags
# rebuild the contact, free other nodes (a new precompute) and equal a fresh filter's result.
flags = np.zeros(bone.GetNumberOfPoints(), dtype=np.uint8)
replace_array("Released", flags)
n9, c9 = updated_count(), contact_builds()
check(n9 == n8, "a Released array of zeros frees nothing: the precompute stays (%d -> %d)" % (n8, n9))
u_zero_flags = displacement(fem)
replace_array("Released", flags.copy())
check(updated_count() == n9 and contact_builds() == c9 and np.abs(displacement(fem) - u_zero_flags).max() == 0.0,
      "a new Released array with the same values keeps the contact, the precompute and the result")
tied_mask = smaller > 0
flags[np.flatnonzero(tied_mask)[::3]] = 1
replace_array("Released", flags)
n10, c10 = updated_count(), contact_builds()
check(c10 == c9 + 1, "a Released array with other values rebuilds the contact (%d -> %d)" % (c9, c10))
check(n10 == n9 + 1, "and frees other nodes: a new precompute (%d -> %d)" % (n9, n10))
check(np.abs(displacement(fem) - u_zero_flags).max() > 0.0, "and changes the result")
fresh = CondensedFEMDeform(Model="LinearElastic", Input=tissue, Bone=bone_source, OutputMode="Surface", Backend="CPU")
fresh.UpdatePipeline()
check(np.abs(displacement(fem) - displacement(fresh)).max() <= 1e-10 * np.abs(displacement(fresh)).max(),
      "after the new Released flags the result equals a fresh filter's")
Delete(fresh)
replace_array("Released", flags.astype(np.float64))
fem.UpdatePipeline()
check(fetch(fem).GetNumberOfPoints() == 0, "a double Released array after a valid update is refused")
replace_array("Released", flags)
fem.UpdatePipeline()
check(fetch(fem).GetNumberOfPoints() > 0, "and the uint8 one is taken again")
replace_array("Sliding", np.zeros((bone.GetNumberOfPoints(), 2), dtype=np.uint8))
fem.UpdatePipeline()
check(fetch(fem).GetNumberOfPoints() == 0, "a two-component Sliding array after a valid update is refused")

finish("TestCondensedFEMDeformCache")
