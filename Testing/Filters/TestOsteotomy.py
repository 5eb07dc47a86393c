# SPDX-License-Identifier: BSD-3-Clause
"""pvpython test of the Osteotomy filter against its contract.

Usage: pvpython TestOsteotomy.py <path to FacePlan plugin> <Data dir>
Checks, on a closed sphere and on the face's mandible: a default-constructed filter's plane starts
through the input's centre and cuts it; the output is triangles, every piece closed (no boundary
edge), cut faces on the plane on both sides; the pieces' volumes add up to the input's; every
undeformed output point (point - Displacement) lies on the undeformed input surface; the segment
is exactly the positive side (or the other with InsideOut; the wedge with two planes); the segment
follows SegmentTransform, the rest does not move; ROIMask/SegmentId; the rotation order and the
pivot (centroid or custom); chained osteotomies compose (ids 1, 2, transforms from the undeformed
bone) and edits upstream or of the move alone equal a fresh filter's result (the cached split);
after BezierCut the Displacement is cumulative and the transform NaN with a note; ParaView's plane
Offset moves the cut; port 1 is the plane within the bounds; the input is not modified; bad input gives an empty output and an
error naming the problem.
"""
import math
import os
import sys

import numpy as np
from paraview.simple import *  # noqa: F401,F403

LoadPlugin(sys.argv[1], ns=globals())
data_dir = sys.argv[2]
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from faceplan_test_util import ErrorCatcher, check, fetch, finish, point_array, points, producer, triangles
from vtkmodules.numpy_interface import dataset_adapter as dsa  # noqa: F401
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkPoints
from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData, vtkUnstructuredGrid, vtkStaticCellLocator
from vtkmodules.vtkFiltersCore import vtkFeatureEdges, vtkTriangleFilter
from vtkmodules.vtkFiltersSources import vtkSphereSource, vtkLineSource, vtkPlaneSource

TOL = 1e-9


def rot(axis, deg):
    a = math.radians(deg)
    c, s = math.cos(a), math.sin(a)
    m = {"x": [[1, 0, 0], [0, c, -s], [0, s, c]], "y": [[c, 0, s], [0, 1, 0], [-s, 0, c]],
         "z": [[c, -s, 0], [s, c, 0], [0, 0, 1]]}[axis]
    return np.array(m, float)


def sphere_polydata(radius=1.0, res=48):
    s = vtkSphereSource()
    s.SetRadius(radius)
    s.SetThetaResolution(res)
    s.SetPhiResolution(res)
    s.SetOutputPointsPrecision(1)  # double
    s.Update()
    return s.GetOutput()


def signed_volume(pts, tris):
    return float(np.sum(np.einsum("ij,ij->i", pts[tris[:, 0]], np.cross(pts[tris[:, 1]], pts[tris[:, 2]]))) / 6.0)


def boundary_edge_count(ds):
    fe = vtkFeatureEdges()
    fe.SetInputData(ds)
    fe.BoundaryEdgesOn()
    fe.FeatureEdgesOff()
    fe.ManifoldEdgesOff()
    fe.NonManifoldEdgesOn()
    fe.Update()
    return fe.GetOutput().GetNumberOfLines()


def field(ds, name):
    a = ds.GetFieldData().GetAbstractArray(name)
    if a is None:
        return None
    if hasattr(a, "GetNumberOfComponents") and a.IsA("vtkDataArray"):
        return vtk_to_numpy(a).astype(float).ravel()
    return [a.GetValue(i) for i in range(a.GetNumberOfValues())]


def distance_to_surface(surface, pts):
    loc = vtkStaticCellLocator()
    loc.SetDataSet(surface)
    loc.BuildLocator()
    import vtkmodules.vtkCommonCore as cc
    out = np.zeros(len(pts))
    closest = [0.0, 0.0, 0.0]
    cid, sub, d2 = cc.reference(0), cc.reference(0), cc.reference(0.0)
    for i, p in enumerate(pts):
        loc.FindClosestPoint(list(p), closest, cid, sub, d2)
        out[i] = math.sqrt(d2.get())
    return out


