# SPDX-License-Identifier: BSD-3-Clause
"""Runs inside the real ParaView GUI (`paraview --script=TestGUIUndoRedo.py`), started by
run_gui_test.py, which passes its inputs in the environment and checks the result file:

    FACEPLAN_GUI_PLUGIN   the built FacePlan.so
    FACEPLAN_GUI_DATA     the repository's Data folder
    FACEPLAN_GUI_SCRIPTS  the repository's scripts folder (faceplan_pipeline.py)
    FACEPLAN_GUI_RESULT   where to write the result (JSON); written last, also on failure

What it does, in the GUI's own session:
 1. loads the plugin and builds the three-filter pipeline on the face scene (ROIExtract ->
    BezierCut -> CondensedFEMDeform, faceplan_pipeline.build), shows it in the GUI's render view;
 2. edits one control point of BezierCut's CurveU property inside an undo set of the GUI's undo
    stack (the pqUndoStackBuilder that pqUndoStack registers with the proxy manager: the same
    begin / end-and-push that the GUI's Apply button does) and checks that the solve changed;
 3. undoes and redoes that set on the GUI's vtkSMUndoStack the way pqUndoStack::undo()/redo()
    (Edit > Undo / Redo and the toolbar buttons) do: undo/redo with changes ignored, then
    UpdateRegisteredProxies in pqUndoStack's order, then render; checks that undo gives back the
    first solve and redo the edited one;
 4. leaves Bezier Cut selected, so the Properties panel shows it for the wrapper's screenshot.

The GUI's exit code does not reflect Python errors, hence the result file.
"""
import os
import sys
import time
import traceback

sys.path.insert(0, os.environ["FACEPLAN_GUI_TESTS"])  # Testing/GUI, set by run_gui_test.py
import gui_scene  # noqa: E402
from gui_result import check, result, write_result  # noqa: E402


