# SPDX-License-Identifier: BSD-3-Clause
"""pvpython test (headless): a drag on the large-deformation model with the Precomputed solver, on
one scene (argv[3]):
- lefort1, bsso, genioplasty: the osteotomy scene as its demo runs it (scripts/osteotomy_scenes.py:
  LiftOff, closed lips, LipSeal Auto); with the suffix -open, the same with open lips (LipSeal 0);
- cut: the main demo's Bezier cut (scripts/faceplan_pipeline.py), made deeper by the step.
After the whole move from rest the bone is dragged 0.5 mm further eight times and then one step
back, each update after WaitForBackgroundWork, so that every step starts from the factor made ahead
of it whatever the machine's load. Checks: every step converges; on the osteotomies the steps
forward after the first need at most two iterations (the predictor from the corrected state
ahead); on the cut, whose deeper surface moves more of the bone at each step so that the state
ahead misses the next targets, no step forward needs a factorization of its own; the step back,
which reverses the drag, needs neither a factorization nor more than 30 iterations (a warm start
judges a refactorization against the settling tolerance while its contact settles: judged against
the whole way the Le Fort I's factored four times and took 154 iterations); and with lift-off the
step back lifts off the nodes that the same move lifted on the way forward. argv[1] is the plugin,
argv[2] the Data folder.
"""
import os
import sys

import numpy as np
from paraview.simple import LoadPlugin

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
import faceplan_pipeline  # noqa: E402
import osteotomy_scenes  # noqa: E402
from faceplan_test_util import ErrorCatcher, check, fetch, finish  # noqa: E402

LoadPlugin(sys.argv[1])


def main():
    # In a function: the osteotomy scenes' programmable filters run their scripts in this module's
    # globals (numpy_interface's algorithms), which shadow top-level names such as `place`.
    scene = sys.argv[3]
    name = scene.replace("-open", "")
    if name == "cut":
        tissue, mandible, roi, cut, fem = faceplan_pipeline.build(sys.argv[2])
        fem.Model = "NeoHookean"
        whole = 1.0
        liftOff = False

        def place(mm):
            """The demo's cut surface lowered by mm - 1 (mm = 1: the demo's cut)."""
            faceplan_pipeline.place_cut(cut, 1.0 - mm)
    else:
        tissue, bone, osteotomy, skeleton, fem = osteotomy_scenes.build(sys.argv[2], name)
        check(int(fem.LiftOff) == 1 and float(fem.LipSeal) == -1.0,
              "the demo's contact: LiftOff, LipSeal Auto")
        if scene.endswith("-open"):
            fem.LipSeal = 0.0
        fem.Model = "NeoHookean"
        direction = np.array(osteotomy_scenes.SCENES[name][2], dtype=float)
        whole = float(np.linalg.norm(direction))
        liftOff = True

        def place(mm):
            """The segment moved mm along the scene's direction."""
            osteotomy.Translation = list(direction * mm / whole)
    fem.LargeDeformationSolver = "Precomputed"

    def move(mm):
        """The bone placed at mm; the solve's field data."""
        place(mm)
        errors = ErrorCatcher(fem)
        fem.UpdatePipeline()
        fem.SMProxy.InvokeCommand("WaitForBackgroundWork")
        fd = fetch(fem).GetFieldData()
        fields = {fd.GetAbstractArray(k).GetName():
                  fd.GetAbstractArray(k).GetVariantValue(0).ToString()
                  for k in range(fd.GetNumberOfArrays())}
        check(not errors.messages and fields.get("Converged") == "1" and
              fields.get("LargeDeformationSolver") == "Precomputed",
              "%s, %.1f mm: converged by the Precomputed solve (%s)" % (scene, mm, errors.messages))
        return fields


    def iterations(fields):
        return int(float(fields["QuasiNewtonIterations"])), int(float(fields["Refactorizations"]))


    if name != "cut":
        move(0.0)
    fields = move(whole)
    print("%s, whole move: %d iterations, %d factorizations" % ((scene,) + iterations(fields)))
    # The cut reaches a few of the face's cells: its refactorization reuses the rest factor.
    partial = int(float(fields.get("PartialRefactorizations", "-1")))
    refactored = iterations(fields)[1]
    check(0 <= partial <= refactored, "%s, whole move: %d partial of %d factorizations" % (
        scene, partial, refactored))
    if name == "cut":
        check(refactored >= 1 and partial == refactored,
              "%s, whole move: every factorization reuses the rest factor (%d of %d)" % (
                  scene, partial, refactored))
    lifted = {}
    for k in range(1, 9):
        fields = move(whole + 0.5 * k)
        lifted[k] = fields.get("LiftedNodes")
        it, refactored = iterations(fields)
        print("step %d forward: %d iterations, %d factorizations" % (k, it, refactored))
        if k > 1 and name != "cut":
            check(it <= 2, "%s, step %d forward: the predictor from the state ahead "
                  "(%d iterations)" % (scene, k, it))
        if k > 1 and name == "cut":
            check(refactored == 0, "%s, step %d forward: the factor made ahead serves "
                  "(%d factorizations)" % (scene, k, refactored))
    fields = move(whole + 0.5 * 7)
    it, refactored = iterations(fields)
    print("step back: %d iterations, %d factorizations" % (it, refactored))
    check(refactored == 0 and it <= 30,
          "%s, the step back: no factorization, at most 30 iterations (%d, %d)" % (
              scene, it, refactored))
    if liftOff:
        check(fields.get("LiftedNodes") == lifted[7],
              "%s, the step back lifts the nodes the same move lifted on the way forward "
              "(%s, %s)" % (scene, fields.get("LiftedNodes"), lifted[7]))



main()
finish("TestCondensedFEMDeformDrag")
