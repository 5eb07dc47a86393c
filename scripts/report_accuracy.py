# SPDX-License-Identifier: BSD-3-Clause
"""Model and discretization error in millimetres at the skin against run time (pvpython), for the
report (scripts/report). Each choice a planner can make -- model, element order, mesh size, contact
-- is measured one axis at a time against the most accurate configuration FacePlan can run on the
scene, through the real filters (Osteotomy, Bezier Cut, Tissue Model From CT, Condensed FEM
Deform) and the demos' own scene definitions.

    pvpython scripts/report_accuracy.py <FacePlan.so> <Data dir> --out DIR [--quick] [--check]
                                        [--scenes demo,lefort1,bsso,genioplasty,ct]

Every configuration runs in its own pvpython process (`--case FILE`), so its peak resident memory
(VmHWM) is its own. Writes DIR/accuracy.csv (one row per subject), DIR/accuracy_landmarks.csv (one
row per subject and soft-tissue landmark), DIR/accuracy_convergence.csv (the large-deformation
solves' iterates), DIR/accuracy.md (the report's sections) and DIR/plots/*.png. --check exits 1
unless every series exists with its landmark errors, every configuration carries out its plan, the
CT errors shrink as the mesh refines and every study's reference is more accurate than its subjects
(see `check`).
"""
import argparse
import csv
import hashlib
import json
import math
import os
import platform
import resource
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

# Skin: boundary nodes of the tissue farther than this from every bone surface (mm). Nodes tied to
# the bone (ContactDistance 1 mm on the face) and the tissue lining the bone are left out.
SKIN_BONE_DISTANCE_MM = 3.0

# The CT plan: the lower face of the bundled head CT (slices from the nasal floor to below the chin;
# in this CT z grows towards the chin and the face looks towards -y), meshed by Tissue Model From
# CT, and a genioplasty: the chin below a horizontal cut and in front of a coronal one advanced
# 4 mm, the tissue released within 3 mm of the cuts (ReleaseDistance; tied across the cut the
# large-deformation solve cannot follow the shear on these meshes). The coronal cut lies behind the
# symphysis (the mandible below the horizontal cut spans y = 55-95 mm here), so the segment is the
# whole chin at every CellSize (a cut through its front cortex leaves a sliver of a few bone nodes
# whose tissue lies within the release distance: on some meshes no tissue moves, and the mesh study
# would compare plans, not meshes).
CT_LOWER_FACE_VOI = [0, 63, 0, 63, 53, 92]
CT_SPACING_Z = 1.5
CT_CUTS = [([92.0, 45.0, 118.0], [0.0, 0.0, 1.0]), ([92.0, 75.0, 120.0], [0.0, -1.0, 0.0])]
CT_MOVE = [0.0, -4.0, 0.0]
CT_RELEASE_DISTANCE = 3.0
CT_SMALLEST_PIECE = 20
# Mesh levels: CellSize in mm, SurfaceDistance scaled with it so that the whole mesh, skin and bone
# included, refines (with a fixed SurfaceDistance the boundary would not).
CT_LEVELS_FULL = [16.0, 12.0, 9.0, 7.0]
CT_LEVELS_QUICK = [16.0, 12.0, 9.0]
CT_SURFACE_DISTANCE_PER_CELL = 0.25

FACE_SCENES = ["demo", "lefort1", "bsso", "genioplasty"]
# Quadratic elements on the face cost about a minute of precompute and 2 GB each: two plans.
ELEMENT_FACE_SCENES = ["demo", "lefort1"]

SCENE_TEXT = {
    "demo": "main demo: chin reduction by a Bezier cut on the mandible",
    "lefort1": "Le Fort I advancement of 5 mm",
    "bsso": "BSSO advancement of 6 mm",
    "genioplasty": "genioplasty advancement of 5 mm",
    "ct": "CT model of the lower face (Data/ct/headsq.vti): genioplasty advancement of 4 mm",
}

# Contact models, as CondensedFEMDeform properties plus whether the bones' Released arrays apply.
# The osteotomy scenes' operation model is "operation": tied to the bone, free where degloved,
# sliding on the teeth and (NeoHookean only) lifting off them. The lips stay open (LipSeal 0) in
# every case: this study compares contact, model and discretization on one tissue topology, and the
# lip seal's effect is measured against the clinical ratios (docs/CLINICAL.md).
CONTACT = {
    "tied": dict(ContactModel="Tied", released=False, LiftOff=0),
    "released": dict(ContactModel="Tied", released=True, LiftOff=0),
    "released+sliding": dict(ContactModel="ByArray", released=True, LiftOff=0),
    "operation": dict(ContactModel="ByArray", released=True, LiftOff=1),
}


# ------------------------------------------------------------------------------------------------
# One configuration, in its own process.


