# SPDX-License-Identifier: BSD-3-Clause
"""Contract tests of CondensedFEMDeform's Model, LargeDeformationSolver and LiftOff (pvpython,
headless), on the Le Fort I scene of scripts/osteotomy_scenes.py: the default, Auto, runs the linear
model for a small move and NeoHookean for a large one, and says why; NeoHookean agrees with the
linear model for a small move and differs for a large one, reports its solve in the field data and
leaves the linear precompute alone; the Precomputed solver equals Newton (with and without LiftOff);
LiftOff (on by default) frees sliding nodes with NeoHookean and is ignored by the linear model, which
says so in its ModelNote without a warning; bad
combinations are errors with an empty output. argv[1] is the plugin, argv[2] the
Data folder.
"""
import os
import sys

import numpy as np
from paraview.simple import LoadPlugin

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
import osteotomy_scenes  # noqa: E402
from faceplan_test_util import ErrorCatcher, WarningCatcher, check, fetch, finish, point_array  # noqa: E402

LoadPlugin(sys.argv[1])
tissue, bone, osteotomy, skeleton, fem = osteotomy_scenes.build(sys.argv[2], "lefort1")
# The solver contract on the open lips: the scenes' LipSeal adds bridges 1000 times as stiff as the
# tissue, which amplify the 1e-9 residual both solvers stop at, so that their results may differ by
# up to 5e-7 (TestCondensedFEMDeformLipSeal covers the sealed scene).
fem.LipSeal = 0.0
fem.OutputMode = "Surface"
check(int(fem.LiftOff) == 1, "LiftOff is on by default")
# Sections 1-3 compare the models with the lips kept on the teeth; section 4 turns LiftOff back on.
fem.LiftOff = 0


def run(**properties):
    for key, value in properties.items():
        setattr(fem, key, value)
    errors, warnings = ErrorCatcher(fem), WarningCatcher(fem)
    fem.UpdatePipeline()
    out = fetch(fem)
    fd = out.GetFieldData()
    fields = {fd.GetAbstractArray(k).GetName(): fd.GetAbstractArray(k).GetVariantValue(0).ToString()
              for k in range(fd.GetNumberOfArrays())}
    return point_array(out, "Displacement"), fields, errors, warnings


def other_warnings(warnings):
    """Warnings other than the count of released tied nodes (the scene's own, not the model's)."""
    return [m for m in warnings.messages if "tied nodes released" not in m]


def rel(a, b):
    return np.linalg.norm(a - b, axis=1).max() / np.linalg.norm(b, axis=1).max()


# 1. The default is Auto: a small move runs the linear model, and the note says why.
check(fem.Model == "Auto" and fem.LargeDeformationSolver == "Precomputed", "defaults: Auto, Precomputed")
osteotomy.Translation = [-0.05, 0.0, 0.0]
u_linear, f, errors, warnings = run()
check(not errors.messages and not other_warnings(warnings) and f.get("Model") == "LinearElastic",
      "Auto: the linear model for a small move (%s), no warning" % f.get("Model"))
check("within the small-strain limit" in f.get("ModelNote", ""), "ModelNote says why (%s)" % f.get("ModelNote"))
precomputes = fem.GetPropertyValue("PrecomputeCount")

# 2. A 0.05 mm move: the large-deformation result is the linear one to first order.
u_small, f, errors, _ = run(Model="NeoHookean")
check(not errors.messages, "NeoHookean runs: %s" % errors.messages)
check(f.get("Model") == "NeoHookean" and f.get("Method") == "LargeDeformationPrecomputed",
      "field data Model/Method say NeoHookean/LargeDeformationPrecomputed (%s, %s)" % (f.get("Model"), f.get("Method")))
check(f.get("LargeDeformationSolver") == "Precomputed" and "SolverNote" not in f,
      "LargeDeformationSolver Precomputed ran (%s)" % f.get("LargeDeformationSolver"))
for name in ("QuasiNewtonIterations", "ForceEvaluations", "FactorSolves", "SmallestVolumeRatio", "RelativeResidual", "ModelNote"):
    check(name in f, "field data %s present" % name)
