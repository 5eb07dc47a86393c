# SPDX-License-Identifier: BSD-3-Clause
"""Fixed bones and the under-held tissue (pvpython, headless), on the Badin face with the README's
Le Fort I plan (maxilla below a horizontal cut advanced 5 mm).

- A Bone connection without a Displacement array is a fixed bone: alone, it holds its tissue (no
  error, every displacement zero); beside the osteotomy, the tissue tied to it stays put.
- With only the maxilla connected the tissue swings far beyond the bone's move: the filter warns
  that a bone is missing ("is every bone connected?"); with the mandible and cranium connected as
  fixed bones it does not, and the largest tissue displacement stays near the bone's move.
- The warning is said once per state: an edit of the same plan does not repeat it.
- It never fires on round-off: a plan moved back to zero (the large-deformation solve, warm-started
  from the previous move, leaves displacements of order 1e-13 mm) or tissue that sags under gravity
  with every bone fixed says nothing.
- Inputs are never modified: the fixed bones' readers keep no Displacement array.
argv[1] is the plugin, argv[2] the Data folder.
"""
import os
import sys

import numpy as np
from paraview.simple import *  # noqa: F401,F403

LoadPlugin(sys.argv[1], ns=globals())
data_dir = sys.argv[2]
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from faceplan_test_util import ErrorCatcher, WarningCatcher, check, fetch, finish, point_array  # noqa: E402

MOVE = 5.0
LOOSE = "is every bone connected"


def reader(name, kind=XMLPolyDataReader):
    return kind(FileName=[os.path.join(data_dir, "face", name)])


tissue = reader("face_tissue.vtu", XMLUnstructuredGridReader)
maxilla, mandible, cranium = reader("maxilla.vtp"), reader("mandible.vtp"), reader("cranium.vtp")
lefort = Osteotomy(Input=maxilla, Translation=[-MOVE, 0.0, 0.0])
lefort.CutPlane1.Origin = [80.0, 0.0, 110.0]
lefort.CutPlane1.Normal = [0.0, 0.0, -1.0]

t = fetch(tissue)
contact_bone = point_array(t, "ContactBone")
tied = point_array(t, "BoneContact") > 0
on_mandible, on_cranium = tied & (contact_bone == 1), tied & (contact_bone == 3)


def run(bones, **properties):
    fem = CondensedFEMDeform(Input=tissue, Bone=bones, ContactDistance=1.0, **properties)
    errors, warnings = ErrorCatcher(fem), WarningCatcher(fem)
    fem.UpdatePipeline()
    out = fetch(fem)
    u = point_array(out, "Displacement")
    ids = point_array(out, "vtkOriginalPointIds")
    return fem, u, ids, errors, warnings


def magnitude(u):
    return np.linalg.norm(u, axis=1) if u is not None and len(u) else np.zeros(0)


# 1. A fixed bone alone holds its tissue.
fem, u, _, errors, warnings = run([mandible], OutputMode="Volume")
check(not errors.messages, "a bone without Displacement is accepted: %s" % errors.messages)
check(u is not None and len(u) == t.GetNumberOfPoints() and np.all(u == 0.0),
      "a fixed bone alone leaves the tissue where it is (largest %s)" % (magnitude(u).max() if u is not None else None))
check(not warnings.messages, "a fixed bone alone gives no warning: %s" % warnings.messages)
check(fetch(mandible).GetPointData().GetArray("Displacement") is None, "the fixed bone's input is not modified")
Delete(fem)

# 2. Only the operated maxilla: the tissue is not held and the filter says so.
fem, u, _, errors, warnings = run([lefort], OutputMode="Volume")
largest = magnitude(u).max() if u is not None else 0.0
print("maxilla only: largest tissue displacement %.2f mm for a %.1f mm move" % (largest, MOVE))
check(not errors.messages, "maxilla only: no error: %s" % errors.messages)
check(largest > 1.5 * MOVE, "maxilla only: the tissue swings beyond the bone (%.2f mm)" % largest)
check(warnings.contains(LOOSE) and warnings.contains("tissue moves"),
      "maxilla only: the under-held tissue is named: %s" % warnings.messages)
said = sum(LOOSE in m for m in warnings.messages)
check(said == 1, "the warning is said once (%d)" % said)
lefort.Translation = [-MOVE - 0.5, 0.0, 0.0]  # an edit of the same plan
fem.UpdatePipeline()
check(sum(LOOSE in m for m in warnings.messages) == 1, "an edit of the same state does not repeat it: %s"
      % warnings.messages)
lefort.Translation = [-MOVE, 0.0, 0.0]
Delete(fem)

# 3. The README's recipe: the mandible and cranium connected as fixed bones.
fem, u, ids, errors, warnings = run([lefort, mandible, cranium], OutputMode="Volume")
largest = magnitude(u).max() if u is not None else 0.0
print("all bones: largest tissue displacement %.2f mm" % largest)
check(not errors.messages, "all bones: no error: %s" % errors.messages)
check(not warnings.contains(LOOSE), "all bones: no under-held warning: %s" % warnings.messages)
check(0.5 * MOVE < largest <= 1.5 * MOVE, "all bones: the largest tissue move is near the bone's (%.2f mm)" % largest)
if u is not None:
    held = magnitude(u)[on_mandible | on_cranium]
    check(held.size > 50 and held.max() < 1e-9,
          "tissue tied to the fixed mandible and cranium stays put (%d nodes, largest %.3g)"
          % (held.size, held.max() if held.size else -1))
Delete(fem)

# 4. Surface output (the default) gives the same check.
fem, u, _, errors, warnings = run([lefort])
check(not errors.messages and warnings.contains(LOOSE), "Surface output: the under-held tissue is named too")
Delete(fem)

# 5. A plan moved back to zero, as a sweep or an undo does: nothing moves, whatever round-off the
#    warm-started large-deformation solve leaves, so nothing is said.
lefort.Translation = [-0.1, 0.0, 0.0]
fem, u, _, errors, warnings = run([lefort, mandible, cranium], Model="NeoHookean", LiftOff=1)
lefort.Translation = [0.0, 0.0, 0.0]
warnings.clear()
fem.UpdatePipeline()
u = point_array(fetch(fem), "Displacement")
print("zero move: largest tissue displacement %.3g mm" % magnitude(u).max())
check(not errors.messages, "zero move: no error: %s" % errors.messages)
check(magnitude(u).max() < 1e-6, "zero move: the tissue stays put (%.3g mm)" % magnitude(u).max())
check(not warnings.contains(LOOSE), "zero move: round-off is not an under-held tissue: %s" % warnings.messages)
lefort.Translation = [-MOVE, 0.0, 0.0]
Delete(fem)

# 6. Gravity with every bone fixed: the tissue sags, which is what gravity does, not a missing bone.
fem, u, _, errors, warnings = run([maxilla, mandible, cranium], Model="LinearElastic", UseGravity=1)
print("gravity, every bone fixed: largest sag %.3g mm" % magnitude(u).max())
check(not errors.messages, "gravity: no error: %s" % errors.messages)
check(magnitude(u).max() > 0.0, "gravity: the tissue sags")
check(not warnings.contains(LOOSE), "gravity: a sag is not an under-held tissue: %s" % warnings.messages)
Delete(fem)

finish("TestFixedBones")
