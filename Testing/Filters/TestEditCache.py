# SPDX-License-Identifier: BSD-3-Clause
"""Bezier Cut and Osteotomy keep what depends only on their input across edits; the result never
depends on it (pvpython, headless).

Bezier Cut keeps its converted input (surface, ROI flags, neighbours, fan triangles, default curves)
while only the control points change: InputConversionCount stays put. Osteotomy keeps its split
bone while only the move changes: SplitCount stays put. After every edit - control points or move
alone, a changed ROI, a changed bone (new points upstream, the same data set modified in place),
a changed plane or side - the output must equal, value for value, that of a fresh filter with the
same settings, and a change of anything but the control points / the move must rebuild.
argv[1] is the plugin, argv[2] the Data folder.
"""
import os
import sys

import numpy as np
from paraview.simple import *  # noqa: F401,F403

LoadPlugin(sys.argv[1], ns=globals())
data = sys.argv[2]
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from faceplan_test_util import check, fetch, finish, point_array, points, producer  # noqa: E402
from vtkmodules.vtkCommonDataModel import vtkPolyData  # noqa: E402


def count(proxy, name):
    proxy.UpdatePropertyInformation()
    return proxy.GetPropertyValue(name)


def same_output(a, b, arrays):
    """Output port 0 of proxies a and b: same points and arrays, value for value."""
    a.UpdatePipeline()
    b.UpdatePipeline()
    x, y = fetch(a), fetch(b)
    if x.GetNumberOfPoints() == 0 or x.GetNumberOfPoints() != y.GetNumberOfPoints():
        return False
    return np.array_equal(points(x), points(y)) and all(
        np.array_equal(point_array(x, n), point_array(y, n)) for n in arrays)


# ------------------------------------------------------------------------------ Bezier Cut
mandible = XMLPolyDataReader(FileName=[data + "/face/mandible.vtp"])
mandible.UpdatePipeline()
mandible_copy = vtkPolyData()
mandible_copy.DeepCopy(mandible.GetClientSideObject().GetOutputDataObject(0))
bone = producer(mandible_copy)
shift = Transform(Input=bone)  # moves the bone when its Translate changes
shift.Transform = "Transform"
roi = ROIExtract(Input=shift)
roi.Region = "Sphere"
roi.Region.Center = [70.0, 0.0, 58.0]
roi.Region.Radius = 22.0
Z = 60.0


def curves(dz):
    u = [40, -30, Z, 60, -30, Z - 0.5, 80, -30, Z - 0.5, 100, -30, Z]
    v = [40, -30, Z, 40, -10, Z + 0.5, 40, 10, Z + 0.5, 40, 30, Z]
    return ([c + dz if i % 3 == 2 else c for i, c in enumerate(u)],
            [c + dz if i % 3 == 2 else c for i, c in enumerate(v)])


cut = BezierCut(Input=roi, FlipNormal=1)
cut.CurveU, cut.CurveV = curves(0.0)
cut.UpdatePipeline()
moved = point_array(fetch(cut), "Displacement")
check(moved is not None and np.abs(moved).max() > 0.5, "the cut moves the chin")
first = count(cut, "InputConversionCount")


def fresh_cut():
    f = BezierCut(Input=roi, FlipNormal=1)
    f.CurveU, f.CurveV = list(cut.CurveU), list(cut.CurveV)
    return f


for k, dz in enumerate((-0.3, 0.2, -0.1, 0.35)):
    cut.CurveU, cut.CurveV = curves(dz)
    cut.UpdatePipeline()
f = fresh_cut()
check(same_output(cut, f, ["Displacement", "ROIMask"]),
      "after edits of the control points the cut equals a fresh filter's")
Delete(f)
check(count(cut, "InputConversionCount") == first,
      "edits of the control points alone do not convert the input again (%d -> %d)"
      % (first, count(cut, "InputConversionCount")))

before = count(cut, "InputConversionCount")
roi.Region.Radius = 18.0
f = fresh_cut()
check(same_output(cut, f, ["Displacement", "ROIMask"]), "after an ROI change the cut equals a fresh filter's")
Delete(f)
check(count(cut, "InputConversionCount") == before + 1, "an ROI change converts the input again")

before = count(cut, "InputConversionCount")
shift.Transform.Translate = [0.0, 0.0, 0.7]
f = fresh_cut()
check(same_output(cut, f, ["Displacement", "ROIMask"]), "after the bone moved the cut equals a fresh filter's")
Delete(f)
check(count(cut, "InputConversionCount") == before + 1, "a moved bone converts the input again")