def vm_hwm_mb():
    """Peak resident memory of this process (MB), from /proc/self/status (getrusage elsewhere)."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return float(line.split()[1]) / 1024.0
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


# The FacialLandmarks frame per scene: the Badin face looks towards -x with z up and its
# midsagittal plane at y = 0 (the filter's defaults); in the head CT the face looks towards -y, z
# grows towards the chin and the midsagittal plane is x = const (the middle of the tissue's bounds).
LANDMARK_FRAME = {
    "ct": dict(MidsagittalNormal=[1.0, 0.0, 0.0], AnteriorDirection=[0.0, -1.0, 0.0],
               SuperiorDirection=[0.0, 0.0, -1.0]),
}


# The CT crop starts below the nose and, at this CT's 3.2 mm in-plane spacing, its chin has no
# soft-tissue prominence: the filter's rules, which start from pronasale (the profile's most anterior
# point), take the upper lip for pronasale and then find fewer than three prominences below it. So on
# the CT the lips are placed by hand at the midline profile's features (the filter snaps each to the
# skin) and its "Pronasale" is left out.
LANDMARK_OVERRIDES = {
    "ct": ["LabraleSuperius 99 27.2 89.5", "Stomion 99 43.2 98.5", "LabraleInferius 99 36.8 110.5"],
}
LANDMARK_LEFT_OUT = {
    "ct": {"Pronasale": "the crop holds no nose: the profile's most anterior point is the upper lip, placed by "
                        "hand as LabraleSuperius"},
}


def landmark_positions(simple, scene, tissue, bone):
    """The soft-tissue landmarks of the undeformed tissue, by the FacialLandmarks filter (its table,
    output 0: columns Landmark, Kind, Found, Pre, Note): {"found": {name: [x, y, z]}, "missing":
    {name: why}, "error": None, or the filter's error when it gave no table, "by_hand": [names]}.
    `bone` (the bone surfaces; moved back by their Displacement) lets it place SoftTissueMenton."""
    landmarks = simple.FacialLandmarks(Input=tissue, Bone=bone)
    frame = dict(LANDMARK_FRAME.get(scene, {}))
    if scene == "ct":
        bounds = tissue.GetDataInformation().GetBounds()
        frame["MidsagittalOrigin"] = [0.5 * (bounds[0] + bounds[1]), 0.5 * (bounds[2] + bounds[3]),
                                      0.5 * (bounds[4] + bounds[5])]
    for name, value in frame.items():
        setattr(landmarks, name, value)
    landmarks.Overrides = LANDMARK_OVERRIDES.get(scene, [])
    landmarks.UpdatePipeline()
    algorithm = landmarks.GetClientSideObject()
    table = algorithm.GetOutputDataObject(0)
    found, missing = {}, {}
    if table.GetNumberOfRows() == 0:
        why = algorithm.GetLastErrorMessage() if hasattr(algorithm, "GetLastErrorMessage") else ""
        simple.Delete(landmarks)
        return dict(found=found, missing=missing, error="FacialLandmarks gave no table: " + (why or "no message"))
    column = {table.GetColumnName(c): table.GetColumn(c) for c in range(table.GetNumberOfColumns())}
    for r in range(table.GetNumberOfRows()):
        if column["Kind"].GetValue(r) != "skin":
            continue
        name = column["Landmark"].GetValue(r)
        if name in LANDMARK_LEFT_OUT.get(scene, {}):
            missing[name] = LANDMARK_LEFT_OUT[scene][name]
        elif column["Found"].GetValue(r):
            found[name] = list(column["Pre"].GetTuple3(r))
        else:
            missing[name] = column["Note"].GetValue(r)
    simple.Delete(landmarks)
    by_hand = [entry.split()[0] for entry in LANDMARK_OVERRIDES.get(scene, [])]
    return dict(found=found, missing=missing, error=None, by_hand=by_hand)


def mesh_ct(simple, data_dir, level, out_dir):
    """Meshes the CT's lower face at `level` (CellSize mm) once and writes tissue and bone files;
    returns (tissue file, bone file, meshing seconds, tets)."""
    from paraview import servermanager
    tissue_file = os.path.join(out_dir, "ct_%g_tissue.vtu" % level)
    bone_file = os.path.join(out_dir, "ct_%g_bone.vtp" % level)
    info_file = os.path.join(out_dir, "ct_%g.json" % level)
    if os.path.exists(info_file):
        with open(info_file) as f:
            info = json.load(f)
        return tissue_file, bone_file, info["seconds"], info["tets"]
    start = time.perf_counter()
    ct = simple.XMLImageDataReader(FileName=[data_dir + "/ct/headsq.vti"])
    lower_face = simple.ExtractSubset(Input=ct, VOI=CT_LOWER_FACE_VOI)
    model = simple.TissueModelFromCT(Input=lower_face)
    model.CellSize = level
    model.SurfaceDistance = CT_SURFACE_DISTANCE_PER_CELL * level
    model.UpdatePipeline()
    seconds = time.perf_counter() - start
    tissue, dropped = without_small_pieces(servermanager.Fetch(model))
    from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridWriter
    writer = vtkXMLUnstructuredGridWriter()
    writer.SetInputData(tissue)
    writer.SetFileName(tissue_file)
    writer.SetDataModeToBinary()
    writer.Write()
    simple.SaveData(bone_file, proxy=simple.OutputPort(model, 1), DataMode="Binary")
    simple.SaveData(bone_file.replace("_bone.vtp", "_skin.vtp"), proxy=simple.OutputPort(model, 2), DataMode="Binary")
    tets = tissue.GetNumberOfCells()
    with open(info_file, "w") as f:
        json.dump(dict(seconds=seconds, tets=tets, dropped_cells=dropped), f)
    return tissue_file, bone_file, seconds, tets


def without_small_pieces(grid, smallest=CT_SMALLEST_PIECE):
    """The tissue without face-connected pieces of fewer than `smallest` cells, and how many cells
    went. On the cropped CT the mesher leaves a few cells joined to the rest by an edge or a node
    only, next to the bone; tied on one or two nodes they could turn freely, and the solve rightly
    refuses such a mesh."""
    import numpy as np
    from vtkmodules.numpy_interface import dataset_adapter as dsa
    from vtkmodules.vtkFiltersCore import vtkExtractCells
    from vtkmodules.vtkCommonCore import vtkIdList
    cells = np.asarray(dsa.WrapDataObject(grid).Cells).reshape(-1, 5)[:, 1:]
    n = len(cells)
    faces = np.sort(np.concatenate([cells[:, [0, 1, 2]], cells[:, [0, 1, 3]], cells[:, [0, 2, 3]],
                                    cells[:, [1, 2, 3]]]), axis=1)
    owner = np.tile(np.arange(n), 4)
    order = np.lexsort(faces.T[::-1])
    faces, owner = faces[order], owner[order]
    shared = np.all(faces[1:] == faces[:-1], axis=1)
    parent = np.arange(n)

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for a, b in zip(owner[:-1][shared], owner[1:][shared]):
        ra, rb = find(a), find(b)
        if ra != rb:
            parent[ra] = rb
    roots = np.array([find(i) for i in range(n)])
    _, inverse, counts = np.unique(roots, return_inverse=True, return_counts=True)
    keep = np.nonzero(counts[inverse] >= smallest)[0]
    if len(keep) == n:
        return grid, 0
    ids = vtkIdList()
    for i in keep:
        ids.InsertNextId(int(i))
    extract = vtkExtractCells()
    extract.SetInputData(grid)
    extract.SetCellList(ids)
    extract.Update()
    return extract.GetOutput(), n - len(keep)


def build_scene(simple, data_dir, case, work_dir):
    """Returns (tissue proxy, the undeformed bone surface or None where the tissue's BoneDistance
    array gives the distance to the bones (the face), fem proxy, meshing seconds). Bezier Cut and
    Osteotomy output the bone moved, so they cannot tell which tissue lies on the bone."""
    scene, contact = case["scene"], CONTACT[case["contact"]]
    meshing = 0.0
    if scene == "demo":
        import faceplan_pipeline
        tissue, mandible, roi, cut, fem = faceplan_pipeline.build(data_dir)
        bone = None
    elif scene == "ct":
        tissue_file, bone_file, meshing, _ = mesh_ct(simple, data_dir, case["level"], work_dir)
        tissue = simple.XMLUnstructuredGridReader(FileName=[tissue_file])
        bone_surface = simple.XMLPolyDataReader(FileName=[bone_file])
        bone = simple.Osteotomy(Input=bone_surface, Operation="Custom")
        (bone.CutPlane1.Origin, bone.CutPlane1.Normal), (bone.CutPlane2.Origin, bone.CutPlane2.Normal) = CT_CUTS
        bone.UseSecondPlane = 1
        bone.Translation = CT_MOVE
        fem = simple.CondensedFEMDeform(Input=tissue, Bone=bone)
        fem.ContactDistance = 0.01  # the bone is made of the tissue's own facets
        fem.ReleaseDistance = CT_RELEASE_DISTANCE
        bone = bone_surface  # undeformed, for the skin's distance to the bone
    else:
        import osteotomy_scenes
        tissue, _, _, skeleton, fem = osteotomy_scenes.build(data_dir, scene)
        bone = None
        if not contact["released"]:
            # Tied everywhere: the bones without their Released flags.
            fem.Bone = [simple.ProgrammableFilter(
                Input=skeleton, OutputDataSetType="vtkPolyData",
                Script="out = self.GetOutput()\nout.ShallowCopy(self.GetInput())\n"
                       "out.GetPointData().RemoveArray('Released')\n")]
        fem.ReleaseDistance = 0.0
    if contact["ContactModel"] != "Tied" and scene in ("demo", "ct"):
        raise ValueError("scene %s has no sliding bone" % scene)
    # The study reads every node's displacement (skin ids index the volume mesh's points).
    fem.OutputMode = "Volume"
    fem.ContactModel = contact["ContactModel"]
    fem.LiftOff = contact["LiftOff"]
    fem.LipSeal = 0.0
    for name, value in case["props"].items():
        setattr(fem, name, value)
    return tissue, bone, fem, meshing


def skin_surface(tissue_data, bone_data):
    """The tissue's boundary triangles (numpy points, triangles, original point ids) and the mask of
    skin nodes among them (farther than SKIN_BONE_DISTANCE_MM from the undeformed bone
    `bone_data`, or by the tissue's BoneDistance array when it is None)."""
    import numpy as np
    from vtkmodules.numpy_interface import dataset_adapter as dsa
    from vtkmodules.vtkFiltersCore import vtkImplicitPolyDataDistance, vtkTriangleFilter
    from vtkmodules.vtkFiltersGeometry import vtkDataSetSurfaceFilter
    surface = vtkDataSetSurfaceFilter()
    surface.SetInputData(tissue_data)
    surface.PassThroughPointIdsOn()
    triangles = vtkTriangleFilter()
    triangles.SetInputConnection(surface.GetOutputPort())
    triangles.Update()
    poly = dsa.WrapDataObject(triangles.GetOutput())
    ids = np.asarray(poly.PointData["vtkOriginalPointIds"]).astype(np.int64)
    points = np.asarray(poly.Points)
    tris = np.asarray(poly.Polygons).reshape(-1, 4)[:, 1:]
    if bone_data is None:
        return points, tris, ids, np.asarray(dsa.WrapDataObject(tissue_data).PointData["BoneDistance"])[ids] > \
            SKIN_BONE_DISTANCE_MM
    from vtkmodules.vtkFiltersGeometry import vtkGeometryFilter
    bone_poly = vtkGeometryFilter()
    bone_poly.SetInputData(bone_data)
    bone_poly.Update()
    distance = vtkImplicitPolyDataDistance()
    distance.SetInput(bone_poly.GetOutput())
    d = np.array([abs(distance.EvaluateFunction(p)) for p in points])
    return points, tris, ids, d > SKIN_BONE_DISTANCE_MM


def on_ct_skin(points, work_dir, level):
    """Mask of `points` that are points of the CT model's skin surface (within 1e-3 mm), away from
    the crop's top and bottom planes."""
    import numpy as np
    from vtkmodules.vtkCommonDataModel import vtkStaticPointLocator
    from vtkmodules.vtkIOXML import vtkXMLPolyDataReader
    reader = vtkXMLPolyDataReader()
    reader.SetFileName(os.path.join(work_dir, "ct_%g_skin.vtp" % level))
    reader.Update()
    skin = reader.GetOutput()
    locator = vtkStaticPointLocator()
    locator.SetDataSet(skin)
    locator.BuildLocator()
    mask = np.zeros(len(points), bool)
    for k, p in enumerate(points):
        i = locator.FindClosestPoint(p)
        mask[k] = i >= 0 and np.linalg.norm(np.asarray(skin.GetPoint(i)) - p) < 1e-3
    z_low, z_high = (CT_LOWER_FACE_VOI[4] + 0.5) * CT_SPACING_Z, (CT_LOWER_FACE_VOI[5] - 0.5) * CT_SPACING_Z
    return mask & (points[:, 2] > z_low) & (points[:, 2] < z_high)


def run_case(case_file):
    """Runs one configuration and writes its .npz (skin geometry and displacement) and .json."""
    import numpy as np
    from paraview import servermanager, simple
    with open(case_file) as f:
        case = json.load(f)
    simple.LoadPlugin(case["plugin"])
    if case.get("mesh_only"):
        mesh_ct(simple, case["data"], case["level"], case["work"])
        return
    tissue, bone, fem, meshing = build_scene(simple, case["data"], case, case["work"])
    for proxy in fem.Bone:
        proxy.UpdatePipeline()
    tissue.UpdatePipeline()
    memory_before = vm_hwm_mb()
    start = time.perf_counter()
    fem.UpdatePipeline()
    first = time.perf_counter() - start
    algorithm = fem.GetClientSideObject()
    out = algorithm.GetOutputDataObject(0)
    fd = out.GetFieldData()
    if fd.GetArray("PrecomputeTimeMs") is None:
        raise SystemExit("Condensed FEM Deform produced no result (its error is above)")
    precompute_ms = fd.GetArray("PrecomputeTimeMs").GetValue(0)
    first_solve_ms = fd.GetArray("SolveTimeMs").GetValue(0)
    history = fd.GetArray("ConvergenceHistory")
    convergence = [list(history.GetTuple2(i)) for i in range(history.GetNumberOfTuples())] if history else []
    solver = fd.GetAbstractArray("LargeDeformationSolver")
    precomputed = solver is not None and solver.GetValue(0) == "Precomputed"
    # Time per update: the filter re-executed with its inputs unchanged, as after an edit of the
    # plan that keeps tissue, ROI and contact (a linear model then reuses its precompute). Not for
    # the precomputed large-deformation solve: re-executed, it starts from its own converged state
    # and has nothing left to do, so its time per update is its first solve's, from rest after the
    # precompute (SolveTimeMs), and that solve's result is the one compared.
    updates = []
    for _ in range(0 if precomputed else case["repeats"]):
        algorithm.Modified()
        t0 = time.perf_counter()
        algorithm.Update()
        updates.append(time.perf_counter() - t0)
    out = algorithm.GetOutputDataObject(0)
    fd = out.GetFieldData()

    def number(name):
        a = fd.GetArray(name)
        return None if a is None else a.GetValue(0)

    def text(name):
        a = fd.GetAbstractArray(name)
        return None if a is None else a.GetValue(0)

    from vtkmodules.numpy_interface import dataset_adapter as dsa
    displacement = np.asarray(dsa.WrapDataObject(out).PointData["Displacement"])
    tissue_data = servermanager.Fetch(tissue)
    bone_data = servermanager.Fetch(bone) if bone is not None else None
    points, tris, ids, skin = skin_surface(tissue_data, bone_data)
    if case["scene"] == "ct":
        # The model's own skin surface (Tissue Model From CT's third output), not the crop's top and
        # bottom planes (cut faces of the image) nor the tissue lining cavities in the bone.
        skin &= on_ct_skin(points, case["work"], case["level"])
    landmarks = landmark_positions(simple, case["scene"], tissue, bone if bone is not None else fem.Bone[0])
    np.savez_compressed(case["result"] + ".npz", points=points, tris=tris, skin=skin,
                        displacement=displacement[ids])
    result = dict(
        first_update_s=first, update_ms=first_solve_ms if precomputed else 1000.0 * statistics.median(updates),
        updates_s=updates, first_solve_ms=first_solve_ms, convergence=convergence,
        quasi_newton_iterations=number("QuasiNewtonIterations"), converged=number("Converged"),
        solver_note=text("SolverNote"), iteration_limit=case["props"].get("QuasiNewtonIterationLimit"),
        precompute_ms=precompute_ms, meshing_s=meshing, peak_mb=vm_hwm_mb(), inputs_peak_mb=memory_before,
        tets=tissue_data.GetNumberOfCells(), points=tissue_data.GetNumberOfPoints(),
        skin_nodes=int(skin.sum()), model=text("Model"), method=text("Method"),
        element_order=text("ElementOrder"), solver=text("LargeDeformationSolver"),
        relative_residual=number("RelativeResidual"), newton_iterations=number("NewtonIterations"),
        lifted_nodes=number("LiftedNodes"), largest_strain=number("LargestStrain"),
        largest_displacement_mm=float(np.max(np.linalg.norm(displacement, axis=1))),
        landmarks=landmarks)
    with open(case["result"] + ".json", "w") as f:
        json.dump(result, f, indent=1)


# ------------------------------------------------------------------------------------------------
# The studies: which configurations, against which reference.


def config(scene, contact="tied", level=None, **props):
    """A configuration: scene, contact (CONTACT key), CT mesh level and filter properties."""
    props.setdefault("Model", "LinearElastic")
    props.setdefault("ElementOrder", "Linear")
    return dict(scene=scene, contact=contact, level=level, props=props)


def key_of(cfg):
    return hashlib.sha1(json.dumps(cfg, sort_keys=True).encode()).hexdigest()[:12]


# The precomputed large-deformation solve stopped after k quasi-Newton iterations (the filter's
# QuasiNewtonIterationLimit): what an update that stops early gives, against its time. From rest
# the main demo's cut and the CT plan converge in 20-35 iterations; the osteotomy plans, whose
# lift-off changes restart the L-BFGS history, in 80-90, so their series goes on to 64.
ITERATION_LIMITS = [1, 2, 4, 8, 16]
ITERATION_LIMITS_LIFT_OFF = ITERATION_LIMITS + [32, 64]


def iteration_label(k):
    return "large deformation, precomputed, %d iteration%s" % (k, "" if k == 1 else "s")


def large_deformation_series(has_solver_choice, reference_props, contact):
    """The model axis's large-deformation subjects beyond the reference: the precomputed solve to
    convergence and stopped after k iterations. One entry per subject."""
    series = []
    if has_solver_choice:
        precomputed = dict(reference_props, LargeDeformationSolver="Precomputed")
        series.append(("large deformation, precomputed factor", precomputed))
        limits = ITERATION_LIMITS_LIFT_OFF if contact["LiftOff"] else ITERATION_LIMITS
        series += [(iteration_label(k), dict(precomputed, QuasiNewtonIterationLimit=k)) for k in limits]
    return series


def studies(scenes, quick, has_solver_choice, ct_levels):
    """[{scene, axis, reference (label, cfg), subjects [(label, cfg)], judge}] -- `judge`, where
    set, is a configuration more accurate than the reference, used to check that the reference
    is more accurate than its subjects."""
    out = []
    newton = dict(LargeDeformationSolver="Newton") if has_solver_choice else {}
    for scene in scenes:
        if scene == "ct":
            continue
        operation = "tied" if scene == "demo" else "operation"
        linear_contact = "tied" if scene == "demo" else "released+sliding"  # LiftOff needs NeoHookean
        reference = ("large deformation (NeoHookean), %s contact" % operation,
                     config(scene, operation, Model="NeoHookean", **newton))
        subjects = [("linear model", config(scene, linear_contact))]
        subjects += [(label, config(scene, operation, **props))
                     for label, props in large_deformation_series(has_solver_choice, reference[1]["props"],
                                                                         CONTACT[reference[1]["contact"]])]
        out.append(dict(scene=scene, axis="model", reference=reference, subjects=subjects))
        if scene != "demo":
            # With every tissue node tied to the moved segment the large-deformation solve finds no
            # path to equilibrium on these plans (the tissue at the cut shears past what its load
            # steps can follow), so "all tied" is measured with the linear model, against the
            # linear model's closest to the operation (released and sliding).
            out.append(dict(scene=scene, axis="contact", reference=reference, subjects=[
                ("released", config(scene, "released", Model="NeoHookean", **newton)),
                ("released + sliding, no lift-off", config(scene, "released+sliding", Model="NeoHookean",
                                                           **newton))]))
            out.append(dict(scene=scene, axis="contact (linear model)",
                            reference=("released + sliding (linear model)", config(scene, "released+sliding")),
                            subjects=[("tied (linear model)", config(scene, "tied")),
                                      ("released (linear model)", config(scene, "released"))]))
        # Quadratic elements: linear model only, and Tied or Released contact (sliding needs linear
        # elements), so this axis runs with the released contact and the linear model.
        element_contact = "tied" if scene == "demo" else "released"
        if not quick and scene in ELEMENT_FACE_SCENES:
            out.append(dict(scene=scene, axis="element",
                            reference=("quadratic elements (linear model)",
                                       config(scene, element_contact, ElementOrder="Quadratic")),
                            subjects=[("linear elements", config(scene, element_contact))]))
    if "ct" in scenes:
        levels = ct_levels
        finest = levels[-1]
        reference = ("large deformation, CellSize %g" % finest,
                     config("ct", level=finest, Model="NeoHookean", **newton))
        out.append(dict(scene="ct", axis="mesh", reference=reference,
                        subjects=[("CellSize %g" % level, config("ct", level=level, Model="NeoHookean", **newton))
                                  for level in levels[:-1]]))
        out.append(dict(scene="ct", axis="model", reference=reference,
                        subjects=[("linear model", config("ct", level=finest))]
                        + [(label, config("ct", level=finest, **props)) for label, props in
                           large_deformation_series(has_solver_choice, reference[1]["props"],
                                                                         CONTACT[reference[1]["contact"]])]))
        # Element order on the coarsest mesh; judged by the quadratic solve one level finer.
        coarse, finer = levels[0], levels[1]
        out.append(dict(scene="ct", axis="element",
                        reference=("quadratic elements, CellSize %g" % coarse,
                                   config("ct", level=coarse, ElementOrder="Quadratic")),
                        subjects=[("linear elements, CellSize %g" % coarse, config("ct", level=coarse))],
                        judge=("quadratic elements, CellSize %g" % finer,
                               config("ct", level=finer, ElementOrder="Quadratic"))))
    return out


# ------------------------------------------------------------------------------------------------
# Comparing results.


def load(result_base):
    import numpy as np
    with open(result_base + ".json") as f:
        info = json.load(f)
    data = dict(np.load(result_base + ".npz"))
    return info, data


def surface_values(data, query):
    """The displacement of `data` (a configuration's boundary: points, tris, displacement) at the
    closest point of its boundary triangles to each of `query` (n x 3), linearly interpolated in the
    triangle; returns (values n x 3, distances n)."""
    import numpy as np
    from vtkmodules.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray
    from vtkmodules.vtkCommonCore import mutable, vtkPoints
    from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkCellLocator, vtkGenericCell, vtkPolyData
    points = data["points"].astype(np.float64)
    tris = data["tris"].astype(np.int64)
    poly = vtkPolyData()
    pts = vtkPoints()
    pts.SetData(numpy_to_vtk(points, deep=1))
    poly.SetPoints(pts)
    cells = vtkCellArray()
    conn = np.hstack([np.full((len(tris), 1), 3, np.int64), tris]).ravel()
    cells.SetCells(len(tris), numpy_to_vtkIdTypeArray(conn, deep=1))
    poly.SetPolys(cells)
    locator = vtkCellLocator()
    locator.SetDataSet(poly)
    locator.BuildLocator()
    closest, cell = [0.0, 0.0, 0.0], vtkGenericCell()
    cell_id, sub_id, dist2 = mutable(0), mutable(0), mutable(0.0)
    query = np.asarray(query, np.float64).reshape(-1, 3)
    found, ids, distances = np.empty_like(query), np.empty(len(query), np.int64), np.empty(len(query))
    for k, p in enumerate(query):
        locator.FindClosestPoint(p, closest, cell, cell_id, sub_id, dist2)
        found[k], ids[k], distances[k] = closest, int(cell_id), math.sqrt(float(dist2))
    # Barycentric weights of each closest point in its triangle.
    corners = tris[ids]
    a, b, c = points[corners[:, 0]], points[corners[:, 1]], points[corners[:, 2]]
    v0, v1, v2 = b - a, c - a, found - a
    d00, d01, d11 = (v0 * v0).sum(1), (v0 * v1).sum(1), (v1 * v1).sum(1)
    d20, d21 = (v2 * v0).sum(1), (v2 * v1).sum(1)
    den = d00 * d11 - d01 * d01
    safe = np.where(den > 0, den, 1.0)
    wb = np.where(den > 0, (d11 * d20 - d01 * d21) / safe, 0.0)
    wc = np.where(den > 0, (d00 * d21 - d01 * d20) / safe, 0.0)
    u = data["displacement"]
    values = (1.0 - wb - wc)[:, None] * u[corners[:, 0]] + wb[:, None] * u[corners[:, 1]] + \
        wc[:, None] * u[corners[:, 2]]
    return values, distances


def same_mesh(subject, reference):
    import numpy as np
    return subject["points"].shape == reference["points"].shape and np.allclose(subject["points"],
                                                                                reference["points"])


def skin_error(subject, reference):
    """|u_subject - u_reference| (mm) at the reference's skin nodes: the same physical points for
    every subject. On another mesh the subject's displacement is interpolated at the closest point
    of its boundary surface (all of it: a mask of its own skin would lose a band one element wide
    where skin meets bone or the crop planes, and points there would take the displacement of
    triangles up to an element away)."""
    import numpy as np
    ref_points = reference["points"][reference["skin"]]
    ref_u = reference["displacement"][reference["skin"]]
    if same_mesh(subject, reference):
        return np.linalg.norm(subject["displacement"][reference["skin"]] - ref_u, axis=1)
    values, _ = surface_values(subject, ref_points)
    return np.linalg.norm(values - ref_u, axis=1)


def landmark_errors(subject, reference, info_ref):
    """{landmark: error (mm)} at the soft-tissue landmarks found on the reference's undeformed skin:
    both displacements interpolated at the landmark (each on its own boundary surface), so every
    subject is compared at the same physical points. Empty when the reference found none."""
    import numpy as np
    found = (info_ref.get("landmarks") or {}).get("found") or {}
    if not found:
        return {}
    names = sorted(found)
    where = np.array([found[n] for n in names], np.float64)
    ref_u, _ = surface_values(reference, where)
    sub_u = ref_u if subject is reference else surface_values(subject, where)[0]
    return {n: float(e) for n, e in zip(names, np.linalg.norm(sub_u - ref_u, axis=1))}


def percentile95(values):
    import numpy as np
    return float(np.percentile(values, 95))


# ------------------------------------------------------------------------------------------------
# The driver.


def run_parallel(jobs, limit, timeout):
    """Runs [(label, argv)] with at most `limit` at a time; returns {label: (ok, output, seconds)}."""
    pending, running, done = list(jobs), {}, {}
    while pending or running:
        while pending and len(running) < limit:
            label, argv = pending.pop(0)
            log = open(os.path.join(os.path.dirname(argv[-1]), "%s.log" % os.path.basename(argv[-1])), "w+")
            running[label] = (subprocess.Popen(argv, stdout=log, stderr=subprocess.STDOUT, text=True), log,
                              time.perf_counter())
        time.sleep(0.2)
        for label, (proc, log, start) in list(running.items()):
            elapsed = time.perf_counter() - start
            if proc.poll() is None and elapsed < timeout:
                continue
            timed_out = proc.poll() is None
            if timed_out:
                proc.kill()
                proc.wait()
            log.seek(0)
            output = log.read()
            log.close()
            done[label] = (proc.returncode == 0 and not timed_out, output + (
                "\nno result within %d s" % timeout if timed_out else ""), elapsed)
            del running[label]
            yield label, done[label]


def run_configs(configs, args, work_dir, repeats_for):
    """Runs each configuration (once; results cached in work_dir) in its own pvpython process,
    --jobs at a time (the CT meshes first, one process per level). Returns {key: (info, data)}, or
    {key: (failure text, None)} for one that failed or ran past --case-timeout."""
    import re
    levels = sorted({c["level"] for c in configs if c["scene"] == "ct"}, reverse=True)
    mesh_jobs = []
    for level in levels:
        if not os.path.exists(os.path.join(work_dir, "ct_%g.json" % level)):
            case = os.path.join(work_dir, "mesh_%g.case.json" % level)
            with open(case, "w") as f:
                json.dump(dict(mesh_only=True, level=level, data=os.path.abspath(args.data),
                               plugin=os.path.abspath(args.plugin), work=work_dir), f)
            mesh_jobs.append((level, [choose_python(), os.path.abspath(__file__), "--case", case]))
    for level, (ok, output, seconds) in run_parallel(mesh_jobs, args.jobs, args.case_timeout):
        print("  ct mesh at CellSize %g: %s (%.1f s)" % (level, "done" if ok else "FAILED", seconds), flush=True)
        if not ok:
            sys.stderr.write(output[-3000:])
    jobs = []
    for cfg in configs:
        base = os.path.join(work_dir, key_of(cfg))
        if not os.path.exists(base + ".json") and not os.path.exists(base + ".failed"):
            case = dict(cfg, plugin=os.path.abspath(args.plugin), data=os.path.abspath(args.data),
                        work=work_dir, result=base, repeats=repeats_for(cfg))
            with open(base + ".case.json", "w") as f:
                json.dump(case, f)
            jobs.append((key_of(cfg), [choose_python(), os.path.abspath(__file__), "--case", base + ".case.json"]))
    by_key = {key_of(c): c for c in configs}
    for key, (ok, output, seconds) in run_parallel(jobs, args.jobs, args.case_timeout):
        base = os.path.join(work_dir, key)
        ok = ok and os.path.exists(base + ".json")
        why = None
        if not ok:
            why = "; ".join(re.findall(r"ERR\|[^:]*\): (.*?)(?:\x1b|$)", output, re.M)) or output.strip()[-300:]
            with open(base + ".failed", "w") as f:
                f.write(why)
        cfg = by_key[key]
        print("  %-11s %-17s level %-5s %-60s %.1f s%s" % (
            cfg["scene"], cfg["contact"], cfg["level"], json.dumps(cfg["props"], sort_keys=True), seconds,
            "" if ok else "  FAILED: " + why), flush=True)
    results = {}
    for cfg in configs:
        base = os.path.join(work_dir, key_of(cfg))
        if os.path.exists(base + ".failed"):
            with open(base + ".failed") as f:
                results[key_of(cfg)] = (f.read(), None)
        else:
            results[key_of(cfg)] = load(base)
    return results


def choose_python():
    """The cases need ParaView's modules and the plugin: they run under pvpython ($PVPYTHON when
    set, as CTest does)."""
    for candidate in (os.environ.get("PVPYTHON"), "pvpython"):
        if candidate:
            return candidate
    return "pvpython"


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("plugin", nargs="?")
    parser.add_argument("data", nargs="?")
    parser.add_argument("--out", default="out/report")
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--check", action="store_true")
    parser.add_argument("--no-plots", action="store_true")
    parser.add_argument("--scenes", default="")
    parser.add_argument("--case")
    parser.add_argument("--case-timeout", type=int, default=900,
                        help="seconds one configuration may run (default 900)")
    parser.add_argument("--ct-levels", default="",
                        help="CT CellSizes, coarse to fine (default %s; --quick %s)" % (
                            ",".join("%g" % h for h in CT_LEVELS_FULL), ",".join("%g" % h for h in CT_LEVELS_QUICK)))
    parser.add_argument("--reuse", action="store_true",
                        help="keep the results of configurations already run in OUT/accuracy_runs (by default "
                             "they are removed and every configuration runs afresh)")
    parser.add_argument("--jobs", type=int, default=1,
                        help="configurations run at a time, each in its own process (default 1)")
    args = parser.parse_args()
    if args.case:
        run_case(args.case)
        return 0
    if not args.plugin or not args.data:
        parser.error("plugin and data are required")
    from paraview import simple
    simple.LoadPlugin(args.plugin)
    has_ct = "TissueModelFromCT" in dir(simple)
    prototype = simple.servermanager.ProxyManager().SMProxyManager.GetPrototypeProxy("filters", "CondensedFEMDeform")
    has_solver_choice = prototype.GetProperty("LargeDeformationSolver") is not None
    scenes = args.scenes.split(",") if args.scenes else (["demo", "ct"] if args.quick else FACE_SCENES + ["ct"])
    if "ct" in scenes and not has_ct:
        print("TissueModelFromCT is absent (FacePlan built without CGAL): the CT scene is left out")
        scenes.remove("ct")
    os.makedirs(args.out, exist_ok=True)
    work_dir = os.path.abspath(os.path.join(args.out, "accuracy_runs"))
    if not args.reuse and os.path.isdir(work_dir):
        import shutil
        shutil.rmtree(work_dir)
    os.makedirs(work_dir, exist_ok=True)
    ct_levels = [float(h) for h in args.ct_levels.split(",")] if args.ct_levels else (
        CT_LEVELS_QUICK if args.quick else CT_LEVELS_FULL)
    plan = studies(scenes, args.quick, has_solver_choice, ct_levels)
    configs, seen = [], set()
    for study in plan:
        for _, cfg in [study["reference"]] + study["subjects"] + ([study["judge"]] if study.get("judge") else []):
            if key_of(cfg) not in seen:
                seen.add(key_of(cfg))
                configs.append(cfg)

    def repeats_for(cfg):
        slow = cfg["props"]["Model"] != "LinearElastic" or cfg["props"]["ElementOrder"] != "Linear"
        return 1 if slow else (3 if args.quick else 5)

    # The CT levels are meshed first, coarse to fine, so a mesher failure shows before the solves.
    start = time.perf_counter()
    print("accuracy study: %d configurations on %s" % (len(configs), ", ".join(scenes)), flush=True)
    results = run_configs(sorted(configs, key=lambda c: (c["scene"] != "ct", -(c["level"] or 0))), args, work_dir,
                          repeats_for)
    # The run's span: from the first configuration's start to the last one's result (with --reuse,
    # those of the run that produced them).
    import glob
    starts = [os.path.getmtime(f) for f in glob.glob(os.path.join(work_dir, "*.case.json"))]
    ends = [os.path.getmtime(f) for f in glob.glob(os.path.join(work_dir, "*.json")) + glob.glob(
        os.path.join(work_dir, "*.failed")) if not f.endswith(".case.json")]
    span = (max(ends) - min(starts)) if starts and ends else time.perf_counter() - start
    rows = evaluate(plan, results)
    write_csv(os.path.join(args.out, "accuracy.csv"), rows)
    write_landmark_csv(os.path.join(args.out, "accuracy_landmarks.csv"), rows)
    write_convergence_csv(os.path.join(args.out, "accuracy_convergence.csv"), rows)
    failures = check(plan, rows)
    write_markdown(os.path.join(args.out, "accuracy.md"), plan, rows, results, failures, args,
                   span, has_solver_choice, ct_levels)
    if not args.no_plots:
        plot(os.path.join(args.out, "plots"), rows)
    for failure in failures:
        print("CHECK FAILED:", failure)
    if args.check:
        if "ct" not in scenes:
            print("accuracy check skipped: no CT scene (FacePlan built without CGAL)")
            return 77
        inverted = inverted_studies(plan)
        caught = check(inverted, evaluate(inverted, results))
        print("the check rejects the inverted studies (coarsest mesh or linear elements as the "
              "reference): %s" % ("yes, %d failures" % len(caught) if len(caught) >= len(inverted) else "NO"))
        for failure in caught:
            print("  expected failure:", failure)
        ok = not failures and len({f.split(":")[0] for f in caught}) >= len(inverted)
        print("accuracy check: %s" % ("passed" if ok else "FAILED"))
        return 0 if ok else 1
    return 0


def inverted_studies(plan):
    """The CT's mesh and element studies with reference and subjects swapped: a coarser mesh or
    linear elements as the reference. `check` must reject both, or it could not catch a study
    whose reference is less accurate than its subject."""
    inverted = []
    for study in plan:
        if study["scene"] != "ct" or study["axis"] not in ("mesh", "element"):
            continue
        if study["axis"] == "mesh":
            coarsest = study["subjects"][0]
            inverted.append(dict(study, axis="mesh", reference=coarsest,
                                 subjects=study["subjects"][1:] + [study["reference"]]))
        else:
            inverted.append(dict(study, axis="element", reference=study["subjects"][0],
                                 subjects=[study["reference"]]))
    return inverted


def evaluate(plan, results):
    """One row per (study, subject) and one per reference (error 0), with errors and costs. A
    configuration that failed gives a row with its reason in `failed` and no figures; a study whose
    reference failed gives only such rows."""
    rows = []
    for study in plan:
        ref_label, ref_cfg = study["reference"]
        ref_info, ref_data = results[key_of(ref_cfg)]
        entries = [(label, cfg, False) for label, cfg in study["subjects"]] + [(ref_label, ref_cfg, True)]
        for label, cfg, is_reference in entries:
            info, data = results[key_of(cfg)]
            row = dict(scene=study["scene"], axis=study["axis"], choice=label, is_reference=int(is_reference),
                       reference=ref_label, level=cfg["level"] or "")
            if data is None or ref_data is None:
                row["failed"] = info if data is None else "the reference failed: " + ref_info
                rows.append(row)
                continue
            errors = skin_error(data, ref_data)
            at_landmarks = landmark_errors(data, ref_data, ref_info)
            row.update(
                tets=info["tets"], max_mm=float(errors.max()), p95_mm=percentile95(errors),
                landmark_max_mm=max(at_landmarks.values()) if at_landmarks else None, landmarks=at_landmarks,
                landmarks_missing=(ref_info.get("landmarks") or {}).get("missing") or {},
                landmarks_by_hand=(ref_info.get("landmarks") or {}).get("by_hand") or [],
                landmarks_error=(ref_info.get("landmarks") or {}).get("error"),
                update_ms=info["update_ms"], first_update_s=info["first_update_s"],
                precompute_ms=info["precompute_ms"], meshing_s=info["meshing_s"], peak_mb=info["peak_mb"],
                model=info["model"], solver=info["solver"], method=info["method"], element_order=info["element_order"],
                newton_iterations=info["newton_iterations"], lifted_nodes=info["lifted_nodes"],
                largest_strain=info["largest_strain"], largest_displacement_mm=info["largest_displacement_mm"],
                skin_nodes=int(ref_data["skin"].sum()), iteration_limit=info.get("iteration_limit"),
                quasi_newton_iterations=info.get("quasi_newton_iterations"),
                relative_residual=info.get("relative_residual"), converged=info.get("converged"),
                solver_note=info.get("solver_note"), convergence=info.get("convergence") or [])
            rows.append(row)
        if study.get("judge"):
            judge_info, judge_data = results[key_of(study["judge"][1])]
            for label, cfg in [study["reference"]] + study["subjects"]:
                info, data = results[key_of(cfg)]
                row = dict(scene=study["scene"], axis=study["axis"] + " (judge)", choice=label,
                           is_reference=int(label == ref_label), reference=study["judge"][0],
                           level=cfg["level"] or "")
                if data is None or judge_data is None:
                    row["failed"] = info if data is None else judge_info
                else:
                    errors = skin_error(data, judge_data)
                    row.update(tets=info["tets"], max_mm=float(errors.max()), p95_mm=percentile95(errors))
                rows.append(row)
    return rows


CSV_FIELDS = ["scene", "axis", "choice", "is_reference", "reference", "level", "tets", "max_mm", "p95_mm",
              "landmark_max_mm", "update_ms", "first_update_s", "precompute_ms", "meshing_s", "peak_mb", "model",
              "solver", "method", "element_order", "newton_iterations", "iteration_limit", "quasi_newton_iterations",
              "relative_residual", "converged", "lifted_nodes", "largest_strain", "largest_displacement_mm",
              "skin_nodes", "failed"]


def write_convergence_csv(path, rows):
    """The large-deformation solves' iterates (the field data ConvergenceHistory): per scene and
    solver, the first solve's time (ms since it started) and relative residual at each iterate."""
    with open(path, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["scene", "choice", "solver", "iterate", "ms", "relative_residual"])
        seen = set()
        for r in rows:
            if r.get("failed") or r["axis"] != "model" or r.get("model") != "NeoHookean" or r.get("iteration_limit"):
                continue
            if (r["scene"], r["choice"]) in seen:
                continue
            seen.add((r["scene"], r["choice"]))
            for i, (ms, residual) in enumerate(r["convergence"], 1):
                writer.writerow([r["scene"], r["choice"], r["solver"], i, "%.6g" % ms, "%.6g" % residual])


def write_csv(path, rows):
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=CSV_FIELDS)
        writer.writeheader()
        for row in rows:
            writer.writerow({k: ("" if row.get(k) is None else row.get(k, "")) for k in CSV_FIELDS})


LANDMARK_CSV_FIELDS = ["scene", "axis", "choice", "is_reference", "reference", "level", "landmark", "found",
                       "error_mm", "note"]


def write_landmark_csv(path, rows):
    """One row per (subject, soft-tissue landmark): its error in mm, or why the landmark was not
    found on the study's reference (found 0, no error)."""
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=LANDMARK_CSV_FIELDS)
        writer.writeheader()
        for row in rows:
            if row.get("failed") or "(judge)" in row["axis"]:
                continue
            base = {k: row[k] for k in ("scene", "axis", "choice", "is_reference", "reference", "level")}
            if row.get("landmarks_error"):
                writer.writerow(dict(base, landmark="", found=0, note=row["landmarks_error"]))
            for name in LANDMARK_NAMES:
                if name in row.get("landmarks", {}):
                    writer.writerow(dict(base, landmark=name, found=1, error_mm="%.6g" % row["landmarks"][name]))
                elif name in row.get("landmarks_missing", {}):
                    writer.writerow(dict(base, landmark=name, found=0, note=row["landmarks_missing"][name]))


