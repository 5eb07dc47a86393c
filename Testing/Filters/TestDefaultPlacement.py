# SPDX-License-Identifier: BSD-3-Clause
"""Filters that start where the anatomy is (pvpython, headless): ROIExtract's sphere starts on the
bone where an operation would be planned (its most anterior point, a fifth of its extent; also
when the input was never updated, where ParaView's own start has Radius -1), its box on the input's
bounds, and a Bezier Cut whose control points were never set places them over the ROI, so a
default-constructed cut on the face's mandible cuts something; a new Bezier Cut proxy's CurveU and
CurveV (what the GUI's handle widgets show) start at those curves; control points set by the user win.
argv[1] is the plugin, argv[2] the Data folder.
"""
import sys

import numpy as np
from paraview.simple import *
from vtkmodules.util.numpy_support import vtk_to_numpy

from faceplan_test_util import check, fetch, finish

LoadPlugin(sys.argv[1], ns=globals())
data = sys.argv[2]

mandible = XMLPolyDataReader(FileName=[data + "/face/mandible.vtp"])
# Created before its input was ever updated, as a pvpython script does.
roi = ROIExtract(Input=mandible)
mandible_points = vtk_to_numpy(fetch(mandible).GetPoints().GetData())
b = mandible.GetDataInformation().GetBounds()
extent = max(b[1] - b[0], b[3] - b[2], b[5] - b[4])
front = mandible_points[np.argmin(mandible_points[:, 0])]
print("default sphere: centre %s, radius %.2f" % (list(roi.Region.Center), roi.Region.Radius))
check(roi.Region.Radius > 0.0, "the default sphere has a positive radius (%g)" % roi.Region.Radius)
check(np.allclose(roi.Region.Center, front), "the default sphere is centred on the bone's most anterior point")
check(abs(roi.Region.Radius - 0.2 * extent) < 1e-9 * extent, "the default sphere's radius is a fifth of the extent")
roi.UpdatePipeline()
marked = int(vtk_to_numpy(fetch(roi).GetPointData().GetArray("ROIMask")).sum())
check(0 < marked < 0.5 * len(mandible_points),
      "the default sphere marks part of the bone, not all of it (%d of %d points)" % (marked, len(mandible_points)))
Delete(roi)
# The box is ParaView's own, placed from the bounds of an input already updated (as in the GUI).
roi = ROIExtract(Input=mandible)
roi.Region = "Box"
check(np.allclose(roi.Region.Position, [b[0], b[2], b[4]]) and
      np.allclose(roi.Region.Length, [b[1] - b[0], b[3] - b[2], b[5] - b[4]]),
      "the default box region is the input's bounding box")


def moved(cut):
    cut.UpdatePipeline()
    out = fetch(cut)
    if out.GetNumberOfPoints() == 0:
        return 0, 0.0
    u = vtk_to_numpy(out.GetPointData().GetArray("Displacement"))
    return int(np.count_nonzero(np.linalg.norm(u, axis=1) > 0)), float(np.linalg.norm(u, axis=1).max())


def roi_box(source):
    out = fetch(source)
    p = vtk_to_numpy(out.GetPoints().GetData())
    m = vtk_to_numpy(out.GetPointData().GetArray("ROIMask")) != 0
    return p[m].min(axis=0), p[m].max(axis=0)


for region in ("Sphere", "Chin", "Box"):
    roi.Region = "Box" if region == "Box" else "Sphere"
    if region == "Chin":  # as in the main pipeline
        roi.Region.Center = [70.0, 0.0, 58.0]
        roi.Region.Radius = 22.0
    cut = BezierCut(Input=roi)
    n, largest = moved(cut)
    print("default cut on the %s ROI: %d points moved, largest %.2f mm" % (region, n, largest))
    check(n > 0 and largest > 0.0, "a default Bezier Cut on the %s ROI cuts something (%d points moved, "
          "largest %.2f mm)" % (region, n, largest))
    lo, hi = roi_box(roi)
    # Visible at the first Apply: a cap of at least 2 % of the ROI's size, not a tenth of a mm.
    check(largest >= 0.02 * (hi - lo).max(), "the default cut on the %s ROI is deep enough to see (%.2f mm "
          "on an ROI of %.1f mm)" % (region, largest, (hi - lo).max()))
    u = np.array(cut.GetClientSideObject().GetOutputDataObject(1).GetBounds()).reshape(3, 2)
    check(np.all(u[:, 0] <= hi + 1e-9) and np.all(u[:, 1] >= lo - 1e-9),
          "the default operative surface lies over the %s ROI" % region)
    Delete(cut)

# The GUI's widgets show the property values: a new filter's CurveU/CurveV must be the curves the
# filter places over the ROI (not the XML's unit square at the origin), and cutting with those
# values as given must cut the bone.
roi.Region = "Sphere"
roi.Region.Center = [70.0, 0.0, 58.0]
roi.Region.Radius = 22.0
lo, hi = roi_box(roi)
cut = BezierCut(Input=roi)
u = np.array(cut.CurveU).reshape(-1, 3)
v = np.array(cut.CurveV).reshape(-1, 3)
unit_u = np.array([-0.5, -0.5, 0, -0.1666667, -0.5, 0, 0.1666667, -0.5, 0, 0.5, -0.5, 0]).reshape(-1, 3)
check(u.shape == (4, 3) and v.shape == (4, 3) and not np.allclose(u, unit_u),
      "a new Bezier Cut's CurveU property is not the XML's unit square (%s)" % u.tolist())
margin = 0.2 * (hi - lo)
inside = np.all((u >= lo - margin) & (u <= hi + margin)) and np.all((v >= lo - margin) & (v <= hi + margin))
check(inside, "a new Bezier Cut's control point properties lie over the ROI's box")
check(np.array_equal(u[0], v[0]), "the curves' first control points are shared")
cut.UpdatePropertyInformation()
check(np.allclose(u.ravel(), cut.GetPropertyValue("DefaultCurveU")) and
      np.allclose(v.ravel(), cut.GetPropertyValue("DefaultCurveV")),
      "the properties equal the filter's own default curves (DefaultCurveU/V)")
n, largest = moved(cut)
check(n > 0 and largest > 0.0, "the curves the properties start with cut the bone (%d points moved)" % n)
placed = BezierCut(Input=roi)
placed.CurveU, placed.CurveV = u.ravel().tolist(), v.ravel().tolist()
n2, _ = moved(placed)
check(n2 == n, "the same curves typed in cut the same (%d and %d points)" % (n, n2))
Delete(placed)
Delete(cut)

# Control points set by the user are kept: a patch far from the bone cuts nothing.
cut = BezierCut(Input=roi)
cut.CurveU = [500, 500, 500, 501, 500, 500, 502, 500, 500, 503, 500, 500]
cut.CurveV = [500, 500, 500, 500, 501, 500, 500, 502, 500, 500, 503, 500]
n, _ = moved(cut)
check(n == 0, "control points set by the user are used (a patch away from the bone moves nothing)")

finish("TestDefaultPlacement")
