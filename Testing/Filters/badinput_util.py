# SPDX-License-Identifier: BSD-3-Clause
"""Small synthetic scenes and expectation helpers for the bad-input contract tests (not a test).

Each case asserts one of the two outcomes of the contract: (a) an error naming the problem
(vtkErrorMacro, from the filter or its executive) and an empty output, or (b) for legal but
extreme input, a finite output and a warning.
"""
import numpy as np
from vtkmodules.util.misc import calldata_type
from vtkmodules.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray, vtk_to_numpy
from vtkmodules.util.vtkConstants import VTK_STRING
from vtkmodules.vtkCommonCore import vtkDoubleArray, vtkPoints, vtkUnsignedCharArray
from vtkmodules.vtkCommonDataModel import (VTK_TETRA, vtkCellArray, vtkImageData, vtkPolyData,
                                           vtkUnstructuredGrid)
from vtkmodules.vtkFiltersCore import vtkTriangleFilter
from vtkmodules.vtkFiltersGeneral import vtkDataSetTriangleFilter
from vtkmodules.vtkFiltersSources import vtkPlaneSource

from faceplan_test_util import check, fetch

# The scene: a flat bone (triangles in z = 0 over [-1, 11]^2) under a tissue block [0, 10]^2 x [0, 3]
# of tetrahedra; the ROI is the bone within 4 of (5, 5), pushed up by 0.3.
ROI_CENTER, ROI_RADIUS, PUSH = np.array([5.0, 5.0, 0.0]), 4.0, np.array([0.0, 0.0, 0.3])


class Catcher:
    """vtkErrorMacro and vtkWarningMacro messages of a proxy's VTK object and of its executive."""

    def __init__(self, proxy):
        self.errors, self.warnings = [], []

        @calldata_type(VTK_STRING)
        def on_error(obj, event, message):
            self.errors.append(message)

        @calldata_type(VTK_STRING)
        def on_warning(obj, event, message):
            self.warnings.append(message)

        self._callbacks = (on_error, on_warning)
        algorithm = proxy.GetClientSideObject()
        for obj in (algorithm, algorithm.GetExecutive()):
            obj.AddObserver("ErrorEvent", on_error)
            obj.AddObserver("WarningEvent", on_warning)

    def clear(self):
        self.errors, self.warnings = [], []


def _text(message):
    """The message without VTK's "ERROR: In <file>, line <n>" header (which would match words)."""
    return "\n".join(l for l in message.splitlines() if not l.startswith(("ERROR: In ", "Warning: In ")))


def _has(messages, words):
    return any(all(w.lower() in _text(m).lower() for w in words) for m in messages)


def _finite_output(ds):
    if ds.GetPoints() is None:
        return True
    ok = bool(np.all(np.isfinite(vtk_to_numpy(ds.GetPoints().GetData()))))
    pd = ds.GetPointData()
    for i in range(pd.GetNumberOfArrays()):
        a = pd.GetArray(i)
        if a is not None and a.GetNumberOfTuples() > 0:
            ok = ok and bool(np.all(np.isfinite(vtk_to_numpy(a).astype(float))))
    return ok


def _empty(ds):
    return ds.GetNumberOfPoints() == 0 and (not hasattr(ds, "GetNumberOfCells") or ds.GetNumberOfCells() == 0)


class Cases:
    def __init__(self, label):
        self.label, self.count = label, 0

    def error(self, name, proxy, catcher, *words, ports=(0,)):
        """Outcome (a): an error containing every word (case-insensitive), empty outputs."""
        self.count += 1
        catcher.clear()
        proxy.UpdatePipeline()
        what = "%s [%s]" % (self.label, name)
        print("%s errors: %s" % (what, [m.strip().splitlines()[-1][:160] for m in catcher.errors]))
        check(_has(catcher.errors, words), what + ": error naming %s (got %s)" % (words, catcher.errors))
        for port in ports:
            check(_empty(fetch(proxy, port)), what + ": empty output on port %d" % port)

    def warning(self, name, proxy, catcher, *words, min_points=1):
        """Outcome (b): finite, non-empty output (port 0), no error, a warning containing every word."""
        self.count += 1
        catcher.clear()
        proxy.UpdatePipeline()
        what = "%s [%s]" % (self.label, name)
        out = fetch(proxy)
        print("%s warnings: %s" % (what, [m.strip().splitlines()[-1][:160] for m in catcher.warnings]))
        check(not catcher.errors, what + ": no error (got %s)" % catcher.errors)
        check(out.GetNumberOfPoints() >= min_points, what + ": non-empty output")
        check(_finite_output(out), what + ": finite output")
        check(_has(catcher.warnings, words), what + ": warning naming %s (got %s)" % (words, catcher.warnings))
        return out

    def ok(self, name, proxy, catcher):
        """Legal input: finite, non-empty output and no error (used by the cache cases)."""
        catcher.clear()
        proxy.UpdatePipeline()
        what = "%s [%s]" % (self.label, name)
        out = fetch(proxy)
        check(not catcher.errors, what + ": no error (got %s)" % catcher.errors)
        check(out.GetNumberOfPoints() > 0 and _finite_output(out), what + ": finite, non-empty output")
        return out


