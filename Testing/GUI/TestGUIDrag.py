"""Runs inside the real ParaView GUI (`paraview --script=TestGUIDrag.py`), started by
run_gui_test.py --script TestGUIDrag.py (inputs in the environment as for TestGUIUndoRedo.py).

Dragging a Bezier Cut control point, as the GUI does it with Auto Apply on: each move of a handle
sets the CurveU property (the handle widget is linked to it), Apply brings the pipeline up to date
and the render view redraws. The script builds the face pipeline (CondensedFEMDeform with Surface
output, the interactive setting), shows bone, operative surface and face, then makes 12 moves of
control point 1 of CurveU and records, for each, the frame time: from setting the property to the
end of the render (BezierCut + CondensedFEMDeform updates + the render in the GUI's view), split
into the pipeline (the two filters and the GUI's reactions to their new data), the representations'
update (geometry extraction, data delivery) and the render itself, each as wall and process CPU
time (all threads, llvmpipe's included: a loaded machine inflates it less). It also times the
render of an unchanged frame, which is what software rendering costs whatever the pipeline does, and
repeats the moves with the view at a quarter of its pixels (View > Preview).
Checks: every move changes the face, no move starts a new precompute. The frame times go into the
result's info (the wrapper prints them; BENCHMARKS.md records them); they are not checked, since a
test must not depend on the machine's speed.
"""
import json
import os
import statistics
import sys
import time
import traceback

result = {"checks": [], "failures": [], "error": None, "info": {}}


def check(cond, what):
    result["checks"].append(what)
    if not cond:
        result["failures"].append(what)
    return bool(cond)


def write_result():
    path = os.environ.get("FACEPLAN_GUI_RESULT", "faceplan_gui_result.json")
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(result, f, indent=1)
    os.replace(tmp, path)  # the wrapper polls for the file: never let it see half of it


try:
    import numpy as np
    from paraview import simple
    from vtkmodules.util.numpy_support import vtk_to_numpy

    sys.path.insert(0, os.environ["FACEPLAN_GUI_SCRIPTS"])
    import faceplan_pipeline

    simple.LoadPlugin(os.environ["FACEPLAN_GUI_PLUGIN"])  # into paraview.simple
    tissue, mandible, roi, cut, fem = faceplan_pipeline.build(os.environ["FACEPLAN_GUI_DATA"])
    fem.OutputMode = "Surface"
    fem.Backend = "CPU"

    view = simple.GetActiveViewOrCreate("RenderView")
    face = simple.Show(simple.OutputPort(fem, 0), view)
    simple.ColorBy(face, ("POINTS", "Displacement", "Magnitude"))
    # Opaque surfaces: translucency means depth peeling, several passes per frame in software.
    bone = simple.Show(simple.OutputPort(cut, 0), view)
    surface = simple.Show(simple.OutputPort(cut, 1), view)
    view.CameraFocalPoint = [85.0, 0.0, 92.0]
    view.CameraPosition = [-260.0, -250.0, 10.0]
    view.CameraViewUp = [0.0, 0.0, 1.0]
    simple.Render(view)

    def face_displacement():
        out = fem.GetClientSideObject().GetOutputDataObject(0)
        return vtk_to_numpy(out.GetPointData().GetArray("Displacement")).copy()

    def precomputes():
        fem.UpdatePropertyInformation()
        return fem.GetPropertyValue("PrecomputeCount")

    start = time.perf_counter()
    fem.UpdatePipeline()
    simple.Render(view)
    result["info"]["first_update_s"] = time.perf_counter() - start
    before = precomputes()
    previous = face_displacement()
    curve = list(cut.CurveU)
    frames_ms, changed = [], []
    phases = {name: {"wall": [], "cpu": []} for name in ("pipeline", "representations", "render")}

    def clock():
        return time.perf_counter(), time.process_time()

    def record(name, start, end):
        phases[name]["wall"].append(1e3 * (end[0] - start[0]))
        phases[name]["cpu"].append(1e3 * (end[1] - start[1]))

    moves = 12
    for k in range(1, moves + 1):
        curve[5] = faceplan_pipeline.CUT_Z - 0.5 - 0.25 * k  # control point 1 dragged down
        t0 = clock()
        cut.CurveU = curve
        fem.UpdatePipeline()  # Apply, as Auto Apply does: the shown outputs update, then draw
        t1 = clock()
        view.Update()  # what Render does first: the representations take the new data
        t2 = clock()
        view.StillRender()
        t3 = clock()
        record("pipeline", t0, t1)
        record("representations", t1, t2)
        record("render", t2, t3)
        frames_ms.append(1e3 * (t3[0] - t0[0]))
        current = face_displacement()
        changed.append(current.shape == previous.shape and float(np.abs(current - previous).max()) > 1e-4)
        previous = current
    check(len(frames_ms) >= 10, "at least 10 widget moves (%d)" % len(frames_ms))
    check(all(changed), "every move changes the face (%d of %d)" % (sum(changed), len(changed)))
    check(precomputes() == before, "no move starts a new precompute")
    median = statistics.median(frames_ms)
    result["info"]["frame_ms"] = [round(t, 2) for t in frames_ms]
    result["info"]["frame_ms_median"] = round(median, 2)
    result["info"]["updates_per_s_median"] = round(1e3 / median, 1)
    for name, times in phases.items():
        result["info"][name + "_ms_median"] = round(statistics.median(times["wall"]), 2)
        result["info"][name + "_cpu_ms_median"] = round(statistics.median(times["cpu"]), 2)
    still_wall, still_cpu = [], []
    for _ in range(10):
        t0 = clock()
        view.StillRender()
        t1 = clock()
        still_wall.append(1e3 * (t1[0] - t0[0]))
        still_cpu.append(1e3 * (t1[1] - t0[1]))
    result["info"]["unchanged_render_ms_median"] = round(statistics.median(still_wall), 2)
    result["info"]["unchanged_render_cpu_ms_median"] = round(statistics.median(still_cpu), 2)
    result["info"]["view_size"] = list(view.ViewSize)
    # The same moves in a render view of a quarter of the pixels (View > Preview), to show how much of
    # the frame is the software rasterizer's per-pixel work.
    layout = simple.GetLayout(view)
    width, height = view.ViewSize
    layout.PreviewMode = [max(width // 2, 1), max(height // 2, 1)]
    small_wall, small_cpu = [], []
    for k in range(1, moves + 1):
        curve[5] = faceplan_pipeline.CUT_Z - 0.5 - 0.25 * (moves - k)  # dragged back up
        t0 = clock()
        cut.CurveU = curve
        fem.UpdatePipeline()
        view.Update()
        view.StillRender()
        t1 = clock()
        small_wall.append(1e3 * (t1[0] - t0[0]))
        small_cpu.append(1e3 * (t1[1] - t0[1]))
    result["info"]["small_view_size"] = list(view.ViewSize)
    result["info"]["small_view_frame_ms_median"] = round(statistics.median(small_wall), 2)
    result["info"]["small_view_frame_cpu_ms_median"] = round(statistics.median(small_cpu), 2)
    layout.PreviewMode = [0, 0]
    result["info"]["render_view"] = view.GetRenderWindow().GetClassName()
    simple.SetActiveSource(cut)
    simple.Render(view)
except Exception:
    result["error"] = traceback.format_exc()
finally:
    write_result()
