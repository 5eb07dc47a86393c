"""pvpython test: the shipped osteotomy demos stay inside linear FEM's small-strain range.

Usage: pvpython TestOsteotomyDemoStrain.py <path to FacePlan plugin> <Data dir>
Builds each scene of scripts/osteotomy_scenes.py (Le Fort I 5 mm, BSSO 6 mm, genioplasty 5 mm) with
the demo's contact settings, exactly as scripts/osteotomy_demo.py does, and fails when Condensed FEM
Deform warns that the largest strain exceeds its limit, or when its field data LargestStrain does.
The tissue must also follow the move (at least half of it somewhere), so that a contact which ties
nothing to the segment cannot pass.
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
LIMIT = 0.1  # Core's strainWarningLimit default, which the filter uses

for scene in osteotomy_scenes.SCENES:
    tissue, bone, osteotomy, skeleton, fem = osteotomy_scenes.build(data_dir, scene)
    contact = osteotomy_scenes.configure_contact(fem)
    errors, warnings = ErrorCatcher(fem), WarningCatcher(fem)
    fem.UpdatePipeline()
    out = fetch(fem)
    strain = out.GetFieldData().GetArray("LargestStrain")
    largest = strain.GetValue(0) if strain else float("nan")
    print("%s (%s): largest strain %.1f %%" % (scene, ", ".join(contact), 100 * largest))
    check(not errors.messages, "%s: the pipeline runs without error: %s" % (scene, errors.messages))
    check(not warnings.contains("small-strain range"),
          "%s: no small-strain warning (largest strain %.1f %%)" % (scene, 100 * largest))
    check(largest < LIMIT, "%s: LargestStrain %.3f below %.2f" % (scene, largest, LIMIT))
    move = float(np.linalg.norm(osteotomy_scenes.SCENES[scene][2]))
    u = point_array(out, "Displacement")
    followed = np.linalg.norm(u, axis=1).max() if u is not None else 0.0
    check(followed >= 0.5 * move, "%s: the tissue follows the %.0f mm move (largest %.2f mm)" % (scene, move, followed))
    for proxy in (fem, skeleton, osteotomy, bone, tissue):
        Delete(proxy)

finish("TestOsteotomyDemoStrain")
