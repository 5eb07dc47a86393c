# SPDX-License-Identifier: BSD-3-Clause
"""FacialLandmarks on a model from TissueModelFromCT (the bundled head CT, CellSize 10 mm; z grows
towards the chin and the face looks towards -y): every landmark is found on the skin and the bone,
the profile and the bony landmarks in their anatomical order, the paired ones on either side of the
midsagittal plane. Exits 77 (skipped) when the plugin was built without CGAL. argv[1] is the plugin,
argv[2] the Data folder.
"""
import os
import sys

from paraview import simple

from facial_landmarks_util import BONE, SKIN, table
from faceplan_test_util import check, finish

simple.LoadPlugin(sys.argv[1])
if not hasattr(simple, "TissueModelFromCT"):
    print("TissueModelFromCT is absent (built without CGAL): skipped")
    sys.exit(77)
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
import faceplan_ct_pipeline  # noqa: E402

ct, model = faceplan_ct_pipeline.build_model(sys.argv[2], 10.0)
model.UpdatePipeline()
landmarks = simple.FacialLandmarks(Input=simple.OutputPort(model, 0), Bone=simple.OutputPort(model, 1),
                                   AnteriorDirection=[0, -1, 0], SuperiorDirection=[0, 0, -1],
                                   MidsagittalNormal=[1, 0, 0])
rows = table(landmarks)
check(len(rows) == 19, "one row per landmark")
for name in SKIN + BONE:
    r = rows.get(name)
    check(r is not None and r["Found"] == 1, "%s is found on the CT model (%s)" % (name, r and r["Note"]))
if all(rows.get(n, {}).get("Found") == 1 for n in SKIN + BONE):
    height = {n: -rows[n]["Pre"][2] for n in SKIN + BONE}  # superior is -z
    order = ["Pronasale", "Subnasale", "LabraleSuperius", "Stomion", "LabraleInferius", "SoftTissueB",
             "SoftTissuePogonion", "SoftTissueMenton"]
    check(all(height[a] > height[b] for a, b in zip(order, order[1:])),
          "CT: the skin profile in order from the nose down: %s" % [(n, round(-height[n], 1)) for n in order])
    bone_order = ["ANS", "UpperIncisorTip", "LowerIncisorTip", "Pogonion"]
    check(all(height[a] > height[b] for a, b in zip(bone_order, bone_order[1:])),
          "CT: ANS, the incisors and pogonion in order: %s" % [(n, round(-height[n], 1)) for n in bone_order])
    centre = rows["Pronasale"]["Pre"][0]
    for right, left in (("CheilionRight", "CheilionLeft"), ("AlarBaseRight", "AlarBaseLeft")):
        check(rows[right]["Pre"][0] > centre + 5 and rows[left]["Pre"][0] < centre - 5,
              "CT: %s and %s either side of the midsagittal plane" % (right, left))
    for soft, hard in (("SoftTissuePogonion", "Pogonion"), ("LabraleSuperius", "UpperIncisorTip")):
        check(rows[soft]["Pre"][1] < rows[hard]["Pre"][1], "CT: %s lies in front of %s" % (soft, hard))
    check(all(rows[n]["Horizontal"] == 0.0 for n in SKIN + BONE), "CT: a model with no Displacement moves nothing")

finish("TestFacialLandmarksCT")
