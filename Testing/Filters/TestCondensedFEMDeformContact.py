# SPDX-License-Identifier: BSD-3-Clause
"""Contract tests of CondensedFEMDeform's operation contact (pvpython, headless): the rigid-segment
path chosen on its own and equal to the general path, several Bone connections merged, the
Sliding and ByArray contact models, ReleaseDistance and the bone's Released array.

The bones are built here with VTK (maxilla moved rigidly as one segment, mandible fixed), so the
test does not depend on the Osteotomy filter. argv[1] is the plugin, argv[2] the Data folder.
"""
import sys

import numpy as np
from paraview.simple import *
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
from vtkmodules.vtkCommonDataModel import vtkPolyData
from vtkmodules.vtkCommonCore import vtkPoints

from faceplan_test_util import ErrorCatcher, WarningCatcher, check, fetch, finish, producer

LoadPlugin(sys.argv[1], ns=globals())
data = sys.argv[2]


def read_surface(name):
    return fetch(XMLPolyDataReader(FileName=[data + "/face/" + name]))


def rotation(ax, ay, az):
    cx, sx, cy, sy, cz, sz = np.cos(ax), np.sin(ax), np.cos(ay), np.sin(ay), np.cos(az), np.sin(az)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rz @ ry @ rx


def bone(surface, transform=None, segment=True, sliding=None, below=None, released=None):
    """The surface with its points below z = `below` (all when None) moved by `transform` (3x4
    [R|t], None = nothing moves), with Displacement, ROIMask, SegmentId and field data
    SegmentTransform as the Osteotomy filter writes them (without its cut faces)."""
    x = vtk_to_numpy(surface.GetPoints().GetData()).astype(float)
    n = x.shape[0]
    moving = np.zeros(n, dtype=bool) if transform is None else (
        np.ones(n, dtype=bool) if below is None else x[:, 2] < below)
    u = np.zeros((n, 3))
    if transform is not None:
        u[moving] = x[moving] @ transform[:, :3].T + transform[:, 3] - x[moving]
    out = vtkPolyData()
    out.DeepCopy(surface)
    pts = vtkPoints()
    pts.SetData(numpy_to_vtk(x + u, deep=True))
    out.SetPoints(pts)
    pd = out.GetPointData()
    for name, values, kind in (("Displacement", u, None),
                               ("ROIMask", moving, np.uint8)):
        a = numpy_to_vtk(values.astype(kind) if kind else values, deep=True)
        a.SetName(name)
        pd.AddArray(a)
    if segment:
        ids = numpy_to_vtk(moving.astype(np.int32), deep=True)
        ids.SetName("SegmentId")
        pd.AddArray(ids)
        if transform is not None:
            t = numpy_to_vtk(transform.reshape(-1).copy(), deep=True)
            t.SetName("SegmentTransform")
            out.GetFieldData().AddArray(t)
    if sliding is not None:
        s = numpy_to_vtk(np.full(n, sliding, dtype=np.uint8), deep=True)
        s.SetName("Sliding")
        pd.AddArray(s)
    if released is not None:
        r = numpy_to_vtk(np.ascontiguousarray(released, dtype=np.uint8), deep=True)
        r.SetName("Released")
        pd.AddArray(r)
    return out


def run(bones, **properties):
    fem = CondensedFEMDeform(Model="LinearElastic", Input=tissue, Bone=bones)
    fem.ContactDistance = 1.0
    fem.OutputMode = "Surface"
    for key, value in properties.items():
        setattr(fem, key, value)
    errors, warnings = ErrorCatcher(fem), WarningCatcher(fem)
    fem.UpdatePipeline()
    out = fetch(fem)
    u = out.GetPointData().GetArray("Displacement")
    method = out.GetFieldData().GetAbstractArray("Method")
    released = out.GetFieldData().GetArray("ReleasedNodes")
    run.released = None if released is None else int(released.GetValue(0))
    return (None if u is None else vtk_to_numpy(u).copy(),
            None if method is None else method.GetValue(0), errors, warnings)


def rel(a, b):
    return np.abs(a - b).max() / np.abs(b).max()


tissue = XMLUnstructuredGridReader(FileName=[data + "/face/face_tissue.vtu"])
maxilla, mandible = read_surface("maxilla.vtp"), read_surface("mandible.vtp")
maxilla_points = vtk_to_numpy(maxilla.GetPoints().GetData())
level = np.median(maxilla_points[:, 2])  # a Le Fort I level: the part below it is the segment
centre = maxilla_points[maxilla_points[:, 2] < level].mean(axis=0)
r = rotation(0.03, -0.02, 0.01)
leFortI = np.hstack([r, (centre - r @ centre + np.array([0.5, -5.0, 1.0]))[:, None]])

moved = producer(bone(maxilla, leFortI, below=level))
fixed = producer(bone(mandible, None))

# 1. Rigid path on its own, with two Bone connections, equal to the general path.
u_rigid, method, errors, warnings = run([moved, fixed])
check(not errors.messages, "rigid plan runs without errors: %s" % errors.messages)
check(method == "RigidSegments", "Auto uses the rigid-segment path (Method = %s)" % method)
u_general, method_general, errors, _ = run([moved, fixed], Method="DenseResponse")
check(method_general == "DenseResponse", "Method DenseResponse is honoured")
check(u_rigid is not None and u_general is not None and rel(u_rigid, u_general) <= 1e-10,
      "rigid path equals the general path to 1e-10")