# The soft-tissue landmarks in FacialLandmarks' order (ARCHITECTURE.md, "Names shared across filters").
LANDMARK_NAMES = ["Pronasale", "Subnasale", "AlarBaseRight", "AlarBaseLeft", "LabraleSuperius", "Stomion",
                  "LabraleInferius", "CheilionRight", "CheilionLeft", "SoftTissueB", "SoftTissuePogonion",
                  "SoftTissueMenton"]


def mesh_series(rows, scene="ct"):
    """[(level, max_mm, p95_mm, row)] of the mesh axis, coarse to fine, the reference last."""
    series = [r for r in rows if r["scene"] == scene and r["axis"] == "mesh"]
    return sorted(series, key=lambda r: -float(r["level"]))


# The statistic the checks use: the 95th percentile over the skin. The largest error sits at a few
# skin nodes next to the cut, where which nodes are tied or released changes with the mesh; it is
# reported, but does not fall steadily with CellSize on these meshes.
CHECK_METRIC = "p95_mm"


def reference_error_estimate(series, metric=CHECK_METRIC):
    """The finest mesh's own error (mm at the skin), by Richardson extrapolation from the errors of
    the two next-finest meshes against it. With u(h) = u* + C h^p, a coarser mesh's error against
    the finest is e(h) = C (h^p - h_n^p): the two give p (bisection; e1/e2 grows with p) and C, and
    the finest mesh's own error is C h_n^p. Returns (error, p), or (None, None) when no p > 0 fits
    (the errors do not shrink as fast as any convergent series would)."""
    if len(series) < 3:
        return None, None
    h1, e1 = float(series[-3]["level"]), series[-3][metric]
    h2, e2 = float(series[-2]["level"]), series[-2][metric]
    hn = float(series[-1]["level"])
    if not (e1 > 0 and e2 > 0 and h1 > h2 > hn):
        return None, None

    def ratio(p):
        return (h1 ** p - hn ** p) / (h2 ** p - hn ** p)

    target = e1 / e2
    if target <= math.log(h1 / hn) / math.log(h2 / hn):  # the ratio's limit as p -> 0
        return None, None
    low, high = 1e-6, 1.0
    while ratio(high) < target and high < 64:
        high *= 2
    if ratio(high) < target:
        return None, None
    for _ in range(100):
        mid = 0.5 * (low + high)
        low, high = (mid, high) if ratio(mid) < target else (low, mid)
    p = 0.5 * (low + high)
    return e2 * hn ** p / (h2 ** p - hn ** p), p


