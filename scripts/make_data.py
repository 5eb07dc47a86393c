#!/usr/bin/env pvpython
# SPDX-License-Identifier: BSD-3-Clause
"""Build the small, real test scenes committed under Data/ from ../shared/data.

Run from anywhere (needs ParaView's Python, i.e. Debian package python3-paraview, plus tetgen
and python3-gmsh):

    pvpython scripts/make_data.py            # writes <repo>/Data/...
    pvpython scripts/make_data.py --check    # only re-reads and checks the committed files

The shared data folder is looked up as <repo>/../shared/data (override with the environment
variable FACEPLAN_SHARED_DATA).  All output is in millimetres.  Every step is deterministic
(fixed decimation / TetGen parameters, no random numbers); the committed files were made with
VTK 9.2 (ParaView 5.11, Debian 12) and TetGen 1.5.0.

Conventions of the written meshes
  * cells are VTK_TETRA only, every tetrahedron has det[x1-x0, x2-x0, x3-x0] > 0
    (negatively oriented ones get nodes 1 and 2 swapped);
  * point array `BoneContact` (uint8): 1 = boundary node to be held fixed, 0 = free.
    Organs: boundary nodes with z <= zmin + 0.2 (zmax - zmin) of the mesh bounding box.
    Face tissue: boundary nodes within CONTACT_MM of the mandible, maxilla or cranium surface.
  * VTK XML, inline binary (base64, zlib) -- no <AppendedData> section.
"""

import hashlib
import json
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import tet_folds  # noqa: E402

from vtkmodules.util import numpy_support as nps
from vtkmodules.vtkCommonCore import vtkPoints, vtkIdList
from vtkmodules.vtkCommonDataModel import (vtkCellArray, vtkPolyData, vtkUnstructuredGrid,
                                           VTK_TETRA)
from vtkmodules.vtkCommonDataModel import vtkStaticCellLocator
from vtkmodules.vtkFiltersCore import (vtkCleanPolyData, vtkTriangleFilter, vtkQuadricDecimation,
                                       vtkConnectivityFilter, vtkPolyDataConnectivityFilter,
                                       vtkFeatureEdges)
from vtkmodules.vtkFiltersVerdict import vtkMeshQuality
from vtkmodules.vtkIOXML import (vtkXMLUnstructuredGridReader, vtkXMLUnstructuredGridWriter,
                                 vtkXMLPolyDataReader, vtkXMLPolyDataWriter)

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SHARED = os.environ.get("FACEPLAN_SHARED_DATA",
                        os.path.normpath(os.path.join(REPO, "..", "shared", "data")))
OUT = os.path.join(REPO, "Data")

CONTACT_MM = 1.0        # contact distance used for the face statistics / BoneContact
ORGAN_FIX_FRACTION = 0.2

# Fixed meshing parameters, tuned once to hit the paper's element counts (see Data/README.md).
ORGANS = {
    # SOFA liver2 surface (boundary of liver2.msh) scaled x50 to kidney size, TetGen directly.
    "kidney_1900": dict(target=1900, tol=0.05, scale=50.0, decimate=None, remesh=None,
                        tetgen="pq1.414a240Y"),
    # SOFA coeur1 surface scaled x3, re-triangulated by Gmsh (h = 6.5 mm), then TetGen.
    "heart_6600": dict(target=6600, tol=0.05, scale=3.0, decimate=None, remesh=(6.5, 40.0),
                       tetgen="pq1.414Y"),
    # ArtiSynth VKH mandible (mm): quadric decimation to 20 %, Gmsh re-triangulation
    # (h = 3.98 mm), then TetGen.
    "mandible_10600": dict(target=10637, tol=0.03, scale=1.0, decimate=0.8, remesh=(3.98, 90.0),
                           tetgen="pq1.414Y"),
}

LOG = []


def log(*args):
    s = " ".join(str(a) for a in args)
    print(s, flush=True)
    LOG.append(s)


# ----------------------------------------------------------------------------------------------
# small helpers
# ----------------------------------------------------------------------------------------------
def read_vtu(path):
    r = vtkXMLUnstructuredGridReader()
    r.SetFileName(path)
    r.Update()
    if r.GetErrorCode() != 0:
        raise RuntimeError("cannot read %s" % path)
    return r.GetOutput()


def read_vtp(path):
    r = vtkXMLPolyDataReader()
    r.SetFileName(path)
    r.Update()
    if r.GetErrorCode() != 0:
        raise RuntimeError("cannot read %s" % path)
    return r.GetOutput()


