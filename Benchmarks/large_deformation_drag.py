# SPDX-License-Identifier: BSD-3-Clause
"""Update time of the large-deformation model through pvpython: Condensed FEM Deform with Model
NeoHookean, LargeDeformationSolver Precomputed against Newton, side by side in one run, on the
three osteotomy scenes of the Badin face (scripts/osteotomy_scenes.py: CondensedFEMDeform's defaults,
so the teeth slide, the degloved tissue is free, the lips may lift off the teeth and are closed on each
other, as the demos run it) and the main demo's Bezier cut (scripts/faceplan_pipeline.py).

Per scene and solver (medians of repeats; the bone's filters are updated before the clock starts):
- full move: from the converged rest state (zero move) to the scene's whole move, after a pause in
  which the background refactorization of the rest state finishes (Newton: every update is cold);
- drag step: a 0.5 mm change of the move from a converged state, after a pause ("paused"), and the
  same steps back to back with no pause ("continuous"; the background refactorization may lag); the
  median of every paused step, and of the steady ones, from the third on (after two equal changes,
  which the solve extrapolates to second order; the first step after the move has no direction);
- where the full move's time goes: each stage's median over the repeats, from the filter's stage
  table (its second output), and the force evaluations, substitutions and refactorizations of the
  repeat nearest the median time;
- the precompute's time (the first update);
- paired full moves (--paired rounds): a Precomputed full move then a Newton one, round after
  round, so that the ratio of their medians is measured within the same minutes of a machine whose
  speed drifts.
It also writes every iterate's time and relative residual (field data ConvergenceHistory) of one full
move, the first drag step and the last one per scene and solver to a CSV
(Benchmarks/plot_large_deformation_convergence.py plots it).

    pvpython Benchmarks/large_deformation_drag.py <FacePlan.so> <Data dir> [--repeats 5]
        [--drag-steps 6] [--scenes lefort1,bsso,genioplasty,cut] [--lip-seal MM] [--paired 3]
        [--json FILE] [--csv FILE]
"""
import argparse
import builtins
import csv
import json
import os
import statistics
import sys
import time

from paraview import simple

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scripts"))
import faceplan_pipeline  # noqa: E402
import osteotomy_scenes  # noqa: E402

parser = argparse.ArgumentParser()
parser.add_argument("plugin")
parser.add_argument("data")
parser.add_argument("--repeats", type=int, default=5)
parser.add_argument("--newton-repeats", type=int, default=3)
parser.add_argument("--drag-steps", type=int, default=6)
parser.add_argument("--pause", type=float, default=1.5, help="seconds before a 'paused' update")
parser.add_argument("--paired", type=int, default=3,
                    help="rounds of a Precomputed and a Newton full move, one after the other")
parser.add_argument("--scenes", default="lefort1,bsso,genioplasty,cut")
parser.add_argument("--lip-seal", type=float,
                    help="LipSeal (mm) of the osteotomy scenes instead of the demos' (0: open lips)")
parser.add_argument("--json")
parser.add_argument("--csv")
args = parser.parse_args()
simple.LoadPlugin(args.plugin)


def fields(fem):
    fd = fem.GetClientSideObject().GetOutputDataObject(0).GetFieldData()
    out = {}
    for i in range(fd.GetNumberOfArrays()):
        a = fd.GetAbstractArray(i)
        if a.GetNumberOfTuples() == 0:
            continue
        if a.IsA("vtkStringArray"):
            out[a.GetName()] = a.GetValue(0)
        elif a.GetNumberOfComponents() == 1:
            out[a.GetName()] = a.GetTuple1(0)
    history = fd.GetArray("ConvergenceHistory")
    out["history"] = [history.GetTuple2(i) for i in range(history.GetNumberOfTuples())] if history else []
    return out


def stage_times(fem):
    """This update's rows of the filter's stage table (its second output), in ms."""
    table = fem.GetClientSideObject().GetOutputDataObject(1)
    names, times = table.GetColumnByName("Stage"), table.GetColumnByName("TimeMs")
    return {names.GetValue(i): times.GetValue(i) for i in range(table.GetNumberOfRows())
            if times.GetValue(i) > 0.0 and names.GetValue(i) != "PrecomputeTotal"}


def timed_update(fem, bone_filters):
    for f in bone_filters:
        f.UpdatePipeline()
    start = time.perf_counter()
    fem.UpdatePipeline()
    wall = time.perf_counter() - start
    if fem.GetClientSideObject().GetOutputDataObject(0).GetNumberOfPoints() == 0:
        raise RuntimeError("CondensedFEMDeform produced no output")
    return wall * 1e3, fields(fem)