def check(plan, rows):
    """The conditions the report's conclusions rest on; returns the failures (empty = all hold)."""
    failures = []
    for study in plan:
        everything = [r for r in rows if r["scene"] == study["scene"] and r["axis"] == study["axis"]]
        subjects = [r for r in everything if not r["is_reference"]]
        if len(subjects) != len(study["subjects"]) or not any(r["is_reference"] for r in everything):
            failures.append("%s %s: a series is missing" % (study["scene"], study["axis"]))
            continue
        for r in everything:
            if r.get("failed"):
                # A contact simplification the large-deformation solve cannot follow is a finding
                # (reported), not a broken study; anything else is.
                if not study["axis"].startswith("contact") or r["is_reference"]:
                    failures.append("%s %s %s: no result (%s)" % (r["scene"], r["axis"], r["choice"], r["failed"]))
                continue
            for name in ("max_mm", "p95_mm", "update_ms", "peak_mb"):
                if r.get(name) is None or not math.isfinite(r[name]) or r[name] < 0:
                    failures.append("%s %s %s: %s is %r" % (r["scene"], r["axis"], r["choice"], name, r[name]))
            if r.get("iteration_limit") and r.get("converged") is None:
                failures.append("%s %s %s: stopped after %d iterations without the field data Converged" % (
                    r["scene"], r["axis"], r["choice"], r["iteration_limit"]))
            if r.get("landmark_max_mm") is None:
                failures.append("%s %s %s: no error at the soft-tissue landmarks (%s)" % (
                    r["scene"], r["axis"], r["choice"], r.get("landmarks_error") or "none found on the reference"))
            elif not all(math.isfinite(e) and e >= 0 for e in r["landmarks"].values()):
                failures.append("%s %s %s: a landmark error is not finite" % (r["scene"], r["axis"], r["choice"]))
        mine = [r for r in everything if not r.get("failed")]
        if len(mine) != len(everything) and not study["axis"].startswith("contact"):
            continue  # already a failure above; the figures below would be incomplete
        # Every configuration must carry out the plan: a mesh on which the moved segment carries no
        # tissue (a thin segment whose nodes all lie within the release distance) would compare
        # another plan, not another mesh.
        reference_move = max((r["largest_displacement_mm"] for r in mine if r["is_reference"]), default=0.0)
        for r in mine:
            if not r["largest_displacement_mm"] >= 0.5 * reference_move:
                failures.append("%s %s %s: the plan moves the tissue by %.2f mm at most, under half the "
                                "reference's %.2f mm" % (r["scene"], r["axis"], r["choice"],
                                                        r["largest_displacement_mm"], reference_move))
        if study["axis"] == "mesh":
            failures += check_mesh_study(mine)
        if study.get("judge"):
            judged = [r for r in rows if r["scene"] == study["scene"] and r["axis"] == study["axis"] + " (judge)"
                      and not r.get("failed")]
            failures += check_judged_study(study, judged)
        if study["axis"] in ("model", "contact"):
            ref = [r for r in mine if r["is_reference"]][0]
            if ref["model"] != "NeoHookean":
                failures.append("%s %s: the reference ran %s, not NeoHookean" % (study["scene"], study["axis"],
                                                                                  ref["model"]))
    return failures