try:
    import numpy as np
    from paraview import servermanager
    from paraview import simple
    from vtkmodules.util.numpy_support import vtk_to_numpy

    sys.path.insert(0, os.environ["FACEPLAN_GUI_SCRIPTS"])
    import faceplan_pipeline

    result["info"]["fromGUI"] = bool(getattr(__import__("paraview"), "fromGUI", False))
    simple.LoadPlugin(os.environ["FACEPLAN_GUI_PLUGIN"])  # into paraview.simple
    tissue, mandible, roi, cut, fem = faceplan_pipeline.build(os.environ["FACEPLAN_GUI_DATA"])
    fem.Model = "LinearElastic"  # the linear model's contract (its baseline, its edit timings)

    view = gui_scene.show_pipeline(simple, fem, cut)
    check(view is not None, "the GUI has a render view")

    def solve():
        """(tissue displacement, bone displacement, CurveU) after bringing the pipeline up to date."""
        fem.UpdatePipeline()
        out = fem.GetClientSideObject().GetOutputDataObject(0)
        bone_out = cut.GetClientSideObject().GetOutputDataObject(0)
        return (vtk_to_numpy(out.GetPointData().GetArray("Displacement")).copy(),
                vtk_to_numpy(bone_out.GetPointData().GetArray("Displacement")).copy(),
                list(cut.CurveU))

    def close(a, b, tol=1e-9):
        scale = max(1.0, float(np.abs(b).max()))
        return a.shape == b.shape and float(np.abs(a - b).max()) <= tol * scale

    d0, b0, curve0 = solve()
    check(d0.shape[0] == fem.GetDataInformation().GetNumberOfPoints() and
          0 < d0.shape[0] < tissue.GetDataInformation().GetNumberOfPoints(),
          "first solve: one displacement per point of the deformed surface (Output Mode Surface)")
    check(float(np.linalg.norm(d0, axis=1).max()) > 0.5, "first solve: the cut moves the chin's soft tissue")

    # The GUI's undo stack: pqUndoStack registers its pqUndoStackBuilder with the proxy manager.
    pxm = servermanager.vtkSMProxyManager.GetProxyManager()
    builder = pxm.GetUndoStackBuilder()
    check(builder is not None and builder.IsA("pqUndoStackBuilder"),
          "the proxy manager holds the GUI's pqUndoStackBuilder")
    stack = builder.GetUndoStack()
    check(stack is not None and stack.IsA("vtkSMUndoStack"), "the builder holds the GUI's vtkSMUndoStack")
    result["info"]["builder"] = builder.GetClassName()
    spxm = servermanager.ProxyManager().SMProxyManager

    def gui_undo_redo(redo):
        """What pqUndoStack::undo()/redo() do (Edit > Undo / Redo, the Undo/Redo toolbar buttons)."""
        previous = builder.GetIgnoreAllChanges()
        builder.SetIgnoreAllChanges(True)  # beginNonUndoableChanges()
        (stack.Redo if redo else stack.Undo)()
        for group in ("sources", "lookup_tables", "representations", "scalar_bars"):
            spxm.UpdateRegisteredProxies(group, 1)  # updateAllModifiedProxies(), in its order
        spxm.UpdateRegisteredProxies(1)
        builder.SetIgnoreAllChanges(previous)  # endNonUndoableChanges()
        simple.Render(view)

    # The edit: control point 1 of CurveU 2 mm lower (P0, shared with CurveV, stays), as one undo
    # set, the way pqUndoStack::beginUndoSet()/endUndoSet() wrap the GUI's Apply.
    label = "Edit Bezier Cut control point"
    curve1 = list(curve0)
    curve1[5] -= 2.0
    builder.Begin(label)
    cut.CurveU = curve1
    builder.EndAndPushToStack()
    check(stack.CanUndo() and stack.GetUndoSetLabel(0) == label, "the edit is on top of the GUI's undo stack")
    check(not stack.CanRedo(), "nothing to redo after the edit")
    start = time.time()
    d1, b1, c1 = solve()
    result["info"]["edit_solve_s"] = time.time() - start
    simple.Render(view)
    change = float(np.abs(d1 - d0).max())
    result["info"]["edit_max_change_mm"] = change
    check(c1 == curve1, "the edited CurveU is on the proxy")
    check(float(np.abs(b1 - b0).max()) > 0.1, "the edit changes the cut bone's displacement")
    check(change > 0.05, "the edit changes the soft tissue's displacement (max change %.3f mm)" % change)

    gui_undo_redo(redo=False)
    check(stack.CanRedo() and stack.GetRedoSetLabel(0) == label, "after undo the edit is on the redo stack")
    d2, b2, c2 = solve()
    result["info"]["undo_max_diff_mm"] = float(np.abs(d2 - d0).max())
    check(c2 == curve0, "undo restores CurveU")
    check(close(b2, b0), "undo gives back the first cut (bone displacement)")
    check(close(d2, d0), "undo gives back the first solve (tissue displacement, max diff %.2e mm)"
          % result["info"]["undo_max_diff_mm"])

    gui_undo_redo(redo=True)
    check(stack.CanUndo() and stack.GetUndoSetLabel(0) == label, "after redo the edit is back on the undo stack")
    d3, b3, c3 = solve()
    result["info"]["redo_max_diff_mm"] = float(np.abs(d3 - d1).max())
    check(c3 == curve1, "redo restores the edited CurveU")
    check(close(b3, b1), "redo gives back the edited cut (bone displacement)")
    check(close(d3, d1), "redo gives back the edited solve (tissue displacement, max diff %.2e mm)"
          % result["info"]["redo_max_diff_mm"])

    # For the screenshot: the pipeline browser with Bezier Cut selected, its properties panel.
    simple.SetActiveSource(cut)
    simple.Render(view)
except Exception:
    result["error"] = traceback.format_exc()
finally:
    write_result()
