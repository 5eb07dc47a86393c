"""pvpython test of a bimaxillary plan end to end on the Badin face.

Usage: pvpython TestOsteotomyBimaxillary.py <path to FacePlan plugin> <Data dir>
Le Fort I on the maxilla (Osteotomy, segment below a horizontal cut) and BSSO on the mandible
(Osteotomy, segment in front of a coronal cut through both rami), appended into one bone
(Append Geometry) that feeds Condensed FEM Deform. Checks: the appended bone carries both
segments' motions exactly (and zero elsewhere); the soft tissue tied to each segment follows it;
the plan is linear in the two moves (the response to both equals the sum of the responses to each,
which also shows that both segments reach the solver); the edits reuse the precompute.
"""
import os
import sys

import numpy as np
from paraview.simple import *  # noqa: F401,F403

LoadPlugin(sys.argv[1], ns=globals())
data_dir = sys.argv[2]
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from faceplan_test_util import ErrorCatcher, check, fetch, finish, point_array, points

LEFORT = np.array([-5.0, 0.0, 1.0])  # advancement (anterior is -x) with a slight impaction
BSSO = np.array([-6.0, 0.0, 0.0])

tissue = XMLUnstructuredGridReader(FileName=[os.path.join(data_dir, "face", "face_tissue.vtu")])
maxilla = XMLPolyDataReader(FileName=[os.path.join(data_dir, "face", "maxilla.vtp")])
mandible = XMLPolyDataReader(FileName=[os.path.join(data_dir, "face", "mandible.vtp")])
lefort = Osteotomy(Input=maxilla)
lefort.CutPlane1.Origin = [80.0, 0.0, 110.0]
lefort.CutPlane1.Normal = [0.0, 0.0, -1.0]  # the tooth-bearing part below the cut moves
bsso = Osteotomy(Input=mandible)
bsso.CutPlane1.Origin = [97.0, 0.0, 80.0]
bsso.CutPlane1.Normal = [-1.0, 0.0, 0.0]  # the body in front of both rami moves
bone = AppendGeometry(Input=[lefort, bsso])
fem = CondensedFEMDeform(Input=tissue, Bone=bone, ContactDistance=1.0)
errors = ErrorCatcher(fem)


def solve(lefort_move, bsso_move):
    lefort.Translation = list(lefort_move)
    bsso.Translation = list(bsso_move)
    fem.UpdatePipeline()
    out = fetch(fem)
    table = fetch(fem, 1)
    reused = {table.GetValue(r, 0).ToString(): table.GetValue(r, 2).ToInt() for r in range(table.GetNumberOfRows())}
    return point_array(out, "Displacement"), out, reused


zero = np.zeros(3)
u_both, out, _ = solve(LEFORT, BSSO)
check(not errors.messages, "the FEM runs without error: %s" % errors.messages)
b = fetch(bone)
bl, bm = fetch(lefort), fetch(bsso)
check(b.GetNumberOfPoints() == bl.GetNumberOfPoints() + bm.GetNumberOfPoints(), "the appended bone holds both bones")
D = point_array(b, "Displacement")
seg = point_array(b, "SegmentId")
mask = point_array(b, "ROIMask")
n_max = bl.GetNumberOfPoints()
check(D is not None and seg is not None and mask is not None, "the appended bone keeps Displacement, SegmentId, ROIMask")
on_max = np.arange(b.GetNumberOfPoints()) < n_max
check(np.abs(D[on_max & (seg == 1)] - LEFORT).max() < 1e-12, "the maxilla's segment moved by the Le Fort I move")
check(np.abs(D[~on_max & (seg == 1)] - BSSO).max() < 1e-12, "the mandible's segment moved by the BSSO move")
check(np.all(D[seg == 0] == 0.0), "the rest of both bones does not move")
check(np.array_equal(mask == 1, seg == 1), "ROIMask marks exactly the two segments")
check((on_max & (seg == 1)).sum() > 200 and (~on_max & (seg == 1)).sum() > 200, "both segments are real")

# Tissue tied to each segment follows it: tissue nodes within 0.05 mm of a segment's undeformed
# surface, away from the cut, move with that segment.
X0 = points(b).astype(float) - D
T0 = points(fetch(tissue)).astype(float)


def nearest(bone_pts, pts):
    best = np.full(len(pts), np.inf)
    idx = np.zeros(len(pts), int)
    for s in range(0, len(bone_pts), 512):
        d = np.linalg.norm(pts[:, None, :] - bone_pts[None, s:s + 512, :], axis=2)
        j = d.argmin(axis=1)
        dj = d[np.arange(len(pts)), j]
        better = dj < best
        best[better], idx[better] = dj[better], j[better] + s
    return best, idx


dist, idx = nearest(X0, T0)
for label, sel, move in (("maxilla", on_max, LEFORT), ("mandible", ~on_max, BSSO)):
    interior = sel & (seg == 1)
    near = (dist < 0.05) & interior[idx]
    # keep nodes whose nearest bone point's neighbours are all in the segment (not at the cut)
    check(near.sum() >= 5, "%s: tissue nodes on the segment (%d)" % (label, near.sum()))
    if near.sum():
        err = np.abs(u_both[near] - move).max()
        check(err < 0.05 * np.linalg.norm(move), "%s: tied tissue follows the segment (max deviation %.3f mm)"
              % (label, err))

# Linearity: both moves = Le Fort I alone + BSSO alone (same bone, same contact, same precompute).
u_lefort, _, reused1 = solve(LEFORT, zero)
u_bsso, _, reused2 = solve(zero, BSSO)
scale = np.abs(u_both).max()
err = np.abs(u_both - (u_lefort + u_bsso)).max() / scale
check(err < 1e-9, "superposition: both = Le Fort I + BSSO (relative %.2e)" % err)
check(np.abs(u_lefort).max() > 4.0 and np.abs(u_bsso).max() > 5.0, "each move alone moves the tissue")
check(reused2.get("Factorization", 0) == 1, "an edit of a move reuses the factorization: %s" % reused2)
strain = out.GetFieldData().GetArray("LargestStrain")
print("bimaxillary: largest strain %.1f %%, method %s" % (100 * strain.GetValue(0) if strain else float("nan"),
      out.GetFieldData().GetAbstractArray("Method").GetValue(0)))

finish("TestOsteotomyBimaxillary")
