# SPDX-License-Identifier: BSD-3-Clause
"""The scenes of the MPI tests, built and split the same way in every run (serial or mpiexec).

face:   the demo's pipeline on the Badin face (ROIExtract -> BezierCut -> CondensedFEMDeform).
osteotomy: the face with a BSSO (Osteotomy on the mandible, maxilla and cranium fixed).
sphere: a hollow sphere whose inner wall is pulled by a bone surface (half of it in the ROI).
A run's tissue (and, except for the .pvtu split, the mandible) goes through one split:
none, RedistributeDataSet, D3 (with ghost cells) or a 2-piece .pvtu written beforehand by
write_scene_files."""
import math
import os

import numpy as np
from paraview import simple
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
from vtkmodules.vtkCommonCore import (VTK_DOUBLE, VTK_FLOAT, VTK_ID_TYPE, VTK_INT, VTK_LONG_LONG,
                                      VTK_UNSIGNED_CHAR, vtkIdList, vtkPoints)
from vtkmodules.vtkCommonDataModel import VTK_HEXAHEDRON, vtkUnstructuredGrid
from vtkmodules.vtkFiltersCore import (vtkCellCenters, vtkExtractCells, vtkIdFilter,
                                       vtkStaticCleanUnstructuredGrid)
from vtkmodules.vtkFiltersGeneral import vtkDataSetTriangleFilter
from vtkmodules.vtkFiltersSources import vtkSphereSource
from vtkmodules.vtkIOXML import (vtkXMLPolyDataWriter,
                                 vtkXMLUnstructuredGridReader, vtkXMLUnstructuredGridWriter)

SPLITS = ["RedistributeDataSet", "D3", "pvtu"]
SERIAL_ID = "SerialPointId"
SCENES = ["face", "sphere"]
OSTEOTOMY_SPLIT = "RedistributeDataSet"  # the osteotomy scene runs with this split only
INNER, OUTER, LAYERS, CELLS_PER_EDGE = 10.0, 20.0, 4, 10


def _hollow_sphere_tissue():
    """Cube-sphere hexahedra between INNER and OUTER, split into tetrahedra by VTK."""
    pts, hexes = [], []
    n, base = CELLS_PER_EDGE, 0
    t = np.linspace(-1.0, 1.0, n + 1)
    for axis in range(3):
        for sign in (-1.0, 1.0):
            ids = np.zeros((LAYERS + 1, n + 1, n + 1), dtype=np.int64)
            for k in range(LAYERS + 1):
                r = INNER + (OUTER - INNER) * k / LAYERS
                for i in range(n + 1):
                    for j in range(n + 1):
                        c = [0.0, 0.0, 0.0]
                        c[axis] = sign
                        c[(axis + 1) % 3], c[(axis + 2) % 3] = t[i], t[j]
                        c = np.array(c)
                        ids[k, i, j] = base
                        pts.append(r * c / np.linalg.norm(c))
                        base += 1
            for k in range(LAYERS):
                for i in range(n):
                    for j in range(n):
                        h = [ids[k, i, j], ids[k, i + 1, j], ids[k, i + 1, j + 1], ids[k, i, j + 1],
                             ids[k + 1, i, j], ids[k + 1, i + 1, j], ids[k + 1, i + 1, j + 1],
                             ids[k + 1, i, j + 1]]
                        a, b, c, d = (np.array(pts[v]) for v in (h[0], h[1], h[3], h[4]))
                        if np.dot(np.cross(b - a, c - a), d - a) < 0.0:  # VTK's positive order
                            h = [h[0], h[3], h[2], h[1], h[4], h[7], h[6], h[5]]
                        hexes.append(h)
    grid = vtkUnstructuredGrid()
    points = vtkPoints()
    points.SetData(numpy_to_vtk(np.array(pts), deep=1))
    grid.SetPoints(points)
    for h in hexes:
        grid.InsertNextCell(VTK_HEXAHEDRON, 8, [int(v) for v in h])
    clean = vtkStaticCleanUnstructuredGrid()  # one point where two cube faces meet
    clean.SetInputData(grid)
    clean.SetTolerance(0.0)
    tets = vtkDataSetTriangleFilter()
    tets.SetInputConnection(clean.GetOutputPort())
    tets.TetrahedraOnlyOn()
    tets.Update()
    return tets.GetOutput()


