# SPDX-License-Identifier: BSD-3-Clause
"""Helpers shared by the FacePlan pvpython filter tests (not a test itself)."""
import sys

import numpy as np
from paraview import servermanager
from paraview.simple import TrivialProducer
from vtkmodules.util.misc import calldata_type
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.util.vtkConstants import VTK_STRING

from faceplan_checks import check, failures, finish  # noqa: F401 (re-exported to the tests)

class _MessageCatcher:
    """Collects the messages a proxy's VTK object sends with one event (vtkErrorMacro: ErrorEvent,
    vtkWarningMacro: WarningEvent)."""

    def __init__(self, proxy, event):
        self.messages = []

        @calldata_type(VTK_STRING)
        def on_message(obj, event_name, message):
            self.messages.append(message)

        self._callback = on_message
        proxy.GetClientSideObject().AddObserver(event, on_message)

    def clear(self):
        self.messages = []

    def contains(self, text):
        return any(text in m for m in self.messages)


class ErrorCatcher(_MessageCatcher):
    """Collects the messages of vtkErrorMacro calls of a proxy's VTK object."""

    def __init__(self, proxy):
        super().__init__(proxy, "ErrorEvent")


class WarningCatcher(_MessageCatcher):
    """Collects the messages of vtkWarningMacro calls of a proxy's VTK object."""

    def __init__(self, proxy):
        super().__init__(proxy, "WarningEvent")


def producer(dataset):
    """A pipeline source that outputs the given VTK data set."""
    tp = TrivialProducer()
    tp.GetClientSideObject().SetOutput(dataset)
    return tp


def fetch(proxy, port=0):
    return servermanager.Fetch(proxy, idx=port)


def points(ds):
    return vtk_to_numpy(ds.GetPoints().GetData()).copy()


def point_array(ds, name):
    a = ds.GetPointData().GetArray(name)
    return None if a is None else vtk_to_numpy(a).copy()


def triangles(ds):
    """(n,3) point ids of a vtkPolyData made of triangles."""
    polys = ds.GetPolys()
    conn = vtk_to_numpy(polys.GetConnectivityArray()).astype(np.int64)
    offs = vtk_to_numpy(polys.GetOffsetsArray()).astype(np.int64)
    assert np.all(np.diff(offs) == 3), "test meshes are triangles"
    return conn.reshape(-1, 3)


def edges_of_triangles(tris):
    e = np.vstack([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]])
    return np.unique(np.sort(e, axis=1), axis=0)


def reference_boundary(tris, mask):
    """ROI vertices with a non-ROI neighbour along a triangle edge (computed independently)."""
    b = np.zeros_like(mask)
    e = edges_of_triangles(tris)
    a, c = e[:, 0], e[:, 1]
    b[a[(mask[a] == 1) & (mask[c] == 0)]] = 1
    b[c[(mask[c] == 1) & (mask[a] == 0)]] = 1
    return b


def area_vectors(pts, tris):
    return 0.5 * np.cross(pts[tris[:, 1]] - pts[tris[:, 0]], pts[tris[:, 2]] - pts[tris[:, 0]])


def cells_equal(a, b):
    """Same cells, same order (connectivity and offsets of the polys)."""
    ca = vtk_to_numpy(a.GetPolys().GetConnectivityArray())
    cb = vtk_to_numpy(b.GetPolys().GetConnectivityArray())
    oa = vtk_to_numpy(a.GetPolys().GetOffsetsArray())
    ob = vtk_to_numpy(b.GetPolys().GetOffsetsArray())
    return np.array_equal(ca, cb) and np.array_equal(oa, ob)


def bezier_curve(ctrl, u):
    """Composite cubic Bezier curve (3k+1 x 3 control points) at parameters u (de Casteljau)."""
    ctrl = np.asarray(ctrl, dtype=float).reshape(-1, 3)
    k = (len(ctrl) - 1) // 3
    u = np.atleast_1d(np.asarray(u, dtype=float))
    seg = np.minimum((u * k).astype(int), k - 1)
    t = (u * k - seg)[:, None]
    q = [ctrl[3 * seg + i] for i in range(4)]
    for r in (3, 2, 1):
        q = [(1 - t) * q[i] + t * q[i + 1] for i in range(r)]
    return q[0]
