# SPDX-License-Identifier: BSD-3-Clause
"""Bad-input contract of ROI Extract through pvpython (properties the GUI's domains would stop, and
malformed inputs): each case gives an error naming the problem and an empty output, or, for legal
but extreme input, a finite output with a warning. argv[1] is the plugin."""
import os
import sys

import numpy as np
from paraview.simple import *  # noqa: F401,F403

LoadPlugin(sys.argv[1], ns=globals())
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from badinput_util import Cases, Catcher, copy, plane_bone, polydata, set_points, unstructured
from faceplan_test_util import check, fetch, finish, producer
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonDataModel import VTK_TETRA, VTK_TRIANGLE, vtkImageData

cases = Cases("ROIExtract")
bone = plane_bone(push=False)
bone_points = vtk_to_numpy(bone.GetPoints().GetData()).copy()


def roi_on(dataset, region="Sphere"):
    f = ROIExtract(Input=producer(dataset))
    f.Region = region
    if region == "Sphere":
        f.Region.Center = [5, 5, 0]
        f.Region.Radius = 4
    return f, Catcher(f)


# Properties.
for radius, words in ((-4.0, ("radius", "-4")), (0.0, ("radius", "0")), (float("nan"), ("radius", "nan")),
                      (float("inf"), ("radius", "inf"))):
    f, c = roi_on(bone)
    f.Region.Radius = radius
    cases.error("sphere radius %g" % radius, f, c, *words)
f, c = roi_on(bone)
f.Region.Center = [5, float("nan"), 0]
cases.error("sphere centre NaN", f, c, "region", "nan")
f, c = roi_on(bone, "Plane")
f.Region.Origin = [5, 5, 0]
f.Region.Normal = [0, 0, 0]
cases.error("plane normal zero", f, c, "plane", "normal")
f, c = roi_on(bone, "Plane")
f.Region.Origin = [5, 5, float("inf")]
cases.error("plane origin inf", f, c, "region", "nan")
f, c = roi_on(bone, "Box")
f.Region.Position = [2, 2, -1]
f.Region.Length = [4, -4, 2]
cases.error("box negative length", f, c, "box", "length")
f, c = roi_on(bone, "Box")
f.Region.Position = [2, 2, -1]
f.Region.Length = [4, 0, 2]
cases.error("box zero length", f, c, "box", "length")
f, c = roi_on(bone)
f.PointIds = [3, bone.GetNumberOfPoints()]
cases.error("point id past the end", f, c, "point id", str(bone.GetNumberOfPoints()), "out of range")
f, c = roi_on(bone)
f.PointIds = [3, -2]
cases.error("negative point id", f, c, "point id", "-2", "out of range")
f, c = roi_on(bone)
f.Region.Center = [500, 500, 0]
out = cases.warning("sphere away from the bone (empty ROI)", f, c, "roi", "empty")
check(out.GetPointData().GetArray("ROIMask") is not None, "ROIExtract [empty ROI]: ROIMask present")

# Inputs.
f, c = roi_on(polydata(np.zeros((0, 3))))
cases.error("empty input", f, c, "no points")
img = vtkImageData()
img.SetDimensions(3, 3, 3)
f, c = roi_on(img)
cases.error("image data input (wrong type)", f, c, "vtkPointSet")
bad = copy(bone)
pts = bone_points.copy()
pts[10] = [np.nan, 0, 0]
set_points(bad, pts)
f, c = roi_on(bad)
cases.error("NaN coordinate", f, c, "point 10", "finite")
bad = polydata(bone_points[:4], polys=[[0, 1, 2], [1, 2, 7]])
f, c = roi_on(bad)
cases.error("triangle id past the end", f, c, "point id 7")
bad = polydata(bone_points[:4], polys=[[0, 1, 2], [1, -3, 3]])
f, c = roi_on(bad)
cases.error("negative triangle id", f, c, "point id -3")
bad = unstructured(bone_points[:8], [[0, 1, 2, 30]], [VTK_TETRA])
f, c = roi_on(bad)
cases.error("tetrahedron id past the end", f, c, "point id 30")
bad = unstructured(bone_points[:8], [[0, 1, 2], [0, -1, 2, 3]], [VTK_TRIANGLE, VTK_TETRA])
f, c = roi_on(bad)
cases.error("mixed cells, negative tetrahedron id", f, c, "point id -1")

# Legal but extreme: a huge coordinate offset keeps an exact selection.
far = copy(bone)
set_points(far, bone_points + 1e8)
f, c = roi_on(far)
f.Region.Center = [1e8 + 5, 1e8 + 5, 1e8]
out = cases.ok("offset 1e8", f, c)
mask = vtk_to_numpy(out.GetPointData().GetArray("ROIMask"))
expected = np.linalg.norm(bone_points - [5, 5, 0], axis=1) < 4
check(np.array_equal(mask.astype(bool), expected), "ROIExtract [offset 1e8]: the same ROI as at the origin")
check(np.array_equal(vtk_to_numpy(far.GetPoints().GetData()), bone_points + 1e8), "ROIExtract: input not modified")

print("ROIExtract bad-input cases: %d" % cases.count)
finish("TestBadInputROIExtract")
