# SPDX-License-Identifier: BSD-3-Clause
"""Bad-input contract of Osteotomy through pvpython: enums out of range, NaN/inf planes and moves,
malformed inputs. Each case gives an error naming the problem and empty outputs, or, for legal
input, a finite output. argv[1] is the plugin."""
import os
import sys

import numpy as np
from paraview.simple import *  # noqa: F401,F403

LoadPlugin(sys.argv[1], ns=globals())
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from badinput_util import Cases, Catcher, copy, polydata, set_points
from faceplan_test_util import check, finish, producer
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonDataModel import vtkImageData
from vtkmodules.vtkFiltersCore import vtkTriangleFilter
from vtkmodules.vtkFiltersSources import vtkSphereSource

cases = Cases("Osteotomy")
PORTS = (0, 1)
src = vtkSphereSource()
src.SetRadius(5)
src.SetThetaResolution(24)
src.SetPhiResolution(16)
tri = vtkTriangleFilter()
tri.SetInputConnection(src.GetOutputPort())
tri.Update()
BONE = copy(tri.GetOutput())
P = vtk_to_numpy(BONE.GetPoints().GetData()).astype(float)


def osteotomy_on(dataset, **props):
    f = Osteotomy(Input=producer(dataset), Operation="Custom")
    f.CutPlane1 = "Plane"
    f.CutPlane1.Origin = [1, 0, 0]
    f.CutPlane1.Normal = [1, 0, 0]
    f.Translation = [0, 0, 1]
    for k, v in props.items():
        f.SetPropertyWithName(k, v)
    return f, Catcher(f)


f, c = osteotomy_on(BONE)
out = cases.ok("a plain cut and move (the cases' baseline)", f, c)
check(np.abs(vtk_to_numpy(out.GetPointData().GetArray("Displacement"))).max() > 0.5, "Osteotomy: the baseline moves")

for value in (2, -1):
    f, c = osteotomy_on(BONE, PivotMode=value)
    cases.error("PivotMode %d" % value, f, c, "PivotMode", str(value), ports=PORTS)
for prop, value in (("Translation", [0, float("nan"), 0]), ("Rotation", [float("inf"), 0, 0]),
                    ("Pivot", [float("nan"), 0, 0])):
    f, c = osteotomy_on(BONE, **{prop: value})
    if prop == "Pivot":
        f.SetPropertyWithName("PivotMode", 1)
    cases.error("%s not finite" % prop, f, c, "finite", ports=PORTS)
f, c = osteotomy_on(BONE)
f.CutPlane1.Normal = [0, 0, 0]
cases.error("cut plane normal zero", f, c, "normal", ports=PORTS)
f, c = osteotomy_on(BONE)
f.CutPlane1.Origin = [float("nan"), 0, 0]
cases.error("cut plane origin NaN", f, c, "finite", ports=PORTS)
f, c = osteotomy_on(BONE)
f.CutPlane1.Origin = [50, 0, 0]
cases.error("cut plane beside the bone", f, c, "side", ports=PORTS)
f, c = osteotomy_on(polydata(np.zeros((0, 3))))
cases.error("empty input", f, c, "no triangles", ports=PORTS)
img = vtkImageData()
img.SetDimensions(3, 3, 3)
f, c = osteotomy_on(img)
cases.error("image data input (wrong type)", f, c, "vtkImageData", ports=PORTS)
f, c = osteotomy_on(polydata(P, lines=[[i, i + 1] for i in range(len(P) - 1)]))
cases.error("bone of lines only", f, c, "no triangles", ports=PORTS)
bad = copy(BONE)
pts = P.copy()
pts[7] = [np.nan, 0, 0]
set_points(bad, pts)
f, c = osteotomy_on(bad)
cases.error("NaN coordinate", f, c, "NaN", ports=PORTS)
bad = copy(BONE)
bad.GetPolys().GetConnectivityArray().SetValue(4, len(P) + 2)
f, c = osteotomy_on(bad)
cases.error("triangle id past the end", f, c, str(len(P) + 2), ports=PORTS)
# The operation presets' properties.
for value in (4, -1):
    f, c = osteotomy_on(BONE, Operation=value)
    cases.error("Operation %d" % value, f, c, "Operation", str(value), ports=PORTS)
for prop, value, text in (("AnteriorDirection", [0, 0, 0], "zero length"),
                          ("AnteriorDirection", [float("nan"), 0, 0], "not finite"),
                          ("SuperiorDirection", [float("inf"), 0, 0], "not finite"),
                          ("SuperiorDirection", [-2, 0, 0.1], "parallel")):
    f, c = osteotomy_on(BONE, Operation=1, **{prop: value})
    cases.error("%s %s with a preset" % (prop, value), f, c, text, ports=PORTS)
f, c = osteotomy_on(BONE, Operation=2)  # a sphere has no ramus above its crest
cases.error("BSSO on a bone without a ramus", f, c, "ramus", ports=PORTS)
f, c = osteotomy_on(polydata(np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, 0.5, 0]], float),
                             polys=[[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]), Operation=1)
cases.error("LeFortI on a flat bone", f, c, "flat", ports=PORTS)
check(np.array_equal(vtk_to_numpy(BONE.GetPoints().GetData()), P), "Osteotomy: input not modified")

print("Osteotomy bad-input cases: %d" % cases.count)
finish("TestBadInputOsteotomy")
