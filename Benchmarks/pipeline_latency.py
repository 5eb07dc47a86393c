# SPDX-License-Identifier: BSD-3-Clause
"""Edit latency through the ParaView pipeline (pvpython; CPU backend unless --backend CUDA).

Three scenes: the Badin face (ROIExtract -> BezierCut -> CondensedFEMDeform, scripts/faceplan_pipeline),
its BSSO (Osteotomy -> Append Geometry -> CondensedFEMDeform, scripts/osteotomy_scenes; the edits
change the segment's translation) and the ~100k-tetrahedron face-like shell of faceplan_benchmark (exported by export_shell_scene; its
inner sphere is the bone, cut by a Bezier plane over a polar ROI cap). After the first update each
edit moves the cut's control points (or the segment) a little, so only the bone's Displacement
changes; per edit it times the bone filters' update and CondensedFEMDeform's update (wall clock around UpdatePipeline, and the
process's CPU time, which a busy shared machine inflates less) and reads SolveTimeMs from
CondensedFEMDeform's output (overhead = update wall time - SolveTimeMs). Prints medians and writes them as JSON.

Each scene runs with Model LinearElastic (the linear edit path); with --large-deformation the two face
scenes run again with Model NeoHookean (the Precomputed solver, warm-started from the previous edit's
equilibrium), and the result adds updates per second and the plugin's share of an edit.

  pvpython Benchmarks/pipeline_latency.py --plugin FacePlan.so --data Data \
      --shell-scene shell.vtk [--edits 30] [--json out.json] [--backend CPU|CUDA] [--shell-only]
      [--large-deformation]
"""
import argparse
import json
import os
import statistics
import sys
import time

from paraview import simple
from vtkmodules.vtkFiltersCore import vtkThreshold
from vtkmodules.vtkFiltersGeometry import vtkDataSetSurfaceFilter, vtkGeometryFilter

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scripts"))


BACKEND = "CPU"  # --backend: the CondensedFEMDeform Backend every scene uses


def field(proxy, name):
    out = proxy.GetClientSideObject().GetOutputDataObject(0)
    array = out.GetFieldData().GetArray(name)
    return array.GetValue(0) if array is not None else float("nan")


def backend_used(fem):
    """The filter's own record of the backend that ran (it falls back to the CPU, with a note, when
    CUDA is not available): a CUDA figure must come from the CUDA backend."""
    array = fem.GetClientSideObject().GetOutputDataObject(0).GetFieldData().GetAbstractArray("Backend")
    return array.GetValue(0) if array is not None else ""


def precompute_count(fem):
    fem.UpdatePropertyInformation()
    return fem.GetPropertyValue("PrecomputeCount")


def run_edits(name, bone_filters, fem, edit, edits, bone_label="BezierCut"):
    """Times `edits` edits after the first update (see the module's docstring)."""
    result = _run_edits(name, bone_filters, fem, edit, edits, bone_label)
    result["model"] = field_string(fem, "Model")
    result["updates_per_s"] = 1e3 / result["whole_edit_ms_median"]
    result["plugin_share"] = result["fem_update_ms_median"] / result["whole_edit_ms_median"]
    if result["model"] == "NeoHookean":
        print("    %s: %.1f updates/s, CondensedFEMDeform %.0f %% of an edit, quasi-Newton iterations "
              "(last edit) %s" % (name, result["updates_per_s"], 100.0 * result["plugin_share"],
                                  field(fem, "QuasiNewtonIterations")))
    return result


def field_string(proxy, name):
    array = proxy.GetClientSideObject().GetOutputDataObject(0).GetFieldData().GetAbstractArray(name)
    return array.GetValue(0) if array is not None and array.GetNumberOfTuples() else ""


