# SPDX-License-Identifier: BSD-3-Clause
"""pvpython test of a bimaxillary plan end to end on the Badin face.

Usage: pvpython TestOsteotomyBimaxillary.py <path to FacePlan plugin> <Data dir>
Le Fort I on the maxilla (Osteotomy, segment below a horizontal cut) and BSSO on the mandible
(Osteotomy, segment in front of a coronal cut through both rami), appended into one bone
(Append Geometry) that feeds Condensed FEM Deform. Checks: the appended bone carries both
segments' motions exactly (and zero elsewhere); the soft tissue tied to each segment follows it;
the plan is linear in the two moves (the response to both equals the sum of the responses to each,
which also shows that both segments reach the solver); the edits reuse the precompute.
The appended bone carries SegmentId 1 on both segments and one SegmentTransform: the filter must
notice when the moves differ, say why and use the exact general path; the supported way, each
Osteotomy its own Bone connection, uses the rigid path with the same result.
"""
import os
import sys

import numpy as np
from paraview.simple import *  # noqa: F401,F403

LoadPlugin(sys.argv[1], ns=globals())
data_dir = sys.argv[2]
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
from vtkmodules.vtkFiltersGeometry import vtkDataSetSurfaceFilter
from vtkmodules.vtkCommonCore import reference
from vtkmodules.vtkCommonDataModel import vtkPolyData, vtkStaticCellLocator
from faceplan_test_util import (ErrorCatcher, WarningCatcher, check, fetch, finish, point_array, points,
                                triangles)

LEFORT = np.array([-5.0, 0.0, 1.0])  # advancement (anterior is -x) with a slight impaction
BSSO = np.array([-6.0, 0.0, 0.0])

tissue = XMLUnstructuredGridReader(FileName=[os.path.join(data_dir, "face", "face_tissue.vtu")])
maxilla = XMLPolyDataReader(FileName=[os.path.join(data_dir, "face", "maxilla.vtp")])
mandible = XMLPolyDataReader(FileName=[os.path.join(data_dir, "face", "mandible.vtp")])
lefort = Osteotomy(Input=maxilla, Operation="Custom")
lefort.CutPlane1.Origin = [80.0, 0.0, 110.0]
lefort.CutPlane1.Normal = [0.0, 0.0, -1.0]  # the tooth-bearing part below the cut moves
bsso = Osteotomy(Input=mandible, Operation="Custom")
bsso.CutPlane1.Origin = [97.0, 0.0, 80.0]
bsso.CutPlane1.Normal = [-1.0, 0.0, 0.0]  # the body in front of both rami moves
bone = AppendGeometry(Input=[lefort, bsso])
fem = CondensedFEMDeform(Model="LinearElastic", Input=tissue, Bone=bone, ContactDistance=1.0, OutputMode="Volume")
errors = ErrorCatcher(fem)
warnings = WarningCatcher(fem)
said = WarningCatcher(fem)  # never cleared: a warning is said once per state, not at every update


def solve(lefort_move, bsso_move):
    lefort.Translation = list(lefort_move)
    bsso.Translation = list(bsso_move)
    fem.UpdatePipeline()
    out = fetch(fem)
    table = fetch(fem, 1)
    reused = {table.GetValue(r, 0).ToString(): table.GetValue(r, 2).ToInt() for r in range(table.GetNumberOfRows())}
    return point_array(out, "Displacement"), out, reused


zero = np.zeros(3)
u_both, out, _ = solve(LEFORT, BSSO)
check(not errors.messages, "the FEM runs without error: %s" % errors.messages)
b = fetch(bone)
bl, bm = fetch(lefort), fetch(bsso)
check(b.GetNumberOfPoints() == bl.GetNumberOfPoints() + bm.GetNumberOfPoints(), "the appended bone holds both bones")
D = point_array(b, "Displacement")
seg = point_array(b, "SegmentId")
mask = point_array(b, "ROIMask")
n_max = bl.GetNumberOfPoints()
check(D is not None and seg is not None and mask is not None, "the appended bone keeps Displacement, SegmentId, ROIMask")
on_max = np.arange(b.GetNumberOfPoints()) < n_max
check(np.abs(D[on_max & (seg == 1)] - LEFORT).max() < 1e-12, "the maxilla's segment moved by the Le Fort I move")
check(np.abs(D[~on_max & (seg == 1)] - BSSO).max() < 1e-12, "the mandible's segment moved by the BSSO move")
check(np.all(D[seg == 0] == 0.0), "the rest of both bones does not move")
check(np.array_equal(mask == 1, seg == 1), "ROIMask marks exactly the two segments")
check((on_max & (seg == 1)).sum() > 200 and (~on_max & (seg == 1)).sum() > 200, "both segments are real")