def polydata(points, polys=(), lines=(), verts=()):
    pd = vtkPolyData()
    p = vtkPoints()
    p.SetDataTypeToDouble()
    p.SetData(numpy_to_vtk(np.ascontiguousarray(points, dtype=float), deep=1))
    pd.SetPoints(p)
    for cells, setter in ((polys, pd.SetPolys), (lines, pd.SetLines), (verts, pd.SetVerts)):
        if len(cells):
            ca = vtkCellArray()
            for c in cells:
                ca.InsertNextCell(len(c))
                for i in c:
                    ca.InsertCellPoint(int(i))
            setter(ca)
    return pd


def plane_bone(offset=(0.0, 0.0, 0.0), resolution=12, push=True):
    """The flat bone: triangles, with ROIMask and (when push) Displacement moving the ROI by PUSH."""
    src = vtkPlaneSource()
    src.SetOrigin(-1, -1, 0)
    src.SetPoint1(11, -1, 0)
    src.SetPoint2(-1, 11, 0)
    src.SetResolution(resolution, resolution)
    tri = vtkTriangleFilter()
    tri.SetInputConnection(src.GetOutputPort())
    tri.Update()
    out = vtkPolyData()
    out.SetPoints(vtkPoints())
    out.GetPoints().SetDataTypeToDouble()
    pts = vtk_to_numpy(tri.GetOutput().GetPoints().GetData()).astype(float)
    mask = (np.linalg.norm(pts - ROI_CENTER, axis=1) < ROI_RADIUS).astype(np.uint8)
    disp = mask[:, None] * PUSH[None, :] if push else np.zeros_like(pts)
    out.GetPoints().SetData(numpy_to_vtk(pts + disp + np.asarray(offset, float), deep=1))
    out.SetPolys(tri.GetOutput().GetPolys())
    m = numpy_to_vtk(mask, deep=1, array_type=vtkUnsignedCharArray().GetDataType())
    m.SetName("ROIMask")
    out.GetPointData().AddArray(m)
    d = numpy_to_vtk(np.ascontiguousarray(disp), deep=1)
    d.SetName("Displacement")
    out.GetPointData().AddArray(d)
    return out


def box_tissue(offset=(0.0, 0.0, 0.0), dims=(11, 11, 4), spacing=(1.0, 1.0, 1.0)):
    """The tissue block of linear tetrahedra (x, y in [0, 10], z in [0, 3])."""
    img = vtkImageData()
    img.SetDimensions(*dims)
    img.SetSpacing(*spacing)
    img.SetOrigin(*offset)
    tet = vtkDataSetTriangleFilter()
    tet.SetInputData(img)
    tet.Update()
    ug = vtkUnstructuredGrid()
    ug.DeepCopy(tet.GetOutput())
    pts = vtkPoints()
    pts.SetDataTypeToDouble()
    pts.SetData(numpy_to_vtk(vtk_to_numpy(ug.GetPoints().GetData()).astype(float), deep=1))
    ug.SetPoints(pts)
    return ug


def tets_of(ug):
    conn = vtk_to_numpy(ug.GetCells().GetConnectivityArray()).astype(np.int64)
    return conn.reshape(-1, 4)


def unstructured(points, cells, types):
    """A vtkUnstructuredGrid from explicit (possibly malformed) cells."""
    ug = vtkUnstructuredGrid()
    p = vtkPoints()
    p.SetDataTypeToDouble()
    p.SetData(numpy_to_vtk(np.ascontiguousarray(points, dtype=float), deep=1))
    ug.SetPoints(p)
    ug.Allocate(len(cells))
    for c, t in zip(cells, types):
        ug.InsertNextCell(int(t), len(c), [int(i) for i in c])
    return ug


def set_points(ds, pts):
    p = vtkPoints()
    p.SetDataTypeToDouble()
    p.SetData(numpy_to_vtk(np.ascontiguousarray(pts, dtype=float), deep=1))
    ds.SetPoints(p)


def point_array(ds, name, values, components=None):
    values = np.ascontiguousarray(values, dtype=float)
    a = numpy_to_vtk(values, deep=1)
    a.SetName(name)
    ds.GetPointData().RemoveArray(name)
    ds.GetPointData().AddArray(a)
    return ds


def cell_array(ds, name, values):
    a = numpy_to_vtk(np.ascontiguousarray(values, dtype=float), deep=1)
    a.SetName(name)
    ds.GetCellData().RemoveArray(name)
    ds.GetCellData().AddArray(a)
    return ds


def copy(ds):
    c = ds.NewInstance()
    c.DeepCopy(ds)
    return c
