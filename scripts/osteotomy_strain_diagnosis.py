# SPDX-License-Identifier: BSD-3-Clause
"""Where an osteotomy scene's largest strains are, and why (pvpython).

    pvpython scripts/osteotomy_strain_diagnosis.py <FacePlan.so> <Data dir> lefort1|bsso|genioplasty
        [--tied] [--sliding] [--segment-tied] [--release MM] [--detach MM] [--neo-hookean] [--lift-off] [--top N]
        [--save file.npz]

Runs the scene's pipeline (scripts/osteotomy_scenes.py; by default with the demo's contact) and
lists the cells of largest small strain: the strain, the cell's shape quality (vtkMeshQuality mean
ratio, 1 = regular, and smallest dihedral angle), whether it is folded (it shares a face with a tet
on the same side of that face: the two overlap) and the state of each of its nodes as the filter's
contact sees it: M = tied to the moving segment, F = tied to bone that stays, R = tied but released,
i = free (interior or untied boundary). The contact is recomputed here the way CondensedFEMDeform
builds it (closest point on the undeformed bone within ContactDistance; ROIMask there; released
where the bone's Released array flags the point of largest weight, or within ReleaseDistance of a
bone point of another segment or ROIMask side).
"""
import argparse
import os
import sys

import numpy as np
from paraview import servermanager
from paraview.simple import LoadPlugin

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import osteotomy_scenes  # noqa: E402
import tet_folds  # noqa: E402
import tet_strain  # noqa: E402
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy  # noqa: E402
from vtkmodules.vtkCommonCore import reference, vtkPoints  # noqa: E402
from vtkmodules.vtkCommonDataModel import (vtkGenericCell, vtkPolyData, vtkStaticCellLocator,  # noqa: E402
                                           vtkStaticPointLocator)
from vtkmodules.vtkFiltersVerdict import vtkMeshQuality  # noqa: E402

parser = argparse.ArgumentParser()
parser.add_argument("plugin")
parser.add_argument("data")
parser.add_argument("scene", choices=sorted(osteotomy_scenes.SCENES))
parser.add_argument("--tied", action="store_true", help="Tied contact instead of the demo's")
parser.add_argument("--sliding", action="store_true", help="Sliding contact everywhere instead of the demo's")
parser.add_argument("--release", type=float, default=None, help="ReleaseDistance (mm)")
parser.add_argument("--top", type=int, default=8)
parser.add_argument("--segment-tied", action="store_true",
                    help="ContactModel ByArray: tied on the moving segment, sliding elsewhere")
parser.add_argument("--detach", type=float, default=0.0,
                    help="drop fixed bone triangles within this distance (mm) of the moving segment")
parser.add_argument("--neo-hookean", action="store_true",
                    help="Model NeoHookean (large deformation); strains are then principal Green-Lagrange")
parser.add_argument("--lift-off", action="store_true", help="LiftOff (with --neo-hookean)")
parser.add_argument("--save", help="write strain, quality, node states and centroids to this .npz")
args = parser.parse_args()

LoadPlugin(args.plugin)
tissue_proxy, _, _, skeleton, fem = osteotomy_scenes.build(args.data, args.scene)
if args.tied:
    fem.ContactModel = "Tied"
if args.sliding:
    fem.ContactModel = "Sliding"
if args.release is not None:
    fem.ReleaseDistance = args.release
