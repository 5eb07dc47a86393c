# SPDX-License-Identifier: BSD-3-Clause
"""Runs inside the real ParaView GUI (`paraview --script=TestGUIDrag.py`), started by
run_gui_test.py --script TestGUIDrag.py (inputs in the environment as for TestGUIUndoRedo.py).

Dragging a Bezier Cut control point, as the GUI does it with Auto Apply on: each move of a handle
sets the CurveU property (the handle widget is linked to it), Apply brings the pipeline up to date
and the render view redraws. The script builds the face pipeline (CondensedFEMDeform with Surface
output, the interactive setting), shows bone, operative surface and face, then makes 12 moves of
control point 1 of CurveU and records, for each, the frame time: from setting the property to the
new picture on the screen, split into the pipeline (the two filters and the GUI's reactions to their
new data), the representations' update (geometry extraction, data delivery), the render into the
view's framebuffer and the paint (Qt's event loop run until idle, as it runs between two mouse
moves: the view's widget shows the new frame, Qt composes the window and the panels that changed
redraw), each as wall and process CPU time (all threads, llvmpipe's included: a loaded machine
inflates it less). Condensed FEM Deform's own solve time in each move (its field data SolveTimeMs)
goes in as `*solve_ms_median`: the plugin's share of the pipeline phase; each thread group's CPU
time per move as `*thread_cpu_ms_per_move` (FacePlan names its threads faceplan-help, -drag, -pre);
each move's start on CLOCK_MONOTONIC and its phases' ends as `*phase_stamps`.

The moves are made twice: first with ParaView's default render settings (keys `default_*`), then
with the drag setting README.md recommends (faceplan_pipeline.drag_render_settings: FXAA off), the
main figures; then once more with Model NeoHookean (keys `large_deformation_*`). It also times an unchanged frame (render + paint) with each, which is what software
rendering costs whatever the pipeline does, and repeats the moves with the drag setting in a view
of a quarter of the pixels (View > Preview). Each figure set says whether it reaches the target of
30 updates per second (`*target_met`). The OpenGL that drew the frames goes into the info too
(`gl_vendor`, `gl_renderer`, `gl_version`, from the render window's ReportCapabilities()).
Checks: every move changes the face, no move starts a new precompute. The frame times go into the
result's info (the wrapper prints them; BENCHMARKS.md records them); they are not checked, since a
test must not depend on the machine's speed.
"""
import ctypes
import ctypes.util
import os
import statistics
import sys
import time
import traceback

TARGET_UPDATES_PER_S = 30.0
MOVES = int(os.environ.get("FACEPLAN_GUI_DRAG_MOVES", "12"))  # more for scripts/profile_gui_drag

sys.path.insert(0, os.environ["FACEPLAN_GUI_TESTS"])  # Testing/GUI, set by run_gui_test.py
from gui_result import check, result, write_result  # noqa: E402


def clock():
    return time.perf_counter(), time.process_time()


def thread_cpu_s():
    """CPU seconds so far of each of this process's threads, by group: "main" (the GUI's thread),
    else the thread's name with a trailing number dropped (llvmpipe-3 -> llvmpipe-*); threads a
    library leaves unnamed carry the program's name. Only os: the GPU host's packed Python holds
    just the modules a GUI run opens."""
    tick = os.sysconf("SC_CLK_TCK")
    groups = {}
    for tid in os.listdir("/proc/self/task"):
        try:
            with open("/proc/self/task/%s/stat" % tid) as f:
                stat = f.read()
        except OSError:  # the thread ended meanwhile
            continue
        name = stat[stat.find("(") + 1:stat.rfind(")")]
        fields = stat[stat.rfind(")") + 2:].split()
        stripped = name.rstrip("0123456789")
        group = ("main" if tid == str(os.getpid())
                 else stripped + "*" if stripped != name and stripped.endswith("-") else name)
        groups[group] = groups.get(group, 0.0) + (int(fields[11]) + int(fields[12])) / tick
    return groups


def median_ms(values):
    return round(statistics.median(values), 2)


def qt_event_loop():
    """QCoreApplication::processEvents(ExcludeUserInputEvents) of the GUI's Qt 5, called through
    ctypes (the GUI's Python has no Qt bindings); None when it cannot be found."""
    try:
        core = ctypes.CDLL(ctypes.util.find_library("Qt5Core") or "libQt5Core.so.5")
        run = getattr(core, "_ZN16QCoreApplication13processEventsE6QFlagsIN10QEventLoop17ProcessEventsFlagEE")
    except (OSError, AttributeError):
        return None
    run.argtypes = [ctypes.c_int]  # QFlags<ProcessEventsFlag>: one int, passed as one
    run.restype = None
    return lambda: run(1)  # 1 = QEventLoop::ExcludeUserInputEvents