def check_result(label, inp, out, segment_side, expected_map, segment_id=1, undeformed_surface=None):
    """The contract on one successful result. segment_side(x0) -> bool per undeformed point."""
    P = points(out).astype(float)
    T = triangles(out)
    check(out.GetPoints().GetDataType() == 11, label + ": double output points")
    D = point_array(out, "Displacement")
    seg = point_array(out, "SegmentId")
    mask = point_array(out, "ROIMask")
    if not check(D is not None and seg is not None and mask is not None, label + ": output arrays"):
        return None
    check(out.GetPointData().GetArray("ROIMask").GetDataTypeAsString() == "unsigned char", label + ": ROIMask uint8")
    check(out.GetPointData().GetArray("SegmentId").GetDataTypeAsString() == "int", label + ": SegmentId int")
    X0 = P - D
    moving = seg == segment_id
    check(moving.sum() > 10 and (~moving).sum() > 10, label + ": both sides kept (%d moving, %d fixed)"
          % (moving.sum(), (~moving).sum()))
    side = segment_side(X0)
    # Points on a cut plane belong to both sides: only those off the planes must agree.
    check(np.all(side[moving] | on_planes(X0[moving])), label + ": every moved point was on the segment side")
    check(np.all(~side[~moving] | on_planes(X0[~moving])), label + ": every fixed point was on the fixed side")
    check(boundary_edge_count(out) == 0, label + ": every piece closed (no boundary or non-manifold edge)")
    if undeformed_surface is not None:
        d = distance_to_surface(undeformed_surface, X0)
        check(d.max() < 1e-8, label + ": undeformed points lie on the undeformed input (max %.2e)" % d.max())
    if expected_map is not None:
        R, t = expected_map
        err = np.abs(X0[moving] @ R.T + t - P[moving]).max()
        check(err < 1e-9, label + ": the segment follows the expected rigid map (%.2e)" % err)
        Tf = field(out, "SegmentTransform")
        if check(Tf is not None and len(Tf) >= 12 * segment_id, label + ": SegmentTransform present"):
            M = np.array(Tf[12 * (segment_id - 1): 12 * segment_id]).reshape(3, 4)
            check(np.abs(M[:, :3] - R).max() < 1e-12 and np.abs(M[:, 3] - t).max() < 1e-9,
                  label + ": SegmentTransform = expected [R | t]")
    check(np.all(mask[moving] == 1), label + ": ROIMask 1 on the segment")
    return P, T, D, seg, mask, X0


planes_now = []


def on_planes(X):
    near = np.zeros(len(X), bool)
    for o, n in planes_now:
        near |= np.abs((X - o) @ n) < 1e-7
    return near


# ------------------------------------------------------------- a plane cut of a closed sphere
sphere_data = sphere_polydata()
sphere_before = points(sphere_data).copy()
sphere = producer(sphere_data)
ost = Osteotomy(Input=sphere, Operation="Custom")
check(np.allclose(ost.CutPlane1.Origin, [0, 0, 0], atol=1e-12), "default plane through the input's centre")
ost.CutPlane1.Origin = [0.1, 0.2, 0.3]
ost.CutPlane1.Normal = [0, 0, 2]  # not unit: the filter normalises
ost.Translation = [1.0, 2.0, 3.0]
ost.UpdatePipeline()
out = fetch(ost)
planes_now = [(np.array([0.1, 0.2, 0.3]), np.array([0, 0, 1.0]))]
res = check_result("plane", sphere_data, out, lambda X: X[:, 2] > 0.3, (np.eye(3), np.array([1.0, 2, 3])),
                   undeformed_surface=None)