fem.Model = "NeoHookean" if args.neo_hookean else "LinearElastic"
fem.LiftOff = int(args.lift_off)
fem.LipSeal = 0.0  # docs/OSTEOTOMY-STRAIN.md's figures are for open lips
fem.OutputMode = "Volume"  # every node: the strains are recomputed per cell below
if args.detach > 0:
    # The fixed bone's triangles within `detach` of the moving segment dropped: tissue there is
    # tied to nothing (an experiment: how far the tissue would have to be detached).
    from paraview import simple
    detached = simple.ProgrammableFilter(Input=skeleton, OutputDataSetType="vtkPolyData", Script="""
import numpy as np
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonCore import reference, vtkIdList, vtkPoints
from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData, vtkStaticPointLocator
inp = self.GetInput()
x = vtk_to_numpy(inp.GetPoints().GetData()) - vtk_to_numpy(inp.GetPointData().GetArray('Displacement'))
mask = vtk_to_numpy(inp.GetPointData().GetArray('ROIMask'))
pts = vtkPoints()
for p in x[mask > 0]:
    pts.InsertNextPoint(p)
segment = vtkPolyData()
segment.SetPoints(pts)
loc = vtkStaticPointLocator()
loc.SetDataSet(segment)
loc.BuildLocator()
near = np.array([mask[i] == 0 and loc.FindClosestPointWithinRadius(%g, x[i].tolist(), reference(0.0)) >= 0
                 for i in range(len(x))])
out = self.GetOutput()
out.DeepCopy(inp)
kept = vtkCellArray()
ids = vtkIdList()
for c in range(out.GetNumberOfCells()):
    out.GetCellPoints(c, ids)
    if not all(near[[ids.GetId(k) for k in range(ids.GetNumberOfIds())]]):
        kept.InsertNextCell(ids)
out.SetPolys(kept)
""" % args.detach)
    fem.Bone = [detached]
    skeleton = detached
if args.segment_tied:
    from paraview import simple
    flagged = simple.ProgrammableFilter(Input=fem.Bone[0], OutputDataSetType="vtkPolyData", Script="""
import numpy as np
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
out = self.GetOutput()
out.ShallowCopy(self.GetInput())
a = numpy_to_vtk((vtk_to_numpy(out.GetPointData().GetArray('ROIMask')) == 0).astype(np.uint8), deep=1)
a.SetName('Sliding')
out.GetPointData().AddArray(a)
""")
    fem.Bone = [flagged]
    fem.ContactModel = "ByArray"
    skeleton = flagged
fem.UpdatePipeline()
out = servermanager.Fetch(fem)
tissue = servermanager.Fetch(tissue_proxy)
bone = servermanager.Fetch(skeleton)

xyz = vtk_to_numpy(tissue.GetPoints().GetData()).astype(float)
conn = vtk_to_numpy(tissue.GetCells().GetConnectivityArray()).reshape(-1, 4)
u = vtk_to_numpy(out.GetPointData().GetArray("Displacement")).astype(float)

strain = tet_strain.largest_principal_strain(xyz, conn, u, green_lagrange=args.neo_hookean)


def quality(measure):
    q = vtkMeshQuality()
    q.SetInputData(tissue)
    getattr(q, "SetTetQualityMeasureTo" + measure)()
    q.Update()
    return vtk_to_numpy(q.GetOutput().GetCellData().GetArray("Quality"))


mean_ratio, min_angle = quality("MeanRatio"), quality("MinAngle")