check(float(f["RelativeResidual"]) <= 1e-9, "converged (%s)" % f["RelativeResidual"])
d_small = rel(u_small, u_linear)
check(0.0 < d_small < 1e-2, "small move agrees with the linear model (%.2e)" % d_small)
check(fem.GetPropertyValue("PrecomputeCount") == precomputes, "NeoHookean starts no precompute")

# 3. A 5 mm move: the two models differ by much more, relative to the move.
osteotomy.Translation = [-5.0, 0.0, 0.0]
u_large, f, errors, warnings = run()
check(not errors.messages and not warnings.contains("small-strain"), "NeoHookean 5 mm: no error, no small-strain warning")
u_newton, f, errors, _ = run(LargeDeformationSolver="Newton")
check(not errors.messages and f.get("Method") == "LargeDeformationNewton" and "NewtonIterations" in f,
      "LargeDeformationSolver Newton ran (%s)" % f.get("Method"))
check(rel(u_large, u_newton) <= 1e-8, "5 mm: Precomputed equals Newton (%.1e)" % rel(u_large, u_newton))
check(f.get("Converged") == "1", "Newton's result is converged (field data Converged %s)" % f.get("Converged"))

# 3b. QuasiNewtonIterationLimit: the iterate after k iterations, labelled as not the equilibrium;
# it is farther from the equilibrium for a smaller k, and the next update without the limit starts
# from the last converged state and converges.
fem.LargeDeformationSolver = "Precomputed"
osteotomy.Translation = [0.0, 0.0, 0.0]
run(QuasiNewtonIterationLimit=0)
osteotomy.Translation = [-5.0, 0.0, 0.0]
distances = []
for k in (1, 4):
    u_k, f, errors, warnings = run(QuasiNewtonIterationLimit=k)
    check(not errors.messages and f.get("Converged") == "0" and int(float(f["QuasiNewtonIterations"])) == k,
          "limit %d: Converged 0 after %s iterations (%s)" % (k, f.get("QuasiNewtonIterations"), errors.messages))
    # The warning is said once: the next update in the same state (k = 4) has the note only.
    check("not the equilibrium" in f.get("SolverNote", "")
          and warnings.contains("not the equilibrium") == (k == 1),
          "limit %d: SolverNote (and, the first time, a warning) say it is not the equilibrium (%s)"
          % (k, f.get("SolverNote")))
    check(float(f["RelativeResidual"]) > 1e-9, "limit %d: residual above the tolerance (%s)" % (k, f["RelativeResidual"]))
    distances.append(rel(u_k, u_large))
check(distances[0] > distances[1] > 0.0, "a larger limit is nearer the equilibrium (%s)" % distances)
u_free, f, errors, warnings = run(QuasiNewtonIterationLimit=0)
check(f.get("Converged") == "1" and "SolverNote" not in f and not other_warnings(warnings),
      "without the limit: converged, no note, no warning (%s)" % f.get("SolverNote"))
check(rel(u_free, u_large) <= 1e-8, "and equal to the unlimited solve (%.1e)" % rel(u_free, u_large))
u_auto, f, errors, warnings = run(Model="Auto", LargeDeformationSolver="Precomputed")
check(not errors.messages and not other_warnings(warnings) and f.get("Model") == "NeoHookean"
      and "beyond the small-strain limit" in f.get("ModelNote", ""),
      "Auto: NeoHookean for the 5 mm move, no warning (%s: %s)" % (f.get("Model"), f.get("ModelNote")))
check(rel(u_auto, u_large) <= 1e-8, "Auto's result is NeoHookean's (%.1e)" % rel(u_auto, u_large))
u_linear_large, f_lin, _, lin_warnings = run(Model="LinearElastic")
check(lin_warnings.contains("Model NeoHookean solves for large deformations"),
      "the linear model's strain warning points to NeoHookean")
d_large = rel(u_large, u_linear_large)
check(d_large > 10 * d_small, "5 mm: models differ (%.2e) far more than at 0.05 mm (%.2e)" % (d_large, d_small))
check(fem.GetPropertyValue("PrecomputeCount") == precomputes,
      "back to LinearElastic: the cached precompute is reused")