def _hollow_sphere_bone():
    """The inner wall, pulled up and out where z > 0 (ROIMask 1), held where z <= 0."""
    sphere = vtkSphereSource()
    sphere.SetRadius(INNER)
    sphere.SetThetaResolution(48)
    sphere.SetPhiResolution(48)
    sphere.Update()
    bone = sphere.GetOutput()
    bone.GetPointData().Initialize()
    p = np.array([bone.GetPoint(i) for i in range(bone.GetNumberOfPoints())])
    mask = (p[:, 2] > 0.0).astype(np.uint8)
    u = np.zeros_like(p)
    u[:, 0] = 0.1 * p[:, 0] / INNER * mask
    u[:, 2] = 0.2 * (p[:, 2] / INNER) ** 2 * mask
    for name, values in (("Displacement", u), ("ROIMask", mask)):
        a = numpy_to_vtk(values, deep=1)
        a.SetName(name)
        bone.GetPointData().AddArray(a)
    return bone


def write_scene_files(data_dir, work_dir):
    """The hollow sphere's files and both tissues' 2-piece .pvtu (serial run only)."""
    os.makedirs(work_dir, exist_ok=True)
    writer = vtkXMLUnstructuredGridWriter()
    writer.SetInputData(_hollow_sphere_tissue())
    writer.SetFileName(os.path.join(work_dir, "sphere_tissue.vtu"))
    writer.Write()
    bone_writer = vtkXMLPolyDataWriter()
    bone_writer.SetInputData(_hollow_sphere_bone())
    bone_writer.SetFileName(os.path.join(work_dir, "sphere_bone.vtp"))
    bone_writer.Write()
    for scene in SCENES:
        _write_two_pieces(tissue_file(scene, data_dir, work_dir),
                          os.path.join(work_dir, scene + "_tissue"))


_XML_TYPES = {VTK_DOUBLE: "Float64", VTK_FLOAT: "Float32", VTK_ID_TYPE: "Int64",
              VTK_LONG_LONG: "Int64", VTK_INT: "Int32", VTK_UNSIGNED_CHAR: "UInt8"}


def _write_two_pieces(source_file, stem):
    """<stem>.pvtu: the cells west and east of the median centroid, seam points in both pieces,
    point coordinates exactly as in the source file."""
    reader = vtkXMLUnstructuredGridReader()
    reader.SetFileName(source_file)
    ids = vtkIdFilter()  # the serial ids travel inside the pieces
    ids.SetInputConnection(reader.GetOutputPort())
    ids.SetPointIdsArrayName(SERIAL_ID)
    ids.SetCellIds(False)
    ids.Update()
    grid = ids.GetOutput()
    centers = vtkCellCenters()
    centers.SetInputData(grid)
    centers.Update()
    x = vtk_to_numpy(centers.GetOutput().GetPoints().GetData())[:, 0]
    west = x <= np.median(x)
    sources = []
    for k, part in enumerate((west, ~west)):
        extract = vtkExtractCells()
        extract.SetInputData(grid)
        cell_ids = vtkIdList()
        for c in np.nonzero(part)[0]:
            cell_ids.InsertNextId(int(c))
        extract.SetCellList(cell_ids)
        writer = vtkXMLUnstructuredGridWriter()
        writer.SetInputConnection(extract.GetOutputPort())
        name = "%s_%d.vtu" % (os.path.basename(stem), k)
        writer.SetFileName(os.path.join(os.path.dirname(stem), name))
        writer.Write()
        sources.append(name)
    arrays = lambda data: "".join(
        '<PDataArray type="%s" Name="%s" NumberOfComponents="%d"/>'
        % (_XML_TYPES[a.GetDataType()], a.GetName(), a.GetNumberOfComponents())
        for a in (data.GetArray(i) for i in range(data.GetNumberOfArrays())) if a is not None)
    with open(stem + ".pvtu", "w") as f:
        f.write('<?xml version="1.0"?>\n<VTKFile type="PUnstructuredGrid" version="1.0" '
                'byte_order="LittleEndian" header_type="UInt64">\n<PUnstructuredGrid GhostLevel="0">'
                "<PPointData>%s</PPointData><PCellData>%s</PCellData>"
                '<PPoints><PDataArray type="%s" NumberOfComponents="3"/></PPoints>%s'
                "</PUnstructuredGrid>\n</VTKFile>\n"
                % (arrays(grid.GetPointData()), arrays(grid.GetCellData()),
                   _XML_TYPES[grid.GetPoints().GetDataType()],
                   "".join('<Piece Source="%s"/>' % n for n in sources)))