def read_obj(path):
    """Minimal OBJ reader in double precision (v and f records only; polygons fanned)."""
    verts, tris = [], []
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                verts.append([float(x) for x in line.split()[1:4]])
            elif line.startswith("f "):
                idx = [int(tok.split("/")[0]) for tok in line.split()[1:]]
                idx = [i - 1 if i > 0 else len(verts) + i for i in idx]
                for k in range(1, len(idx) - 1):
                    tris.append([idx[0], idx[k], idx[k + 1]])
    return np.array(verts, dtype=np.float64), np.array(tris, dtype=np.int64)


def get_points(ds):
    return nps.vtk_to_numpy(ds.GetPoints().GetData()).astype(np.float64)


def make_points(xyz):
    pts = vtkPoints()
    pts.SetDataTypeToDouble()
    pts.SetData(nps.numpy_to_vtk(np.ascontiguousarray(xyz, dtype=np.float64), deep=True))
    return pts


def make_cells(conn):
    conn = np.ascontiguousarray(conn, dtype=np.int64)
    n, k = conn.shape
    offsets = np.arange(0, (n + 1) * k, k, dtype=np.int64)
    ca = vtkCellArray()
    ca.SetData(nps.numpy_to_vtkIdTypeArray(offsets, deep=True),
               nps.numpy_to_vtkIdTypeArray(conn.ravel(), deep=True))
    return ca


def polydata(xyz, tris):
    pd = vtkPolyData()
    pd.SetPoints(make_points(xyz))
    pd.SetPolys(make_cells(tris))
    return pd


def poly_arrays(pd):
    xyz = get_points(pd)
    polys = pd.GetPolys()
    off = nps.vtk_to_numpy(polys.GetOffsetsArray())
    con = nps.vtk_to_numpy(polys.GetConnectivityArray())
    assert np.all(np.diff(off) == 3), "not a triangle mesh"
    return xyz, con.reshape(-1, 3).astype(np.int64)


def ugrid(xyz, tets, point_arrays=(), cell_arrays=()):
    ug = vtkUnstructuredGrid()
    ug.SetPoints(make_points(xyz))
    ug.SetCells(VTK_TETRA, make_cells(tets))
    for name, arr in point_arrays:
        a = nps.numpy_to_vtk(np.ascontiguousarray(arr), deep=True)
        a.SetName(name)
        ug.GetPointData().AddArray(a)
    for name, arr in cell_arrays:
        a = nps.numpy_to_vtk(np.ascontiguousarray(arr), deep=True)
        a.SetName(name)
        ug.GetCellData().AddArray(a)
    return ug


def ugrid_tets(ug):
    types = nps.vtk_to_numpy(ug.GetCellTypesArray())
    cells = ug.GetCells()
    off = nps.vtk_to_numpy(cells.GetOffsetsArray())
    con = nps.vtk_to_numpy(cells.GetConnectivityArray())
    keep = types == VTK_TETRA
    assert np.all(np.diff(off)[keep] == 4)
    starts = off[:-1][keep]
    tets = con[starts[:, None] + np.arange(4)[None, :]].astype(np.int64)
    return tets, keep


def tet_dets(xyz, tets):
    p = xyz[tets]
    return np.einsum("ij,ij->i", p[:, 1] - p[:, 0],
                     np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]))


def orient_tets(xyz, tets, label):
    """Make det[x1-x0,x2-x0,x3-x0] > 0 by swapping nodes 1 and 2 of negative tets."""
    d = tet_dets(xyz, tets)
    neg = d < 0
    tets = tets.copy()
    tets[neg, 1], tets[neg, 2] = tets[neg, 2].copy(), tets[neg, 1].copy()
    d = tet_dets(xyz, tets)
    zero = int(np.sum(d == 0.0))
    log("  %s: %d tets, %d reoriented, %d with zero volume, volume min %.4g mean %.4g mm^3"
        % (label, len(tets), int(neg.sum()), zero, d.min() / 6, d.mean() / 6))
    return tets, int(neg.sum()), zero


def boundary_faces(tets):
    """Faces used by exactly one tet, oriented outward (for positively oriented tets)."""
    # faces opposite node 0,1,2,3 with outward orientation for det>0 tets
    loc = np.array([[1, 3, 2], [0, 2, 3], [0, 3, 1], [0, 1, 2]])
    faces = tets[:, loc].reshape(-1, 3)
    key = np.sort(faces, axis=1)
    _, inv, cnt = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    inv = inv.ravel()
    return faces[cnt[inv] == 1]


def folded_faces(xyz, tets):
    """Interior faces whose two tets lie on the same side of the face (or one of them on it): the
    tets overlap although each has a positive volume."""
    _, sides = tet_folds.face_pair_sides(xyz, tets)
    return int((sides >= 0).sum())


def n_components_ug(ug):
    c = vtkConnectivityFilter()
    c.SetInputData(ug)
    c.SetExtractionModeToAllRegions()
    c.Update()
    return c.GetNumberOfExtractedRegions()


