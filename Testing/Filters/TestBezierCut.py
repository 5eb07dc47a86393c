# SPDX-License-Identifier: BSD-3-Clause
"""pvpython test of the BezierCut filter against its contract.

Usage: pvpython TestBezierCut.py <path to FacePlan plugin>
Checks, on generated meshes: topology unchanged; exactly the ROI (not boundary) vertices on the cut
side move; moved vertices lie on the Bezier surface (1e-8; output points are double);
unmoved vertices keep their values exactly; Displacement = new - old (exactly zero where unmoved);
no flipped or degenerate triangles and every triangle that moved entirely faces the surface normal;
the input is not modified; output port 1 is the surface; ill-defined control points give an empty
output and an error naming the problem.
"""
import os
import sys

import numpy as np
from paraview.simple import *  # noqa: F401,F403

LoadPlugin(sys.argv[1], ns=globals())
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from faceplan_test_util import (ErrorCatcher, area_vectors, bezier_curve, cells_equal, check, fetch, finish,
                                point_array, points, producer, triangles)
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkFiltersCore import vtkTriangleFilter, vtkCleanPolyData
from vtkmodules.vtkFiltersSources import vtkTessellatedBoxSource

SURFACE_TOL = 1e-8  # the chord distance used for the curved case overestimates by < 1e-8