def osteotomy_scene(name):
    tissue, bone, osteotomy, skeleton, fem = osteotomy_scenes.build(args.data, name)
    if args.lip_seal is not None:
        fem.LipSeal = args.lip_seal
    fem.Model = "NeoHookean"
    fem.LiftOff = 1
    full = list(osteotomy_scenes.SCENES[name][2])
    length = builtins.sum(c * c for c in full) ** 0.5

    def move(mm):  # the segment moved mm along the scene's direction
        osteotomy.Translation = [c * mm / length for c in full]
    return fem, [osteotomy, skeleton], move, length


def cut_scene():
    tissue, mandible, roi, cut, fem = faceplan_pipeline.build(args.data)
    fem.Model = "NeoHookean"

    def move(mm):  # mm: how far the cut goes below the demo's (0 = no cut: the surface far below)
        offset = 0.0 if mm > 0.0 else -200.0  # rest: the surface below the chin cuts nothing
        deeper = mm - 1.0 if mm > 0.0 else 0.0
        faceplan_pipeline.place_cut(cut, offset - deeper)
    return fem, [roi, cut], move, 1.0


def measure(name, fem, bone, move, full, solver, repeats, rows, histories):
    fem.LargeDeformationSolver = solver
    r = dict(solver=solver)
    move(0.0)
    r["first_update_ms"], f = timed_update(fem, bone)  # the precompute (Precomputed) and rest
    full_ms, full_iter, full_stages, full_counts = [], [], [], []
    for k in range(repeats):
        move(0.0)
        timed_update(fem, bone)
        time.sleep(args.pause if solver == "Precomputed" else 0.0)
        move(full)
        ms, f = timed_update(fem, bone)
        full_ms.append(ms)
        full_iter.append(f.get("QuasiNewtonIterations", f.get("NewtonIterations", float("nan"))))
        full_stages.append(stage_times(fem))
        full_counts.append({c: f[c] for c in ("ForceEvaluations", "FactorSolves", "Refactorizations")
                            if c in f})
        if k == 0:
            histories.append((name, solver, "full_move", f["history"]))
        r["ran"] = f.get("LargeDeformationSolver", "?")
        r["solver_note"] = f.get("SolverNote", "")
    r["full_move_ms"] = statistics.median(full_ms)
    r["full_move_ms_all"] = full_ms
    r["full_move_iterations"] = statistics.median(full_iter)
    # Where the full move's time goes: each stage's median over the repeats, and the counts of the
    # repeat nearest the median time.
    r["full_move_stages_ms"] = {s: statistics.median(t.get(s, 0.0) for t in full_stages)
                                for s in sorted(set().union(*full_stages))}
    nearest = builtins.min(range(len(full_ms)), key=lambda i: abs(full_ms[i] - r["full_move_ms"]))
    r["full_move_counts"] = full_counts[nearest]
    r["full_move_solve_ms"] = f.get("SolveTimeMs")
    r["largest_strain"] = f.get("LargestStrain")
    r["lifted_nodes"] = f.get("LiftedNodes", 0)
    r["refactorizations_full"] = f.get("Refactorizations", 0)
    r["partial_refactorizations_full"] = f.get("PartialRefactorizations", 0)
    drag_paused, drag_cont, drag_iter = [], [], []
    steps = args.drag_steps if solver == "Precomputed" else builtins.min(args.drag_steps, repeats)
    time.sleep(args.pause if solver == "Precomputed" else 0.0)
    for k in range(1, steps + 1):
        move(full + 0.5 * k)
        ms, f = timed_update(fem, bone)
        drag_paused.append(ms)
        drag_iter.append(f.get("QuasiNewtonIterations", f.get("NewtonIterations", float("nan"))))
        if k == 1:
            histories.append((name, solver, "drag_step", f["history"]))
        elif k == steps:  # a drag step that follows one (the factor made ahead of it)
            histories.append((name, solver, "later_drag_step", f["history"]))
        time.sleep(args.pause if solver == "Precomputed" else 0.0)
    if solver == "Precomputed":
        for k in range(steps - 1, -1, -1):  # back again, step after step with no pause
            move(full + 0.5 * k)
            ms, f = timed_update(fem, bone)
            drag_cont.append(ms)
    r["drag_step_ms"] = statistics.median(drag_paused)
    r["drag_step_ms_all"] = drag_paused
    r["drag_step_iterations"] = statistics.median(drag_iter)
    r["drag_step_iterations_all"] = drag_iter
    if len(drag_paused) > 2:
        r["steady_drag_step_ms"] = statistics.median(drag_paused[2:])
        r["steady_drag_step_iterations"] = statistics.median(drag_iter[2:])
    if drag_cont:
        r["drag_step_continuous_ms"] = statistics.median(drag_cont)
        r["drag_step_continuous_ms_all"] = drag_cont
    print("  %-11s %-11s full move %8.1f ms (%s it)  drag step %7.1f ms (%s it)%s%s  first update %7.1f ms  %s"
          % (name, solver, r["full_move_ms"], r["full_move_iterations"], r["drag_step_ms"],
             r["drag_step_iterations"],
             ", steady %.1f ms (%s it)" % (r["steady_drag_step_ms"], r["steady_drag_step_iterations"])
             if "steady_drag_step_ms" in r else "",
             ", continuous %.1f ms" % r["drag_step_continuous_ms"] if drag_cont else "",
             r["first_update_ms"], r["solver_note"]), flush=True)
    print("  %-11s %-11s full move: %s ms (median of %d)"
          % (name, solver, ", ".join("%.1f" % t for t in full_ms), len(full_ms)), flush=True)
    print("  %-11s %-11s full move's stages (ms, medians): %s%s"
          % (name, solver, ", ".join("%s %.1f" % kv for kv in r["full_move_stages_ms"].items()),
             "".join("; %s %d" % kv for kv in r["full_move_counts"].items())), flush=True)
    if solver == "Precomputed":
        print("  %-11s %-11s paused drag steps (ms): %s (iterations %s); back to back: %s"
              % (name, solver, ", ".join("%.1f" % t for t in drag_paused),
                 ", ".join("%d" % i for i in drag_iter), ", ".join("%.0f" % t for t in drag_cont)),
              flush=True)
    return r


