# SPDX-License-Identifier: BSD-3-Clause
"""Bad-input contract of Bezier Cut through pvpython: every property (control point lists of the wrong
length or 3k+1 count, NaN/inf/huge control points, enums and resolutions out of range) and malformed
inputs (missing, short or NaN ROI arrays, lines-only or cell-less bones, volume cells, bad ids). Each
case gives an error naming the problem and empty outputs, or, for legal but extreme input, a finite
output with a warning. argv[1] is the plugin."""
import os
import sys

import numpy as np
from paraview.simple import *  # noqa: F401,F403

LoadPlugin(sys.argv[1], ns=globals())
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from badinput_util import Cases, Catcher, copy, plane_bone, point_array, polydata, set_points, unstructured
from faceplan_test_util import check, fetch, finish, producer
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonDataModel import VTK_TETRA, vtkImageData

cases = Cases("BezierCut")
PORTS = (0, 1)


def line(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    return [float(x) for i in range(4) for x in (a + (b - a) * i / 3.0)]


def roi_bone(offset=(0.0, 0.0, 0.0)):
    """The flat bone with ROIMask/ROIBoundary from ROI Extract (as the filter would get it)."""
    from vtkmodules.vtkCommonDataModel import vtkSphere
    from paraview import servermanager
    b = plane_bone(offset=offset, push=False)
    b.GetPointData().RemoveArray("ROIMask")
    b.GetPointData().RemoveArray("Displacement")
    roi = ROIExtract(Input=producer(b))
    roi.Region = "Sphere"
    roi.Region.Center = list(np.add([5, 5, 0], offset))
    roi.Region.Radius = 4
    roi.UpdatePipeline()
    out = copy(fetch(roi))
    Delete(roi)
    return out


BONE = roi_bone()
U = line([0, 0, -0.5], [10, 0, -0.5])
V = line([0, 0, -0.5], [0, 10, -0.5])


def cut_on(dataset, u=U, v=V):
    f = BezierCut(Input=producer(dataset))
    f.CurveU = list(u)
    f.CurveV = list(v)
    return f, Catcher(f)


f, c = cut_on(BONE)
good = cases.ok("the plain cut (the cases' baseline)", f, c)
check(good.GetFieldData().GetArray("NumberOfMovedPoints").GetValue(0) > 10, "BezierCut: the baseline cut moves points")

# Properties: control point lists.
f, c = cut_on(BONE, u=U[:-3] + [5, 0, -0.5, 6, 0, -0.5])
cases.error("CurveU with 5 points (not 3k+1)", f, c, "CurveU", "5 points", "3k+1", ports=PORTS)
f, c = cut_on(BONE, v=V[:9])
cases.error("CurveV with 3 points", f, c, "CurveV", "3 points", "3k+1", ports=PORTS)
f, c = cut_on(BONE, u=U[:-1])
cases.error("CurveU list not a multiple of 3", f, c, "CurveU", "3k+1", ports=PORTS)
f, c = cut_on(BONE, u=U[:4] + [float("nan")] + U[5:])
cases.error("CurveU NaN", f, c, "CurveU point 1", "not finite", ports=PORTS)
f, c = cut_on(BONE, v=V[:7] + [float("inf")] + V[8:])
cases.error("CurveV inf", f, c, "CurveV point 2", "not finite", ports=PORTS)
f, c = cut_on(BONE, u=U[:9] + [1e200, 0, -0.5])
cases.error("CurveU point at 1e200", f, c, "too large", ports=PORTS)
f, c = cut_on(BONE, v=[0, 0.5, -0.5] + V[3:])
cases.error("curves not sharing P0", f, c, "first control points not shared", ports=PORTS)
f, c = cut_on(BONE, u=U[:3] + U[:3] + U[6:])
cases.error("coincident control points", f, c, "control points 0 and 1 coincide", ports=PORTS)
f, c = cut_on(BONE, u=line([20, 20, -0.5], [30, 20, -0.5]), v=line([20, 20, -0.5], [20, 30, -0.5]))
cases.error("surface away from the ROI", f, c, "surface not meeting the ROI", ports=PORTS)

# Properties: enums and ranges (pvpython bypasses the GUI's domains; nothing is clamped).
for value in (7, -1):
    f, c = cut_on(BONE)
    f.Operation = value
    cases.error("Operation %d" % value, f, c, "Operation", str(value), ports=PORTS)
for value in (0, 1000):
    f, c = cut_on(BONE)
    f.SurfaceResolution = value
    cases.error("SurfaceResolution %d" % value, f, c, "SurfaceResolution", str(value), ports=PORTS)

# Inputs.
f, c = cut_on(polydata(np.zeros((0, 3))))
cases.error("empty input", f, c, "no points", ports=PORTS)
img = vtkImageData()
img.SetDimensions(3, 3, 3)
f, c = cut_on(img)
cases.error("image data input (wrong type)", f, c, "vtkPointSet", ports=PORTS)
bad = copy(BONE)
bad.GetPointData().RemoveArray("ROIMask")
f, c = cut_on(bad)
cases.error("no ROIMask", f, c, "ROIMask", "ROI Extract", ports=PORTS)
bad = copy(BONE)
point_array(bad, "ROIBoundary", np.zeros((BONE.GetNumberOfPoints(), 3)))
f, c = cut_on(bad)
cases.error("ROIBoundary with 3 components", f, c, "one-component", ports=PORTS)
bad = copy(BONE)
mask = vtk_to_numpy(BONE.GetPointData().GetArray("ROIMask")).astype(float)
point_array(bad, "ROIMask", mask[:-20])
f, c = cut_on(bad)
cases.error("ROIMask too short", f, c, "ROIMask", "values", "one per point", ports=PORTS)
bad = copy(BONE)
m = mask.copy()
m[np.argmax(m)] = np.nan
point_array(bad, "ROIMask", m)
f, c = cut_on(bad)
cases.error("ROIMask NaN", f, c, "ROIMask", "NaN", ports=PORTS)
bad = copy(BONE)
point_array(bad, "ROIMask", np.zeros_like(mask))
f, c = cut_on(bad)
cases.error("ROIMask all zero", f, c, "ROI is empty", ports=PORTS)
P = vtk_to_numpy(BONE.GetPoints().GetData()).copy()
lines_only = polydata(P, lines=[[i, i + 1] for i in range(len(P) - 1)])
for name in ("ROIMask", "ROIBoundary"):
    lines_only.GetPointData().AddArray(BONE.GetPointData().GetArray(name))
f, c = cut_on(lines_only)
cases.error("bone of lines only", f, c, "no surface cells", ports=PORTS)
no_cells = polydata(P)
for name in ("ROIMask", "ROIBoundary"):
    no_cells.GetPointData().AddArray(BONE.GetPointData().GetArray(name))
f, c = cut_on(no_cells)
cases.error("bone with no cells", f, c, "no surface cells", ports=PORTS)
vol = unstructured(P, [[0, 1, 14, 13]], [VTK_TETRA])
for name in ("ROIMask", "ROIBoundary"):
    vol.GetPointData().AddArray(BONE.GetPointData().GetArray(name))
f, c = cut_on(vol)
cases.error("volume cells", f, c, "not a surface cell", ports=PORTS)
bad = copy(BONE)
pts = P.copy()
pts[30] = [0, np.nan, 0]
set_points(bad, pts)
f, c = cut_on(bad)
cases.error("NaN coordinate", f, c, "point 30", "NaN", ports=PORTS)
bad = copy(BONE)
bad.GetPolys().GetConnectivityArray().SetValue(7, -5)
f, c = cut_on(bad)
cases.error("negative triangle id", f, c, "point id -5", ports=PORTS)
bad = copy(BONE)
bad.GetPolys().GetConnectivityArray().SetValue(7, len(P) + 3)
f, c = cut_on(bad)
cases.error("triangle id past the end", f, c, "point id %d" % (len(P) + 3), ports=PORTS)

# Legal but extreme.
mixed = copy(BONE)
from vtkmodules.vtkCommonDataModel import vtkCellArray
lines = vtkCellArray()
lines.InsertNextCell(2, [0, 1])
mixed.SetLines(lines)
f, c = cut_on(mixed)
out = cases.warning("triangles and a line", f, c, "line", "ignored")
check(np.allclose(vtk_to_numpy(out.GetPointData().GetArray("Displacement")).sum(),
                  vtk_to_numpy(good.GetPointData().GetArray("Displacement")).sum(), rtol=0, atol=1e-12),
      "BezierCut [triangles and a line]: the same cut as without the line")
far_bone = roi_bone(offset=(1e6, 1e6, 1e6))
shift = np.array([1e6, 1e6, 1e6] * 4)
f, c = cut_on(far_bone, u=list(np.add(U, shift)), v=list(np.add(V, shift)))
out = cases.ok("offset 1e6", f, c)
d_far = vtk_to_numpy(out.GetPointData().GetArray("Displacement"))
d_near = vtk_to_numpy(good.GetPointData().GetArray("Displacement"))
check(np.allclose(d_far, d_near, rtol=0, atol=1e-9), "BezierCut [offset 1e6]: the same displacements as at the origin "
      "(max difference %.3g)" % np.abs(d_far - d_near).max())
check(np.array_equal(vtk_to_numpy(BONE.GetPoints().GetData()), P), "BezierCut: input not modified")

print("BezierCut bad-input cases: %d" % cases.count)
finish("TestBadInputBezierCut")