def line(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    return [float(x) for i in range(4) for x in (a + (b - a) * i / 3.0)]


def check_cut(label, inp, out, expected_moved, on_surface, normal_of_full=None):
    """The contract on one result. on_surface(points) -> distances to the Bezier surface."""
    P0, P1 = points(inp).astype(float), points(out).astype(float)
    T = triangles(inp)
    check(out.GetNumberOfPoints() == inp.GetNumberOfPoints(), label + ": same number of points")
    check(cells_equal(out, inp), label + ": identical cells (topology unchanged)")
    disp = point_array(out, "Displacement")
    if not check(disp is not None and disp.shape == P0.shape, label + ": Displacement array"):
        return
    moved = np.any(points(out).astype(float) != points(inp).astype(float), axis=1)
    check(np.array_equal(moved, expected_moved),
          label + ": moved set = ROI interior on the cut side (%d moved, %d expected, %d differ)"
          % (moved.sum(), expected_moved.sum(), np.sum(moved != expected_moved)))
    check(moved.sum() > 20, label + ": a real cut (%d moved)" % moved.sum())
    steps = out.GetFieldData().GetArray("IntermediarySteps")
    print("%s: %d of %d points moved, intermediary surfaces: %s"
          % (label, moved.sum(), len(moved), steps.GetValue(0) if steps else "?"))
    check(np.all(disp[~moved] == 0.0), label + ": Displacement exactly zero where unmoved")
    check(np.allclose(disp, P1 - P0, atol=1e-12), label + ": Displacement = new - old")
    d = on_surface(P1[moved])
    check(d.max() < SURFACE_TOL, label + ": moved points on the surface (max distance %.3g)" % d.max())
    for name in ("ROIMask", "ROIBoundary"):
        check(np.array_equal(point_array(out, name), point_array(inp, name)), label + ": %s passed through" % name)
    A0, A1 = area_vectors(P0, T), area_vectors(P1, T)
    touched = moved[T].any(axis=1)
    full = moved[T].all(axis=1)
    norm0, norm1 = np.linalg.norm(A0, axis=1), np.linalg.norm(A1, axis=1)
    check(np.all(norm1[touched] > 1e-8 * norm0[touched]), label + ": no degenerate triangle")
    partial = touched & ~full
    check(np.all(np.sum(A0[partial] * A1[partial], axis=1) > 0), label + ": partially moved triangles not flipped")
    if normal_of_full is not None:
        n = normal_of_full(P1[T[full]].mean(axis=1))
        check(np.all(np.sum(A1[full] * n, axis=1) > 0), label + ": fully moved triangles face the surface normal")
        faced = full & (np.sum(A0 * normal_of_full(P0[T].mean(axis=1)), axis=1) > 0)
        check(np.all(np.sum(A0[faced] * A1[faced], axis=1) > 0), label + ": triangles that faced the normal keep their sign")
    else:
        check(np.all(np.sum(A0[full] * A1[full], axis=1) > 0), label + ": fully moved triangles not flipped")


# ---------------------------------------------------------------- a plane cut of a sphere cap
sphere = Sphere(ThetaResolution=64, PhiResolution=64, Radius=1.0)
roi = ROIExtract(Input=sphere)
roi.Region = "Sphere"
roi.Region.Center = [0, 0, 1]
roi.Region.Radius = 0.8
roi.UpdatePipeline()
roi_data = fetch(roi)
P = points(roi_data).astype(float)
mask, boundary = point_array(roi_data, "ROIMask"), point_array(roi_data, "ROIBoundary")

cut = BezierCut(Input=roi)
errors = ErrorCatcher(cut)
h = 0.75
cut.CurveU = line([-1.2, -1.2, h], [1.2, -1.2, h])
cut.CurveV = line([-1.2, -1.2, h], [-1.2, 1.2, h])
cut.Operation = "Cut"
cut.UpdatePipeline()
out = fetch(cut)
check(not errors.messages, "plane cut: no error (%s)" % errors.messages)
expected = (mask == 1) & (boundary == 0) & (P[:, 2] > h)
check_cut("plane cut", roi_data, out, expected, lambda X: np.abs(X[:, 2] - h),
          normal_of_full=lambda X: np.tile([0, 0, 1.0], (len(X), 1)))
surf = fetch(cut, 1)
check(surf.GetNumberOfPoints() == 17 * 17 and surf.GetNumberOfCells() == 2 * 16 * 16,
      "port 1: the operative surface tessellation (%d points)" % surf.GetNumberOfPoints())
check(np.allclose(points(surf)[:, 2], h), "port 1: lies on the plane")
check(np.array_equal(points(fetch(roi)), points(roi_data)), "input points not modified")

# FlipNormal: now the band between the ROI boundary and the plane is on the cut side.
cut.FlipNormal = 1
cut.UpdatePipeline()
out = fetch(cut)
if out.GetNumberOfPoints() > 0:
    expected = (mask == 1) & (boundary == 0) & (P[:, 2] < h)
    check_cut("flipped cut", roi_data, out, expected, lambda X: np.abs(X[:, 2] - h))
else:
    check(errors.contains("without folding"), "flipped cut: failure only for a folding reason (%s)" % errors.messages)
cut.FlipNormal = 0
errors.clear()

# ---------------------------------------------------------------- fill
cut.Operation = "Fill"
hf = 0.97
cut.CurveU = line([-1.2, -1.2, hf], [1.2, -1.2, hf])
cut.CurveV = line([-1.2, -1.2, hf], [-1.2, 1.2, hf])
cut.UpdatePipeline()
out = fetch(cut)
check(not errors.messages, "fill: no error (%s)" % errors.messages)
expected = (mask == 1) & (boundary == 0) & (P[:, 2] < hf)
check_cut("fill", roi_data, out, expected, lambda X: np.abs(X[:, 2] - hf),
          normal_of_full=lambda X: np.tile([0, 0, 1.0], (len(X), 1)))
cut.Operation = "Cut"

# ---------------------------------------------------------------- a curved surface
# U: an arch in the xz plane, V: straight along y, so a point is on S iff its (x, z) is on U.
U = [-1.2, -1.2, 0.45, -0.4, -1.2, 0.95, 0.4, -1.2, 0.95, 1.2, -1.2, 0.45]
cut.CurveU = U
cut.CurveV = line([-1.2, -1.2, 0.45], [-1.2, 1.2, 0.45])
cut.UpdatePipeline()
out = fetch(cut)
check(not errors.messages, "curved cut: no error (%s)" % errors.messages)
uu = np.linspace(0, 1, 20001)
arch = bezier_curve(U, uu)[:, [0, 2]]


def dist_to_arch(X):
    """Distance in the xz plane to the densely sampled arch, through its two nearest chords."""
    res = []
    for p in X[:, [0, 2]]:
        j = int(np.argmin(np.linalg.norm(arch - p, axis=1)))
        best = np.inf
        for a, b in ((max(j - 1, 0), j), (j, min(j + 1, len(arch) - 1))):
            ab = arch[b] - arch[a]
            s = 0.0 if not ab.any() else np.clip(np.dot(p - arch[a], ab) / np.dot(ab, ab), 0, 1)
            best = min(best, np.linalg.norm(arch[a] + s * ab - p))
        res.append(best)
    return np.array(res)


# Expected side: above the arch (the normal Su x Sv = (x' , 0, z') x (0,1,0) points up in the middle).
def above_arch(X):
    out_ = np.zeros(len(X), dtype=bool)
    for i, p in enumerate(X):
        j = np.argmin(np.linalg.norm(arch - p[[0, 2]], axis=1))
        tangent = arch[min(j + 1, len(arch) - 1)] - arch[max(j - 1, 0)]
        n = np.array([-tangent[1], tangent[0]])  # (x', z') rotated: normal of Su x Sv in the xz plane
        out_[i] = np.dot(p[[0, 2]] - arch[j], n) > 0 and 0 < j < len(arch) - 1
    return out_


expected = (mask == 1) & (boundary == 0) & above_arch(P)
check_cut("curved cut", roi_data, out, expected, lambda X: dist_to_arch(X) + 0.0)

# ---------------------------------------------------------------- a plate that needs intermediary surfaces
box = vtkTessellatedBoxSource()
box.SetBounds(-0.15, 0.15, -0.6, 0.6, -1.0, 1.0)
box.SetLevel(12)
box.QuadsOn()
box.DuplicateSharedPointsOff()
clean = vtkCleanPolyData()
clean.SetInputConnection(box.GetOutputPort())
tri = vtkTriangleFilter()
tri.SetInputConnection(clean.GetOutputPort())
tri.Update()
plate = producer(tri.GetOutput())
roi2 = ROIExtract(Input=plate)
roi2.Region = "Plane"
roi2.Region.Origin = [0, 0, 0.0]
roi2.Region.Normal = [0, 0, -1]
roi2.UpdatePipeline()
plate_roi = fetch(roi2)
PP = points(plate_roi).astype(float)
cut2 = BezierCut(Input=roi2)
errors2 = ErrorCatcher(cut2)
hp = 0.55
cut2.CurveU = line([-1, -1, hp], [1, -1, hp])
cut2.CurveV = line([-1, -1, hp], [-1, 1, hp])
cut2.UpdatePipeline()
out = fetch(cut2)
check(not errors2.messages, "plate: no error (%s)" % errors2.messages)
if out.GetNumberOfPoints():
    steps = out.GetFieldData().GetArray("IntermediarySteps").GetValue(0)
    check(steps > 0, "plate: mapped through intermediary surfaces (%d)" % steps)
    m2, b2 = point_array(plate_roi, "ROIMask"), point_array(plate_roi, "ROIBoundary")
    check_cut("plate", plate_roi, out, (m2 == 1) & (b2 == 0) & (PP[:, 2] > hp), lambda X: np.abs(X[:, 2] - hp),
              normal_of_full=lambda X: np.tile([0, 0, 1.0], (len(X), 1)))

# ---------------------------------------------------------------- the real mandible (Data/face)
# Lower-border reduction: a horizontal plane 15 % of the height above the lowest point, normal -z
# (U along y, V along x), ROI = everything up to 25 % above it.
mandible_file = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "Data", "face", "mandible.vtp")
if check(os.path.exists(mandible_file), "mandible data present (%s)" % mandible_file):
    mand = XMLPolyDataReader(FileName=[mandible_file])
    MP = points(fetch(mand)).astype(float)
    lo, hi = MP.min(axis=0), MP.max(axis=0)
    hm = lo[2] + 0.15 * (hi[2] - lo[2])
    roi3 = ROIExtract(Input=mand)
    roi3.Region = "Plane"
    roi3.Region.Origin = [0, 0, lo[2] + 0.40 * (hi[2] - lo[2])]
    roi3.Region.Normal = [0, 0, 1]
    roi3.UpdatePipeline()
    mand_roi = fetch(roi3)
    cut3 = BezierCut(Input=roi3)
    errors4 = ErrorCatcher(cut3)
    cut3.CurveU = line([lo[0] - 10, lo[1] - 10, hm], [lo[0] - 10, hi[1] + 10, hm])
    cut3.CurveV = line([lo[0] - 10, lo[1] - 10, hm], [hi[0] + 10, lo[1] - 10, hm])
    cut3.UpdatePipeline()
    out = fetch(cut3)
    check(not errors4.messages, "mandible: no error (%s)" % errors4.messages)
    if out.GetNumberOfPoints():
        m3, b3 = point_array(mand_roi, "ROIMask"), point_array(mand_roi, "ROIBoundary")
        check_cut("mandible", mand_roi, out, (m3 == 1) & (b3 == 0) & (MP[:, 2] < hm), lambda X: np.abs(X[:, 2] - hm),
                  normal_of_full=lambda X: np.tile([0, 0, -1.0], (len(X), 1)))
    # An ROI whose boundary dips below the cut cannot be cut cleanly: a clear error, no output.
    roi3.Region.Origin = [0, 0, hm + 0.02 * (hi[2] - lo[2])]
    errors4.clear()
    cut3.UpdatePipeline()
    tight_failed = fetch(cut3).GetNumberOfPoints() == 0
    print("mandible, tight ROI:", "error" if tight_failed else "cut succeeded")
    if tight_failed:
        check(errors4.contains("ROIBoundary vertices"), "mandible, tight ROI: the error names the ROI boundary (%s)"
              % errors4.messages)

