# SPDX-License-Identifier: BSD-3-Clause
"""pvpython test of the ROIExtract filter against its contract.

Usage: pvpython TestROIExtract.py <path to FacePlan plugin>
Checks: ROIMask equals the region predicate computed here; ROIBoundary equals the edge-based
definition computed here from the triangles; geometry, topology and input arrays unchanged; InsideOut
complements; PointIds replace the region; errors give an empty output and an error message; the input
is never modified.
"""
import os
import sys

import numpy as np
from paraview.simple import *  # noqa: F401,F403

LoadPlugin(sys.argv[1], ns=globals())
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from faceplan_test_util import (ErrorCatcher, cells_equal, check, fetch, finish, point_array, points,
                                reference_boundary, triangles)

sphere = Sphere(ThetaResolution=48, PhiResolution=48, Radius=1.0)
sphere_data = fetch(sphere)
P = points(sphere_data).astype(float)
T = triangles(sphere_data)
input_arrays = [sphere_data.GetPointData().GetArrayName(i) for i in range(sphere_data.GetPointData().GetNumberOfArrays())]

roi = ROIExtract(Input=sphere)
errors = ErrorCatcher(roi)


def run_and_check(label, expected_mask):
    roi.UpdatePipeline()
    out = fetch(roi)
    mask = point_array(out, "ROIMask")
    boundary = point_array(out, "ROIBoundary")
    if not check(mask is not None and boundary is not None, label + ": ROIMask and ROIBoundary exist"):
        return
    check(out.GetPointData().GetArray("ROIMask").GetDataTypeAsString() == "unsigned char", label + ": ROIMask is uint8")
    check(np.array_equal(mask, expected_mask.astype(np.uint8)), label + ": ROIMask equals the region predicate")
    check(np.array_equal(boundary, reference_boundary(T, expected_mask.astype(np.uint8))),
          label + ": ROIBoundary equals the edge-based reference")
    check(np.all(boundary <= mask), label + ": boundary vertices are ROI vertices")
    check(0 < boundary.sum() < mask.sum(), label + ": a non-trivial ROI with a boundary ring and an interior")
    check(np.array_equal(points(out), points(sphere_data)), label + ": points unchanged bit for bit")
    check(cells_equal(out, sphere_data), label + ": cells unchanged")
    for name in input_arrays:
        check(out.GetPointData().GetArray(name) is not None, label + ": input array %s passed through" % name)
    check(not errors.messages, label + ": no error (%s)" % errors.messages)


# Sphere region.
roi.Region = "Sphere"
roi.Region.Center = [0.2, 0.1, 0.8]
roi.Region.Radius = 0.6
run_and_check("sphere region", np.linalg.norm(P - [0.2, 0.1, 0.8], axis=1) < 0.6)

roi.InsideOut = 1
run_and_check("inside out", ~(np.linalg.norm(P - [0.2, 0.1, 0.8], axis=1) < 0.6))
roi.InsideOut = 0

# Plane region: the side against the normal.
roi.Region = "Plane"
roi.Region.Origin = [0, 0, 0.3]
roi.Region.Normal = [0, 0, -1]
run_and_check("plane region", (P - [0, 0, 0.3]) @ np.array([0, 0, -1.0]) < 0)

# Box region (axis aligned: Position is the low corner, Length the size).
roi.Region = "Box"
roi.Region.UseReferenceBounds = 0
roi.Region.Position = [-0.5, -0.5, 0.2]
roi.Region.Length = [1.0, 1.0, 1.0]
roi.Region.Rotation = [0, 0, 0]
inside_box = np.all((P > [-0.5, -0.5, 0.2]) & (P < [0.5, 0.5, 1.2]), axis=1)
run_and_check("box region", inside_box)

# Point ids replace the region.
ids = [int(i) for i in np.nonzero(P[:, 0] > 0.5)[0]]
roi.PointIds = ids
expected = np.zeros(len(P), dtype=bool)
expected[ids] = True
run_and_check("point ids", expected)

# Errors: an id out of range gives an error and an empty output.
errors.clear()
roi.PointIds = [0, len(P) + 5]
roi.UpdatePipeline()
out = fetch(roi)
check(out.GetNumberOfPoints() == 0, "bad id: empty output")
check(errors.contains("out of range"), "bad id: error message names the problem (%s)" % errors.messages)
roi.PointIds = []

# The input was never modified.
after = fetch(sphere)
check(after.GetPointData().GetArray("ROIMask") is None, "input has no ROIMask afterwards")
check(np.array_equal(points(after), points(sphere_data)), "input points unchanged")

finish("TestROIExtract")