def tissue_file(scene, data_dir, work_dir):
    if scene in ("face", "osteotomy"):
        return os.path.join(data_dir, "face", "face_tissue.vtu")
    return os.path.join(work_dir, "sphere_tissue.vtu")


def _split(source, split):
    if split == "RedistributeDataSet":  # cell GlobalIds, no point GlobalIds: merge by coordinates
        return simple.RedistributeDataSet(Input=source, GenerateGlobalCellIds=1)
    # D3 adds point GlobalIds and ghost cells; the .pvtu has neither.
    if split == "D3":
        return simple.D3(Input=source)
    return source


def build(scene, split, data_dir, work_dir):
    """(fem, bone, edit): the pipeline's CondensedFEMDeform, its Bone input and a function making one
    edit of the bone. The face's bone (BezierCut's output) carries serial point ids too."""
    if split == "pvtu":
        tissue = simple.XMLPartitionedUnstructuredGridReader(
            FileName=[os.path.join(work_dir, scene + "_tissue.pvtu")])
    else:
        tissue = simple.XMLUnstructuredGridReader(FileName=[tissue_file(scene, data_dir, work_dir)])
        # Before the split: the first process reads the whole file, so these are the serial ids.
        tissue = _split(simple.GenerateIds(Input=tissue, PointIdsArrayName=SERIAL_ID,
                                           GenerateCellIds=0), split)
    if scene == "face":
        import faceplan_pipeline
        mandible = simple.XMLPolyDataReader(FileName=[os.path.join(data_dir, "face", "mandible.vtp")])
        mandible = simple.GenerateIds(Input=mandible, PointIdsArrayName=SERIAL_ID, GenerateCellIds=0)
        bone_piece = mandible if split == "pvtu" else _split(mandible, split)
        roi = simple.ROIExtract(Input=bone_piece)
        roi.Region = "Sphere"
        roi.Region.Center = [70.0, 0.0, 58.0]
        roi.Region.Radius = 22.0
        cut = simple.BezierCut(Input=roi)
        cut.CurveU = faceplan_pipeline.CURVE_U
        cut.CurveV = faceplan_pipeline.CURVE_V
        cut.FlipNormal = 1
        bone = cut

        def edit():
            faceplan_pipeline.place_cut(cut, -0.5)
    elif scene == "osteotomy":  # BSSO: the mandible's body moved, maxilla and cranium fixed
        import osteotomy_scenes
        _, operation, translation, _ = osteotomy_scenes.SCENES["bsso"]
        mandible = simple.XMLPolyDataReader(FileName=[os.path.join(data_dir, "face", "mandible.vtp")])
        if split != "none":  # Osteotomy takes triangles as vtkPolyData
            mandible = simple.ExtractSurface(Input=_split(mandible, split))
        osteotomy = simple.Osteotomy(Input=mandible, Operation=operation)
        osteotomy.Translation = translation
        fixed = [osteotomy_scenes.unmoved(simple.XMLPolyDataReader(
            FileName=[os.path.join(data_dir, "face", name + ".vtp")])) for name in ("maxilla", "cranium")]
        bone = simple.AppendGeometry(Input=[osteotomy] + fixed)

        def edit():
            osteotomy.Translation = [t * 0.5 for t in translation]
    else:
        reader = simple.XMLPolyDataReader(FileName=[os.path.join(work_dir, "sphere_bone.vtp")])
        scaled = simple.Calculator(Input=_split(reader, split) if split != "pvtu" else reader)
        scaled.ResultArrayName = "Displacement"
        scaled.Function = "Displacement"
        bone = scaled

        def edit():
            scaled.Function = "0.5*Displacement"
    fem = simple.CondensedFEMDeform(Model="LinearElastic", Input=tissue, Bone=bone)
    fem.ContactDistance = 1.0
    return fem, bone, edit