# The same plan with the connections in the other order gives the same result.
u_swapped, method, _, _ = run([fixed, moved])
check(method == "RigidSegments" and rel(u_swapped, u_rigid) <= 1e-12,
      "merging renumbers segments whatever the connection order")

# 2. A transform that the Displacement does not follow: general path, and a warning says why.
wrong = bone(maxilla, leFortI, below=level)
values = wrong.GetFieldData().GetArray("SegmentTransform")
values.SetValue(3, values.GetValue(3) + 0.5)
u_wrong, method, errors, warnings = run([producer(wrong), fixed])
check(method != "RigidSegments", "a mismatching transform falls back to the general path")
check(warnings.contains("rigid-segment path not used"), "and a warning says why")
# The fallback ties nodes to the bone's interpolated Displacement (partial motion on triangles that
# straddle the cut), where the rigid path moves a node with the segment of its nearest bone point.
check(u_wrong is not None and np.all(np.isfinite(u_wrong)), "the general fallback gives a result")

# 3. Sliding: different from tied; ByArray with Sliding = 0 is Tied and with 1 is Sliding.
u_sliding, method, errors, _ = run([moved, fixed], ContactModel="Sliding")
check(not errors.messages, "Sliding runs without errors: %s" % errors.messages)
check(u_sliding is not None and rel(u_sliding, u_rigid) > 1e-3, "Sliding differs from Tied")
check(method == "RigidSegments", "the rigid path stays with Sliding contact")
u_none, _, _, _ = run([producer(bone(maxilla, leFortI, sliding=0, below=level)), producer(bone(mandible, None, sliding=0))],
                      ContactModel="ByArray")
u_all, _, _, _ = run([producer(bone(maxilla, leFortI, sliding=1, below=level)), producer(bone(mandible, None, sliding=1))],
                     ContactModel="ByArray")
check(u_none is not None and rel(u_none, u_rigid) <= 1e-10, "ByArray with Sliding = 0 equals Tied")
check(u_all is not None and rel(u_all, u_sliding) <= 1e-10, "ByArray with Sliding = 1 equals Sliding")
_, _, errors, _ = run([moved, fixed], ContactModel="ByArray")
check(errors.contains("Sliding"), "ByArray without a Sliding array is an error naming it")

# 4. ReleaseDistance: tied nodes near the cut (the Le Fort I level) become free.
u_released, _, errors, warnings = run([moved, fixed], ReleaseDistance=4.0)
check(not errors.messages, "release runs without errors: %s" % errors.messages)
check(run.released and run.released > 0, "some tied nodes are released (field data ReleasedNodes %s)"
      % run.released)
check(not warnings.contains("released"), "releasing nodes is information, not a warning: %s" % warnings.messages)
check(u_released is not None and rel(u_released, u_rigid) > 1e-6, "released nodes change the result")

# 5. Released: tied nodes whose bone point is flagged become free. The tissue nodes the data file
# ties to the mandible (ContactBone 1) are held at zero while tied; flag the mandible's points on
# one side (y > 0) and those nodes there move, as free nodes do, while the other side stays held.
mandible_points = vtk_to_numpy(mandible.GetPoints().GetData())
tissue_data = fetch(tissue)
tissue_points = vtk_to_numpy(tissue_data.GetPoints().GetData())
on_mandible = (vtk_to_numpy(tissue_data.GetPointData().GetArray("BoneContact")) > 0) & (
    vtk_to_numpy(tissue_data.GetPointData().GetArray("ContactBone")) == 1)
flagged_side = on_mandible & (tissue_points[:, 1] > 3.0)
held_side = on_mandible & (tissue_points[:, 1] < -3.0)
u_tied, _, errors, _ = run([moved, fixed], OutputMode="Volume")
u_zero, _, errors_zero, _ = run([moved, producer(bone(mandible, None, released=np.zeros(len(mandible_points))))],
                                OutputMode="Volume")
check(not errors_zero.messages and u_zero is not None and np.abs(u_zero - u_tied).max() == 0.0,
      "Released = 0 everywhere gives the tied result")
u_free, _, errors, warnings = run(
    [moved, producer(bone(mandible, None, released=mandible_points[:, 1] > 0.0))], OutputMode="Volume")
check(not errors.messages, "Released runs without errors: %s" % errors.messages)
check(flagged_side.sum() > 20 and held_side.sum() > 20,
      "both sides hold mandible-tied nodes (%d, %d)" % (flagged_side.sum(), held_side.sum()))
check(u_free is not None and np.all(np.linalg.norm(u_tied[flagged_side], axis=1) == 0.0),
      "tied to the fixed mandible, the nodes are held at zero")
moving_free = np.linalg.norm(u_free[flagged_side], axis=1) > 0.0
check(moving_free.all(), "Released nodes are free in the result: %d of %d move"
      % (moving_free.sum(), flagged_side.sum()))
check(np.all(np.linalg.norm(u_free[held_side], axis=1) == 0.0),
      "nodes tied to unflagged bone points stay held")
check(run.released is not None and run.released >= flagged_side.sum(),
      "ReleasedNodes counts the released nodes (%s, at least %d)" % (run.released, flagged_side.sum()))
# With two connections the flags of the one that has them are kept, the other's filled with 0.
u_merged, _, errors, _ = run([producer(bone(mandible, None, released=mandible_points[:, 1] > 0.0)), moved],
                             OutputMode="Volume")
check(u_merged is not None and rel(u_merged, u_free) <= 1e-12,
      "Released survives the merge of Bone connections in either order")

finish("TestCondensedFEMDeformContact")
