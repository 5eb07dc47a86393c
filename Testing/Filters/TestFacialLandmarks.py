# SPDX-License-Identifier: BSD-3-Clause
"""FacialLandmarks on the Badin face (pvpython, headless): the BSSO scene of scripts/osteotomy_scenes.py
(the preset's model, linear for speed). Every landmark is found, in its anatomical order; the table's
movements equal the displacement field at the landmark (probed independently in the tissue volume
with vtkProbeFilter); the bony landmarks on the moved segment move with it; the points output holds
the post-operative positions; an override moves one landmark onto the skin, and so does the point
handle's Placed Landmark, which wins over a list entry for the same landmark and is shown in the
panel only while a landmark is chosen. argv[1] is the plugin, argv[2] the Data folder.
"""
import os
import sys

import numpy as np
from paraview import simple
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkPoints
from vtkmodules.vtkCommonDataModel import vtkPolyData
from vtkmodules.vtkFiltersCore import vtkProbeFilter
from vtkmodules.vtkFiltersGeneral import vtkWarpVector

from facial_landmarks_util import BONE, SKIN, table
from faceplan_test_util import check, finish

simple.LoadPlugin(sys.argv[1])
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
import osteotomy_scenes  # noqa: E402

tissue, bone, osteotomy, skeleton, fem = osteotomy_scenes.build(sys.argv[2], "bsso")
landmarks = simple.FacialLandmarks(Input=fem, Bone=skeleton, Operation="BSSO")
rows = table(landmarks)
check(len(rows) == 19, "one row per landmark (%d)" % len(rows))
for name in SKIN + BONE:
    r = rows.get(name)
    check(r is not None and r["Found"] == 1, "%s is found on the Badin face (%s)" % (name, r and r["Note"]))
if len(rows) != 19 or any(rows[n]["Found"] != 1 for n in SKIN + BONE):
    finish("TestFacialLandmarks")

pre = {n: rows[n]["Pre"] for n in SKIN + BONE}
z = {n: p[2] for n, p in pre.items()}
# The face looks towards -x with z up; anatomical order from the nose down.
order = ["Pronasale", "Subnasale", "LabraleSuperius", "Stomion", "LabraleInferius", "SoftTissueB",
         "SoftTissuePogonion", "SoftTissueMenton"]
check(all(z[a] > z[b] for a, b in zip(order, order[1:])), "skin profile in order from the nose down: %s"
      % [(n, round(z[n], 1)) for n in order])
bone_order = ["ANS", "APoint", "UpperIncisorTip", "LowerIncisorTip", "BPoint", "Pogonion", "Menton"]
check(all(z[a] > z[b] for a, b in zip(bone_order, bone_order[1:])), "bony landmarks in order from ANS down: %s"
      % [(n, round(z[n], 1)) for n in bone_order])
check(all(pre[n][0] >= pre["Pronasale"][0] for n in SKIN), "pronasale is the face's most anterior landmark")
for n in SKIN[:-1] + ["SoftTissueMenton"]:
    if n.endswith(("Right", "Left")):
        continue
    check(abs(pre[n][1]) < 1e-6, "%s lies on the midsagittal plane" % n)
for pair in (("CheilionRight", "CheilionLeft"), ("AlarBaseRight", "AlarBaseLeft")):
    r, l = pre[pair[0]], pre[pair[1]]
    check(r[1] > 5 and l[1] < -5 and abs(r[1] + l[1]) < 0.05 * (r[1] - l[1]),
          "%s on the right (+y: the face looks towards -x) and %s mirrored" % pair)
mouth = pre["CheilionRight"][1] - pre["CheilionLeft"][1]
nose = pre["AlarBaseRight"][1] - pre["AlarBaseLeft"][1]
check(30 < mouth < 65 and 20 < nose < 50, "mouth width %.1f mm and alar base width %.1f mm are adult sizes" % (mouth, nose))
# Skin landmarks lie in front of their bony ones.
for soft, hard in (("SoftTissuePogonion", "Pogonion"), ("SoftTissueB", "BPoint"), ("Subnasale", "APoint"),
                   ("LabraleInferius", "LowerIncisorTip"), ("LabraleSuperius", "UpperIncisorTip")):
    check(pre[soft][0] < pre[hard][0], "%s lies in front of %s" % (soft, hard))

# The movements: the displacement field interpolated at the landmark (the tissue taken back to its
# pre-operative position and probed there).
fem.UpdatePipeline()
volume = fem.GetClientSideObject().GetOutputDataObject(0)
volume.GetPointData().SetActiveVectors("Displacement")
warp = vtkWarpVector()
warp.SetInputData(volume)
warp.SetScaleFactor(-1.0)
warp.Update()
probe_points = vtkPoints()
probe_points.SetData(numpy_to_vtk(np.array([pre[n] for n in SKIN]), deep=1))
where = vtkPolyData()
where.SetPoints(probe_points)
probe = vtkProbeFilter()
probe.SetInputData(where)
probe.SetSourceData(warp.GetOutput())
probe.SetTolerance(1e-6)
probe.Update()
valid = vtk_to_numpy(probe.GetOutput().GetPointData().GetArray(probe.GetValidPointMaskArrayName()))
u = vtk_to_numpy(probe.GetOutput().GetPointData().GetArray("Displacement"))
for k, n in enumerate(SKIN):
    r = rows[n]
    ok = valid[k] == 1 and abs(r["Horizontal"] - (-u[k, 0])) < 1e-6 and abs(r["Vertical"] - u[k, 2]) < 1e-6 \
        and np.allclose(r["Post"], r["Pre"] + u[k], atol=1e-6)
    check(ok, "%s: the table's movement (%.4f, %.4f) is the field at the landmark (%s)"
          % (n, r["Horizontal"], r["Vertical"], u[k] if valid[k] else "not in the mesh"))