# Folds: two tets that share a face but lie on the same side of it overlap (each alone is positive).
pairs, sides = tet_folds.face_pair_sides(xyz, conn)
fold_pairs = pairs[sides > 0]
folded = np.zeros(len(conn), bool)
folded[fold_pairs.ravel() // 4] = True

# The contact, as the filter builds it.
disp = vtk_to_numpy(bone.GetPointData().GetArray("Displacement")).astype(float)
undeformed = vtkPolyData()
undeformed.DeepCopy(bone)
undeformed.GetPoints().SetData(numpy_to_vtk(vtk_to_numpy(bone.GetPoints().GetData()) - disp, deep=1))
seg = vtk_to_numpy(bone.GetPointData().GetArray("SegmentId"))
mask = vtk_to_numpy(bone.GetPointData().GetArray("ROIMask"))
region = 2 * seg.astype(int) + (mask > 0)
locator = vtkStaticCellLocator()
locator.SetDataSet(undeformed)
locator.BuildLocator()
boundary = set()
face_count = {}
for tet in conn:
    for f in ((1, 2, 3), (0, 2, 3), (0, 1, 3), (0, 1, 2)):
        key = tuple(sorted(tet[list(f)]))
        face_count[key] = face_count.get(key, 0) + 1
for key, count in face_count.items():
    if count == 1:
        boundary.update(key)
release = float(fem.ReleaseDistance)
distance = float(fem.ContactDistance)
point_locators = {}
for label in np.unique(region):
    pd = vtkPolyData()
    pd.SetPoints(vtkPoints())
    pd.GetPoints().SetData(numpy_to_vtk(np.ascontiguousarray(
        vtk_to_numpy(undeformed.GetPoints().GetData())[region == label]), deep=1))
    loc = vtkStaticPointLocator()
    loc.SetDataSet(pd)
    loc.BuildLocator()
    point_locators[label] = loc
cell = vtkGenericCell()
state = np.full(len(xyz), "i", dtype="<U1")
for node in boundary:
    closest = [0.0, 0.0, 0.0]
    cid, sub, d2, inside = reference(0), reference(0), reference(0.0), reference(0)
    if not locator.FindClosestPointWithinRadius(xyz[node].tolist(), distance, closest, cell, cid, sub, d2,
                                                inside):
        continue
    ids = [undeformed.GetCell(int(cid)).GetPointId(k) for k in range(3)]
    pc, w, dd, s = [0.0] * 3, [0.0] * 3, reference(0.0), reference(0)
    undeformed.GetCell(int(cid)).EvaluatePosition(closest, [0.0] * 3, s, pc, dd, w)
    movable = float(np.dot(w, mask[ids])) > 1e-12  # (paraview.simple shadows the builtin sum)
    own = region[ids[int(np.argmax(w))]]
    flags = bone.GetPointData().GetArray("Released")
    released = bool(flags is not None and flags.GetValue(ids[int(np.argmax(w))]) > 0)
    for lab, loc in point_locators.items():
        if release > 0 and lab != own:
            released |= loc.FindClosestPointWithinRadius(release, xyz[node].tolist(), reference(0.0)) >= 0
    state[node] = "R" if released else ("M" if movable else "F")

worst = np.argsort(-strain)[:args.top]
fd = out.GetFieldData()
print("scene %s, ContactModel %s, LiftOff %d, LipSeal %g mm, ReleaseDistance %g mm" % (
    args.scene, fem.ContactModel, fem.LiftOff, fem.LipSeal, release))
print("filter's largest strain %.1f %% (numpy over all cells %.1f %%), Method %s" % (
    100 * fd.GetArray("LargestStrain").GetValue(0), 100 * strain.max(),
    fd.GetAbstractArray("Method").GetValue(0)))
print("cells above 10 %%: %d; of them mean ratio < 0.1: %d" % (
    (strain > 0.1).sum(), ((strain > 0.1) & (mean_ratio < 0.1)).sum()))
print("strain percentiles 50/90/99/99.9: %s %%; cells above 25 %%: %d, above 50 %%: %d, above 100 %%: %d" % (
    " / ".join("%.1f" % (100 * np.percentile(strain, q)) for q in (50, 90, 99, 99.9)),
    (strain > 0.25).sum(), (strain > 0.5).sum(), (strain > 1.0).sum()))
good = mean_ratio >= 0.1
print("largest strain over cells of mean ratio >= 0.1: %.1f %% (cell %d)" % (
    100 * strain[good].max(), np.where(good)[0][strain[good].argmax()]))
print("folded shared faces %d, folded tets %d; cells above 10 %% that are folded: %d" % (
    len(fold_pairs), folded.sum(), (folded & (strain > 0.1)).sum()))
print("nodes: M %d, F %d, R %d" % ((state == "M").sum(), (state == "F").sum(), (state == "R").sum()))
print("%7s %8s %9s %8s %6s  nodes (state)" % ("cell", "strain%", "meanratio", "mindih", "folded"))
for c in worst:
    print("%7d %8.1f %9.4f %8.2f %6s  %s" % (c, 100 * strain[c], mean_ratio[c], min_angle[c],
                                              "yes" if folded[c] else "no",
                                              " ".join("%d(%s)" % (n, state[n]) for n in conn[c])))
if args.save:
    np.savez(args.save, strain=strain, mean_ratio=mean_ratio, min_angle=min_angle, state=state,
             folded=folded, centroid=xyz[conn].mean(axis=1), conn=conn, xyz=xyz, u=u)