def check_mesh_study(mine):
    """Errors shrink as the mesh refines, and the reference's own refinement error is below every
    subject's error."""
    failures = []
    series = sorted(mine, key=lambda r: -float(r["level"]))
    subjects = [r for r in series if not r["is_reference"]]
    if [r["is_reference"] for r in series][-1] != 1:
        failures.append("ct mesh: the reference is not the finest mesh")
    for coarse, fine in zip(subjects, subjects[1:]):
        if not fine[CHECK_METRIC] < coarse[CHECK_METRIC]:
            failures.append("ct mesh: the skin error (%s) does not shrink from CellSize %s (%.3f mm) to %s "
                            "(%.3f mm)" % (CHECK_METRIC, coarse["level"], coarse[CHECK_METRIC], fine["level"],
                                           fine[CHECK_METRIC]))
    estimate, _ = reference_error_estimate(series)
    smallest = min((r[CHECK_METRIC] for r in subjects), default=None)
    if smallest is None or len(subjects) < 2:
        failures.append("ct mesh: fewer than two coarser meshes, the reference's own error cannot be estimated")
    elif estimate is None:
        # No convergent series fits the errors: the finest mesh is not shown to be converged. This is
        # reported with the figures (write_markdown), not counted as a failure: the errors do shrink
        # towards it, which the loop above requires.
        pass
    elif not estimate < smallest:
        failures.append("ct mesh: the reference's estimated own error %.3f mm is not below the subjects' "
                        "smallest error %.3f mm" % (estimate, smallest))
    return failures