# The same data set object changed in place, with Modified() as VTK asks: a new stamp.
roi_data = vtkPolyData()
roi_data.DeepCopy(fetch(roi))
given = producer(roi_data)
direct = BezierCut(Input=given, FlipNormal=1)
direct.CurveU, direct.CurveV = list(cut.CurveU), list(cut.CurveV)
direct.UpdatePipeline()


def fresh_direct():
    f = BezierCut(Input=given, FlipNormal=1)
    f.CurveU, f.CurveV = list(direct.CurveU), list(direct.CurveV)
    return f


def changed_in_place(what, change):
    before = count(direct, "InputConversionCount")
    change()
    given.MarkModified(given)
    f = fresh_direct()
    check(same_output(direct, f, ["Displacement", "ROIMask"]),
          "after %s in place the cut equals a fresh filter's" % what)
    Delete(f)
    check(count(direct, "InputConversionCount") == before + 1, "%s in place converts the input again" % what)


def shrink_roi():
    mask = roi_data.GetPointData().GetArray("ROIMask")
    for i in range(roi_data.GetNumberOfPoints()):
        if roi_data.GetPoint(i)[0] > 72.0:
            mask.SetValue(i, 0)
    mask.Modified()


def lift_points():
    pts = roi_data.GetPoints()
    for i in range(pts.GetNumberOfPoints()):
        x, y, z = pts.GetPoint(i)
        pts.SetPoint(i, x, y, z + 0.3)
    pts.Modified()


changed_in_place("ROIMask changed", shrink_roi)
changed_in_place("points changed", lift_points)

# --------------------------------------------------------------------------------- Osteotomy
ost = Osteotomy(Input=shift, Operation="Custom")
ost.CutPlane1.Origin = [97.0, 0.0, 80.0]
ost.CutPlane1.Normal = [-1.0, 0.0, 0.0]
ost.Translation = [-6.0, 0.0, 0.0]
ost.UpdatePipeline()
splits = count(ost, "SplitCount")


def fresh_osteotomy():
    f = Osteotomy(Input=shift, Operation="Custom")
    f.CutPlane1.Origin, f.CutPlane1.Normal = list(ost.CutPlane1.Origin), list(ost.CutPlane1.Normal)
    f.UseSecondPlane = ost.UseSecondPlane
    f.CutPlane2.Origin, f.CutPlane2.Normal = list(ost.CutPlane2.Origin), list(ost.CutPlane2.Normal)
    f.InsideOut = ost.InsideOut
    f.Translation, f.Rotation = list(ost.Translation), list(ost.Rotation)
    f.PivotMode, f.Pivot = ost.PivotMode, list(ost.Pivot)
    return f


arrays = ["Displacement", "ROIMask", "SegmentId"]
for t in ([-5.0, 0.0, 0.0], [-4.0, 1.0, 0.5], [-6.5, 0.0, -0.3]):
    ost.Translation = t
    ost.Rotation = [t[2], 0.0, 2.0]
    ost.UpdatePipeline()
ost.PivotMode = "Custom"
ost.Pivot = [90.0, 0.0, 70.0]
f = fresh_osteotomy()
check(same_output(ost, f, arrays), "after edits of the move the osteotomy equals a fresh filter's")
Delete(f)
check(count(ost, "SplitCount") == splits, "edits of the move alone do not split the bone again (%d -> %d)"
      % (splits, count(ost, "SplitCount")))

for what, change in (("a moved plane", lambda: setattr(ost.CutPlane1, "Origin", [95.0, 0.0, 80.0])),
                     ("a turned plane", lambda: setattr(ost.CutPlane1, "Normal", [-1.0, 0.1, 0.0])),
                     ("Inside Out", lambda: setattr(ost, "InsideOut", 1)),
                     ("a second plane", lambda: (setattr(ost, "UseSecondPlane", 1),
                                                 setattr(ost.CutPlane2, "Origin", [70.0, 0.0, 68.0]),
                                                 setattr(ost.CutPlane2, "Normal", [0.0, 0.0, 1.0]))),
                     ("a moved bone", lambda: setattr(shift.Transform, "Translate", [0.0, 0.5, 0.0]))):
    before = count(ost, "SplitCount")
    change()
    f = fresh_osteotomy()
    check(same_output(ost, f, arrays), "after %s the osteotomy equals a fresh filter's" % what)
    Delete(f)
    check(count(ost, "SplitCount") == before + 1, "%s splits the bone again" % what)

finish("TestEditCache")
