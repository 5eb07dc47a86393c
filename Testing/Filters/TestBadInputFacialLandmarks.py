# SPDX-License-Identifier: BSD-3-Clause
"""Bad-input contract of FacialLandmarks through pvpython: no skin, NaN coordinates and displacements,
a degenerate frame (model axes and Frankfort), enums out of range, overrides that name no landmark,
lie outside the mesh or are not finite. Each gives an error naming the problem and empty outputs; the
inputs are not modified. A face without a bone finds the skin landmarks and says why the bony ones
are missing. argv[1] is the plugin, argv[2] the Data folder."""
import sys

import numpy as np
from paraview.simple import *  # noqa: F401,F403
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
from vtkmodules.vtkCommonDataModel import vtkPolyData
from vtkmodules.vtkCommonCore import vtkPoints

LoadPlugin(sys.argv[1], ns=globals())
from badinput_util import Catcher, _has  # noqa: E402
from facial_landmarks_util import BONE, SKIN, table  # noqa: E402
from faceplan_test_util import check, fetch, finish, producer  # noqa: E402

face = XMLUnstructuredGridReader(FileName=[sys.argv[2] + "/face/face_tissue.vtu"])
face.UpdatePipeline()
FACE = fetch(face)
P = vtk_to_numpy(FACE.GetPoints().GetData()).copy()
mandible = XMLPolyDataReader(FileName=[sys.argv[2] + "/face/mandible.vtp"])
count = 0


def expect_error(label, proxy, *words):
    global count
    count += 1
    c = Catcher(proxy)
    proxy.UpdatePipeline()
    t = proxy.GetClientSideObject().GetOutputDataObject(0)
    pts = proxy.GetClientSideObject().GetOutputDataObject(1)
    print("FacialLandmarks [%s] errors: %s" % (label, [m.strip().splitlines()[-1][:150] for m in c.errors]))
    check(_has(c.errors, words), "FacialLandmarks [%s]: an error naming %s (got %s)" % (label, words, c.errors))
    check(t.GetNumberOfRows() == 0 and pts.GetNumberOfPoints() == 0, "FacialLandmarks [%s]: empty outputs" % label)


def with_displacement(points, u):
    ug = FACE.NewInstance()
    ug.DeepCopy(FACE)
    p = vtkPoints()
    p.SetDataTypeToDouble()
    p.SetData(numpy_to_vtk(np.ascontiguousarray(points, float), deep=1))
    ug.SetPoints(p)
    a = numpy_to_vtk(np.ascontiguousarray(u, float), deep=1)
    a.SetName("Displacement")
    ug.GetPointData().AddArray(a)
    return ug


# The baseline: the undeformed face, no bone: skin landmarks found, bony ones said missing.
ok = FacialLandmarks(Input=face)
rows = table(ok)
check(all(rows[n]["Found"] == 1 for n in SKIN if n != "SoftTissueMenton"),
      "without a bone the skin landmarks are found")
check(all(rows[n]["Found"] == 0 and "bone" in rows[n]["Note"] for n in BONE + ["SoftTissueMenton"]),
      "without a bone the bony landmarks are not found, and the note says why")
check(all(rows[n]["Horizontal"] == 0.0 for n in SKIN if rows[n]["Found"]), "no Displacement: nothing moves")

# No skin: a point cloud (vertices only) and an empty data set.
cloud = vtkPolyData()
cp = vtkPoints()
cp.SetData(numpy_to_vtk(P[:50].copy(), deep=1))
cloud.SetPoints(cp)
expect_error("no skin: points without a surface", FacialLandmarks(Input=producer(cloud)), "no surface")
expect_error("no skin: empty input", FacialLandmarks(Input=producer(vtkPolyData())), "empty")

# NaN.
bad = P.copy()
bad[17] = [np.nan, 0, 0]
expect_error("NaN coordinate", FacialLandmarks(Input=producer(with_displacement(bad, np.zeros_like(P)))), "NaN")
u = np.zeros_like(P)
u[5] = [0, np.inf, 0]
expect_error("infinite displacement", FacialLandmarks(Input=producer(with_displacement(P, u))), "Displacement", "NaN")
expect_error("2-component displacement",
             FacialLandmarks(Input=producer(with_displacement(P, np.zeros((len(P), 2))))), "3 components")

