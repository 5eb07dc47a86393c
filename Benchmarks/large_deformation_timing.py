# SPDX-License-Identifier: BSD-3-Clause
"""Time of the large-deformation model on the three osteotomy scenes (pvpython): the whole
Condensed FEM Deform update with Model NeoHookean, LargeDeformationSolver Newton and LiftOff (as the demos run it), Core's solve
time and its stages, the load steps and Newton iterations, against the linear model's first update
(precompute + solve) and a re-execution with its precompute cached, on the same scene, and NeoHookean without LiftOff. Medians of repeats.

    pvpython Benchmarks/large_deformation_timing.py <FacePlan.so> <Data dir> [repeats] [--json FILE]
"""
import json
import os
import statistics
import sys
import time

from paraview.simple import Delete, LoadPlugin

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scripts"))
import osteotomy_scenes  # noqa: E402

args = [a for a in sys.argv[1:] if not a.startswith("--")]
json_path = sys.argv[sys.argv.index("--json") + 1] if "--json" in sys.argv else None
if json_path in args:
    args.remove(json_path)
plugin, data_dir = args[0], args[1]
repeats = int(args[2]) if len(args) > 2 else 5
LoadPlugin(plugin)


def update(fem):
    """Re-executes the filter (not its inputs, which are up to date) and returns (wall s, output)."""
    algorithm = fem.GetClientSideObject()
    algorithm.Modified()
    start = time.perf_counter()
    algorithm.Update()
    return time.perf_counter() - start, algorithm.GetOutputDataObject(0)


def stages(out_table):
    rows = {}
    for r in range(out_table.GetNumberOfRows()):
        rows[out_table.GetValue(r, 0).ToString()] = out_table.GetValue(r, 1).ToDouble()
    return rows


results = {}
for scene in osteotomy_scenes.SCENES:
    tissue, bone, osteotomy, skeleton, fem = osteotomy_scenes.build(data_dir, scene)
    fem.UpdatePipeline()  # inputs and the contact map, outside the timings
    linear_first, linear_edit = [], []
    for k in range(repeats):
        fem.YoungsModulus = 15000.0 * (1.0 + 1e-9 * (k + 1))  # a new material: a fresh precompute
        linear_first.append(update(fem)[0])
        linear_edit.append(update(fem)[0])
    fem.YoungsModulus = 15000.0
    osteotomy_scenes.configure_model(fem)
    fem.LargeDeformationSolver = "Newton"  # this benchmark's subject (large_deformation_drag.py: both)
    walls, cores, last = [], [], None
    for k in range(repeats):
        wall, out = update(fem)
        walls.append(wall)
        cores.append(out.GetFieldData().GetArray("SolveTimeMs").GetValue(0))
        last = out
    fd = last.GetFieldData()
    table = stages(fem.GetClientSideObject().GetOutputDataObject(1))
    values = {name: fd.GetArray(name).GetValue(0) for name in (
        "LoadSteps", "NewtonIterations", "LiftedNodes", "LargestStrain", "SmallestVolumeRatio")}
    fem.LiftOff = 0
    bilateral = statistics.median(update(fem)[0] for _ in range(repeats))
    bilateral_iterations = fem.GetClientSideObject().GetOutputDataObject(0).GetFieldData().GetArray(
        "NewtonIterations").GetValue(0)
    r = dict(update_s=statistics.median(walls), core_s=statistics.median(cores) / 1000.0,
             load_steps=values["LoadSteps"],
             newton_iterations=values["NewtonIterations"],
             lifted_nodes=values["LiftedNodes"],
             largest_strain=values["LargestStrain"],
             smallest_volume_ratio=values["SmallestVolumeRatio"],
             stages_ms={k: table[k] for k in ("Reordering", "ElementStiffness", "Assembly",
                                              "Factorization", "Solve")},
             linear_first_update_s=statistics.median(linear_first),
             linear_edit_s=statistics.median(linear_edit),
             without_lift_off_update_s=bilateral, without_lift_off_newton_iterations=bilateral_iterations)
    results[scene] = r
    print("%-11s NeoHookean+LiftOff update %.2f s (Core %.2f s: %s); %d load step(s), %d Newton "
          "iterations, %d nodes lifted, largest Green strain %.0f %%, smallest det F %.2f; linear model: "
          "first update (precompute + solve) %.2f s, re-execution with the precompute cached %.1f ms; "
          "NeoHookean without LiftOff %.2f s, %d Newton iterations (medians of %d)" % (
              scene, r["update_s"], r["core_s"],
              ", ".join("%s %.0f ms" % kv for kv in r["stages_ms"].items()), r["load_steps"],
              r["newton_iterations"], r["lifted_nodes"], 100 * r["largest_strain"],
              r["smallest_volume_ratio"], r["linear_first_update_s"], 1000 * r["linear_edit_s"],
              bilateral, bilateral_iterations, repeats))
    for proxy in (fem, skeleton, osteotomy, bone, tissue):
        Delete(proxy)
if json_path:
    with open(json_path, "w") as f:
        json.dump(results, f, indent=2)