# ---------------------------------------------------------------- ill-defined control points
good_u, good_v = line([-1.2, -1.2, h], [1.2, -1.2, h]), line([-1.2, -1.2, h], [-1.2, 1.2, h])
cases = [
    # Both first points moved, to different places: nothing tells which P0 is meant.
    ("first points not shared", line([-1.25, -1.2, h], [1.2, -1.2, h]), line([-1.2, -1.1, h], [-1.2, 1.2, h]),
     "first control points not shared"),
    ("wrong count", good_u + [1.5, -1.2, h], good_v, "3k+1"),
    ("coincident", good_u[:3] + good_u[:3] + good_u[6:], good_v, "degenerate"),
    ("parallel", good_u, line([-1.2, -1.2, h], [0, -1.2, h]), "degenerate"),
    ("loop", [0, 0, 0, 2, 1.5, 0, -1, 1.5, 0, 1, 0, 0], line([0, 0, 0], [0, 0, 1]), "self-intersecting"),
    ("far away", line([10, 10, h], [11, 10, h]), line([10, 10, h], [10, 11, h]), "not meeting the ROI"),
]
for label, u, v, text in cases:
    errors.clear()
    cut.CurveU = u
    cut.CurveV = v
    cut.UpdatePipeline()
    o0, o1 = fetch(cut, 0), fetch(cut, 1)
    check(o0.GetNumberOfPoints() == 0 and o1.GetNumberOfPoints() == 0, label + ": empty outputs")
    check(errors.contains(text), label + ": error says '%s' (%s)" % (text, errors.messages))

