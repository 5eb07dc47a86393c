# SPDX-License-Identifier: BSD-3-Clause
"""The clinical ratios of the three osteotomy demos (scripts/osteotomy_scenes.py: Le Fort I 5 mm,
BSSO 6 mm, genioplasty 5 mm advancements, each the model a user gets from Osteotomy's Operation
preset and CondensedFEMDeform's defaults: the preset's Sliding and Released arrays taken by
ContactModel Auto, the lips closed by LipSeal Auto, NeoHookean chosen by Model Auto, LiftOff) against the
published bands that FacialLandmarks reports (Core/Landmarks/ClinicalBands.cpp). Every banded ratio
must be in its band, the BSSO's labrale inferius included (docs/CLINICAL.md, section 5: the lip seal
brings it from 0.91 into its band). argv[1] is the plugin, argv[2] the Data folder.
"""
import os
import sys

from paraview import simple

from facial_landmarks_util import table
from faceplan_test_util import check, finish

simple.LoadPlugin(sys.argv[1])
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
import osteotomy_scenes  # noqa: E402

EXPECTED = {"lefort1": {"Subnasale", "Pronasale", "LabraleSuperius"},
            "bsso": {"SoftTissuePogonion", "SoftTissueB", "LabraleInferius"},
            "genioplasty": {"SoftTissuePogonion"}}

for scene in osteotomy_scenes.SCENES:
    tissue, bone, osteotomy, skeleton, fem = osteotomy_scenes.build(sys.argv[2], scene)
    landmarks = simple.FacialLandmarks(Input=fem, Bone=skeleton)  # the bands of the bone's Operation
    rows = table(landmarks)
    # Nothing was set on the filter: its defaults, given the preset's bone, are the operation's model.
    for name, default in (("ContactModel", "Auto"), ("LipSeal", -1.0), ("LiftOff", 1), ("Model", "Auto")):
        check(fem.GetPropertyValue(name) == default, "%s: %s is its default %s" % (scene, name, default))
    fd = fem.GetClientSideObject().GetOutputDataObject(0).GetFieldData()
    used = {name: fd.GetAbstractArray(name).GetValue(0) for name in ("Model", "ContactModel")}
    gap, bridges = fd.GetArray("LipSealGap").GetValue(0), fd.GetArray("LipSealBridges").GetValue(0)
    check(used == {"Model": "NeoHookean", "ContactModel": "ByArray"} and abs(gap - 3.0) < 1e-12 and bridges > 0,
          "%s: the defaults ran NeoHookean with ByArray contact and closed lips (%s, gap %g, %d bridges)" % (
              scene, used, gap, bridges))
    banded = {n for n, r in rows.items() if r["Band"]}
    check(banded == EXPECTED[scene], "%s: the published bands apply to %s (got %s)" % (scene, sorted(EXPECTED[scene]),
                                                                                        sorted(banded)))
    for name in sorted(banded):
        r = rows[name]
        print("%s %s: ratio %.2f, band %s (%s)" % (scene, name, r["Ratio"], r["Band"], r["Source"]))
        check(r["Check"] == "in" and r["BandLow"] <= r["Ratio"] <= r["BandHigh"],
              "%s %s: ratio %.2f in the published band %.2f-%.2f" % (scene, name, r["Ratio"], r["BandLow"],
                                                                      r["BandHigh"]))
    for proxy in (landmarks, fem, skeleton, osteotomy):
        simple.Delete(proxy)

finish("TestFacialLandmarksDemos")
