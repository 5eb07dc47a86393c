# SPDX-License-Identifier: BSD-3-Clause
"""pvpython test: CondensedFEMDeform keeps its tissue-bone contact across osteotomy edits.

Usage: pvpython TestOsteotomyContactCache.py <path to FacePlan plugin> <Data dir>
Le Fort I on the Badin face, the bone fed directly and with a BSSO as a second Bone connection (a
new merged bone with new arrays on every edit). Checks, by the filter's ContactBuildCount: an edit of the
Osteotomy's Translation or Rotation re-uses the contact (and the precompute) and gives the same
result as a fresh filter; a changed bone (the cut plane moved, the sides flipped) rebuilds it, and so
does a bone moved as a whole (same cells and arrays, other undeformed points), unless the move is
within round-off of the bone's size. The released tissue is logged (INFO) once per contact build,
not at every edit.
"""
import os
import sys

import numpy as np
from paraview.simple import *  # noqa: F401,F403
from vtkmodules.vtkCommonCore import VTK_DOUBLE, vtkLogger

LoadPlugin(sys.argv[1], ns=globals())
data_dir = sys.argv[2]
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from faceplan_test_util import ErrorCatcher, check, fetch, finish, point_array

tissue = XMLUnstructuredGridReader(FileName=[os.path.join(data_dir, "face", "face_tissue.vtu")])
maxilla = XMLPolyDataReader(FileName=[os.path.join(data_dir, "face", "maxilla.vtp")])
mandible = XMLPolyDataReader(FileName=[os.path.join(data_dir, "face", "mandible.vtp")])
lefort = Osteotomy(Input=maxilla, Operation="Custom")
lefort.CutPlane1.Origin = [80.0, 0.0, 113.0]
lefort.CutPlane1.Normal = [0.0, 0.0, -1.0]
lefort.Translation = [-5.0, 0.0, 0.0]
bsso = Osteotomy(Input=mandible, Operation="Custom")
bsso.CutPlane1.Origin = [97.0, 0.0, 80.0]
bsso.CutPlane1.Normal = [-1.0, 0.0, 0.0]
bsso.Translation = [-6.0, 0.0, 0.0]


def contact_builds(fem):
    fem.UpdatePropertyInformation()
    return fem.GetPropertyValue("ContactBuildCount")


def precomputes(fem):
    fem.UpdatePropertyInformation()
    return fem.GetPropertyValue("PrecomputeCount")


def fresh_result(bone):
    """The displacement a new filter (no cache) computes for the current bone."""
    fresh = CondensedFEMDeform(Model="LinearElastic", Input=tissue, Bone=bone, ContactDistance=1.0, OutputMode="Surface",
                               ReleaseDistance=3.0)
    fresh.UpdatePipeline()
    u = point_array(fetch(fresh), "Displacement").copy()
    Delete(fresh)
    return u


