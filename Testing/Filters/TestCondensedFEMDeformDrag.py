# SPDX-License-Identifier: BSD-3-Clause
"""pvpython test (headless): a drag on the large-deformation model, on the Le Fort I scene as the
demo runs it (scripts/osteotomy_scenes.py: LiftOff, closed lips, the Precomputed solver). After the
whole move from rest the segment is dragged 0.5 mm further eight times and then one step back, each
update after WaitForBackgroundWork, so that every step starts from the factor made ahead of it
whatever the machine's load. Checks: every step converges; the steps forward after the first need
at most two iterations (the predictor from the corrected state ahead); the step back, which
reverses the drag, needs neither a factorization nor more than 30 iterations (a warm start judges
a refactorization against the settling tolerance while its contact settles: judged against the
whole way it factored four times and took 154 iterations); and the step back lifts off the nodes
that the same move lifted on the way forward. argv[1] is the plugin, argv[2] the Data folder.
"""
import os
import sys

import numpy as np
from paraview.simple import LoadPlugin

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
import osteotomy_scenes  # noqa: E402
from faceplan_test_util import ErrorCatcher, check, fetch, finish  # noqa: E402

LoadPlugin(sys.argv[1])
tissue, bone, osteotomy, skeleton, fem = osteotomy_scenes.build(sys.argv[2], "lefort1")
fem.Model = "NeoHookean"
fem.LargeDeformationSolver = "Precomputed"
check(int(fem.LiftOff) == 1 and float(fem.LipSeal) == -1.0, "the demo's contact: LiftOff, LipSeal Auto")
direction = np.array(osteotomy_scenes.SCENES["lefort1"][2], dtype=float)
whole = float(np.linalg.norm(direction))


def move(mm):
    """The segment moved mm along the scene's direction; the solve's field data."""
    osteotomy.Translation = list(direction * mm / whole)
    errors = ErrorCatcher(fem)
    fem.UpdatePipeline()
    fem.SMProxy.InvokeCommand("WaitForBackgroundWork")
    fd = fetch(fem).GetFieldData()
    fields = {fd.GetAbstractArray(k).GetName(): fd.GetAbstractArray(k).GetVariantValue(0).ToString()
              for k in range(fd.GetNumberOfArrays())}
    check(not errors.messages and fields.get("Converged") == "1" and
          fields.get("LargeDeformationSolver") == "Precomputed",
          "%.1f mm: converged by the Precomputed solve (%s)" % (mm, errors.messages))
    return fields


def iterations(fields):
    return int(float(fields["QuasiNewtonIterations"])), int(float(fields["Refactorizations"]))


move(0.0)
fields = move(whole)
print("whole move: %d iterations, %d factorizations" % iterations(fields))
lifted = {}
for k in range(1, 9):
    fields = move(whole + 0.5 * k)
    lifted[k] = fields.get("LiftedNodes")
    it, refactored = iterations(fields)
    print("step %d forward: %d iterations, %d factorizations" % (k, it, refactored))
    if k > 1:
        check(it <= 2, "step %d forward: the predictor from the state ahead (%d iterations)" % (k, it))
fields = move(whole + 0.5 * 7)
it, refactored = iterations(fields)
print("step back: %d iterations, %d factorizations" % (it, refactored))
check(refactored == 0 and it <= 30, "the step back: no factorization, at most 30 iterations (%d, %d)" % (it, refactored))
check(fields.get("LiftedNodes") == lifted[7],
      "the step back lifts the nodes the same move lifted on the way forward (%s, %s)" % (
          fields.get("LiftedNodes"), lifted[7]))

finish("TestCondensedFEMDeformDrag")