# A degenerate frame.
expect_error("midsagittal normal zero", FacialLandmarks(Input=face, MidsagittalNormal=[0, 0, 0]), "zero length")
expect_error("midsagittal normal NaN", FacialLandmarks(Input=face, MidsagittalNormal=[np.nan, 1, 0]), "not finite")
expect_error("anterior along the plane's normal", FacialLandmarks(Input=face, AnteriorDirection=[0, 1, 0]), "degenerate")
expect_error("superior along anterior", FacialLandmarks(Input=face, SuperiorDirection=[-1, 0, 0.01]), "degenerate")
expect_error("Frankfort points collinear",
             FacialLandmarks(Input=face, ReferenceFrame="FrankfortHorizontal",
                             FrankfortPoints=[100, 50, 150, 100, -50, 150, 100, 0, 150]), "collinear")
expect_error("Frankfort point NaN",
             FacialLandmarks(Input=face, ReferenceFrame="FrankfortHorizontal",
                             FrankfortPoints=[100, 50, 150, 100, -50, 150, np.nan, 0, 150]), "not finite")
# A valid Frankfort frame equal to the model axes gives the model axes' landmarks.
frankfort = FacialLandmarks(Input=face, ReferenceFrame="FrankfortHorizontal",
                            FrankfortPoints=[120, 60, 150, 120, -60, 150, 60, 0, 150])
rf = table(frankfort)
check(len(rf) == 19 and np.allclose(rf["Pronasale"]["Pre"], rows["Pronasale"]["Pre"]),
      "a level Frankfort frame through the midline gives the model axes' pronasale")

# Enums out of range (pvpython bypasses the GUI's domain).
for prop, value in (("Operation", 7), ("Operation", -1), ("ReferenceFrame", 2)):
    f = FacialLandmarks(Input=face)
    f.SetPropertyWithName(prop, value)
    expect_error("%s %d" % (prop, value), f, prop, str(value))

# Overrides.
prn = rows["Pronasale"]["Pre"]
expect_error("override outside the mesh", FacialLandmarks(Input=face, Overrides=["Pronasale 0 0 400"]), "outside the mesh")
expect_error("override of an unknown landmark",
             FacialLandmarks(Input=face, Overrides=["Nasion %r %r %r" % tuple(prn)]), "names no landmark")
expect_error("override not 'Name x y z'", FacialLandmarks(Input=face, Overrides=["Pronasale 1 2"]), "Name x y z")
expect_error("override NaN", FacialLandmarks(Input=face, Overrides=["Pronasale nan 0 0"]), "Name x y z")
expect_error("bony override without a bone", FacialLandmarks(Input=face, Overrides=["Menton 68 0 55"]), "no bone")
# The point handle's landmark (Placed Landmark): out of range, not finite, off the mesh (the
# handle's start, the centre of the tissue's bounds, if left there), bony without a bone.
for value in (-2, 19):
    f = FacialLandmarks(Input=face)
    f.SetPropertyWithName("PlacedLandmark", value)
    expect_error("PlacedLandmark %d" % value, f, "PlacedLandmark", str(value))
expect_error("placed landmark NaN", FacialLandmarks(Input=face, PlacedLandmark="Pronasale",
                                                    PlacedLandmarkPosition=[float("nan"), 0.0, 0.0]),
             "PlacedLandmark Pronasale", "non-finite")
expect_error("placed landmark at the handle's start", FacialLandmarks(Input=face, PlacedLandmark="Pronasale"),
             "PlacedLandmark Pronasale", "outside the mesh", "press P")
expect_error("placed bony landmark without a bone",
             FacialLandmarks(Input=face, PlacedLandmark="Menton", PlacedLandmarkPosition=[68.0, 0.0, 55.0]),
             "PlacedLandmark Menton", "no bone")
# A bone input with NaN displacement.
mandible.UpdatePipeline()
nanbone = fetch(mandible).NewInstance()
nanbone.DeepCopy(fetch(mandible))
ub = np.zeros((nanbone.GetNumberOfPoints(), 3))
ub[3] = [np.nan, 0, 0]
ua = numpy_to_vtk(ub, deep=1)
ua.SetName("Displacement")
nanbone.GetPointData().AddArray(ua)
expect_error("bone displacement not finite", FacialLandmarks(Input=face, Bone=producer(nanbone)), "bone", "NaN")

check(np.array_equal(vtk_to_numpy(fetch(face).GetPoints().GetData()), P), "FacialLandmarks: input not modified")
print("FacialLandmarks bad-input cases: %d" % count)
finish("TestBadInputFacialLandmarks")
