# SPDX-License-Identifier: BSD-3-Clause
"""Runs inside the real ParaView GUI (`paraview --script=TestGUIOsteotomy.py`), started by
run_gui_test.py --script TestGUIOsteotomy.py, which passes its inputs in the environment (see
TestGUIUndoRedo.py: FACEPLAN_GUI_PLUGIN, _DATA, _SCRIPTS, _RESULT) and checks the result file.

What it does, in the GUI's own session:
 1. loads the plugin and builds the Le Fort I plan on the face (maxilla -> Osteotomy ->
    CondensedFEMDeform, osteotomy_scenes.build("lefort1")) and shows it in the GUI's render view;
 2. moves the segment further (Osteotomy's Translation, 5 -> 7 mm advancement) inside an undo set
    of the GUI's undo stack and checks that the bone and the soft tissue follow;
 3. undoes and redoes that set the way Edit > Undo / Redo do and checks that undo gives back the
    first plan and redo the moved one;
 4. leaves Osteotomy selected, so the Properties panel shows it for the wrapper's screenshot.
"""
import os
import sys
import traceback

sys.path.insert(0, os.environ["FACEPLAN_GUI_TESTS"])  # Testing/GUI, set by run_gui_test.py
from gui_result import check, result, write_result  # noqa: E402


try:
    import numpy as np
    from paraview import servermanager
    from paraview import simple
    from vtkmodules.util.numpy_support import vtk_to_numpy

    sys.path.insert(0, os.environ["FACEPLAN_GUI_SCRIPTS"])
    import osteotomy_scenes

    simple.LoadPlugin(os.environ["FACEPLAN_GUI_PLUGIN"])
    tissue, maxilla, osteotomy, skeleton, fem = osteotomy_scenes.build(os.environ["FACEPLAN_GUI_DATA"], "lefort1")
    fem.Model = "LinearElastic"  # the linear model's contract (its baseline, its edit timings)
    move0 = list(osteotomy.Translation)

    view = simple.GetActiveViewOrCreate("RenderView")
    check(view is not None, "the GUI has a render view")
    lut = simple.GetColorTransferFunction("Displacement")
    lut.ApplyPreset("Viridis (matplotlib)", True)
    lut.AutomaticRescaleRangeMode = "Never"
    face = simple.Show(simple.OutputPort(fem, 0), view)
    simple.ColorBy(face, ("POINTS", "Displacement", "Magnitude"))
    face.Opacity = 0.3
    bone = simple.Show(simple.OutputPort(osteotomy, 0), view)
    simple.ColorBy(bone, ("POINTS", "Displacement", "Magnitude"))
    bone.LookupTable = face.LookupTable = lut
    planes = simple.Show(simple.OutputPort(osteotomy, 1), view)
    planes.ColorArrayName = ["POINTS", ""]
    planes.AmbientColor = planes.DiffuseColor = [0.2, 0.5, 0.9]
    planes.Opacity = 0.4
    bar = simple.GetScalarBar(lut, view)
    bar.Title, bar.ComponentTitle = "displacement (mm)", ""
    bone.SetScalarBarVisibility(view, True)
    lut.RescaleTransferFunction(0.0, 7.0)
    view.CameraFocalPoint = [85.0, 0.0, 105.0]
    view.CameraPosition = [-180.0, -300.0, 150.0]
    view.CameraViewUp = [0.0, 0.0, 1.0]
    simple.Render(view)

    def solve():
        fem.UpdatePipeline()
        out = fem.GetClientSideObject().GetOutputDataObject(0)
        b = osteotomy.GetClientSideObject().GetOutputDataObject(0)
        return (vtk_to_numpy(out.GetPointData().GetArray("Displacement")).copy(),
                vtk_to_numpy(b.GetPointData().GetArray("Displacement")).copy(),
                vtk_to_numpy(b.GetPointData().GetArray("SegmentId")).copy(), list(osteotomy.Translation))

    def close(a, b, tol=1e-9):
        return a.shape == b.shape and float(np.abs(a - b).max()) <= tol * float(np.maximum(1.0, np.abs(b).max()))

    d0, b0, s0, t0 = solve()
    check(np.abs(b0[s0 == 1] - np.array(move0)).max() < 1e-12, "first plan: the segment moved by Translation")
    check(float(np.linalg.norm(d0, axis=1).max()) > 3.0, "first plan: the upper lip's tissue moves")

    pxm = servermanager.vtkSMProxyManager.GetProxyManager()
    builder = pxm.GetUndoStackBuilder()
    check(builder is not None and builder.IsA("pqUndoStackBuilder"), "the proxy manager holds the GUI's pqUndoStackBuilder")
    # Not named `stack`: ParaView's Programmable Filter (the scene makes its unmoved bones with
    # one) imports numpy's names into the shell's namespace each time it executes.
    undo_stack = builder.GetUndoStack()
    spxm = servermanager.ProxyManager().SMProxyManager

    def gui_undo_redo(redo):
        previous = builder.GetIgnoreAllChanges()
        builder.SetIgnoreAllChanges(True)
        (undo_stack.Redo if redo else undo_stack.Undo)()
        for group in ("sources", "lookup_tables", "representations", "scalar_bars"):
            spxm.UpdateRegisteredProxies(group, 1)
        spxm.UpdateRegisteredProxies(1)
        builder.SetIgnoreAllChanges(previous)
        simple.Render(view)

    label = "Move the Le Fort I segment"
    move1 = [move0[0] - 2.0, move0[1], move0[2]]
    builder.Begin(label)
    osteotomy.Translation = move1
    builder.EndAndPushToStack()
    check(undo_stack.CanUndo() and undo_stack.GetUndoSetLabel(0) == label, "the move is on top of the GUI's undo stack")
    d1, b1, s1, t1 = solve()
    simple.Render(view)
    check(t1 == move1, "the new Translation is on the proxy")
    check(np.abs(b1[s1 == 1] - np.array(move1)).max() < 1e-12, "the segment follows the new Translation")
    change = float(np.abs(d1 - d0).max())
    result["info"]["move_max_change_mm"] = change
    check(change > 1.0, "the soft tissue follows the segment (max change %.3f mm)" % change)

    gui_undo_redo(redo=False)
    check(undo_stack.CanRedo() and undo_stack.GetRedoSetLabel(0) == label, "after undo the move is on the redo stack")
    d2, b2, s2, t2 = solve()
    check(t2 == move0, "undo restores Translation")
    check(close(b2, b0), "undo gives back the first bone")
    check(close(d2, d0), "undo gives back the first soft-tissue solve")

    gui_undo_redo(redo=True)
    d3, b3, s3, t3 = solve()
    check(t3 == move1, "redo restores the new Translation")
    check(close(b3, b1), "redo gives back the moved bone")
    check(close(d3, d1), "redo gives back the moved soft-tissue solve")

    simple.SetActiveSource(osteotomy)
    simple.Render(view)
except Exception:
    result["error"] = traceback.format_exc()
finally:
    write_result()