# 4. LiftOff: nodes leave the teeth with NeoHookean; the linear model ignores it and says so in its note.
u_lift, f, errors, _ = run(Model="NeoHookean", LiftOff=1)
check(not errors.messages and float(f.get("LiftedNodes", 0)) > 0,
      "LiftOff lifts sliding nodes (%s)" % f.get("LiftedNodes"))
check(rel(u_lift, u_large) > 1e-3, "lift-off changes the result")
u_lift_newton, f_newton, errors, _ = run(LargeDeformationSolver="Newton")
check(not errors.messages and f_newton.get("LiftedNodes") == f.get("LiftedNodes"),
      "LiftOff: Newton lifts the same nodes (%s, %s)" % (f_newton.get("LiftedNodes"), f.get("LiftedNodes")))
check(rel(u_lift, u_lift_newton) <= 1e-8, "LiftOff: Precomputed equals Newton (%.1e)" % rel(u_lift, u_lift_newton))
fem.LargeDeformationSolver = "Precomputed"
u_lin_lift, f, _, warnings = run(Model="LinearElastic")
check(not warnings.contains("LiftOff") and "LiftOff applies to Model NeoHookean only" in f.get("ModelNote", ""),
      "LinearElastic ignores LiftOff and says so in ModelNote, not as a warning (%s; %s)" % (
          f.get("ModelNote"), warnings.messages))
check(rel(u_lin_lift, u_linear_large) == 0.0, "and its result is unchanged")
fem.LiftOff = 0
# Backend CUDA runs the large-deformation solve's steps on the GPU; without one, on the CPU with a
# warning saying why. The answer is the CPU's: to round-off on the CPU from the same start, to the
# solvers' agreement on the GPU (its force sums run in another order).
u_cuda, f_cuda, errors, warnings = run(Model="NeoHookean", Backend="CUDA")
on_gpu = str(f_cuda.get("Backend", "")).startswith("CUDA")
check(not errors.messages and (on_gpu or warnings.contains("Backend CUDA is not available")),
      "Backend CUDA with NeoHookean: on the GPU, or on the CPU with a warning saying why (%s; %s)" % (
          f_cuda.get("Backend"), warnings.messages))
check(rel(u_cuda, u_large) <= 1e-8, "and the same result (%.1e)" % rel(u_cuda, u_large))
# Its precompute is new, so it solved from rest, where u_large was warm-started from the 0.05 mm
# state: the two agree to the solves' tolerance. The CPU's own solve from rest gives its answer
# to round-off.
osteotomy.Translation = [0.0, 0.0, 0.0]
run(Backend="CPU")
osteotomy.Translation = [-5.0, 0.0, 0.0]
u_cold, f_cold, errors, _ = run()
check(not errors.messages and float(f_cold.get("WarmStarted", 1)) == 0.0 and
      float(f_cuda.get("WarmStarted", 1)) == 0.0,
      "the CPU's solve from rest (warm-started: %s, %s)" % (f_cold.get("WarmStarted"), f_cuda.get("WarmStarted")))
check(on_gpu or rel(u_cuda, u_cold) <= 1e-12,
      "without a GPU, the CPU's result from rest to round-off (%.1e)" % rel(u_cuda, u_cold))
fem.Backend = "Auto"

# 5. Bad values and combinations: an error naming the property, and an empty output.
for properties, words in (({"Model": 7}, "Model must be"), ({"LargeDeformationSolver": 5}, "LargeDeformationSolver must be"),
                          ({"QuasiNewtonIterationLimit": -1}, "QuasiNewtonIterationLimit must be"),
                          ({"Model": "NeoHookean", "ElementOrder": "Quadratic"}, "ElementOrder Linear only"),
                          ({"Model": "NeoHookean", "ElementOrder": "Linear", "Verify": 1}, "Verify")):
    u, _, errors, _ = run(**properties)
    check(any(words in m for m in errors.messages), "%s: error mentions %r (%s)" % (properties, words, errors.messages))
    check(u is None or len(u) == 0, "%s: empty output" % properties)
    fem.Verify = 0
    fem.ElementOrder = "Linear"
    fem.Model = "LinearElastic"
    fem.LargeDeformationSolver = "Precomputed"
    fem.QuasiNewtonIterationLimit = 0

finish("TestCondensedFEMDeformLargeDeformation")