if res:
    P, T, D, seg, mask, X0 = res
    check(np.all(D[seg == 0] == 0.0) and np.all(P[seg == 0] == X0[seg == 0]), "plane: fixed side does not move")
    check(np.all(mask[seg == 0] == 0), "plane: ROIMask 0 off the segment")
    # Cut faces: triangles on the plane, on both sides.
    on = np.all(np.abs(X0[T][:, :, 2] - 0.3) < 1e-9, axis=1)
    moved_tri = seg[T[:, 0]] == 1
    check((on & moved_tri).sum() > 10 and (on & ~moved_tri).sum() > 10,
          "plane: cut faces on both sides (%d, %d triangles)" % ((on & moved_tri).sum(), (on & ~moved_tri).sum()))
    # Volumes of the closed pieces (undeformed) add up to the sphere's.
    v_in = signed_volume(points(sphere_data).astype(float), triangles(sphere_data))
    v_seg = signed_volume(X0, T[moved_tri])
    v_fix = signed_volume(X0, T[~moved_tri])
    check(abs(v_seg + v_fix - v_in) < 1e-9 * abs(v_in) and v_seg > 0 and v_fix > 0,
          "plane: piece volumes add up (%.12f + %.12f vs %.12f)" % (v_seg, v_fix, v_in))
    check(abs(signed_volume(P, T[moved_tri]) - v_seg) < 1e-9, "plane: the moved segment keeps its volume")
    # Undeformed points on the sphere mesh or on the cap (inside the sphere, on the plane).
    on_sphere = distance_to_surface(sphere_data, X0) < 1e-9
    on_cap = (np.abs(X0[:, 2] - 0.3) < 1e-9) & (np.linalg.norm(X0, axis=1) <= 1.0 + 1e-9)
    check(np.all(on_sphere | on_cap), "plane: undeformed points on the sphere or the cap")
    check(field(out, "SegmentNote") == [""], "plane: SegmentNote has one empty entry")
check(np.array_equal(points(sphere_data), sphere_before), "the input is not modified")
planes_out = fetch(ost, 1)
pp = points(planes_out).astype(float) if planes_out.GetNumberOfPoints() else np.zeros((0, 3))
check(planes_out.GetNumberOfCells() == 1 and len(pp) == 4 and np.allclose(pp[:, 2], 0.3)
      and np.all(np.abs(pp[:, :2]) <= 1.0 + 1e-12), "port 1: the plane within the input's bounds")

# InsideOut: the other side moves.
ost.InsideOut = 1
ost.UpdatePipeline()
check_result("inside out", sphere_data, fetch(ost), lambda X: X[:, 2] < 0.3, (np.eye(3), np.array([1.0, 2, 3])))
ost.InsideOut = 0

# Rotation about the segment's centroid: X then Y then Z.
ost.Translation = [0, 0, 0]
ost.Rotation = [20, -30, 45]
ost.UpdatePipeline()
o1 = fetch(ost)
R = rot("z", 45) @ rot("y", -30) @ rot("x", 20)
Tf = np.array(field(o1, "SegmentTransform")).reshape(3, 4)
check(np.abs(Tf[:, :3] - R).max() < 1e-12, "rotation: R = Rz Ry Rx")
c = Tf[:, 3]
res = check_result("rotation", sphere_data, o1, lambda X: X[:, 2] > 0.3, (R, c))
if res:
    P, T, D, seg, mask, X0 = res
    tris = T[seg[T[:, 0]] == 1]
    area = np.linalg.norm(np.cross(X0[tris[:, 1]] - X0[tris[:, 0]], X0[tris[:, 2]] - X0[tris[:, 0]]), axis=1) / 2
    centroid = (area[:, None] * X0[tris].mean(axis=1)).sum(axis=0) / area.sum()
    check(np.abs(R @ centroid + c - centroid).max() < 1e-9,
          "rotation: the segment's area-weighted centroid is the pivot (it stays put)")
    check(abs(centroid[2] - 0.3) > 0.05, "rotation: the centroid is off the plane (a real check)")

