# SPDX-License-Identifier: BSD-3-Clause
"""Runs inside the real ParaView GUI (`paraview --script=TestGUIPipeline.py`), started by
run_gui_test.py --script TestGUIPipeline.py, which passes its inputs in the environment (see
TestGUIUndoRedo.py: FACEPLAN_GUI_PLUGIN, _DATA, _SCRIPTS, _RESULT) and checks the result file.
The README's GUI screenshot (docs/gui_pipeline.png) is this test's --screenshot.

What it does, in the GUI's own session:
 1. loads the plugin and builds the three-filter pipeline on the face scene (ROIExtract ->
    BezierCut -> CondensedFEMDeform, faceplan_pipeline.build) with the filters' defaults (Model
    Auto), as a surgeon who follows the README starts, and shows it in the GUI's render view;
 2. checks that the cut moves the chin's soft tissue and that the field data Model names the model
    that ran;
 3. checks that the session said no warning and no error: the GUI pops its Output Messages window
    over the view at each one. They are read from the GUI's vtkOutputWindow, which fires
    WarningEvent / ErrorEvent after showing the text, so observing it hides none;
 4. leaves Bezier Cut selected, so the Properties panel shows it for the wrapper's screenshot.
"""
import os
import sys
import traceback

sys.path.insert(0, os.environ["FACEPLAN_GUI_TESTS"])  # Testing/GUI, set by run_gui_test.py
import gui_scene  # noqa: E402
from gui_result import check, result, watch_messages, write_result  # noqa: E402


try:
    import numpy as np
    from paraview import simple
    from vtkmodules.util.numpy_support import vtk_to_numpy

    said = watch_messages()

    sys.path.insert(0, os.environ["FACEPLAN_GUI_SCRIPTS"])
    import faceplan_pipeline

    simple.LoadPlugin(os.environ["FACEPLAN_GUI_PLUGIN"])  # into paraview.simple
    tissue, mandible, roi, cut, fem = faceplan_pipeline.build(os.environ["FACEPLAN_GUI_DATA"])
    check(fem.Model == "Auto", "Model starts at the filter's default, Auto (%s)" % fem.Model)

    view = gui_scene.show_pipeline(simple, fem, cut)
    check(view is not None, "the GUI has a render view")
    fem.UpdatePipeline()
    out = fem.GetClientSideObject().GetOutputDataObject(0)
    u = out.GetPointData().GetArray("Displacement")
    largest = float(np.linalg.norm(vtk_to_numpy(u), axis=1).max()) if u else 0.0
    ran = out.GetFieldData().GetAbstractArray("Model")
    result["info"]["model"] = ran.GetValue(0) if ran else None
    result["info"]["largest_mm"] = largest
    check(largest > 0.5, "the cut moves the chin's soft tissue (largest %.2f mm)" % largest)
    check(result["info"]["model"] in ("LinearElastic", "NeoHookean"),
          "the field data Model names the model that ran (%s)" % result["info"]["model"])

    # For the screenshot: the pipeline browser with Bezier Cut selected, its properties panel.
    simple.SetActiveSource(cut)
    simple.Render(view)
    check(not said, "the session said no warning and no error (%d)" % len(said))
except Exception:
    result["error"] = traceback.format_exc()
finally:
    write_result()
