# SPDX-License-Identifier: BSD-3-Clause
"""Bad-input contract of Condensed FEM Deform through pvpython: every property (out of range, NaN and
inf, enums out of range), malformed tissue and bone inputs (types, cells, ids, arrays, frames), legal
but extreme inputs (finite output and a warning), and the cache (invalid values and back; tissue, bone
or ROI replaced after a precompute: the result equals a fresh pipeline's to 1e-12).
argv[1] is the plugin."""
import os
import sys

import numpy as np
from paraview.simple import *  # noqa: F401,F403

LoadPlugin(sys.argv[1], ns=globals())
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from badinput_util import (Cases, Catcher, box_tissue, cell_array, copy, plane_bone, point_array, polydata,
                           set_points, tets_of, unstructured)
from faceplan_test_util import check, fetch, finish, producer
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
from vtkmodules.vtkCommonDataModel import VTK_HEXAHEDRON, VTK_TETRA, VTK_TRIANGLE, vtkCellArray

cases = Cases("CondensedFEMDeform")
PORTS = (0,)
TISSUE, BONE = box_tissue(), plane_bone()
TP = vtk_to_numpy(TISSUE.GetPoints().GetData()).copy()
BP = vtk_to_numpy(BONE.GetPoints().GetData()).copy()
TETS = tets_of(TISSUE)


def fem_on(tissue=TISSUE, bone=BONE, **props):
    f = CondensedFEMDeform(Model="LinearElastic", Input=producer(tissue), Bone=producer(bone))
    f.ContactDistance = 0.5
    for k, v in props.items():
        f.SetPropertyWithName(k, v)
    return f, Catcher(f)


def displacement(proxy):
    a = fetch(proxy).GetPointData().GetArray("Displacement")
    return None if a is None else vtk_to_numpy(a).copy()


def equals_fresh(label, proxy, tissue, bone, **props):
    """The proxy's current result against a new filter on the same inputs (<= 1e-12 relative)."""
    f, c = fem_on(tissue, bone, **props)
    f.UpdatePipeline()
    ref, got = displacement(f), displacement(proxy)
    Delete(f)
    ok = ref is not None and got is not None and ref.shape == got.shape
    diff = np.abs(ref - got).max() / max(np.abs(ref).max(), 1e-300) if ok else np.inf
    print("%s: relative difference to a fresh pipeline %.3g" % (label, diff))
    check(ok and diff <= 1e-12, label + ": equals a fresh pipeline's result to 1e-12 (%.3g)" % diff)


f, c = fem_on()
base = cases.ok("the plain scene (the cases' baseline)", f, c)
U0 = displacement(f)
check(np.abs(U0).max() > 0.1, "CondensedFEMDeform: the baseline moves the tissue")

# Properties: out of range, NaN and inf, enums out of range (nothing is clamped).
NAN, INF = float("nan"), float("inf")
for prop, value, words in (("YoungsModulus", 0.0, ("YoungsModulus",)), ("YoungsModulus", -5.0, ("YoungsModulus",)),
                           ("YoungsModulus", NAN, ("YoungsModulus", "nan")), ("YoungsModulus", INF, ("YoungsModulus",)),
                           ("PoissonRatio", 0.5, ("PoissonRatio",)), ("PoissonRatio", NAN, ("PoissonRatio",)),
                           ("PoissonRatio", -1.0, ("PoissonRatio",)),
                           ("LengthUnit", 0.0, ("LengthUnit",)), ("LengthUnit", NAN, ("LengthUnit",)),
                           ("ContactDistance", -1.0, ("ContactDistance",)), ("ContactDistance", INF, ("ContactDistance",)),
                           ("ContactDistance", NAN, ("ContactDistance",)),
                           ("OutputMode", 7, ("OutputMode", "7")), ("Backend", 5, ("Backend", "5")),
                           ("Method", 9, ("Method", "9")), ("Method", -1, ("Method", "-1")),
                           ("ElementOrder", 99, ("ElementOrder", "99")), ("Model", 7, ("Model", "7")),
                           ("Model", -1, ("Model", "-1")), ("Model", 3, ("Model", "3")),
                           ("LargeDeformationSolver", 2, ("LargeDeformationSolver", "2")),
                           ("LargeDeformationSolver", -1, ("LargeDeformationSolver", "-1")),
                           ("QuasiNewtonIterationLimit", -3, ("QuasiNewtonIterationLimit", "-3"))):
    f, c = fem_on(**{prop: value})
    cases.error("%s = %s" % (prop, value), f, c, *words, ports=PORTS)
f, c = fem_on(UseGravity=1, Density=-1100.0)
cases.error("negative Density with gravity", f, c, "Density", ports=PORTS)
f, c = fem_on(UseGravity=1, Density=NAN)
cases.error("NaN Density with gravity", f, c, "Density", ports=PORTS)
f, c = fem_on(UseGravity=1, Gravity=[0, NAN, -9.81])
cases.error("NaN Gravity", f, c, "Gravity", ports=PORTS)