# Custom pivot.
ost.PivotMode = "Custom"
ost.Pivot = [0.5, -1.0, 2.0]
ost.Translation = [0.0, 0.0, -1.0]
ost.UpdatePipeline()
o2 = fetch(ost)
Tf = np.array(field(o2, "SegmentTransform")).reshape(3, 4)
p = np.array([0.5, -1.0, 2.0])
check(np.abs(Tf[:, :3] @ p + Tf[:, 3] - (p + [0, 0, -1])).max() < 1e-12, "custom pivot: pivot + translation")
check_result("custom pivot", sphere_data, o2, lambda X: X[:, 2] > 0.3, (R, Tf[:, 3]))

# Two planes: the wedge on the positive side of both.
ost.PivotMode = "Segment Centroid"
ost.Rotation = [0, 0, 0]
ost.Translation = [0.5, 0, 0]
ost.UseSecondPlane = 1
ost.CutPlane2.Origin = [0.2, 0, 0]
ost.CutPlane2.Normal = [1, 1, 0]
ost.UpdatePipeline()
o3 = fetch(ost)
n2 = np.array([1, 1, 0]) / math.sqrt(2)
planes_now = [(np.array([0.1, 0.2, 0.3]), np.array([0, 0, 1.0])), (np.array([0.2, 0, 0]), n2)]
res = check_result("wedge", sphere_data, o3, lambda X: (X[:, 2] > 0.3) & ((X - [0.2, 0, 0]) @ n2 > 0),
                   (np.eye(3), np.array([0.5, 0, 0])))
if res:
    P, T, D, seg, mask, X0 = res
    moved_tri = seg[T[:, 0]] == 1
    v_in = signed_volume(points(sphere_data).astype(float), triangles(sphere_data))
    v = signed_volume(X0, T[moved_tri]) + signed_volume(X0, T[~moved_tri])
    check(abs(v - v_in) < 1e-9 * abs(v_in), "wedge: piece volumes add up (%.12f vs %.12f)" % (v, v_in))
check(fetch(ost, 1).GetNumberOfCells() == 2, "wedge: port 1 shows both planes")
ost.UseSecondPlane = 0

# ------------------------------------------------------------- chained osteotomies compose
ost.Translation = [0.0, 0.0, 1.0]
ost.Rotation = [10, 0, 0]
second = Osteotomy(Input=ost, Operation="Custom")
second.CutPlane1.Origin = [0, 0, 1.6]
second.CutPlane1.Normal = [0.2, 0, 1]  # cuts the moved segment only
second.Rotation = [0, 15, -5]
second.Translation = [0.3, 0.1, 0.0]
second.UpdatePipeline()
o4 = fetch(second)
seg = point_array(o4, "SegmentId")
check(set(np.unique(seg).tolist()) == {0, 1, 2}, "chain: segment ids 0, 1, 2")
Tf = field(o4, "SegmentTransform")
check(Tf is not None and len(Tf) == 24 and np.all(np.isfinite(Tf)), "chain: 24 finite SegmentTransform values")
P = points(o4).astype(float)
X0 = P - point_array(o4, "Displacement")
on_sphere = distance_to_surface(sphere_data, X0) < 1e-9
on_cap = (np.abs(X0[:, 2] - 0.3) < 1e-9) & (np.linalg.norm(X0, axis=1) <= 1 + 1e-9)
check(np.all(on_sphere | on_cap | (seg > 0)), "chain: undeformed fixed points on the sphere or cap")
for s in (1, 2):
    M = np.array(Tf[12 * (s - 1): 12 * s]).reshape(3, 4)
    err = np.abs(X0[seg == s] @ M[:, :3].T + M[:, 3] - P[seg == s]).max()
    check(err < 1e-9, "chain: segment %d follows its SegmentTransform from the undeformed bone (%.2e)" % (s, err))