def check_judged_study(study, judged):
    """Against a more accurate judge, the reference must be closer than every subject."""
    ref = [r for r in judged if r["is_reference"]]
    subjects = [r for r in judged if not r["is_reference"]]
    if not ref or not subjects:
        return ["%s %s: the judged series is missing" % (study["scene"], study["axis"])]
    failures = []
    for r in subjects:
        if not ref[0][CHECK_METRIC] < r[CHECK_METRIC]:
            failures.append("%s %s: against %s the reference (%s, %.3f mm) is not more accurate than %s "
                            "(%.3f mm)" % (study["scene"], study["axis"], ref[0]["reference"], ref[0]["choice"],
                                           ref[0][CHECK_METRIC], r["choice"], r[CHECK_METRIC]))
    return failures


# ------------------------------------------------------------------------------------------------
# Report text and plots.


def fmt(value, digits=3):
    if value is None or value == "":
        return "–"
    if isinstance(value, float):
        if value == 0:
            return "0"
        if abs(value) >= 100:
            return "%.0f" % value
        return ("%%.%dg" % digits) % value
    return str(value)


def cpu_model():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def git_commit():
    try:
        return subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                              cwd=HERE).stdout.strip() or "unknown"
    except OSError:
        return "unknown"


def cost_ms(row):
    """What a choice costs the surgeon per update (ms)."""
    return row["update_ms"]


def landmark_coverage(main_rows):
    """Which soft-tissue landmarks each scene's reference gives, and why the others are missing."""
    parts = []
    for scene in dict.fromkeys(r["scene"] for r in main_rows):
        mine = [r for r in main_rows if r["scene"] == scene]
        ref = ([r for r in mine if r["axis"] == "model" and r["is_reference"]] or
               [r for r in mine if r["is_reference"]])[0]
        if ref.get("landmarks_error"):
            parts.append("**%s** none: %s" % (scene, ref["landmarks_error"]))
            continue
        found, missing = sorted(ref.get("landmarks", {}), key=LANDMARK_NAMES.index), ref.get("landmarks_missing", {})
        found = [n + (" (placed by hand)" if n in ref.get("landmarks_by_hand", []) else "") for n in found]
        if not missing:
            parts.append("**%s** all %d" % (scene, len(found)))
            continue
        reasons = {}
        for name in LANDMARK_NAMES:
            if name in missing:
                reasons.setdefault(missing[name], []).append(name)
        parts.append("**%s** %s; not %s" % (
            scene, ", ".join(found) if found else "none",
            "; ".join("%s (%s)" % (", ".join(names), why) for why, names in reasons.items())))
    return "; ".join(parts)


def iteration_section(w, main_rows):
    """The precomputed large-deformation solve stopped after k iterations, per scene."""
    limited = [r for r in main_rows if r["axis"] == "model" and r.get("iteration_limit")]
    if not limited:
        return
    w("### The large-deformation solve stopped early")
    w("")
    w("![residual against iterations and time, and skin error against iterations](plots/large_deformation_iterations.png)")
    w("")
    w("The precomputed large-deformation solve (L-BFGS with the precompute's factor) stopped after k quasi-Newton "
      "iterations (QuasiNewtonIterationLimit), from rest after the precompute: what an update that is cut short "
      "gives, against its time. Its output is that iterate, marked Converged 0, not the equilibrium. Against the "
      "Newton reference of each scene's model axis; the fully converged precomputed solve (k = –) and the "
      "reference's own solve time are given for comparison. Each solve's iterates are in `%s`.%s" % (
          "accuracy_convergence.csv",
          " On the osteotomy plans, whose lips may lift off the teeth, the first iterations converge towards the "
          "equilibrium with the contact of the rest state: the skin error stalls there, the residual jumps where "
          "the contact changes (Newton's rule, on iterates converged to a relative residual of 1e-3), and the error falls again after it."
          if any(r["scene"] in ("lefort1", "bsso", "genioplasty") for r in limited) else ""))
    w("")
    w("| scene | k | iterations run | relative residual | converged | per update ms | largest mm | 95th pct mm | "
      "landmarks mm |")
    w("|---|---|---|---|---|---|---|---|---|")
    for scene in dict.fromkeys(r["scene"] for r in limited):
        mine = sorted((r for r in limited if r["scene"] == scene), key=lambda r: r["iteration_limit"])
        full = [r for r in main_rows if r["scene"] == scene and r["axis"] == "model" and not r.get("iteration_limit")
                and r.get("solver") == "Precomputed"]
        ref = [r for r in main_rows if r["scene"] == scene and r["axis"] == "model" and r["is_reference"]]
        for r in mine + full + ref:
            k = r["iteration_limit"] or ("– (reference, Newton)" if r["is_reference"] else "–")
            w("| %s | %s | %s | %s | %s | %s | %s | %s | %s |" % (
                scene, k, fmt(r.get("quasi_newton_iterations") if not r["is_reference"] else r.get("newton_iterations")),
                fmt(r.get("relative_residual"), 2), {1.0: "yes", 0.0: "no"}.get(r.get("converged"), "yes"),
                fmt(r["update_ms"]), fmt(r["max_mm"]), fmt(r["p95_mm"]), fmt(r["landmark_max_mm"])))
    w("")


def landmark_table(w, main_rows):
    """Per landmark and scene, the linear model's error against the large-deformation reference (mm);
    the other subjects' are in the landmark CSV."""
    linear = {r["scene"]: r for r in main_rows if r["axis"] == "model" and r["choice"] == "linear model"
              and r.get("landmarks")}
    if not linear:
        return
    w("The linear model's error at each soft-tissue landmark against the large-deformation reference (mm; "
      "– where the scene's reference has no such landmark):")
    w("")
    w("| landmark | " + " | ".join(linear) + " |")
    w("|---|" + "---|" * len(linear))
    for name in LANDMARK_NAMES:
        cells = [fmt(r["landmarks"].get(name)) for r in linear.values()]
        if any(c != "–" for c in cells):
            w("| %s | %s |" % (name, " | ".join(cells)))
    w("")