# Tissue tied to each segment follows it exactly: a tissue boundary node within ContactDistance (1 mm) of the
# undeformed bone is tied to its closest point there; when that point's triangle belongs to one
# segment, the node moves with the segment.
undeformed = vtkPolyData()
undeformed.DeepCopy(b)
undeformed.GetPoints().SetData(numpy_to_vtk(points(b).astype(float) - D, deep=1))
locator = vtkStaticCellLocator()
locator.SetDataSet(undeformed)
locator.BuildLocator()
tris = triangles(b)
T0 = points(fetch(tissue)).astype(float)
closest, cell, sub, dist2 = [0.0, 0.0, 0.0], reference(0), reference(0), reference(0.0)
followers = {True: [], False: []}
surface = vtkDataSetSurfaceFilter()
surface.SetInputData(fetch(tissue))
surface.PassThroughPointIdsOn()
surface.Update()
boundary = vtk_to_numpy(surface.GetOutput().GetPointData().GetArray(surface.GetOriginalPointIdsName()))
for i in boundary:
    x = T0[i]
    locator.FindClosestPoint(list(x), closest, cell, sub, dist2)
    ids = tris[cell.get()]
    if dist2.get() <= 1.0 and np.all(seg[ids] == 1) and on_max[ids[0]] == on_max[ids[1]] == on_max[ids[2]]:
        followers[bool(on_max[ids[0]])].append(int(i))
for label, key, move in (("maxilla", True, LEFORT), ("mandible", False, BSSO)):
    nodes = followers[key]
    check(len(nodes) >= 10, "%s: tissue nodes tied to the segment (%d)" % (label, len(nodes)))
    if nodes:
        err = np.abs(u_both[nodes] - move).max()
        check(err < 1e-9 * np.linalg.norm(move), "%s: tied tissue moves with the segment (max deviation %.2e mm)"
              % (label, err))

# Linearity: both moves = Le Fort I alone + BSSO alone (same bone, same contact, same precompute).
u_lefort, _, reused1 = solve(LEFORT, zero)
u_bsso, _, reused2 = solve(zero, BSSO)
scale = np.abs(u_both).max()
err = np.abs(u_both - (u_lefort + u_bsso)).max() / scale
check(err < 1e-9, "superposition: both = Le Fort I + BSSO (relative %.2e)" % err)
check(np.abs(u_lefort).max() > 4.0 and np.abs(u_bsso).max() > 5.0, "each move alone moves the tissue")
check(reused2.get("Factorization", 0) == 1, "an edit of a move reuses the factorization: %s" % reused2)
strain = out.GetFieldData().GetArray("LargestStrain")
print("bimaxillary: largest strain %.1f %%, method %s" % (100 * strain.GetValue(0) if strain else float("nan"),
      out.GetFieldData().GetAbstractArray("Method").GetValue(0)))



def method_of(data):
    return data.GetFieldData().GetAbstractArray("Method").GetValue(0)


# Appended segments: different moves cannot follow the one transform the appended bone keeps.
APPENDED_NOTE = "separate pieces of the bone that move differently"
connected = CondensedFEMDeform(Model="LinearElastic", Input=tissue, Bone=[lefort, bsso], ContactDistance=1.0, OutputMode="Volume")
connected_warnings = WarningCatcher(connected)
for label, lefort_move in (("different moves", LEFORT), ("equal moves", BSSO)):
    warnings.clear()
    connected_warnings.clear()
    u_appended, out, _ = solve(lefort_move, BSSO)
    connected.UpdatePipeline()
    joined = fetch(connected)
    u_connected = point_array(joined, "Displacement")
    scale = np.abs(u_connected).max()
    check(np.abs(u_appended - u_connected).max() < 1e-9 * scale,
          "%s: appended and connected bones give the same tissue motion" % label)
    check(method_of(joined) == "RigidSegments",
          "%s: several Bone connections use the rigid path (%s)" % (label, method_of(joined)))
    check(not connected_warnings.contains(APPENDED_NOTE), "%s: no appended-segments note for connections"
          % label)
    if label == "different moves":
        check(method_of(out) != "RigidSegments", "appended segments with different moves use the general path")
        check(said.contains(APPENDED_NOTE) and said.contains("Bone port"),
              "the note names appended segments and the Bone port: %s" % said.messages)
    else:
        # One transform fits both segments: the rigid path is exact, and nothing needs saying.
        check(method_of(out) == "RigidSegments", "appended segments with equal moves may use the rigid path")
        check(not warnings.contains(APPENDED_NOTE), "no appended-segments note when one transform fits")

finish("TestOsteotomyBimaxillary")