try:
    import numpy as np
    from paraview import simple
    from vtkmodules.util.numpy_support import vtk_to_numpy

    sys.path.insert(0, os.environ["FACEPLAN_GUI_SCRIPTS"])
    import faceplan_pipeline

    process_events = qt_event_loop()
    if not check(process_events is not None, "the GUI's Qt event loop can be run from the script"):
        raise RuntimeError("QCoreApplication::processEvents not found: the paint cannot be timed")
    simple.LoadPlugin(os.environ["FACEPLAN_GUI_PLUGIN"])  # into paraview.simple
    tissue, mandible, roi, cut, fem = faceplan_pipeline.build(os.environ["FACEPLAN_GUI_DATA"])
    fem.Model = "LinearElastic"  # the linear model's contract (its baseline, its edit timings)
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

    def solve_ms():
        """The solve's own time in the last update (field data SolveTimeMs): FacePlan's
        Condensed FEM Deform share of the frame."""
        array = fem.GetClientSideObject().GetOutputDataObject(0).GetFieldData().GetArray("SolveTimeMs")
        return array.GetValue(0) if array is not None else None

    def precomputes():
        fem.UpdatePropertyInformation()
        return fem.GetPropertyValue("PrecomputeCount")

    # Bezier Cut is the active source while its handles are dragged: its properties panel (with the
    # Curve U / Curve V widgets) is the one shown and repainted.
    simple.SetActiveSource(cut)
    start = time.perf_counter()
    fem.UpdatePipeline()
    simple.Render(view)
    result["info"]["first_update_s"] = time.perf_counter() - start
    for _ in range(20):  # the window's layout settles: the view gets its size in the GUI
        process_events()
        time.sleep(0.05)
    before = precomputes()
    curve = list(cut.CurveU)
    state = {"previous": face_displacement(), "changed": [], "down": True}

    def drag(prefix, phases_too):
        """MOVES moves of control point 1 (alternately down and back up, so that every move
        changes the face); records the frame figures under info[prefix + ...]."""
        frames_wall, frames_cpu, solves, stamps = [], [], [], []
        threads_before = thread_cpu_s()
        span_start = time.clock_gettime(time.CLOCK_MONOTONIC)  # perf -k CLOCK_MONOTONIC's clock
        phases = {name: {"wall": [], "cpu": []}
                  for name in ("pipeline", "representations", "render", "paint")}

        def record(name, t_start, t_end):
            phases[name]["wall"].append(1e3 * (t_end[0] - t_start[0]))
            phases[name]["cpu"].append(1e3 * (t_end[1] - t_start[1]))

        for k in range(1, MOVES + 1):
            step = k if state["down"] else MOVES - k
            curve[5] = faceplan_pipeline.CUT_Z - 0.5 - 3.0 * step / MOVES  # over 3 mm whatever MOVES
            move_start = time.clock_gettime(time.CLOCK_MONOTONIC)
            t0 = clock()
            cut.CurveU = curve
            fem.UpdatePipeline()  # Apply, as Auto Apply does: the shown outputs update, then draw
            t1 = clock()
            view.Update()  # what Render does first: the representations take the new data
            t2 = clock()
            view.StillRender()
            t3 = clock()
            process_events()  # what the GUI does before the next mouse move: paint
            t4 = clock()
            # When each phase ended, for scripts/profile_gui_drag's split of perf's samples.
            stamps.append([round(move_start, 6)] + [round(t[0] - t0[0], 6) for t in (t1, t2, t3, t4)])
            record("pipeline", t0, t1)
            record("representations", t1, t2)
            record("render", t2, t3)
            record("paint", t3, t4)
            frames_wall.append(1e3 * (t4[0] - t0[0]))
            frames_cpu.append(1e3 * (t4[1] - t0[1]))
            solves.append(solve_ms())
            current = face_displacement()
            previous = state["previous"]
            state["changed"].append(current.shape == previous.shape
                                    and float(np.abs(current - previous).max()) > 1e-4)
            state["previous"] = current
        state["down"] = not state["down"]
        info = result["info"]
        info[prefix + "monotonic_span_s"] = [span_start, time.clock_gettime(time.CLOCK_MONOTONIC)]
        info[prefix + "phase_stamps"] = stamps
        threads_after = thread_cpu_s()
        info[prefix + "thread_cpu_ms_per_move"] = {
            group: round(1e3 * (cpu - threads_before.get(group, 0.0)) / MOVES, 1)
            for group, cpu in sorted(threads_after.items()) if cpu > threads_before.get(group, 0.0)}
        median = statistics.median(frames_wall)
        info[prefix + "frame_ms"] = [round(t, 2) for t in frames_wall]
        info[prefix + "frame_ms_median"] = round(median, 2)
        info[prefix + "frame_cpu_ms_median"] = median_ms(frames_cpu)
        info[prefix + "updates_per_s_median"] = round(1e3 / median, 1)
        info[prefix + "target_met"] = 1e3 / median >= TARGET_UPDATES_PER_S
        if None not in solves:
            info[prefix + "solve_ms_median"] = median_ms(solves)
        if phases_too:
            for name, times in phases.items():
                info[prefix + name + "_ms_median"] = median_ms(times["wall"])
                info[prefix + name + "_cpu_ms_median"] = median_ms(times["cpu"])
            still = {name: {"wall": [], "cpu": []} for name in ("render", "paint")}
            for _ in range(10):
                t0 = clock()
                view.StillRender()
                t1 = clock()
                process_events()
                t2 = clock()
                for name, (a, b) in (("render", (t0, t1)), ("paint", (t1, t2))):
                    still[name]["wall"].append(1e3 * (b[0] - a[0]))
                    still[name]["cpu"].append(1e3 * (b[1] - a[1]))
            for name, times in still.items():
                info[prefix + "unchanged_" + name + "_ms_median"] = median_ms(times["wall"])
                info[prefix + "unchanged_" + name + "_cpu_ms_median"] = median_ms(times["cpu"])
        return len(frames_wall)

    result["info"]["target_updates_per_s"] = TARGET_UPDATES_PER_S
    result["info"]["default_settings"] = {"UseFXAA": view.UseFXAA, "UseLight": view.UseLight}
    moves = [drag("default_", True)]
    result["info"]["drag_settings"] = faceplan_pipeline.drag_render_settings(view)
    moves.append(drag("", True))
    result["info"]["view_size"] = list(view.ViewSize)  # in run_gui_test.py's 1280x1024 window
    # The same moves in a render view of a quarter of the pixels (View > Preview), to show how much of
    # the frame is the software rasterizer's per-pixel work.
    layout = simple.GetLayout(view)
    width, height = view.ViewSize
    layout.PreviewMode = [max(width // 2, 1), max(height // 2, 1)]
    moves.append(drag("small_view_", False))
    result["info"]["small_view_size"] = list(view.ViewSize)
    layout.PreviewMode = [0, 0]
    # The same moves on the large-deformation model: the Precomputed solver, warm-started from the
    # previous move's equilibrium (keys large_deformation_*).
    fem.Model = "NeoHookean"
    fem.UpdatePipeline()
    simple.Render(view)
    state["previous"] = face_displacement()
    moves.append(drag("large_deformation_", True))
    fields = fem.GetClientSideObject().GetOutputDataObject(0).GetFieldData()
    model, converged = fields.GetAbstractArray("Model"), fields.GetArray("Converged")
    check(model is not None and model.GetValue(0) == "NeoHookean"
          and converged is not None and converged.GetValue(0) == 1,
          "the large-deformation moves ran Model NeoHookean to convergence")
    iterations = fields.GetArray("QuasiNewtonIterations")
    result["info"]["large_deformation_last_iterations"] = (
        iterations.GetValue(0) if iterations is not None else None)
    check(min(moves) >= 10, "at least 10 widget moves per run (%s)" % moves)
    check(all(state["changed"]),
          "every move changes the face (%d of %d)" % (sum(state["changed"]), len(state["changed"])))
    check(precomputes() == before, "no move starts a new precompute")
    window = view.GetRenderWindow()
    result["info"]["render_view"] = window.GetClassName()
    # Which OpenGL drew the frames (llvmpipe, or a GPU's driver): the figures mean nothing without it.
    capabilities = window.ReportCapabilities() or ""
    for key, label in (("gl_vendor", "OpenGL vendor string:"), ("gl_renderer", "OpenGL renderer string:"),
                       ("gl_version", "OpenGL version string:")):
        line = next((l for l in capabilities.splitlines() if l.startswith(label)), "")
        result["info"][key] = line[len(label):].strip() or None
    simple.Render(view)
except Exception:
    result["error"] = traceback.format_exc()
finally:
    write_result()