def write_markdown(path, plan, rows, results, failures, args, seconds, has_solver_choice, ct_levels):
    no_result = [r for r in rows if r.get("failed") and "(judge)" not in r["axis"]]
    rows = [r for r in rows if not r.get("failed")]
    main_rows = [r for r in rows if "(judge)" not in r["axis"]]
    scenes = []
    for r in main_rows:
        if r["scene"] not in scenes:
            scenes.append(r["scene"])
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    lines = []
    w = lines.append
    w("## Model error against time")
    w("")
    w("What a planner's choices cost in millimetres at the skin, and what they save in time. Each choice "
      "is measured one axis at a time (model, element, mesh, contact) against the most accurate "
      "configuration FacePlan runs on the scene, through the plugin's filters on the demos' own scenes: "
      "the three osteotomy plans and the main demo's Bezier cut on the Badin face (37,297 tetrahedra), and a "
      "genioplasty on the lower face meshed from the bundled head CT by Tissue Model From CT.")
    w("")
    w("* **Error:** |u − u_reference| at the skin nodes (boundary nodes of the tissue farther than %g mm "
      "from every bone): largest and 95th percentile over the skin, in mm. Where the meshes differ (mesh "
      "axis), the subject's displacement is taken at the closest point of its boundary surface to each reference "
      "skin node." % SKIN_BONE_DISTANCE_MM)
    w("* **Time per update:** Condensed FEM Deform re-executed with its inputs unchanged, as after an edit "
      "of the plan that keeps tissue, ROI and contact (the linear model reuses its precompute and only "
      "re-solves; the large-deformation model solves the whole equilibrium again); median of repeats. "
      "**Precompute:** the filter's PrecomputeTimeMs (factorization and condensation, done once per tissue, "
      "ROI and contact); for a CT mesh, its meshing time is listed beside it. **Peak memory:** the peak "
      "resident memory (VmHWM) of the pvpython process that ran the configuration (one process per configuration, %d at a time), ParaView included." % args.jobs)
    w("* **Soft-tissue landmarks:** |u − u_reference| at the skin landmarks the FacialLandmarks filter finds "
      "on the reference's undeformed tissue and bone (its definitions, docs/CLINICAL.md), both displacements "
      "interpolated at the landmark on their own boundary surface, so every subject is compared at the same "
      "points; the table gives the largest over the landmarks found, `%s` each one. Found per scene (on the "
      "model axis's reference): %s." % ("accuracy_landmarks.csv", landmark_coverage(main_rows)))
    w("")
    w("![skin error against time per update](plots/model_error_vs_time.png)")
    w("")
    w("References, per axis:")
    w("")
    w("* **model:** the large-deformation model (NeoHookean, Newton's method%s) with the operation's contact "
      "on the same mesh and linear elements (the large-deformation model is linear-element only). Subject: the "
      "linear model with the same contact (lift-off needs the large-deformation model, so the linear model "
      "keeps sliding tissue on the teeth)%s." % (
          ", LargeDeformationSolver Newton" if has_solver_choice else "",
          "; the precomputed large-deformation solve (the default solver: L-BFGS with a factor made once), "
          "converged and stopped after k = %s iterations (%s with lift-off)" % (
              ", ".join(map(str, ITERATION_LIMITS)), ", ".join(map(str, ITERATION_LIMITS_LIFT_OFF)))
          if has_solver_choice else
          "; the precomputed large-deformation solve is added as a series when the filter offers "
          "LargeDeformationSolver"))
    w("* **element:** quadratic tetrahedra (mean dilatation) with the linear model: quadratic elements are "
      "available with the linear model only, and with tied or released contact only (sliding needs linear "
      "elements), so this axis runs the released contact on the osteotomy scenes. Subject: linear tetrahedra.")
    w("* **mesh (CT):** the large-deformation model on the finest CT mesh (CellSize %s mm; SurfaceDistance "
      "%.2f × CellSize, so skin and bone refine with the interior). Subjects: the coarser CellSizes." % (
          fmt(ct_levels[-1]), CT_SURFACE_DISTANCE_PER_CELL))
    w("* **contact:** the operation's model (tied to the bone, released where degloved, sliding on the teeth "
      "and lifting off them), large-deformation model. Subjects: released only; released and sliding "
      "without lift-off. All tied is compared within the linear model (below). This axis is the model's "
      "sensitivity to the contact, not a discretization error: the reference is the operation model by "
      "definition.")
    w("* **CT plan:** the lower face of the head CT (slices %d–%d), CellSize %s mm, the tissue's face-connected "
      "pieces of fewer than %d cells left out (the mesher leaves a few cells hanging on an edge next to the "
      "bone, which the solve rightly refuses), the chin below a horizontal and in front of a coronal cut "
      "(behind the symphysis, so that the segment is the whole chin on every mesh) advanced %g mm, tissue "
      "released within %g mm of the cuts (ReleaseDistance; tied across the cut, the "
      "large-deformation solve cannot follow the shear on these meshes). Its skin: the model's own skin "
      "surface (Tissue Model From CT's third output) away from the crop planes." % (
          CT_LOWER_FACE_VOI[4], CT_LOWER_FACE_VOI[5], ", ".join("%g" % h for h in ct_levels), CT_SMALLEST_PIECE,
          -CT_MOVE[1], CT_RELEASE_DISTANCE))
    w("")
    w("Precompute is – for the large-deformation model solved by Newton's method: it has none, every update is "
      "a full solve. The precomputed large-deformation solve's time per update is its first solve, from rest "
      "after the precompute (an edit from a converged plan starts from that plan and needs fewer iterations).")
    w("")
    w("| scene | axis | choice | largest mm | 95th pct mm | landmarks mm | per update ms | precompute ms | peak MB | tets |")
    w("|---|---|---|---|---|---|---|---|---|---|")
    for r in main_rows:
        if r.get("iteration_limit"):
            continue  # the precomputed solve stopped early: its own table below
        choice = ("**%s** (reference)" % r["choice"]) if r["is_reference"] else r["choice"]
        w("| %s | %s | %s | %s | %s | %s | %s | %s | %s | %d |" % (
            r["scene"], r["axis"], choice, fmt(r["max_mm"]), fmt(r["p95_mm"]), fmt(r["landmark_max_mm"]),
            fmt(r["update_ms"]), fmt(r["precompute_ms"] if r["model"] == "LinearElastic" or
                                     r.get("solver") == "Precomputed" else None),
            fmt(r["peak_mb"]), r["tets"]))
    w("")
    if no_result:
        w("No result: " + "; ".join("%s, %s axis, %s: %s" % (r["scene"], r["axis"], r["choice"], r["failed"])
                                    for r in no_result) + ".")
        w("")
    w("Scenes: " + "; ".join("**%s** %s" % (s, SCENE_TEXT[s]) for s in scenes) + ".")
    w("")
    # Largest reference displacement, for scale.
    refs = {}
    for r in main_rows:
        if r["is_reference"] and r["axis"] == "model":
            refs[r["scene"]] = r
    if refs:
        w("For scale, the reference's largest displacement and largest principal Green–Lagrange strain: " +
          "; ".join("%s %.1f mm, %.0f %%" % (s, r["largest_displacement_mm"], 100 * (r["largest_strain"] or 0))
                    for s, r in refs.items()) + ".")
        w("")

    landmark_table(w, main_rows)
    iteration_section(w, main_rows)
    w("## Discretization")
    w("")
    w("![skin error against CellSize and element order](plots/discretization.png)")
    w("")
    mesh = mesh_series(main_rows)
    if mesh:
        estimate, order = reference_error_estimate(mesh)
        w("Mesh (CT plan, large-deformation model; precompute = meshing + the first update, which for this "
          "model is the whole solve):")
        w("")
        w("| CellSize mm | tets | largest mm | 95th pct mm | meshing s | first update s | per update ms | peak MB |")
        w("|---|---|---|---|---|---|---|---|")
        for r in mesh:
            w("| %s%s | %d | %s | %s | %.1f | %.1f | %s | %s |" % (
                fmt(float(r["level"])), " (reference)" if r["is_reference"] else "", r["tets"], fmt(r["max_mm"]),
                fmt(r["p95_mm"]), r["meshing_s"], r["first_update_s"], fmt(r["update_ms"]), fmt(r["peak_mb"])))
        w("")
        subjects = [r for r in mesh if not r["is_reference"]]
        largest_falls = all(b["max_mm"] < a["max_mm"] for a, b in zip(subjects, subjects[1:]))
        p95_falls = all(b["p95_mm"] < a["p95_mm"] for a, b in zip(subjects, subjects[1:]))
        text = "The 95th-percentile skin error %s as the mesh refines (%s mm); the largest %s (%s mm)%s. " % (
            "shrinks" if p95_falls else "does not shrink steadily",
            " → ".join(fmt(r["p95_mm"]) for r in subjects),
            "too" if largest_falls else "does not fall steadily",
            " → ".join(fmt(r["max_mm"]) for r in subjects),
            "" if largest_falls else ": it sits at a few skin nodes next to the cut, where which nodes are tied "
            "to the segment or released changes with the mesh")
        if estimate is not None:
            text += ("It falls at an observed order p = %.2f (the two next-finest meshes against the finest); "
                     "by Richardson extrapolation the finest mesh's own 95th-percentile error is about %s mm%s." % (
                         order, fmt(estimate), ", below every coarser mesh's" if estimate < min(
                             r["p95_mm"] for r in subjects) else ", not below every coarser mesh's"))
        elif len(subjects) < 2:
            text += "With one coarser mesh, the finest mesh's own error cannot be extrapolated."
        else:
            text += ("**Caveat:** from the next-coarser mesh to the next-finest it falls more slowly than any "
                     "convergent series u(h) = u* + C h^p (p > 0) would against a reference this close, so the "
                     "finest mesh's own error cannot be extrapolated: differences of up to the next-finest "
                     "mesh's error (%s mm) may remain at the finest CellSize. Part of it is the plan itself "
                     "changing with the mesh: the skin and bone surfaces move with SurfaceDistance, and which "
                     "tissue nodes are tied to the chin or released within the release distance of the cuts "
                     "changes." % fmt(subjects[-1]["p95_mm"]))
        w(text)
        w("")
    element = [r for r in main_rows if r["axis"] == "element"]
    if element:
        w("Element order (linear model):")
        w("")
        w("| scene | elements | largest mm | 95th pct mm | precompute ms | per update ms | peak MB |")
        w("|---|---|---|---|---|---|---|")
        for r in element:
            w("| %s | %s | %s | %s | %s | %s | %s |" % (
                r["scene"], r["choice"] + (" (reference)" if r["is_reference"] else ""), fmt(r["max_mm"]),
                fmt(r["p95_mm"]), fmt(r["precompute_ms"]), fmt(r["update_ms"]), fmt(r["peak_mb"])))
        w("")
        judged = [r for r in rows if r["axis"] == "element (judge)"]
        if judged:
            w("Is the quadratic reference more accurate? Against quadratic elements one CellSize finer "
              "(largest / 95th percentile): " +
              "; ".join("%s %s / %s mm" % (r["choice"], fmt(r["max_mm"]), fmt(r["p95_mm"])) for r in judged) + ".")
            w("")

    w("## What to choose for a target accuracy")
    w("")
    w("The cheapest choice per update whose largest skin error is within the target, per scene, among the "
      "measured choices that keep the operation's contact: the model axis (linear or large-deformation "
      "model) and, on the CT plan, the mesh axis (CellSize). The reference's error is 0 by definition; its "
      "own discretization error is under Discretization. Element order is left out: quadratic elements "
      "exist for the linear model only, whose model error they do not remove.")
    w("")
    targets = [1.0, 0.5, 0.1]
    w("| scene | " + " | ".join("≤ %g mm at the skin" % t for t in targets) + " |")
    w("|---|" + "---|" * len(targets))
    for scene in scenes:
        # Not the solve stopped early: it is not the equilibrium of any model.
        candidates = [r for r in main_rows if r["scene"] == scene and r["axis"] in ("model", "mesh")
                      and not r.get("iteration_limit")]
        cells = []
        for t in targets:
            ok = [r for r in candidates if r["max_mm"] <= t]
            if not ok:
                cells.append("none measured")
                continue
            best = min(ok, key=cost_ms)
            cells.append("%s (%s axis): %s ms per update, %s mm" % (best["choice"], best["axis"], fmt(best["update_ms"]),
                                                                   fmt(best["max_mm"])))
        w("| %s | %s |" % (scene, " | ".join(cells)))
    w("")
    contact = [r for r in main_rows if r["axis"].startswith("contact")]
    if contact:
        w("## Contact: the model's sensitivity")
        w("")
        w("How far the skin moves when the operation's contact (released where degloved, sliding and lifting "
          "off the teeth) is simplified. Large-deformation model against the operation model; and, since with "
          "every tissue node tied the large-deformation solve finds no path to equilibrium on these plans, all "
          "tied with the linear model against the linear model's closest to the operation (released and "
          "sliding; lift-off needs the large-deformation model):")
        w("")
        w("| scene | model | contact | largest mm | 95th pct mm | per update ms | lifted nodes |")
        w("|---|---|---|---|---|---|---|")
        for r in contact:
            w("| %s | %s | %s | %s | %s | %s | %s |" % (
                r["scene"], r["model"], r["choice"] + (" (reference)" if r["is_reference"] else ""),
                fmt(r["max_mm"]), fmt(r["p95_mm"]), fmt(r["update_ms"]), fmt(r["lifted_nodes"])))
        w("")
    w("Checks (`--check`; CTest runs them on the quick subset), on the 95th-percentile skin error: every "
      "series exists, each with its errors at the soft-tissue landmarks (the runs stopped after k iterations "
      "labelled unconverged); every configuration carries out the plan (moves the tissue by at least half the "
      "reference's largest displacement); on the CT plan the error shrinks as the mesh refines and, where it can be "
      "extrapolated, the finest mesh's own error is below every coarser mesh's; the quadratic reference is closer than linear "
      "elements to a finer quadratic solve; the model and contact references ran the large-deformation "
      "model. The same checks reject the CT studies with reference and subject swapped. This run: %s." % (
          "all hold" if not failures else "**failed**: " + "; ".join(failures)))
    w("")
    w("Measured by `pvpython scripts/report_accuracy.py%s --jobs %d` (run by `scripts/report`): the "
      "configurations ran for %.0f min on %d hardware threads (%s), commit %s, evaluated %s UTC. The machine "
      "was shared with other work (load average %.1f at the end): times are those of a loaded machine, and "
      "the same kind of update can take ten times longer in one configuration than in another, so compare "
      "them by order of magnitude only; uncontended edit latencies are in BENCHMARKS.md. Errors and peak "
      "memory do not depend on the load. Raw numbers: `%s`." % (
          " --quick" if args.quick else "", args.jobs, seconds / 60.0, os.cpu_count() or 0, cpu_model(),
          git_commit(), time.strftime("%Y-%m-%d %H:%M", time.gmtime()), load, "accuracy.csv"))
    w("")
    with open(path, "w") as f:
        f.write("\n".join(lines))


