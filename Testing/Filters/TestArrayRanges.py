# SPDX-License-Identifier: BSD-3-Clause
"""The filters leave the ranges of their new output arrays in VTK's range cache
(Filters/FacePlanArrayRanges.h), so that ParaView's data information after each update does not
compute them again. For every output port of ROI Extract, Bezier Cut, Condensed FEM Deform (surface
and volume output, and its table), Osteotomy and Facial Landmarks, before and after an edit:
every numeric array of 64 values or more the filter made (points, point, cell, row and field data)
has its ranges cached and valid (newer than the array), and each cached range, per component and of
the magnitude, of all and of finite values, equals the one VTK computes itself on a fresh copy of the
array; an array the filter kept unchanged from the last update keeps its cache as it was (not stored
again); the arrays of the filter's inputs are left as they were (their information unmodified).
argv[1] is the plugin, argv[2] the Data folder.
"""
import builtins
import os
import sys

import numpy as np
from paraview import simple
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkDataArray

from faceplan_test_util import check, finish

simple.LoadPlugin(sys.argv[1])
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
import faceplan_pipeline  # noqa: E402
import osteotomy_scenes  # noqa: E402

# builtins.all: a Programmable Filter (osteotomy_scenes' unmoved bones) runs its script in this
# module's namespace, which then holds numpy_interface's all().
SMALLEST_CACHED = 64  # values; smaller arrays are left to VTK
RANGE_KEYS = (vtkDataArray.L2_NORM_RANGE(), vtkDataArray.L2_NORM_FINITE_RANGE())
COMPONENT_KEYS = (vtkDataArray.PER_COMPONENT(), vtkDataArray.PER_FINITE_COMPONENT())


def arrays_of(data):
    """(where, array) for the points' array and every array of the point, cell, row and field data."""
    found = []
    if data is None:
        return found
    if data.IsA("vtkPointSet") and data.GetPoints() is not None:
        found.append(("points", data.GetPoints().GetData()))
    groups = [("field", data.GetFieldData())]
    if data.IsA("vtkDataSet"):
        groups += [("point", data.GetPointData()), ("cell", data.GetCellData())]
    if data.IsA("vtkTable"):
        groups.append(("row", data.GetRowData()))
    for where, fd in groups:
        for i in range(fd.GetNumberOfArrays() if fd is not None else 0):
            found.append((where, fd.GetAbstractArray(i)))
    return found


def inputs_of(proxy):
    algorithm = proxy.GetClientSideObject()
    return [algorithm.GetInputDataObject(port, c) for port in range(algorithm.GetNumberOfInputPorts())
            for c in range(algorithm.GetNumberOfInputConnections(port))]


def cached(array):
    """The ranges VTK will return from its cache, or None when it would compute them."""
    info = array.GetInformation()
    if info.GetMTime() < array.GetMTime() or not builtins.all(info.Has(k) for k in RANGE_KEYS):
        return None
    for key in COMPONENT_KEYS:
        vector = info.Get(key)
        if vector is None or vector.GetNumberOfInformationObjects() < array.GetNumberOfComponents():
            return None
        if not builtins.all(vector.GetInformationObject(c).Has(vtkDataArray.COMPONENT_RANGE())
                   for c in range(array.GetNumberOfComponents())):
            return None
    return ranges(array)


def ranges(array):
    return [tuple(array.GetRange(c)) + tuple(array.GetFiniteRange(c))
            for c in range(-1, array.GetNumberOfComponents())]


def fresh_copy(array):
    """The same values in a new array of the same type, with an empty range cache."""
    values = vtk_to_numpy(array).copy()
    return numpy_to_vtk(values, deep=1, array_type=array.GetDataType())


kept = {}  # filter name -> {id: (array, information's time, array's time)} after its last update


def check_filter(name, proxy, expect_some=True):
    algorithm = proxy.GetClientSideObject()
    for port in range(algorithm.GetNumberOfInputPorts()):  # the inputs are up to date first
        for c in range(algorithm.GetNumberOfInputConnections(port)):
            connection = algorithm.GetInputConnection(port, c)
            connection.GetProducer().Update(connection.GetIndex())
    # VTK caches an array's ranges in its information the first time anything asks for them (the
    # filter's own VTK calls may): asked here first, the inputs' information changes afterwards
    # only if the filter itself writes into it.
    held_arrays = [a for data in inputs_of(proxy) for _, a in arrays_of(data)]
    for a in held_arrays:
        if a.IsA("vtkDataArray"):
            ranges(a)
    before = {id(a): (a, a.GetInformation().GetMTime(), a.GetMTime()) for a in held_arrays}
    proxy.UpdatePipeline()
    touched = [a.GetName() for a, info_time, time in before.values()
               if (a.GetInformation().GetMTime(), a.GetMTime()) != (info_time, time)]
    check(not touched, "%s leaves its inputs' arrays as they were (touched: %s)" % (name, touched))
    held = set(before)
    checked, missing, wrong, restored = 0, [], [], []
    last = kept.get(name, {})
    now = {}
    for port in range(algorithm.GetNumberOfOutputPorts()):
        for where, array in arrays_of(algorithm.GetOutputDataObject(port)):
            if id(array) in held or not array.IsA("vtkDataArray"):
                continue
            now[id(array)] = (array, array.GetInformation().GetMTime(), array.GetMTime())
            if id(array) in last and last[id(array)][2] == array.GetMTime() \
                    and last[id(array)][1] != array.GetInformation().GetMTime():
                restored.append(array.GetName())
            if array.GetNumberOfValues() < SMALLEST_CACHED:
                continue
            values = vtk_to_numpy(array)
            if not np.isfinite(values).all():
                continue
            label = "%d:%s:%s" % (port, where, array.GetName())
            got = cached(array)
            if got is None:
                missing.append(label)
                continue
            checked += 1
            if got != ranges(fresh_copy(array)):
                wrong.append((label, got, ranges(fresh_copy(array))))
    kept[name] = now
    check((checked > 0 or not expect_some) and not missing,
          "%s: the ranges of its %d new arrays are cached (not: %s)" % (name, checked, missing))
    check(not restored, "%s: arrays kept unchanged keep their cache (stored again: %s)" % (name, restored))
    check(not wrong, "%s: each cached range equals VTK's own (differ: %s)" % (name, wrong))


tissue, mandible, roi, cut, fem = faceplan_pipeline.build(sys.argv[2])
fem.Model = "LinearElastic"
for edit in range(2):
    faceplan_pipeline.place_cut(cut, -0.5 * edit)
    check_filter("ROIExtract", roi)
    check_filter("BezierCut", cut)
    for mode in ("Surface", "Volume"):
        fem.OutputMode = mode
        check_filter("CondensedFEMDeform (%s)" % mode, fem)

_, _, osteotomy, skeleton, bsso = osteotomy_scenes.build(sys.argv[2], "bsso")
bsso.Model = "LinearElastic"
landmarks = simple.FacialLandmarks(Input=bsso, Bone=skeleton, Operation="BSSO")
for edit in range(2):
    if edit:  # the preset's move, then 1 mm further along each axis
        osteotomy.Translation = [x + 1.0 for x in osteotomy.Translation]
    check_filter("Osteotomy", osteotomy)
    check_filter("CondensedFEMDeform (BSSO)", bsso)
    check_filter("FacialLandmarks", landmarks, expect_some=False)  # 19 landmarks: small arrays
finish("TestArrayRanges")