M1 = np.array(Tf[:12]).reshape(3, 4)
first_map = np.array(field(fetch(ost), "SegmentTransform")).reshape(3, 4)
check(np.abs(M1 - first_map).max() < 1e-14, "chain: segment 1's transform carried over")
mask = point_array(o4, "ROIMask")
check(np.all(mask[seg > 0] == 1) and np.all(mask[seg == 0] == 0), "chain: ROIMask OR-ed")
check(boundary_edge_count(o4) == 0, "chain: every piece closed")
# An edit upstream reaches the second osteotomy (its cached split must not hide it), and an edit of
# the move alone gives what a fresh filter gives.
ost.Translation = [0.0, 0.0, 1.2]
second.Translation = [0.1, 0.2, 0.3]
second.UpdatePipeline()
o4b = fetch(second)
fresh = Osteotomy(Input=ost, Operation="Custom")
fresh.CutPlane1.Origin, fresh.CutPlane1.Normal = second.CutPlane1.Origin, second.CutPlane1.Normal
fresh.Rotation, fresh.Translation = second.Rotation, second.Translation
fresh.UpdatePipeline()
o4c = fetch(fresh)
check(np.array_equal(points(o4b), points(o4c)) and np.array_equal(point_array(o4b, "Displacement"),
                                                                  point_array(o4c, "Displacement")),
      "chain: after edits upstream and of the move, the output equals a fresh filter's")
M1 = np.array(field(fetch(ost), "SegmentTransform")).reshape(3, 4)
check(np.abs(M1[:, 3] - np.array(field(o4, "SegmentTransform"))[:12].reshape(3, 4)[:, 3]).max() > 0.1,
      "chain: the upstream edit changed segment 1's transform")
P = points(o4b).astype(float)
X0 = P - point_array(o4b, "Displacement")
one = point_array(o4b, "SegmentId") == 1
check(np.abs(X0[one] @ M1[:, :3].T + M1[:, 3] - P[one]).max() < 1e-9, "chain: segment 1 follows the new upstream move")
Delete(fresh)

# ------------------------------------------------------------- after a Bezier cut
roi = ROIExtract(Input=sphere)
roi.Region = "Sphere"
roi.Region.Center = [0, 0, 1]
roi.Region.Radius = 0.8
cut = BezierCut(Input=roi, Operation="Cut", FlipNormal=0)
z = 0.8
cut.CurveU = [-1, -1, z, -1 / 3, -1, z, 1 / 3, -1, z, 1, -1, z]
cut.CurveV = [-1, -1, z, -1, -1 / 3, z, -1, 1 / 3, z, -1, 1, z]
after = Osteotomy(Input=cut, Operation="Custom")
after.CutPlane1.Origin = [0, 0, 0.5]
after.CutPlane1.Normal = [0, 0, 1]
after.Translation = [0, 0, 2]
after.UpdatePipeline()
bez = fetch(cut)
check(np.abs(point_array(bez, "Displacement")).max() > 0.05, "bezier: the Bezier cut moved points")
o5 = fetch(after)
P = points(o5).astype(float)
X0 = P - point_array(o5, "Displacement")
d = distance_to_surface(sphere_data, X0)
# The cut (z = 0.5) crosses only edges the Bezier cut left alone, so every undeformed point,
# cap points included, lies on the undeformed sphere.
check(d.max() < 1e-9, "bezier: Displacement cumulative (undeformed points on the sphere, max %.2e)" % d.max())
Tf = field(o5, "SegmentTransform")
notes = field(o5, "SegmentNote")
check(Tf is not None and len(Tf) == 12 and np.all(np.isnan(Tf)), "bezier: the segment's transform is NaN")
check(notes is not None and len(notes) == 1 and "rigid" in notes[0], "bezier: SegmentNote says why: %r" % notes)
# Segment on the side the Bezier cut did not touch: rigid, finite transform.
after.InsideOut = 1
after.UpdatePipeline()
o6 = fetch(after)
Tf = field(o6, "SegmentTransform")
check(Tf is not None and len(Tf) == 12 and np.all(np.isfinite(Tf)), "bezier: an untouched segment stays rigid")
check(field(o6, "SegmentNote") == [""], "bezier: no note for a rigid segment")

