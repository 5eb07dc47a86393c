# SPDX-License-Identifier: BSD-3-Clause
"""pvpython test: CondensedFEMDeform's LipSeal (closed lips) on the Badin BSSO scene
(scripts/osteotomy_scenes.py: a 6 mm advancement, the operation's contact, NeoHookean with LiftOff).

Open (LipSeal 0) the lower lip follows the mandible and the upper lip stays; sealed (3 mm, Auto's gap
for an operation preset's bone) the unmoved upper lip holds the lower lip back at the oral fissure
(stomion moves less than half as far) and is dragged forward a little itself, with no warning and the
output's cells and points those of the open result. Auto (the default) seals 3 mm with the preset's
bone, exactly as the gap set by hand, and nothing where no Bone input names an Operation. Bad input: a
negative LipSeal other than -1 (Auto) or NaN is an error naming it, with empty output; a gap set by
hand that ties nothing says so. argv[1] is the plugin, argv[2] the Data folder.
"""
import os
import sys

import numpy as np
from paraview import simple
from vtkmodules.util.numpy_support import vtk_to_numpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
import osteotomy_scenes  # noqa: E402
from facial_landmarks_util import table  # noqa: E402
from faceplan_test_util import ErrorCatcher, WarningCatcher, check, fetch, finish  # noqa: E402

simple.LoadPlugin(sys.argv[1])
tissue, bone, osteotomy, skeleton, fem = osteotomy_scenes.build(sys.argv[2], "bsso")
osteotomy_scenes.configure_model(fem)
landmarks = simple.FacialLandmarks(Input=fem, Bone=skeleton)
seen_shapes = []  # the output's (cells, points), the same with and without the seal


def field(name):
    a = fetch(fem).GetFieldData().GetAbstractArray(name)
    return a.GetValue(0) if a is not None else None


def solve(seal):
    fem.LipSeal = seal
    errors, warnings = ErrorCatcher(fem), WarningCatcher(fem)
    rows = table(landmarks)
    out = fetch(fem)
    others = [m for m in warnings.messages if "tied nodes released" not in m]
    check(not errors.messages and not others, "LipSeal %g: no error or warning (%s %s)" % (seal, errors.messages, others))
    seen_shapes.append((out.GetNumberOfCells(), out.GetNumberOfPoints()))
    check(seen_shapes[-1] == seen_shapes[0] and seen_shapes[0][0] > 0, "LipSeal %g: the output's cells and points are the unsealed "
          "output's (no bridge shows): %s" % (seal, seen_shapes))
    print("LipSeal %g: %s bridges; stomion %.2f mm, labrale superius %.2f mm, labrale inferius ratio %.2f" % (
        seal, field("LipSealBridges"), rows["Stomion"]["Horizontal"], rows["LabraleSuperius"]["Horizontal"],
        rows["LabraleInferius"]["Ratio"]))
    return rows


open_lips = solve(0.0)
check(field("LipSealBridges") == 0, "LipSeal 0 ties nothing")
closed = solve(osteotomy_scenes.OPERATION_LIP_SEAL)
check(field("LipSealBridges") > 0, "LipSeal %g ties the lips" % osteotomy_scenes.OPERATION_LIP_SEAL)
check(field("Model") == "NeoHookean" and field("RelativeResidual") <= 1e-9, "sealed: the converged neo-Hookean result")
check(open_lips["Stomion"]["Horizontal"] > 0.8 * 6.0, "open: the lower lip follows the mandible at the fissure")
check(closed["Stomion"]["Horizontal"] < 0.5 * open_lips["Stomion"]["Horizontal"],
      "sealed: the upper lip holds the lower lip back at the fissure (%.2f against %.2f mm)" % (
          closed["Stomion"]["Horizontal"], open_lips["Stomion"]["Horizontal"]))
check(closed["LabraleSuperius"]["Horizontal"] > open_lips["LabraleSuperius"]["Horizontal"] + 0.2,
      "sealed: the lower lip drags the upper lip forward")
check(closed["LabraleInferius"]["Ratio"] < open_lips["LabraleInferius"]["Ratio"] - 0.05,
      "sealed: the lower lip follows its jaw less")
closed_bridges = field("LipSealBridges")
closed_u = vtk_to_numpy(fetch(fem).GetPointData().GetArray("Displacement")).copy()

# Auto: the preset's bone (field data Operation) gets the 3 mm seal: the same bridges, and the same
# equilibrium to the agreement tolerance (the update re-solves from the last converged state).
fem.LipSeal = -1
fem.UpdatePipeline()
auto_u = vtk_to_numpy(fetch(fem).GetPointData().GetArray("Displacement"))
difference = np.linalg.norm(auto_u - closed_u, axis=1).max() / np.linalg.norm(closed_u, axis=1).max()
check(field("LipSealGap") == osteotomy_scenes.OPERATION_LIP_SEAL and field("LipSealBridges") == closed_bridges and
      difference <= 1e-8,
      "LipSeal Auto with an operation preset's bone: the 3 mm seal (gap %s, %s bridges, difference %.1e)" % (
          field("LipSealGap"), field("LipSealBridges"), difference))
# The same bone without its Operation field data (a bone no preset made): Auto ties nothing.
anonymous = simple.ProgrammableFilter(Input=skeleton, OutputDataSetType="vtkPolyData", Script=(
    "out = self.GetOutput(); out.ShallowCopy(self.GetInput()); fd = out.GetFieldData().NewInstance(); "
    "fd.DeepCopy(out.GetFieldData()); fd.RemoveArray('Operation'); out.SetFieldData(fd)"))
fem.Bone = anonymous
warnings = WarningCatcher(fem)
fem.UpdatePipeline()
check(field("LipSealGap") == 0 and field("LipSealBridges") == 0 and field("ContactModel") == "ByArray"
      and not [m for m in warnings.messages if "tied nodes released" not in m],
      "LipSeal Auto without an operation: no seal and no warning (ContactModel Auto still takes Sliding)")
fem.Bone = skeleton
fem.LipSeal = 0.0
solve(0.0)
check(field("LipSealBridges") == 0 and abs(table(landmarks)["Stomion"]["Horizontal"] - open_lips["Stomion"]["Horizontal"]) < 1e-9,
      "back to LipSeal 0: the open result again (no stale seal)")

# A gap smaller than any facing distance ties nothing, and says so.
fem.LipSeal = 1e-3
warnings = WarningCatcher(fem)
fem.UpdatePipeline()
check(warnings.contains("nothing is tied") and field("LipSealBridges") == 0, "a gap that ties nothing says so")

for bad in (-2.0, -0.5, float("nan")):
    fem.LipSeal = bad
    errors = ErrorCatcher(fem)
    fem.UpdatePipeline()
    out = fetch(fem)
    check(errors.contains("LipSeal") and out.GetNumberOfPoints() == 0,
          "LipSeal %s: an error naming LipSeal and empty output (%s)" % (bad, errors.messages))

finish("TestCondensedFEMDeformLipSeal")