# Tissue input.
f, c = fem_on(tissue=unstructured(np.zeros((0, 3)), [], []))
cases.error("empty tissue", f, c, "empty", ports=PORTS)
f, c = fem_on(tissue=polydata(TP, polys=[[0, 1, 2]]))
cases.error("tissue is polydata (wrong type)", f, c, "vtkUnstructuredGrid", ports=PORTS)
tris = unstructured(TP, [[0, 1, 12]], [VTK_TRIANGLE])
f, c = fem_on(tissue=tris)
cases.error("tissue of triangles", f, c, "not a linear tetrahedron", "Tetrahedralize", ports=PORTS)
mixed = unstructured(TP, list(TETS) + [[0, 1, 12, 11, 121, 122, 133, 132]], [VTK_TETRA] * len(TETS) + [VTK_HEXAHEDRON])
f, c = fem_on(tissue=mixed)
cases.error("tetrahedra and a hexahedron", f, c, "cell %d" % len(TETS), "not a linear tetrahedron", ports=PORTS)
for name, bad_id, words in (("negative", -1, ("point id -1",)), ("past the end", len(TP) + 4, ("point id %d" % (len(TP) + 4),))):
    t = TETS.copy()
    t[5, 2] = bad_id
    f, c = fem_on(tissue=unstructured(TP, t, [VTK_TETRA] * len(t)))
    cases.error("tetrahedron id %s" % name, f, c, *words, ports=PORTS)
t = TETS.copy()
t[5, 2] = t[5, 1]
f, c = fem_on(tissue=unstructured(TP, t, [VTK_TETRA] * len(t)))
cases.error("repeated id in a tetrahedron", f, c, "tetrahedron 5", "twice", ports=PORTS)
bottom = np.where(TP[:, 2] == 0)[0]
pts = TP.copy()
pts[bottom[7]] = [np.nan, 1, 0]
bad = copy(TISSUE)
set_points(bad, pts)
f, c = fem_on(tissue=bad)
cases.error("NaN coordinate on a tissue node touching the bone", f, c, "point %d" % bottom[7], "NaN", ports=PORTS)
t = TETS.copy()
t[3] = t[3][[1, 0, 2, 3]]
f, c = fem_on(tissue=unstructured(TP, t, [VTK_TETRA] * len(t)))
cases.error("inverted tetrahedron", f, c, "invert", ports=PORTS)
flat = TP.copy()
a, b_, c_, d = TETS[3]
flat[d] = (flat[a] + flat[b_] + flat[c_]) / 3.0  # a zero-volume tetrahedron (and its neighbours distorted)
bad = copy(TISSUE)
set_points(bad, flat)
f, c = fem_on(tissue=bad)
cases.error("zero-volume tetrahedron", f, c, "volume", ports=PORTS)
for name, length, comps in (("short", TISSUE.GetNumberOfCells() - 3, 1), ("2 components", TISSUE.GetNumberOfCells(), 2)):
    bad = copy(TISSUE)
    values = np.full((length, comps), 15000.0) if comps > 1 else np.full(length, 15000.0)
    cell_array(bad, "YoungsModulus", values)
    f, c = fem_on(tissue=bad)
    cases.error("cell YoungsModulus %s" % name, f, c, "YoungsModulus", ports=PORTS)
bad = copy(TISSUE)
nu = np.full(TISSUE.GetNumberOfCells(), 0.45)
nu[11] = np.nan
cell_array(bad, "PoissonRatio", nu)
f, c = fem_on(tissue=bad)
cases.error("cell PoissonRatio NaN", f, c, "PoissonRatio", "NaN", ports=PORTS)
f, c = fem_on(tissue=box_tissue(offset=(1000.0, 0.0, 0.0)))
cases.error("tissue in another frame (no contact)", f, c, "ContactDistance", "frame", ports=PORTS)
f, c = fem_on(tissue=box_tissue(spacing=(1000.0, 1000.0, 1000.0), offset=(0.0, 0.0, 5.0)))
cases.error("tissue in other units (metres vs mm)", f, c, "ContactDistance", ports=PORTS)
# A second block beside the first, touching no bone: it has no support.
second = box_tissue(offset=(30.0, 0.0, 5.0))
two = unstructured(np.vstack([TP, vtk_to_numpy(second.GetPoints().GetData())]),
                   list(TETS) + list(tets_of(second) + len(TP)), [VTK_TETRA] * (2 * len(TETS)))
f, c = fem_on(tissue=two)
cases.error("a tissue piece touching no bone", f, c, "piece", ports=PORTS)