def _run_edits(name, bone_filters, fem, edit, edits, bone_label):
    """edit(k) changes the bone's filter for edit k (edit 0: the first, precomputing update);
    bone_filters are updated in order and timed together as the bone's update."""
    edit(0)
    for f in bone_filters:
        f.UpdatePipeline()
    start = time.perf_counter()
    fem.UpdatePipeline()
    first_ms = 1e3 * (time.perf_counter() - start)
    if fem.GetClientSideObject().GetOutputDataObject(0).GetNumberOfPoints() == 0:
        raise RuntimeError(name + ": CondensedFEMDeform produced no output")
    used = backend_used(fem)
    if BACKEND == "CUDA" and "CUDA" not in used:
        raise RuntimeError("%s: asked for the CUDA backend, the filter ran on %r" % (name, used))
    precomputes = precompute_count(fem)
    cut_ms, fem_ms, solve_ms, fem_cpu_ms = [], [], [], []
    for k in range(1, edits + 1):
        edit(k)
        t0 = time.perf_counter()
        for f in bone_filters:
            f.UpdatePipeline()
        t1, c1 = time.perf_counter(), time.process_time()
        fem.UpdatePipeline()
        t2, c2 = time.perf_counter(), time.process_time()
        fem_cpu_ms.append(1e3 * (c2 - c1))
        cut_ms.append(1e3 * (t1 - t0))
        fem_ms.append(1e3 * (t2 - t1))
        solve_ms.append(field(fem, "SolveTimeMs"))
    if precompute_count(fem) != precomputes:
        raise RuntimeError(name + ": an edit of the cut started a new precompute")
    overhead = [f - s for f, s in zip(fem_ms, solve_ms)]
    whole = [c + f for c, f in zip(cut_ms, fem_ms)]
    med = statistics.median
    result = {
        "scene": name,
        "backend": BACKEND,
        "backend_used": used,
        "tissue_cells": fem.GetClientSideObject().GetInputDataObject(0, 0).GetNumberOfCells(),
        "output_points": fem.GetClientSideObject().GetOutputDataObject(0).GetNumberOfPoints(),
        "first_update_ms": first_ms,
        "edits": edits,
        "fem_update_ms_median": med(fem_ms),
        "fem_update_ms_p90": sorted(fem_ms)[int(0.9 * (len(fem_ms) - 1))],
        "fem_update_cpu_ms_median": med(fem_cpu_ms),  # all threads of this process
        "solve_ms_median": med(solve_ms),
        "overhead_ms_median": med(overhead),
        "bone_filter": bone_label,
        "bone_update_ms_median": med(cut_ms),
        "whole_edit_ms_median": med(whole),
    }
    print("[%s] %-28s tets %7d  first %8.1f ms | per edit (median of %d): CondensedFEMDeform %6.2f ms "
          "(p90 %6.2f, CPU %6.2f), SolveTimeMs %6.2f, overhead %5.2f; %s %6.2f; whole edit "
          "%6.2f ms"
          % (used, name, result["tissue_cells"], first_ms, edits, result["fem_update_ms_median"],
             result["fem_update_ms_p90"], result["fem_update_cpu_ms_median"], result["solve_ms_median"],
             result["overhead_ms_median"], bone_label, result["bone_update_ms_median"],
             result["whole_edit_ms_median"]))
    return result


def face_scene(data, edits, output_mode, model="LinearElastic"):
    import faceplan_pipeline as fp
    tissue, mandible, roi, cut, fem = fp.build(data)
    fem.Backend = BACKEND
    fem.OutputMode = output_mode
    fem.Model = model

    def edit(k):
        dz = 0.25 * ((k * 7) % 9 - 4) / 4.0  # -0.25 .. 0.25 mm, a different cut each edit
        cut.CurveU = [c + (dz if i % 3 == 2 else 0.0) for i, c in enumerate(fp.CURVE_U)]
        cut.CurveV = [c + (dz if i % 3 == 2 else 0.0) for i, c in enumerate(fp.CURVE_V)]

    result = run_edits("face (%s output, %s)" % (output_mode, model), [cut], fem, edit, edits)
    for p in (fem, cut, roi, mandible, tissue):
        simple.Delete(p)
    return result