# Recovers after an error.
errors.clear()
cut.CurveU, cut.CurveV = good_u, good_v
cut.UpdatePipeline()
check(fetch(cut).GetNumberOfPoints() == roi_data.GetNumberOfPoints() and not errors.messages, "recovers after errors")

# The shared first point is linked: moving one curve's first point (as a GUI drag of one handle
# does) moves P0 for both, and the bone stays; a later edit of the other curve, whose first point
# is still the old one, keeps the moved P0.
def displacement_of(proxy):
    out = fetch(proxy)
    return None if out.GetNumberOfPoints() == 0 else vtk_to_numpy(out.GetPointData().GetArray("Displacement")).copy()


def fresh_cut(u, v):
    f = BezierCut(Input=roi, CurveU=u, CurveV=v)
    f.UpdatePipeline()
    d = displacement_of(f)
    Delete(f)
    return d


errors.clear()
cut.CurveU, cut.CurveV = good_u, good_v
cut.UpdatePipeline()
p0 = [-1.1, -1.15, h]
moved_u = p0 + good_u[3:]
cut.CurveU = moved_u
cut.UpdatePipeline()
linked = displacement_of(cut)
expected = fresh_cut(moved_u, p0 + good_v[3:])
check(not errors.messages and linked is not None, "moving Curve U's first point alone keeps the bone (%s)" % errors.messages)
check(linked is not None and expected is not None and np.abs(linked - expected).max() == 0.0,
      "moving Curve U's first point moves Curve V's with it")
stale_v = good_v[:3] + [-1.2, -0.5, h] + good_v[6:]  # Curve V edited, its first point as before
cut.CurveV = stale_v
cut.UpdatePipeline()
kept = displacement_of(cut)
expected = fresh_cut(moved_u, p0 + stale_v[3:])
check(not errors.messages and kept is not None and expected is not None and np.abs(kept - expected).max() == 0.0,
      "an edit of Curve V keeps the moved P0 (%s)" % errors.messages)
cut.CurveV = [-1.0, -1.2, h] + stale_v[3:]  # now Curve V's first point moves: P0 follows it
cut.UpdatePipeline()
followed = displacement_of(cut)
expected = fresh_cut([-1.0, -1.2, h] + moved_u[3:], [-1.0, -1.2, h] + stale_v[3:])
check(not errors.messages and followed is not None and expected is not None and
      np.abs(followed - expected).max() == 0.0, "moving Curve V's first point moves P0 for both")
cut.CurveU, cut.CurveV = good_u, good_v

# Input without ROI arrays.
bare = BezierCut(Input=sphere)
errors3 = ErrorCatcher(bare)
bare.CurveU, bare.CurveV = good_u, good_v
bare.UpdatePipeline()
check(fetch(bare).GetNumberOfPoints() == 0 and errors3.contains("ROIMask"), "missing ROI arrays: error")

finish("TestBezierCut")