# Bone input.
f, c = fem_on(bone=polydata(np.zeros((0, 3))))
cases.error("empty bone", f, c, "Bone", "no cells", ports=PORTS)
no_cells = polydata(BP)
no_cells.GetPointData().ShallowCopy(BONE.GetPointData())
f, c = fem_on(bone=no_cells)
cases.error("bone with no cells", f, c, "Bone", "no cells", ports=PORTS)
lines_only = polydata(BP, lines=[[i, i + 1] for i in range(len(BP) - 1)])
lines_only.GetPointData().ShallowCopy(BONE.GetPointData())
f, c = fem_on(bone=lines_only)
cases.error("bone of lines only", f, c, "no surface cells", ports=PORTS)
bad = copy(BONE)
pts = BP.copy()
pts[40] = [np.nan, 0, 0]
set_points(bad, pts)
f, c = fem_on(bone=bad)
cases.error("NaN bone coordinate", f, c, "bone's point 40", "NaN", ports=PORTS)
bad = copy(BONE)
bad.GetPolys().GetConnectivityArray().SetValue(4, -2)
f, c = fem_on(bone=bad)
cases.error("negative bone id", f, c, "point id -2", ports=PORTS)
# Found by FuzzContactMapping: VTK's closest-point search aborts (coordinates near 1e150) or writes out
# of bounds (a triangle strip whose triangles have no area) on these; the validation refuses them.
bad = copy(BONE)
pts = BP.copy()
pts[40] = [1e150, 0, 0]
set_points(bad, pts)
f, c = fem_on(bone=bad)
cases.error("bone coordinate 1e150", f, c, "bone's point 40", "beyond 1e30", ports=PORTS)
bad = copy(BONE)
strip = vtkCellArray()
strip.InsertNextCell(4, [2, 5, 5, 5])
bad.SetStrips(strip)
f, c = fem_on(bone=bad)
cases.error("bone with a triangle strip", f, c, "triangle strip", "Triangulate", ports=PORTS)
D = vtk_to_numpy(BONE.GetPointData().GetArray("Displacement")).copy()
M = vtk_to_numpy(BONE.GetPointData().GetArray("ROIMask")).astype(float)
# Without Displacement a bone is fixed (it stays put): no error, a tissue that does not move.
bad = copy(BONE)
bad.GetPointData().RemoveArray("Displacement")
f, c = fem_on(bone=bad)
cases.ok("bone without Displacement (a fixed bone)", f, c)
u = displacement(f)
check(u is not None and len(u) > 0 and np.all(u == 0.0), "a fixed bone leaves the tissue where it is")
for name, values, words in (("2 components", D[:, :2], ("Displacement", "2 components")),
                            ("too short", D[:-9], ("Displacement", "values", "one per point")),
                            ("NaN", np.where(np.arange(len(D))[:, None] == 50, np.nan, D), ("Displacement", "NaN"))):
    bad = copy(BONE)
    bad.GetPointData().RemoveArray("Displacement")
    if values is not None:
        point_array(bad, "Displacement", values)
    f, c = fem_on(bone=bad)
    cases.error("bone Displacement %s" % name, f, c, *words, ports=PORTS)
for name, values, words in (("too short", M[:-1], ("ROIMask", "one per point")),
                            ("NaN", np.where(np.arange(len(M)) == 50, np.nan, M), ("ROIMask", "NaN"))):
    bad = copy(BONE)
    point_array(bad, "ROIMask", values)
    f, c = fem_on(bone=bad)
    cases.error("bone ROIMask %s" % name, f, c, *words, ports=PORTS)

# Released (uint8 flags): the wrong length or shape, a NaN and a type other than uint8 are refused.
R = np.zeros(len(M), dtype=np.uint8)
for name, values, words in (("too short", R[:-1], ("Released", "one per point")),
                            ("2 components", np.zeros((len(R), 2), dtype=np.uint8), ("Released", "2 components")),
                            ("NaN", np.where(np.arange(len(R)) == 50, np.nan, 0.0), ("Released", "NaN")),
                            ("of type double", np.ones(len(R)), ("Released", "double", "uint8"))):
    bad = copy(BONE)
    flags = numpy_to_vtk(np.ascontiguousarray(values), deep=1)
    flags.SetName("Released")
    bad.GetPointData().AddArray(flags)
    f, c = fem_on(bone=bad)
    cases.error("bone Released %s" % name, f, c, *words, ports=PORTS)
    f, c = fem_on(bone=bad)
    f.Bone = [producer(bad), producer(BONE)]
    cases.error("bone Released %s, one of two connections" % name, f, c, "Bone connection 0", *words,
                ports=PORTS)

bad = copy(BONE)
flags = numpy_to_vtk(np.ones(len(R), dtype=np.uint8), deep=1)
flags.SetName("Released")
bad.GetPointData().AddArray(flags)
f, c = fem_on(bone=bad)
cases.error("bone Released everywhere", f, c, "no constrained node", ports=PORTS)