# A BSSO as a second connection gives a merged bone (new arrays every update), the bimaxillary
# plan; a single connection passes the Osteotomy's output as it is.
for label, bone in (("direct", [lefort]), ("two connections", [lefort, bsso])):
    lefort.Translation = [-5.0, 0.0, 0.0]
    lefort.Rotation = [0.0, 0.0, 0.0]
    lefort.CutPlane1.Origin = [80.0, 0.0, 113.0]
    lefort.InsideOut = 0
    log = os.path.abspath("TestOsteotomyContactCache-%d.log" % len(bone))
    vtkLogger.LogToFile(log, vtkLogger.TRUNCATE, vtkLogger.VERBOSITY_INFO)
    fem = CondensedFEMDeform(Model="LinearElastic", Input=tissue, Bone=bone, ContactDistance=1.0, OutputMode="Surface",
                             ReleaseDistance=3.0)
    errors = ErrorCatcher(fem)
    fem.UpdatePipeline()
    check(not errors.messages, "%s: the FEM runs without error: %s" % (label, errors.messages))
    check(contact_builds(fem) == 1, "%s: the first update builds the contact once" % label)
    first = point_array(fetch(fem), "Displacement").copy()
    count = precomputes(fem)

    lefort.Translation = [-3.0, 0.0, 1.0]
    fem.UpdatePipeline()
    moved = point_array(fetch(fem), "Displacement").copy()
    check(contact_builds(fem) == 1, "%s: a Translation edit re-uses the contact (builds %d)"
          % (label, contact_builds(fem)))
    check(precomputes(fem) == count, "%s: a Translation edit re-uses the precompute" % label)
    check(np.abs(moved - first).max() > 0.5, "%s: the edit changed the result" % label)
    check(np.abs(moved - fresh_result(bone)).max() < 1e-9,
          "%s: the re-used contact gives a fresh filter's result" % label)

    lefort.Rotation = [0.0, 4.0, 0.0]
    fem.UpdatePipeline()
    check(contact_builds(fem) == 1, "%s: a Rotation edit re-uses the contact" % label)

    lefort.CutPlane1.Origin = [80.0, 0.0, 111.0]
    fem.UpdatePipeline()
    check(contact_builds(fem) == 2, "%s: a moved cut (new bone cells) rebuilds the contact" % label)
    check(np.abs(point_array(fetch(fem), "Displacement") - fresh_result(bone)).max() < 1e-9,
          "%s: after the rebuild the result equals a fresh filter's" % label)

    lefort.InsideOut = 1
    fem.UpdatePipeline()
    check(contact_builds(fem) == 3, "%s: flipped sides (new SegmentId, ROIMask) rebuild the contact"
          % label)
    vtkLogger.EndLogToFile(log)
    this = fem.GetClientSideObject().GetObjectDescription()  # not fresh_result's filters
    with open(log) as f:
        released = [line for line in f if this in line and "tied nodes released" in line]
    os.remove(log)
    check(len(released) == contact_builds(fem),
          "%s: the released nodes are logged once per contact build (%d lines for %d builds in 5 updates)"
          % (label, len(released), contact_builds(fem)))
    Delete(fem)

# The same cells and arrays with the undeformed points moved (the whole bone translated, its
# Displacement unchanged): the contact is rebuilt. A move within the comparison's tolerance (1e-9 of
# the bone's diagonal, about 1e-7 mm here) keeps it: the points are the same up to round-off.
lefort.Translation = [-5.0, 0.0, 0.0]
lefort.Rotation = [0.0, 0.0, 0.0]
lefort.CutPlane1.Origin = [80.0, 0.0, 113.0]
lefort.InsideOut = 0
shifted = Transform(Input=lefort)
shifted.Transform.Translate = [0.0, 0.0, 0.0]
fem = CondensedFEMDeform(Model="LinearElastic", Input=tissue, Bone=[shifted], ContactDistance=1.0,
                         OutputMode="Surface", ReleaseDistance=3.0)
fem.UpdatePipeline()
check(contact_builds(fem) == 1, "shifted bone: the first update builds the contact once")
check(fetch(shifted).GetPoints().GetDataType() == VTK_DOUBLE, "shifted bone: the points are doubles")
shifted.Transform.Translate = [1e-9, 0.0, 0.0]
fem.UpdatePipeline()
check(contact_builds(fem) == 1, "a bone moved by 1e-9 mm keeps the contact (builds %d)" % contact_builds(fem))
shifted.Transform.Translate = [1e-3, 0.0, 0.0]
fem.UpdatePipeline()
check(contact_builds(fem) == 2, "a bone moved by 1e-3 mm rebuilds the contact (builds %d)" % contact_builds(fem))
check(np.abs(point_array(fetch(fem), "Displacement") - fresh_result([shifted])).max() < 1e-9,
      "after the moved bone's rebuild the result equals a fresh filter's")
Delete(fem)

finish("TestOsteotomyContactCache")