def surface_checks(pd):
    fe = vtkFeatureEdges()
    fe.SetInputData(pd)
    fe.BoundaryEdgesOn()
    fe.NonManifoldEdgesOn()
    fe.FeatureEdgesOff()
    fe.ManifoldEdgesOff()
    fe.Update()
    c = vtkPolyDataConnectivityFilter()
    c.SetInputData(pd)
    c.SetExtractionModeToAllRegions()
    c.Update()
    return fe.GetOutput().GetNumberOfCells(), c.GetNumberOfExtractedRegions()


def quality(ug):
    out = {}
    for name, setter in (("radius_ratio", "SetTetQualityMeasureToRadiusRatio"),
                         ("aspect_ratio", "SetTetQualityMeasureToAspectRatio"),
                         ("min_dihedral_deg", "SetTetQualityMeasureToMinAngle"),
                         ("mean_ratio", "SetTetQualityMeasureToMeanRatio")):
        q = vtkMeshQuality()
        q.SetInputData(ug)
        getattr(q, setter)()
        q.Update()
        v = nps.vtk_to_numpy(q.GetOutput().GetCellData().GetArray("Quality"))
        out[name] = (float(v.min()), float(v.mean()), float(v.max()))
    return out


def fmt_quality(q):
    return ("radius ratio (1 = ideal) min %.3f mean %.3f max %.2f; aspect ratio min %.3f mean %.3f "
            "max %.2f; min dihedral angle min %.2f mean %.2f deg; mean ratio (1 = ideal) min %.4f "
            "mean %.3f" % (q["radius_ratio"] + q["aspect_ratio"] + q["min_dihedral_deg"][:2]
                           + q["mean_ratio"][:2]))


def write_xml(ds, path):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    w = vtkXMLUnstructuredGridWriter() if path.endswith(".vtu") else vtkXMLPolyDataWriter()
    w.SetFileName(path)
    w.SetInputData(ds)
    w.SetDataModeToBinary()          # inline base64, no <AppendedData>
    w.SetCompressorTypeToZLib()
    w.SetHeaderTypeToUInt32()
    if w.Write() != 1:
        raise RuntimeError("cannot write " + path)
    with open(path, "rb") as f:
        assert b"AppendedData" not in f.read()
    back = read_vtu(path) if path.endswith(".vtu") else read_vtp(path)
    assert back.GetNumberOfPoints() == ds.GetNumberOfPoints(), path
    assert back.GetNumberOfCells() == ds.GetNumberOfCells(), path
    assert np.array_equal(get_points(back), get_points(ds)), path
    log("  wrote %s: %d points, %d cells, %d bytes (read back OK)"
        % (os.path.relpath(path, REPO), back.GetNumberOfPoints(), back.GetNumberOfCells(),
           os.path.getsize(path)))
    return back


def decimate(xyz, tris, reduction):
    pd = polydata(xyz, tris)
    d = vtkQuadricDecimation()
    d.SetInputData(pd)
    d.SetTargetReduction(reduction)
    d.VolumePreservationOn()
    d.Update()
    c = vtkCleanPolyData()
    c.SetInputConnection(d.GetOutputPort())
    c.PointMergingOn()
    c.SetTolerance(0.0)
    c.Update()
    return poly_arrays(c.GetOutput())


def write_smesh(path, xyz, tris):
    with open(path, "w") as f:
        f.write("%d 3 0 0\n" % len(xyz))
        for i, p in enumerate(xyz):
            f.write("%d %.17g %.17g %.17g\n" % (i, p[0], p[1], p[2]))
        f.write("%d 0\n" % len(tris))
        for t in tris:
            f.write("3 %d %d %d\n" % (t[0], t[1], t[2]))
        f.write("0\n0\n")


def tetgen(xyz, tris, switches, workdir):
    """Run TetGen on a closed triangle surface, return (points, tets)."""
    base = os.path.join(workdir, "surf")
    write_smesh(base + ".smesh", xyz, tris)
    for ext in (".1.node", ".1.ele", ".1.face"):
        if os.path.exists(base + ext):
            os.remove(base + ext)
    cmd = ["tetgen", "-" + switches + "Q", base + ".smesh"]
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if r.returncode != 0 or not os.path.exists(base + ".1.ele"):
        raise RuntimeError("tetgen failed (%s):\n%s" % (" ".join(cmd), r.stdout[-2000:]))
    node = np.loadtxt(base + ".1.node", comments="#", skiprows=1)
    ele = np.loadtxt(base + ".1.ele", comments="#", skiprows=1, dtype=np.int64)
    ids = node[:, 0].astype(np.int64)
    assert np.array_equal(ids, np.arange(len(ids)) + ids[0])
    return node[:, 1:4].copy(), ele[:, 1:5] - ids[0]