def run_scenes():
    # In a function: the programmable filters of the scenes run their scripts in this module's
    # globals (numpy_interface's algorithms: max, min, full, ...), which shadow top-level names and
    # builtins (hence builtins.min).
    results, histories = {}, []
    for name in args.scenes.split(","):
        fem, bone, move, full = cut_scene() if name == "cut" else osteotomy_scene(name)
        scene = {}
        scene["Precomputed"] = measure(name, fem, bone, move, full, "Precomputed", args.repeats, None,
                                       histories)
        scene["Newton"] = measure(name, fem, bone, move, full, "Newton", args.newton_repeats, None,
                                  histories)
        p, n = scene["Precomputed"], scene["Newton"]
        scene["speedup_full_move"] = n["full_move_ms"] / p["full_move_ms"]
        scene["speedup_drag_step"] = n["drag_step_ms"] / p["drag_step_ms"]
        print("  %-11s Newton / Precomputed: full move %.1fx, drag step %.1fx"
              % (name, scene["speedup_full_move"], scene["speedup_drag_step"]), flush=True)
        if args.paired > 0:
            paired = {"Precomputed": [], "Newton": []}
            for k in range(args.paired):
                for solver in ("Precomputed", "Newton"):
                    fem.LargeDeformationSolver = solver
                    move(0.0)
                    timed_update(fem, bone)
                    time.sleep(args.pause)  # the Precomputed's background work finishes
                    move(full)
                    ms, f = timed_update(fem, bone)
                    paired[solver].append(ms)
            scene["paired_full_move_ms_all"] = paired
            scene["speedup_full_move_paired"] = (statistics.median(paired["Newton"])
                                                 / statistics.median(paired["Precomputed"]))
            print("  %-11s paired full moves (Precomputed, then Newton, round after round): Precomputed %s ms, "
                  "Newton %s ms: medians %.1fx (rounds %s)"
                  % (name, ", ".join("%.1f" % t for t in paired["Precomputed"]),
                     ", ".join("%.0f" % t for t in paired["Newton"]), scene["speedup_full_move_paired"],
                     ", ".join("%.1fx" % (n / p) for p, n in zip(paired["Precomputed"], paired["Newton"]))),
                  flush=True)
        results[name] = scene
        for proxy in list(simple.GetSources().values()):
            simple.Delete(proxy)

    return results, histories


results, histories = run_scenes()
if args.json:
    with open(args.json, "w") as f:
        json.dump(results, f, indent=1)
if args.csv:
    with open(args.csv, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["scene", "solver", "case", "iterate", "time_ms", "relative_residual"])
        for scene, solver, case, history in histories:
            for k, (ms, residual) in enumerate(history):
                w.writerow([scene, solver, case, k, "%.3f" % ms, "%.6e" % residual])