def osteotomy_scene(data, edits, output_mode, model="LinearElastic"):
    """The BSSO advancement of scripts/osteotomy_scenes: each edit changes the segment's move (the
    planes stay), as dragging the translation does; the bone's update is Osteotomy + the Append
    Geometry that joins the fixed bones."""
    import osteotomy_scenes as scenes
    tissue, bone, osteotomy, skeleton, fem = scenes.build(data, "bsso")
    fem.Backend = BACKEND
    fem.OutputMode = output_mode
    fem.Model = model

    def edit(k):
        dx = 0.25 * ((k * 7) % 9 - 4) / 4.0  # -0.25 .. 0.25 mm around the 6 mm advancement
        osteotomy.Translation = [-6.0 + dx, 0.0, 0.0]

    result = run_edits("face BSSO (%s output, %s)" % (output_mode, model), [osteotomy, skeleton], fem,
                       edit, edits,
                       bone_label="Osteotomy+Append")
    for p in [fem, skeleton, osteotomy, bone, tissue] + list(skeleton.Input[1:]):
        simple.Delete(p)
    return result


def shell_scene(path, edits, output_mode):
    tissue = simple.LegacyVTKReader(FileNames=[path])
    tissue.UpdatePipeline()
    grid = tissue.GetClientSideObject().GetOutputDataObject(0)
    # The bone: the tissue's boundary triangles on the inner sphere (Layer 0).
    surface = vtkDataSetSurfaceFilter()
    surface.SetInputData(grid)
    inner = vtkThreshold()
    inner.SetInputConnection(surface.GetOutputPort())
    inner.SetInputArrayToProcess(0, 0, 0, 0, "Layer")
    inner.SetLowerThreshold(0)
    inner.SetUpperThreshold(0)
    inner.SetAllScalars(True)
    to_poly = vtkGeometryFilter()
    to_poly.SetInputConnection(inner.GetOutputPort())
    to_poly.Update()
    bone = simple.TrivialProducer()
    bone.GetClientSideObject().SetOutput(to_poly.GetOutput())
    roi = simple.ROIExtract(Input=bone)
    roi.Region = "Sphere"
    roi.Region.Center = [0.0, 0.0, 80.0]  # the inner sphere's pole (radius 80 mm)
    roi.Region.Radius = 50.0
    cut = simple.BezierCut(Input=roi)
    fem = simple.CondensedFEMDeform(Input=tissue, Bone=cut)
    fem.Backend = BACKEND
    fem.OutputMode = output_mode
    fem.Model = "LinearElastic"
    fem.ContactDistance = 0.5

    def edit(k):
        z = 75.0 + 0.25 * ((k * 7) % 9 - 4) / 4.0  # a plane cutting the pole's cap
        cut.CurveU = [-70, -70, z, -23, -70, z, 23, -70, z, 70, -70, z]
        cut.CurveV = [-70, -70, z, -70, -23, z, -70, 23, z, -70, 70, z]

    result = run_edits("shell ~100k (%s output)" % output_mode, [cut], fem, edit, edits)
    for p in (fem, cut, roi, bone, tissue):
        simple.Delete(p)
    return result


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--plugin", required=True)
    parser.add_argument("--data", required=True)
    parser.add_argument("--shell-scene", help="export_shell_scene's .vtk (the ~100k scene)")
    parser.add_argument("--edits", type=int, default=30)
    parser.add_argument("--json")
    parser.add_argument("--shell-only", action="store_true",
                        help="only the shell scene (to compare with Benchmarks/FilterLatency's driver)")
    parser.add_argument("--backend", choices=["CPU", "CUDA"], default="CPU")
    parser.add_argument("--large-deformation", action="store_true",
                        help="also the face scenes with Model NeoHookean")
    args = parser.parse_args()
    global BACKEND
    BACKEND = args.backend
    simple.LoadPlugin(args.plugin)  # into paraview.simple, where faceplan_pipeline finds the filters
    results = []
    if not args.shell_only:
        results = [face_scene(args.data, args.edits, "Volume"),
                   face_scene(args.data, args.edits, "Surface"),
                   osteotomy_scene(args.data, args.edits, "Surface")]
    if args.shell_scene:
        results.append(shell_scene(args.shell_scene, args.edits, "Surface"))
    if args.large_deformation and not args.shell_only:
        results += [face_scene(args.data, args.edits, "Surface", "NeoHookean"),
                    osteotomy_scene(args.data, args.edits, "Surface", "NeoHookean")]
    if args.json:
        with open(args.json, "w") as f:
            json.dump(results, f, indent=1)


if __name__ == "__main__":
    main()