# Legal but extreme: finite output and a warning.
bad = copy(BONE)
point_array(bad, "ROIMask", np.zeros_like(M))
f, c = fem_on(bone=bad)
out = cases.warning("moving bone whose ROIMask is all zero", f, c, "ROIMask", "0", "Displacement")
check(np.all(vtk_to_numpy(out.GetPointData().GetArray("Displacement")) == 0),
      "CondensedFEMDeform [ROIMask all zero]: nothing moves (as the warning says)")
f, c = fem_on(tissue=box_tissue(offset=(1e6, 1e6, 1e6)), bone=plane_bone(offset=(1e6, 1e6, 1e6)))
out = cases.ok("offset 1e6", f, c)
far = displacement(f)
check(np.allclose(far, U0, rtol=0, atol=1e-6 * np.abs(U0).max()),
      "CondensedFEMDeform [offset 1e6]: the displacements at the origin (max difference %.3g)" % np.abs(far - U0).max())

# Cache: invalid values and back; inputs replaced after a precompute.
f, c = fem_on()
f.UpdatePipeline()
for prop, bad_value, good_value in (("PoissonRatio", 0.7, 0.45), ("ElementOrder", 99, 0), ("YoungsModulus", NAN, 15000.0),
                                    ("ContactDistance", -1.0, 0.5)):
    f.SetPropertyWithName(prop, bad_value)
    cases.error("cache: %s invalid" % prop, f, c, prop, ports=PORTS)
    f.SetPropertyWithName(prop, good_value)
    cases.ok("cache: %s back" % prop, f, c)
    equals_fresh("CondensedFEMDeform [cache: %s invalid and back]" % prop, f, TISSUE, BONE)
other_tissue = box_tissue(dims=(11, 11, 5), spacing=(1.0, 1.0, 0.8))
f.Input = producer(other_tissue)
cases.ok("cache: tissue replaced", f, c)
equals_fresh("CondensedFEMDeform [cache: tissue replaced]", f, other_tissue, BONE)
fewer = unstructured(vtk_to_numpy(other_tissue.GetPoints().GetData()), tets_of(other_tissue)[:-40],
                     [VTK_TETRA] * (other_tissue.GetNumberOfCells() - 40))
f.Input = producer(fewer)
cases.ok("cache: same points, tetrahedra removed", f, c)
equals_fresh("CondensedFEMDeform [cache: same points, tetrahedra removed]", f, fewer, BONE)
other_bone = plane_bone(resolution=17)
f.Bone = producer(other_bone)
cases.ok("cache: bone replaced", f, c)
equals_fresh("CondensedFEMDeform [cache: bone replaced]", f, fewer, other_bone)
flipped = copy(other_bone)
conn = vtk_to_numpy(flipped.GetPolys().GetConnectivityArray())
tri = conn.reshape(-1, 3).copy()
shared = [p for p in tri[0] if p in tri[1]]
a, b_ = [p for p in tri[0] if p not in shared][0], [p for p in tri[1] if p not in shared][0]
tri[0], tri[1] = [a, shared[0], b_], [a, b_, shared[1]]  # the quad's other diagonal
for k, v in enumerate(tri[:2].ravel()):
    flipped.GetPolys().GetConnectivityArray().SetValue(k, int(v))
check(len(shared) == 2, "CondensedFEMDeform [cache]: the flipped triangles share an edge")
f.Bone = producer(flipped)
f.UpdatePipeline()
equals_fresh("CondensedFEMDeform [cache: bone with the same points, a changed triangle]", f, fewer, flipped)
roi_bone = copy(other_bone)
mask2 = vtk_to_numpy(other_bone.GetPointData().GetArray("ROIMask")).copy()
pts2 = vtk_to_numpy(other_bone.GetPoints().GetData()) - vtk_to_numpy(other_bone.GetPointData().GetArray("Displacement"))
mask2 = (np.linalg.norm(pts2 - [4.0, 6.0, 0.0], axis=1) < 3.0).astype(float)
point_array(roi_bone, "ROIMask", mask2)
disp2 = mask2[:, None] * np.array([0.1, 0.0, 0.4])
point_array(roi_bone, "Displacement", disp2)
set_points(roi_bone, pts2 + disp2)
f.Bone = producer(roi_bone)
cases.ok("cache: ROI replaced", f, c)
equals_fresh("CondensedFEMDeform [cache: ROI replaced]", f, fewer, roi_bone)
check(np.array_equal(vtk_to_numpy(TISSUE.GetPoints().GetData()), TP) and
      np.array_equal(vtk_to_numpy(BONE.GetPoints().GetData()), BP), "CondensedFEMDeform: inputs not modified")

print("CondensedFEMDeform bad-input cases: %d" % cases.count)
finish("TestBadInputCondensedFEMDeform")