def plot_iterations(plt, plot_dir, main_rows, scenes):
    """The large-deformation solves' relative residual against iterations and against time (the
    first solve's ConvergenceHistory: precomputed solid, Newton dashed), and the skin error of the
    precomputed solve stopped after k iterations."""
    model = [r for r in main_rows if r["axis"] == "model" and r.get("model") == "NeoHookean"]
    if not any(r.get("iteration_limit") for r in model):
        return
    fig, (a, b, c) = plt.subplots(1, 3, figsize=(14, 4.3))
    for n, scene in enumerate(scenes):
        colour = "C%d" % n
        for r in model:
            if r["scene"] != scene or r.get("iteration_limit") or not r["convergence"]:
                continue
            style = "-" if r.get("solver") == "Precomputed" else "--"
            ms = [p[0] for p in r["convergence"]]
            residual = [p[1] for p in r["convergence"]]
            a.plot(range(1, len(residual) + 1), residual, style, color=colour, lw=1)
            b.plot(ms, residual, style, color=colour, lw=1)
        limited = sorted((r for r in model if r["scene"] == scene and r.get("iteration_limit")),
                         key=lambda r: r["iteration_limit"])
        if limited:
            c.plot([r["iteration_limit"] for r in limited], [r["max_mm"] for r in limited], "o-", color=colour,
                   label=scene + ": largest")
            c.plot([r["iteration_limit"] for r in limited], [r["p95_mm"] for r in limited], "s:", color=colour,
                   ms=4, label=scene + ": 95th percentile")
    for axis in (a, b):
        axis.set_yscale("log")
        axis.set_ylabel("relative residual")
        axis.grid(True, which="both", alpha=0.3)
    a.set_xlabel("iterate (ConvergenceHistory entry)")
    a.set_title("Residual against iterates")
    b.set_xscale("log")
    b.set_xlabel("time since the solve started (ms)")
    b.set_title("Residual against time")
    for n, scene in enumerate(scenes):
        a.plot([], [], color="C%d" % n, label=scene)
    a.plot([], [], "-", color="grey", label="precomputed (L-BFGS)")
    a.plot([], [], "--", color="grey", label="Newton (reference)")
    a.legend(fontsize=7)
    c.set_xscale("log", base=2)
    ks = sorted({r["iteration_limit"] for r in model if r.get("iteration_limit")})
    c.set_xticks(ks)
    c.set_xticklabels([str(k) for k in ks])
    c.minorticks_off()
    c.set_yscale("log")
    c.set_xlabel("quasi-Newton iterations k (stopped there)")
    c.set_ylabel("error at the skin against the reference (mm)")
    c.set_title("Stopped after k iterations")
    c.grid(True, which="both", alpha=0.3)
    c.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(plot_dir, "large_deformation_iterations.png"), dpi=110)
    plt.close(fig)


def plot(plot_dir, rows):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker  # noqa: F401 (matplotlib.ticker below)
    os.makedirs(plot_dir, exist_ok=True)
    main_rows = [r for r in rows if "(judge)" not in r["axis"] and not r.get("failed")]
    scenes = []
    for r in main_rows:
        if r["scene"] not in scenes:
            scenes.append(r["scene"])
    markers = {"model": "o", "element": "s", "mesh": "^"}
    floor = 1e-3  # the reference itself (error 0) is drawn here
    fig, ax = plt.subplots(figsize=(8.5, 5.5))
    for k, scene in enumerate(scenes):
        colour = "C%d" % k
        mine = [r for r in main_rows if r["scene"] == scene and r["axis"] in ("model", "mesh", "element")]
        seen = set()
        for r in mine:
            key = (r["choice"], r["axis"])
            if key in seen:
                continue
            seen.add(key)
            if r.get("iteration_limit"):
                continue
            ax.scatter(r["update_ms"], max(r["max_mm"], floor), color=colour, marker=markers[r["axis"]],
                       facecolors="none" if r["is_reference"] else colour, s=45)
        # The precomputed solve stopped after k iterations: a line from k = 1 to the converged solve.
        series = sorted((r for r in mine if r["axis"] == "model" and r.get("solver") == "Precomputed"),
                        key=lambda r: r.get("iteration_limit") or 1e9)
        if len(series) > 1:
            ax.plot([r["update_ms"] for r in series], [max(r["max_mm"], floor) for r in series], color=colour,
                    lw=0.8, marker=".", ms=5)
            for r in series:
                if r.get("iteration_limit"):
                    ax.annotate(str(r["iteration_limit"]), (r["update_ms"], max(r["max_mm"], floor)), fontsize=6,
                                color=colour, textcoords="offset points", xytext=(2, 2))
        ax.plot([], [], color=colour, marker="o", linestyle="", label=scene)
    for axis, m in markers.items():
        ax.plot([], [], color="grey", marker=m, linestyle="", label="axis: " + axis)
    ax.plot([], [], color="grey", marker="o", markerfacecolor="none", linestyle="", label="reference (0 mm drawn at %g)" % floor)
    ax.plot([], [], color="grey", marker=".", lw=0.8, label="precomputed solve stopped after k iterations")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.axhline(1.0, color="grey", lw=0.6, ls=":")
    ax.axhline(0.1, color="grey", lw=0.6, ls=":")
    ax.set_xlabel("time per update (ms)")
    ax.set_ylabel("largest error at the skin (mm)")
    ax.set_title("Model, element and mesh error against time per update")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="best")
    fig.tight_layout()
    fig.savefig(os.path.join(plot_dir, "model_error_vs_time.png"), dpi=110)
    plt.close(fig)

    plot_iterations(plt, plot_dir, main_rows, scenes)

    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.5))
    mesh = [r for r in mesh_series(main_rows) if not r["is_reference"]]
    if mesh:
        h = [float(r["level"]) for r in mesh]
        left.plot(h, [r["max_mm"] for r in mesh], "o-", label="largest")
        left.plot(h, [r["p95_mm"] for r in mesh], "s--", label="95th percentile")
        for r in mesh:
            left.annotate("%d tets\nmesh %.0f s + solve %.1f s" % (r["tets"], r["meshing_s"], r["first_update_s"]),
                          (float(r["level"]), r["max_mm"]), fontsize=7, textcoords="offset points", xytext=(4, 4))
        left.set_xscale("log")
        left.set_yscale("log")
        finest = [float(r["level"]) for r in mesh_series(main_rows) if r["is_reference"]]
        for level in finest:
            left.axvline(level, color="grey", ls=":", lw=0.8)
            left.annotate("reference\nCellSize %g" % level, (level, 1), xycoords=("data", "axes fraction"),
                          fontsize=7, va="top", ha="right", textcoords="offset points", xytext=(-3, -3))
        ticks = sorted(set(h + finest))
        left.xaxis.set_major_locator(matplotlib.ticker.FixedLocator(ticks))
        left.xaxis.set_minor_locator(matplotlib.ticker.NullLocator())
        left.xaxis.set_major_formatter(matplotlib.ticker.FormatStrFormatter("%g"))
        left.invert_xaxis()
        left.set_xlabel("CellSize (mm), finer to the right")
        left.set_ylabel("error at the skin (mm)")
        left.set_title("CT plan: mesh against the finest (large deformation)")
        left.grid(True, which="both", alpha=0.3)
        left.legend(fontsize=8)
    element = [r for r in main_rows if r["axis"] == "element" and not r["is_reference"]]
    refs = {r["scene"]: r for r in main_rows if r["axis"] == "element" and r["is_reference"]}
    if element:
        x = range(len(element))
        right.bar(x, [r["max_mm"] for r in element], color="C1", label="linear elements: largest")
        right.bar(x, [r["p95_mm"] for r in element], color="C0", label="95th percentile")
        right.set_xticks(list(x))
        right.set_xticklabels([r["scene"] for r in element])
        for i, r in enumerate(element):
            q = refs.get(r["scene"])
            right.annotate("precompute\nlinear %.2f s\nquadratic %s s" % (
                r["precompute_ms"] / 1000.0, fmt(q["precompute_ms"] / 1000.0) if q else "–"),
                (i, r["max_mm"]), fontsize=7, ha="center", textcoords="offset points", xytext=(0, 3))
        right.set_ylabel("error against quadratic elements (mm)")
        right.set_title("Element order (linear model)")
        right.legend(fontsize=8)
        right.margins(y=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(plot_dir, "discretization.png"), dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())