# ------------------------------------------------------------- ParaView's plane offset moves the cut
shifted = Osteotomy(Input=sphere, Operation="Custom", Translation=[0, 0, 1])
shifted.CutPlane1.Origin, shifted.CutPlane1.Normal, shifted.CutPlane1.Offset = [0, 0, 0.1], [0, 0, 1], 0.2
shifted.UpdatePipeline()
o8 = fetch(shifted)
X0 = points(o8).astype(float) - point_array(o8, "Displacement")
seg = point_array(o8, "SegmentId")
check(abs(X0[seg == 1][:, 2].min() - 0.3) < 1e-12 and abs(X0[seg == 0][:, 2].max() - 0.3) < 1e-12,
      "offset: the cut lies at origin + offset along the normal")
Delete(shifted)

# ------------------------------------------------------------- the face: default filter cuts it
mandible = XMLPolyDataReader(FileName=[os.path.join(data_dir, "face", "mandible.vtp")])
mandible.UpdatePipeline()
bounds = mandible.GetDataInformation().GetBounds()
centre = [(bounds[0] + bounds[1]) / 2, (bounds[2] + bounds[3]) / 2, (bounds[4] + bounds[5]) / 2]
default = Osteotomy(Input=mandible, Operation="Custom")
check(np.allclose(default.CutPlane1.Origin, centre, atol=1e-9), "face: default plane through the mandible's centre")
default.Translation = [-2, 0, 0]
default.UpdatePipeline()
o7 = fetch(default)
seg = point_array(o7, "SegmentId")
check(seg is not None and (seg == 1).sum() > 100 and (seg == 0).sum() > 100,
      "face: a default-constructed filter cuts the mandible (%s moved)" % (None if seg is None else (seg == 1).sum()))
check(o7.GetNumberOfPoints() > 0 and boundary_edge_count(o7) == 0, "face: the cut mandible's pieces are closed")

# ------------------------------------------------------------- bad input
def expect_error(label, source, text, **props):
    f = Osteotomy(Input=source, Operation="Custom")
    for k, v in props.items():
        if k.startswith("plane_"):
            setattr(f.CutPlane1, k[6:], v)
        else:
            setattr(f, k, v)
    errors = ErrorCatcher(f)
    f.UpdatePipeline()
    o = fetch(f)
    check(errors.contains(text), "%s: error naming the problem (%r in %r)" % (label, text, errors.messages))
    check(o.GetNumberOfPoints() == 0 and fetch(f, 1).GetNumberOfPoints() == 0, label + ": empty outputs")
    Delete(f)


lines = vtkLineSource()
lines.Update()
expect_error("lines only", producer(lines.GetOutput()), "no triangles")
expect_error("empty", producer(vtkPolyData()), "no triangles")
mixed = vtkPolyData()
mixed.DeepCopy(sphere_data)
mixed.SetLines(lines.GetOutput().GetLines())
expect_error("lines mixed in", producer(mixed), "line or vertex cells")
grid = vtkUnstructuredGrid()
grid.SetPoints(sphere_data.GetPoints())
expect_error("wrong type", producer(grid), "vtkUnstructuredGrid")
nan = vtkPolyData()
nan.DeepCopy(sphere_data)
nan.GetPoints().SetPoint(5, float("nan"), 0, 0)
expect_error("NaN coordinate", producer(nan), "NaN or infinite coordinate")
expect_error("nothing moves", sphere, "no vertex of the bone on the moving side", plane_Origin=[0, 0, 5], plane_Normal=[0, 0, 1])
expect_error("everything moves", sphere, "no vertex of the bone on the fixed side", plane_Origin=[0, 0, -5], plane_Normal=[0, 0, 1])
expect_error("non-finite move", sphere, "translation is not finite", Translation=[float("inf"), 0, 0])
expect_error("non-finite rotation", sphere, "rotation angle is not finite", Rotation=[0, float("nan"), 0])
expect_error("zero normal", sphere, "zero-length normal", plane_Normal=[0, 0, 0])
expect_error("non-finite plane", sphere, "non-finite origin or normal", plane_Origin=[0, float("nan"), 0])

