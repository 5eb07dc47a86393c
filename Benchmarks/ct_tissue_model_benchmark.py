# SPDX-License-Identifier: BSD-3-Clause
"""Benchmark of TissueModelFromCT on the bundled head CT (pvpython; no rendering).

    pvpython Benchmarks/ct_tissue_model_benchmark.py <FacePlan.so> <Data dir> [--sizes 12,10,8,6]
             [--repeats 3] [--pipeline-size 10] [--json out.json]

For each CellSize: meshing time (CT -> model, median of the repeats; a fresh reader and filter each
time), tetrahedra, meshing attempts, the cell estimate against the first attempt's cells (every
label), worst dihedral angle, smallest mean ratio, largest boundary-to-interface distance, and
whether the quality bound and SurfaceDistance hold. Then, at --pipeline-size: CT to first deformation (reader, model, ROIExtract, BezierCut,
CondensedFEMDeform in one first update; median of the repeats). Prints a Markdown table.
"""
import argparse
import json
import os
import statistics
import sys
import time

from paraview import simple, servermanager

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scripts"))
import faceplan_ct_pipeline

parser = argparse.ArgumentParser()
parser.add_argument("plugin")
parser.add_argument("data")
parser.add_argument("--sizes", default="12,10,8,6")
parser.add_argument("--repeats", type=int, default=3)
parser.add_argument("--pipeline-size", type=float, default=10.0)
parser.add_argument("--surface-distance", type=float, default=2.5)
parser.add_argument("--json", default="")
args = parser.parse_args()
simple.LoadPlugin(args.plugin)
if "TissueModelFromCT" not in dir(simple):
    sys.exit("TissueModelFromCT is absent: FacePlan was built without CGAL")


def clean():
    for proxy in list(simple.GetSources().values()):
        simple.Delete(proxy)


def field(ds, name):
    return ds.GetFieldData().GetArray(name).GetValue(0)


rows = []
for size in [float(s) for s in args.sizes.split(",")]:
    times, stats = [], None
    for _ in range(args.repeats):
        clean()
        start = time.perf_counter()
        ct, model = faceplan_ct_pipeline.build_model(args.data, size, args.surface_distance)
        model.UpdatePipeline()
        times.append(time.perf_counter() - start)
        tissue = servermanager.Fetch(model)
        stats = dict(cell_size=size, tets=tissue.GetNumberOfCells(), points=tissue.GetNumberOfPoints(),
                     estimated=field(tissue, "EstimatedCells"), first_attempt_cells=field(tissue, "FirstAttemptCells"),
                     meshed_cells=field(tissue, "MeshedCells"), attempts=int(field(tissue, "MeshingAttempts")),
                     quality_bound=model.QualityBound, worst_dihedral=field(tissue, "WorstDihedralAngle"),
                     smallest_mean_ratio=field(tissue, "SmallestMeanRatio"),
                     largest_boundary_distance=field(tissue, "LargestBoundaryDistance"))
    stats["mesh_seconds"] = times
    stats["mesh_median"] = statistics.median(times)
    rows.append(stats)
    print("CellSize %.1f: %d tets, median %.1f s %s" % (size, stats["tets"], stats["mesh_median"],
                                                        ["%.1f" % t for t in times]), flush=True)

pipeline_times, pipeline_tets = [], 0
for _ in range(args.repeats):
    clean()
    start = time.perf_counter()
    ct, model, roi, cut, fem = faceplan_ct_pipeline.build(args.data, args.pipeline_size, args.surface_distance)
    fem.UpdatePipeline()
    pipeline_times.append(time.perf_counter() - start)
    pipeline_tets = servermanager.Fetch(model).GetNumberOfCells()
print("CT to first deformation at CellSize %.1f (%d tets): median %.1f s %s"
      % (args.pipeline_size, pipeline_tets, statistics.median(pipeline_times), ["%.1f" % t for t in pipeline_times]))

print()
print("| CellSize (mm) | tetrahedra | attempts | cells, all labels | estimate / first attempt's cells | meshing, median (s) "
      "| worst dihedral (deg) | smallest mean ratio | largest boundary distance (mm) |")
print("|---|---|---|---|---|---|---|---|---|")
for r in rows:
    print("| %.1f | %d | %d | %d | %d / %d | %.1f | %.2f | %.3f | %.2f |"
          % (r["cell_size"], r["tets"], r["attempts"], r["meshed_cells"], r["estimated"], r["first_attempt_cells"],
             r["mesh_median"], r["worst_dihedral"], r["smallest_mean_ratio"], r["largest_boundary_distance"]))
print()
quality_ok = all(r["worst_dihedral"] >= r["quality_bound"] for r in rows)
distance_ok = all(r["largest_boundary_distance"] <= args.surface_distance for r in rows)
estimate_ok = all(r["estimated"] >= r["first_attempt_cells"] for r in rows)
print("Quality bound met at every size: %s; SurfaceDistance (%.2f mm) met at every size: %s; "
      "estimate >= first attempt's cells at every size: %s" % (quality_ok, args.surface_distance, distance_ok, estimate_ok))
print()
print("CT to first deformation (CellSize %.1f, %d tetrahedra): median %.1f s of %d" %
      (args.pipeline_size, pipeline_tets, statistics.median(pipeline_times), len(pipeline_times)))
if args.json:
    with open(args.json, "w") as f:
        json.dump(dict(rows=rows, pipeline=dict(cell_size=args.pipeline_size, tets=pipeline_tets,
                                                seconds=pipeline_times)), f, indent=1)