def compact(xyz, cells):
    used = np.unique(cells)
    remap = -np.ones(len(xyz), dtype=np.int64)
    remap[used] = np.arange(len(used))
    return xyz[used], remap[cells], used


def sha256(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        h.update(f.read())
    return h.hexdigest()


def write_stl(path, xyz, tris):
    with open(path, "w") as f:
        f.write("solid s\n")
        for t in tris:
            a, b, c = xyz[t]
            n = np.cross(b - a, c - a)
            ln = np.linalg.norm(n)
            n = n / ln if ln > 0 else n
            f.write("facet normal %.9g %.9g %.9g\nouter loop\n" % tuple(n))
            for p in (a, b, c):
                f.write("vertex %.17g %.17g %.17g\n" % tuple(p))
            f.write("endloop\nendfacet\n")
        f.write("endsolid s\n")


def gmsh_remesh(xyz, tris, h, angle_deg, workdir):
    """Isotropic re-triangulation of a closed surface with Gmsh (classify + reparametrize,
    Frontal-Delaunay 2D, uniform size h).  Returns (points, triangles)."""
    import math
    import gmsh
    stl = os.path.join(workdir, "remesh_in.stl")
    write_stl(stl, xyz, tris)
    gmsh.initialize(["gmsh"], readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("General.NumThreads", 1)
        gmsh.merge(stl)
        gmsh.model.mesh.classifySurfaces(angle_deg * math.pi / 180, True, True, math.pi)
        gmsh.model.mesh.createGeometry()
        gmsh.option.setNumber("Mesh.MeshSizeMin", h)
        gmsh.option.setNumber("Mesh.MeshSizeMax", h)
        gmsh.option.setNumber("Mesh.Algorithm", 6)
        gmsh.model.mesh.generate(2)
        tags, coords, _ = gmsh.model.mesh.getNodes()
        _, enodes = gmsh.model.mesh.getElementsByType(2)
    finally:
        gmsh.finalize()
    tags = tags.astype(np.int64)
    idx = np.zeros(int(tags.max()) + 1, dtype=np.int64)
    idx[tags] = np.arange(len(tags))
    pts = coords.reshape(-1, 3)
    tri = idx[enodes.astype(np.int64).reshape(-1, 3)]
    pts, tri, _ = compact(pts, tri)
    return pts, tri


def sliver_counts(xyz, tets):
    q = vtkMeshQuality()
    q.SetInputData(ugrid(xyz, tets))
    q.SetTetQualityMeasureToMinAngle()
    q.Update()
    v = nps.vtk_to_numpy(q.GetOutput().GetCellData().GetArray("Quality"))
    return int((v < 5).sum()), int((v < 10).sum())


# ----------------------------------------------------------------------------------------------
# checks shared by the build and --check
# ----------------------------------------------------------------------------------------------
def check_tet_file(path):
    ug = read_vtu(path)
    tets, keep = ugrid_tets(ug)
    assert keep.all(), "%s: non-tetra cells" % path
    xyz = get_points(ug)
    d = tet_dets(xyz, tets)
    assert (d > 0).all(), "%s: %d tets with det <= 0" % (path, int((d <= 0).sum()))
    folds = folded_faces(xyz, tets)
    assert folds == 0, "%s: %d folded faces (overlapping tets)" % (path, folds)
    ncomp = n_components_ug(ug)
    assert ncomp == 1, "%s: %d components" % (path, ncomp)
    bc = ug.GetPointData().GetArray("BoneContact")
    assert bc is not None and bc.GetDataTypeAsString() == "unsigned char", path
    bc = nps.vtk_to_numpy(bc)
    bnodes = np.unique(boundary_faces(tets))
    assert not bc[np.setdiff1d(np.arange(len(xyz)), bnodes)].any(), "BoneContact on interior node"
    q = quality(ug)
    b = ug.GetBounds()
    return dict(points=ug.GetNumberOfPoints(), cells=ug.GetNumberOfCells(), components=ncomp,
                boundary_nodes=int(len(bnodes)), bone_contact_nodes=int(bc.sum()),
                min_volume_mm3=float(d.min() / 6), total_volume_mm3=float(d.sum() / 6),
                extent_mm=[round(b[1] - b[0], 2), round(b[3] - b[2], 2), round(b[5] - b[4], 2)],
                folded_faces=folds, quality=q, slivers_lt5deg_lt10deg=list(sliver_counts(xyz, tets)))


def check_surface_file(path):
    pd = read_vtp(path)
    xyz, tris = poly_arrays(pd)
    open_edges, comps = surface_checks(pd)
    b = pd.GetBounds()
    return dict(points=pd.GetNumberOfPoints(), cells=pd.GetNumberOfCells(),
                boundary_or_nonmanifold_edges=open_edges, components=comps,
                extent_mm=[round(b[1] - b[0], 2), round(b[3] - b[2], 2), round(b[5] - b[4], 2)])


# ----------------------------------------------------------------------------------------------
# scene 1: Badin face (ArtiSynth), metres -> millimetres
# ----------------------------------------------------------------------------------------------
FACE_BONES = (("mandible", "badinjaw.obj", 1), ("maxilla", "badinmaxilla.obj", 2),
              ("cranium", "badincranium.obj", 3))


def bone_surface(path):
    xyz, tris = read_obj(path)
    pd = polydata(xyz * 1000.0, tris)
    tf = vtkTriangleFilter()
    tf.SetInputData(pd)
    cl = vtkCleanPolyData()
    cl.SetInputConnection(tf.GetOutputPort())
    cl.SetTolerance(0.0)
    cl.Update()
    out = vtkPolyData()
    out.SetPoints(make_points(get_points(cl.GetOutput())))
    out.SetPolys(cl.GetOutput().GetPolys())
    return out, len(xyz), len(tris)


def distances_to(pd, xyz):
    loc = vtkStaticCellLocator()
    loc.SetDataSet(pd)
    loc.BuildLocator()
    cp = [0.0, 0.0, 0.0]
    import vtkmodules.vtkCommonCore as cc
    cell_id = cc.reference(0)
    sub_id = cc.reference(0)
    dist2 = cc.reference(0.0)
    out = np.empty(len(xyz))
    for i, p in enumerate(xyz):
        loc.FindClosestPoint(p.tolist(), cp, cell_id, sub_id, dist2)
        out[i] = float(dist2) ** 0.5
    return out


# TetGen on the face's boundary surface: -Y keeps the boundary triangles (so the tissue-bone
# contact is the source's), q1.2 bounds the radius-edge ratio, a45 (mm^3) the volume, which keeps
# the problem size close to the source's 37,688 tets.
FACE_TETGEN = "pq1.2a45Y"
# How far a boundary vertex that pokes through the facing lip is pushed back along its normal.
FACE_UNTANGLE_MM = 0.1


def self_intersections(xyz, tris, workdir):
    """Pairs of intersecting triangles (indices into tris) as `tetgen -d` reports them."""
    import re
    base = os.path.join(workdir, "selfcheck")
    write_smesh(base + ".smesh", xyz, tris)
    r = subprocess.run(["tetgen", "-d", base + ".smesh"], stdout=subprocess.PIPE,
                       stderr=subprocess.STDOUT, text=True)
    index = {tuple(sorted(t)): k for k, t in enumerate(tris.tolist())}
    found = re.findall(r"\((\d+), (\d+), (\d+)\) and \((\d+), (\d+), (\d+)\)", r.stdout)
    return [(index[tuple(sorted(map(int, m[:3])))], index[tuple(sorted(map(int, m[3:])))])
            for m in found]


def vertex_normal(xyz, tris, v):
    ring = tris[(tris == v).any(axis=1)]
    n = np.cross(xyz[ring[:, 1]] - xyz[ring[:, 0]], xyz[ring[:, 2]] - xyz[ring[:, 0]]).sum(axis=0)
    return n / np.linalg.norm(n)


def untangle_surface(xyz, tris, workdir):
    """Minimal local repair of a self-intersecting closed surface, so that TetGen can mesh it.
    The Badin face's lips touch at the mouth corners, where a vertex of one lip pokes 0.015 mm
    through the other lip's surface. In each group of intersecting pairs, the vertex shared by all
    the first triangles (the one poking through) moves FACE_UNTANGLE_MM along its outward
    normal, back to its own side. Returns the repaired points and the ids of the moved vertices."""
    xyz = xyz.copy()
    pairs = self_intersections(xyz, tris, workdir)
    first = {}
    for a, b in pairs:
        first.setdefault(b, set()).add(a)
    moved = set()
    for group in first.values():
        shared = set.intersection(*(set(tris[a].tolist()) for a in group))
        moved |= shared
    for v in sorted(moved):
        xyz[v] += FACE_UNTANGLE_MM * vertex_normal(xyz, tris, v)
    left = self_intersections(xyz, tris, workdir)
    log("  boundary surface: %d intersecting triangle pairs; moved vertices %s by %g mm along "
        "their normals; %d pairs left" % (len(pairs), sorted(moved), FACE_UNTANGLE_MM, len(left)))
    assert not left, "face boundary still intersects itself"
    return xyz, sorted(moved)


def make_face(info, workdir):
    log("== face (Badin model, ArtiSynth), scaled x1000 to mm")
    src = os.path.join(SHARED, "artisynth_models", "face", "derived", "face_skullconformed_tet.vtu")
    ug = read_vtu(src)
    src_xyz = get_points(ug) * 1000.0
    src_tets, keep = ugrid_tets(ug)
    src_tets, _, _ = orient_tets(src_xyz, src_tets, "source")
    log("  source: %d points, %d cells, %d of them VTK_TETRA, %d folded faces"
        % (ug.GetNumberOfPoints(), ug.GetNumberOfCells(), int(keep.sum()),
           folded_faces(src_xyz, src_tets)))
    # Only the source's boundary surface is kept: its split hexahedra overlap (folded faces).
    surf_xyz, surf_tris, surf_used = compact(src_xyz, boundary_faces(src_tets))
    surf_xyz, moved = untangle_surface(surf_xyz, surf_tris, workdir)
    xyz, tets = tetgen(surf_xyz, surf_tris, FACE_TETGEN, workdir)
    assert np.array_equal(xyz[:len(surf_xyz)], surf_xyz), "TetGen renumbered the surface points"
    tets, nre, nzero = orient_tets(xyz, tets, "face_tissue")
    assert nzero == 0
    assert len(np.unique(boundary_faces(tets))) == len(surf_xyz), "TetGen changed the boundary"
    vol = tet_dets(xyz, tets) / 6
    tiny = int((vol < 1e-6 * vol.mean()).sum())
    src_node_id = nps.vtk_to_numpy(ug.GetPointData().GetArray("ansys_node_id"))
    node_id = np.full(len(xyz), -1, dtype=np.int64)
    node_id[:len(surf_xyz)] = src_node_id[surf_used]
    log("  tetgen -%s: %d points (%d on the boundary), %d tets"
        % (FACE_TETGEN, len(xyz), len(surf_xyz), len(tets)))

    fdir = os.path.join(OUT, "face")
    bones = {}
    for name, fname, label in FACE_BONES:
        pd, nv, nf = bone_surface(os.path.join(SHARED, "artisynth_models", "face", fname))
        log("  %s: %s %d verts %d faces -> %d points %d triangles"
            % (name, fname, nv, nf, pd.GetNumberOfPoints(), pd.GetNumberOfCells()))
        write_xml(pd, os.path.join(fdir, name + ".vtp"))
        bones[name] = pd

    bnodes = np.unique(boundary_faces(tets))
    dist = np.stack([distances_to(bones[n], xyz) for n, _, _ in FACE_BONES], axis=1)
    dmin = dist.min(axis=1)
    nearest = dist.argmin(axis=1) + 1
    is_b = np.zeros(len(xyz), bool)
    is_b[bnodes] = True
    contact = is_b & (dmin <= CONTACT_MM)
    label = np.where(contact, nearest, 0).astype(np.uint8)

    stats = dict(boundary_nodes=int(len(bnodes)), reoriented=nre, zero_volume=nzero,
                 tiny_volume_below_1e6th_of_mean=tiny, tetgen_switches=FACE_TETGEN,
                 untangled_boundary_vertices=[int(v) for v in moved],
                 untangle_mm=FACE_UNTANGLE_MM)
    for thr in (0.1, 0.5, 1.0, 2.0):
        stats["mandible_within_%gmm" % thr] = int((dist[bnodes, 0] <= thr).sum())
        stats["any_bone_within_%gmm" % thr] = int((dmin[bnodes] <= thr).sum())
    for k, (name, _, _) in enumerate(FACE_BONES):
        stats["%s_contact_nodes_1mm" % name] = int((label == k + 1).sum())
    frac = stats["mandible_within_1mm"] / len(bnodes)
    stats["mandible_fraction_1mm"] = frac
    log("  tissue boundary nodes: %d; within 1 mm of mandible: %d (%.1f %%); within 1 mm of any "
        "of mandible/maxilla/cranium: %d (%.1f %%); within 0.1 mm of mandible: %d"
        % (len(bnodes), stats["mandible_within_1mm"], 100 * frac, stats["any_bone_within_1mm"],
           100 * stats["any_bone_within_1mm"] / len(bnodes), stats["mandible_within_0.1mm"]))

    tissue = ugrid(xyz, tets,
                   point_arrays=[("BoneContact", contact.astype(np.uint8)),
                                 ("ContactBone", label),
                                 ("BoneDistance", dmin.astype(np.float32)),
                                 ("ansys_node_id", node_id.astype(np.int32))])
    path = os.path.join(fdir, "face_tissue.vtu")
    write_xml(tissue, path)
    info["face/face_tissue.vtu"] = check_tet_file(path)
    log("  quality: " + fmt_quality(info["face/face_tissue.vtu"]["quality"]))
    for name, _, _ in FACE_BONES:
        info["face/%s.vtp" % name] = check_surface_file(os.path.join(fdir, name + ".vtp"))
    info["face_stats"] = stats


# ----------------------------------------------------------------------------------------------
# scene 2: organ meshes at the benchmark sizes
# ----------------------------------------------------------------------------------------------
def organ_source_surface(name):
    if name == "kidney_1900":
        ug = read_vtu(os.path.join(SHARED, "sofa", "derived", "liver2_tets.vtu"))
        xyz = get_points(ug)
        tets, keep = ugrid_tets(ug)
        tets, _, _ = orient_tets(xyz, tets, "liver2 source (SOFA units, volumes not mm^3)")
        xyz, tris, _ = compact(xyz, boundary_faces(tets))
        return xyz, tris
    if name == "heart_6600":
        return poly_arrays(read_vtp(os.path.join(SHARED, "sofa", "derived", "coeur1.vtp")))
    if name == "mandible_10600":
        return read_obj(os.path.join(SHARED, "artisynth_models", "vkhUpperAirway", "Mandible.obj"))
    raise KeyError(name)


def make_organ(name, cfg, info, workdir):
    log("== organ %s" % name)
    xyz, tris = organ_source_surface(name)
    xyz = xyz * cfg["scale"]
    log("  source surface: %d points, %d triangles, open/non-manifold edges and components %s"
        % (len(xyz), len(tris), surface_checks(polydata(xyz, tris))))
    if cfg["decimate"]:
        xyz, tris = decimate(xyz, tris, cfg["decimate"])
        log("  quadric decimation (target reduction %g): %d points, %d triangles"
            % (cfg["decimate"], len(xyz), len(tris)))
    if cfg["remesh"]:
        h, ang = cfg["remesh"]
        xyz, tris = gmsh_remesh(xyz, tris, h, ang, workdir)
        log("  gmsh re-triangulation (h %g mm, classify angle %g deg): %d points, %d triangles"
            % (h, ang, len(xyz), len(tris)))
    ebad, ncomp = surface_checks(polydata(xyz, tris))
    assert ebad == 0 and ncomp == 1, "surface not closed/manifold/connected"
    pts, tets = tetgen(xyz, tris, cfg["tetgen"], workdir)
    tets, nre, nzero = orient_tets(pts, tets, name)
    assert nzero == 0
    pts, tets, _ = compact(pts, tets)
    n = len(tets)
    dev = (n - cfg["target"]) / cfg["target"]
    log("  tetgen -%s: %d tets (target %d, %+.1f %%)" % (cfg["tetgen"], n, cfg["target"], 100 * dev))
    assert abs(dev) <= cfg["tol"], "tet count off target"

    bnodes = np.unique(boundary_faces(tets))
    z = pts[:, 2]
    zcut = z.min() + ORGAN_FIX_FRACTION * (z.max() - z.min())
    bc = np.zeros(len(pts), np.uint8)
    bc[bnodes[z[bnodes] <= zcut]] = 1
    odir = os.path.join(OUT, "organs")
    path = os.path.join(odir, name + ".vtu")
    write_xml(ugrid(pts, tets, point_arrays=[("BoneContact", bc)]), path)
    info["organs/%s.vtu" % name] = check_tet_file(path)
    info["organs/%s.vtu" % name]["target_cells"] = cfg["target"]
    if name == "mandible_10600":
        # the surface the tetrahedra were built on (TetGen -Y keeps it unchanged)
        surf = polydata(pts, boundary_faces(tets))
        cl = vtkCleanPolyData()
        cl.SetInputData(surf)
        cl.SetTolerance(0.0)
        cl.Update()
        spath = os.path.join(odir, name + "_surface.vtp")
        write_xml(cl.GetOutput(), spath)
        info["organs/%s_surface.vtp" % name] = check_surface_file(spath)
    log("  quality: " + fmt_quality(info["organs/%s.vtu" % name]["quality"]))


# ----------------------------------------------------------------------------------------------
# CT: VTK's quarter-resolution head CT
# ----------------------------------------------------------------------------------------------
CT_DIMS = (64, 64, 93)           # x, y, slices
CT_SPACING = (3.2, 3.2, 1.5)     # mm, from quarter.nhdr
CT_RAW_TO_HU = -1024             # raw CT numbers 0..3926 -> Hounsfield units


def make_ct(info):
    """Stacks headsq/quarter.1 .. quarter.93 (int16 LE, 64 x 64 each) into Data/ct/headsq.vti,
    point scalars `HU` (int16) = raw - 1024, origin 0, spacing 3.2 x 3.2 x 1.5 mm."""
    from vtkmodules.vtkCommonDataModel import vtkImageData
    from vtkmodules.vtkIOXML import vtkXMLImageDataWriter
    src = os.path.join(SHARED, "pyvista_vtk-data", "headsq")
    nx, ny, nz = CT_DIMS
    slices = []
    for k in range(1, nz + 1):
        raw = np.fromfile(os.path.join(src, "quarter.%d" % k), dtype="<i2")
        assert raw.size == nx * ny, "quarter.%d has %d values" % (k, raw.size)
        slices.append(raw)
    raw = np.concatenate(slices)
    hu = (raw.astype(np.int32) + CT_RAW_TO_HU).astype(np.int16)
    img = vtkImageData()
    img.SetDimensions(nx, ny, nz)
    img.SetSpacing(*CT_SPACING)
    img.SetOrigin(0.0, 0.0, 0.0)
    arr = nps.numpy_to_vtk(hu, deep=True)
    arr.SetName("HU")
    img.GetPointData().SetScalars(arr)
    os.makedirs(os.path.join(OUT, "ct"), exist_ok=True)
    path = os.path.join(OUT, "ct", "headsq.vti")
    w = vtkXMLImageDataWriter()
    w.SetFileName(path)
    w.SetDataModeToBinary()
    w.SetCompressorTypeToZLib()
    w.SetInputData(img)
    if not w.Write():
        sys.exit("could not write " + path)
    info["ct/headsq.vti"] = check_ct_file(path)
    log("  ct/headsq.vti: %s voxels, HU %d..%d" % ("x".join(map(str, CT_DIMS)), hu.min(), hu.max()))


def check_ct_file(path):
    from vtkmodules.vtkIOXML import vtkXMLImageDataReader
    r = vtkXMLImageDataReader()
    r.SetFileName(path)
    r.Update()
    img = r.GetOutput()
    dims = img.GetDimensions()
    assert tuple(dims) == CT_DIMS, "%s: dimensions %s" % (path, dims)
    assert np.allclose(img.GetSpacing(), CT_SPACING), "%s: spacing %s" % (path, img.GetSpacing())
    hu = nps.vtk_to_numpy(img.GetPointData().GetArray("HU"))
    assert hu.size == np.prod(CT_DIMS)
    return {"dims": list(dims), "spacing": list(img.GetSpacing()), "hu_min": int(hu.min()),
            "hu_max": int(hu.max())}


def copy_licenses():
    ldir = os.path.join(OUT, "licenses")
    os.makedirs(ldir, exist_ok=True)
    shutil.copyfile(os.path.join(SHARED, "artisynth_models", "LICENSE"),
                    os.path.join(ldir, "ArtiSynth-models-LICENSE.txt"))
    shutil.copyfile(os.path.join(SHARED, "sofa", "LICENSE-LGPL.md"),
                    os.path.join(ldir, "SOFA-LICENSE-LGPL.md"))
    shutil.copyfile(os.path.join(SHARED, "pyvista_vtk-data", "Copyright.txt"),
                    os.path.join(ldir, "VTK-data-Copyright.txt"))


def check_all():
    info = {}
    for rel in ("face/face_tissue.vtu", "organs/kidney_1900.vtu", "organs/heart_6600.vtu",
                "organs/mandible_10600.vtu"):
        info[rel] = check_tet_file(os.path.join(OUT, rel))
    for rel in ("face/mandible.vtp", "face/maxilla.vtp", "face/cranium.vtp",
                "organs/mandible_10600_surface.vtp"):
        info[rel] = check_surface_file(os.path.join(OUT, rel))
    for rel, v in info.items():
        log("  %-36s %6d points %6d cells" % (rel, v["points"], v["cells"]))
    info["ct/headsq.vti"] = check_ct_file(os.path.join(OUT, "ct", "headsq.vti"))
    log("  %-36s %s voxels" % ("ct/headsq.vti", "x".join(map(str, CT_DIMS))))
    return info


def main():
    if "--check" in sys.argv:
        check_all()
        log("all Data/ files read back and pass the checks")
        return
    if not os.path.isdir(SHARED):
        sys.exit("shared data not found at %s (set FACEPLAN_SHARED_DATA)" % SHARED)
    info = {}
    with tempfile.TemporaryDirectory() as wd:
        make_face(info, wd)
        for name, cfg in ORGANS.items():
            make_organ(name, cfg, info, wd)
        make_ct(info)
    copy_licenses()
    info["files_sha256"] = {
        os.path.relpath(os.path.join(dp, f), OUT): sha256(os.path.join(dp, f))
        for dp, _, fs in os.walk(OUT) for f in sorted(fs)
        if f.endswith((".vtu", ".vtp", ".vti"))}
    with open(os.path.join(OUT, "manifest.json"), "w") as f:
        json.dump(info, f, indent=1, sort_keys=True)
        f.write("\n")
    log("wrote Data/manifest.json")


if __name__ == "__main__":
    main()