# Quads are triangulated.
quads = vtkPlaneSource()
quads.SetResolution(4, 4)
quads.Update()
from vtkmodules.vtkFiltersModeling import vtkLinearExtrusionFilter
box = vtkLinearExtrusionFilter()
box.SetInputConnection(quads.GetOutputPort())
box.SetScaleFactor(1.0)
box.CappingOn()
box.Update()
qb = Osteotomy(Input=producer(box.GetOutput()), Operation="Custom")
qb.CutPlane1.Origin = [0.1, 0, 0]
qb.Translation = [1, 0, 0]
qb.UpdatePipeline()
oq = fetch(qb)
offs = vtk_to_numpy(oq.GetPolys().GetOffsetsArray()) if oq.GetNumberOfCells() else np.array([0])
check(oq.GetNumberOfCells() > 0 and np.all(np.diff(offs) == 3), "quads: output is triangles only")

# The input's other one-component point arrays come along: equal at the input's points,
# interpolated between them at the points the cut adds (a uint8 flag rounds to 0 or 1). Vectors
# (normals) are left out.
flagged = vtkPolyData()
flagged.DeepCopy(sphere_data)
flag_values = (points(sphere_data)[:, 0] > 0.0).astype(np.uint8)
weight_values = points(sphere_data)[:, 1].astype(float) * 2.0
for name, values in (("Released", flag_values), ("Weight", weight_values),
                     ("Normals", points(sphere_data).astype(float))):
    a = numpy_to_vtk(values, deep=1)
    a.SetName(name)
    flagged.GetPointData().AddArray(a)
carry = Osteotomy(Input=producer(flagged), Operation="Custom")
carry.CutPlane1.Origin = [0.1, 0.2, 0.3]
carry.CutPlane1.Normal = [0, 0, 1]
carry.Translation = [1.0, 2.0, 3.0]
carry.UpdatePipeline()
oc = fetch(carry)
released_out, weight_out = point_array(oc, "Released"), point_array(oc, "Weight")
check(released_out is not None and oc.GetPointData().GetArray("Released").GetDataTypeAsString() == "unsigned char",
      "carried: the input's uint8 array is on the output, still uint8")
if released_out is not None and weight_out is not None:
    X0c = points(oc).astype(float) - point_array(oc, "Displacement")
    # Each output point's undeformed position is an input point or lies on the cut plane.
    from vtkmodules.vtkCommonDataModel import vtkStaticPointLocator
    loc = vtkStaticPointLocator()
    loc.SetDataSet(sphere_data)
    loc.BuildLocator()
    nearest = np.array([loc.FindClosestPoint(x.tolist()) for x in X0c])
    same = np.linalg.norm(X0c - points(sphere_data)[nearest], axis=1) < 1e-12
    check(same.sum() > 100 and np.array_equal(released_out[same], flag_values[nearest[same]])
          and np.allclose(weight_out[same], weight_values[nearest[same]], atol=1e-12),
          "carried: values equal the input's at its points (%d points)" % same.sum())
    new_points = ~same
    check(new_points.sum() > 10 and np.allclose(weight_out[new_points], 2.0 * X0c[new_points, 1], atol=0.05),
          "carried: interpolated at the %d points the cut adds" % new_points.sum())
    check(set(np.unique(released_out)) <= {0, 1}, "carried: the flag stays 0 or 1")
check(oc.GetPointData().GetArray("Normals") is None, "carried: a 3-component array (normals) is left out")

finish("TestOsteotomy")
