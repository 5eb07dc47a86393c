# SPDX-License-Identifier: BSD-3-Clause
"""pvpython test: the shipped osteotomy demos use a model that is valid for their strains.

Usage: pvpython TestOsteotomyDemoStrain.py <path to FacePlan plugin> <Data dir>
Builds each scene of scripts/osteotomy_scenes.py (Le Fort I 5 mm, BSSO 6 mm, genioplasty 5 mm) with
the demo's contact and model settings, exactly as scripts/osteotomy_demo.py does, and fails when
Condensed FEM Deform reports an error or any warning but the count of released nodes (in particular
its small-strain warning), when the model is not the large-deformation one, when the result has an
inverted or collapsed cell or did not converge, or when the tissue does not follow the move (at
least half of it somewhere, so that a contact which ties nothing to the segment cannot pass). The
linear model on the same scenes must warn (the reason the demos use the other one): a test of the
test.
"""
import os
import sys

import numpy as np

from paraview.simple import Delete, LoadPlugin

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
import osteotomy_scenes  # noqa: E402
from faceplan_test_util import ErrorCatcher, WarningCatcher, check, fetch, finish, point_array  # noqa: E402

LoadPlugin(sys.argv[1])
data_dir = sys.argv[2]


def field(out, name):
    a = out.GetFieldData().GetAbstractArray(name)
    return a.GetValue(0) if a is not None else None


for scene in osteotomy_scenes.SCENES:
    tissue, bone, osteotomy, skeleton, fem = osteotomy_scenes.build(data_dir, scene)
    settings = osteotomy_scenes.OPERATION_MODEL + osteotomy_scenes.configure_model(fem)
    errors, warnings = ErrorCatcher(fem), WarningCatcher(fem)
    fem.UpdatePipeline()
    out = fetch(fem)
    largest = field(out, "LargestStrain")
    print("%s (%s): largest strain %s, model %s, smallest volume ratio %s, residual %s" % (
        scene, ", ".join(settings), largest, field(out, "Model"), field(out, "SmallestVolumeRatio"),
        field(out, "RelativeResidual")))
    check(not errors.messages, "%s: the pipeline runs without error: %s" % (scene, errors.messages))
    others = [m for m in warnings.messages if "tied nodes released" not in m]
    check(not others, "%s: no warning but the released count: %s" % (scene, others))
    check(not warnings.contains("small-strain range"), "%s: no small-strain warning" % scene)
    check(field(out, "Model") == "NeoHookean", "%s: the large-deformation model" % scene)
    ratio = field(out, "SmallestVolumeRatio")
    check(ratio is not None and ratio > 0.1, "%s: no cell inverted or collapsed (det F %s)" % (scene, ratio))
    residual = field(out, "RelativeResidual")
    check(residual is not None and residual <= 1e-9, "%s: converged (residual %s)" % (scene, residual))
    move = float(np.linalg.norm(osteotomy_scenes.SCENES[scene][2]))
    u = point_array(out, "Displacement")
    followed = np.linalg.norm(u, axis=1).max() if u is not None else 0.0
    check(followed >= 0.5 * move, "%s: the tissue follows the %.0f mm move (largest %.2f mm)" % (scene, move, followed))

    # The linear model on the same scene is outside its range and says so.
    fem.Model = "LinearElastic"
    fem.LiftOff = 0
    linear_warnings = WarningCatcher(fem)
    fem.UpdatePipeline()
    check(linear_warnings.contains("small-strain range"),
          "%s: the linear model warns (largest strain %s)" % (scene, field(fetch(fem), "LargestStrain")))
    for proxy in (fem, skeleton, osteotomy, bone, tissue):
        Delete(proxy)

finish("TestOsteotomyDemoStrain")