translation = np.array(osteotomy_scenes.SCENES["bsso"][2])
for n in ("LowerIncisorTip", "BPoint", "Pogonion", "Menton"):
    check(abs(rows[n]["Horizontal"] + translation[0]) < 1e-9 and abs(rows[n]["Vertical"]) < 1e-9,
          "%s moves with the BSSO segment (%.3f mm forward)" % (n, rows[n]["Horizontal"]))
for n in ("ANS", "APoint", "UpperIncisorTip"):
    check(abs(rows[n]["Horizontal"]) < 1e-9, "%s stays with the fixed maxilla" % n)
r = rows["SoftTissuePogonion"]
check(r["PairedBone"] == "Pogonion" and abs(r["Ratio"] - r["Horizontal"] / r["BoneHorizontal"]) < 1e-12
      and r["BandLow"] == 0.8 and r["BandHigh"] == 1.2 and "Mobarak" in r["Source"],
      "soft pogonion: ratio against pogonion with its band and source")
check(r["Check"] == ("in" if 0.8 <= r["Ratio"] <= 1.2 else "out"), "soft pogonion: in/out follows the band")

# The points output: the found landmarks at their post-operative positions.
points = landmarks.GetClientSideObject().GetOutputDataObject(1)
names = points.GetPointData().GetAbstractArray("Landmark")
check(points.GetNumberOfPoints() == 19 and points.GetNumberOfVerts() == 19, "19 landmark points")
for i in range(points.GetNumberOfPoints()):
    n = names.GetValue(i)
    check(np.allclose(points.GetPoint(i), rows[n]["Post"]), "%s's point is its post-operative position" % n)

# An override: a point near the skin is snapped onto it and used.
landmarks.Overrides = ["Stomion %r %r %r" % (pre["Stomion"][0] - 0.5, 3.0, pre["Stomion"][2])]
moved = table(landmarks)
s = moved.get("Stomion")
check(s is not None and abs(s["Pre"][1] - 3.0) < 1.0 and not np.allclose(s["Pre"], pre["Stomion"]),
      "an override places Stomion where the user put it (snapped onto the skin)")
check(s is not None and np.allclose(moved["Pronasale"]["Pre"], pre["Pronasale"]), "an override leaves the other landmarks")

# The point handle: Placed Landmark places one landmark at the handle's position, after the
# Overrides list (so it wins for its landmark); None places nothing.
handle_at = [pre["Stomion"][0] - 0.5, -3.0, pre["Stomion"][2]]
landmarks.PlacedLandmark = "Stomion"
landmarks.PlacedLandmarkPosition = handle_at
placed = table(landmarks)
s = placed.get("Stomion")
check(s is not None and abs(s["Pre"][1] + 3.0) < 1.0 and not np.allclose(s["Pre"], moved["Stomion"]["Pre"]),
      "the handle places Stomion where it is (snapped onto the skin), over the list's entry (%s)"
      % (s and s["Pre"]))
check(s is not None and np.allclose(placed["Pronasale"]["Pre"], pre["Pronasale"]), "the handle leaves the other landmarks")
landmarks.Overrides = []
landmarks.PlacedLandmark = "None"
check(np.allclose(table(landmarks)["Stomion"]["Pre"], pre["Stomion"]), "Placed Landmark None places nothing")

# The panel: the handle (ParaView's InteractiveHandle widget on PlacedLandmarkPosition) is shown
# only while a landmark is chosen.
sm = landmarks.SMProxy
groups = [sm.GetPropertyGroup(g) for g in range(sm.GetNumberOfPropertyGroups())]
handle = [g for g in groups if g.GetPanelWidget() == "InteractiveHandle"]
check(len(handle) == 1 and handle[0].GetProperty("WorldPosition") is sm.GetProperty("PlacedLandmarkPosition"),
      "one point handle drives PlacedLandmarkPosition")
decorator = handle[0].GetHints().FindNestedElementByName("PropertyWidgetDecorator") if handle and handle[0].GetHints() else None
check(decorator is not None and decorator.GetAttribute("property") == "PlacedLandmark" and
      decorator.GetAttribute("mode") == "visibility" and decorator.GetAttribute("value") == "-1" and
      decorator.GetAttribute("inverse") == "1", "the handle is hidden while Placed Landmark is None")
names = [landmarks.GetProperty("PlacedLandmark").SMProperty.FindDomain("vtkSMEnumerationDomain").GetEntryText(i)
         for i in range(20)]
check(names == ["None"] + SKIN + BONE, "Placed Landmark offers None and the 19 landmarks in the table's order: %s" % names)

finish("TestFacialLandmarks")
