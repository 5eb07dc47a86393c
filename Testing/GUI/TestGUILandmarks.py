# SPDX-License-Identifier: BSD-3-Clause
"""Runs inside the real ParaView GUI (`paraview --script=TestGUILandmarks.py`), started by
run_gui_test.py --script TestGUILandmarks.py, which passes its inputs in the environment (see
TestGUIUndoRedo.py: FACEPLAN_GUI_PLUGIN, _DATA, _SCRIPTS, _RESULT) and checks the result file.
Its screenshot is docs/gui_landmarks.png (docs/CLINICAL.md).

What it does, in the GUI's own session:
 1. loads the plugin and builds the BSSO advancement plan as the demos do
    (osteotomy_scenes.build("bsso"), the operation's contact and model), adds FacialLandmarks and
    shows the deformed face with the landmarks (FacialLandmarks' point output) over it, from the
    side, in the GUI's render view;
 2. checks that every skin and bone landmark is a point of that output and that the BSSO's banded
    ratios are in their bands;
 3. checks that the session said no warning and no error (read from the GUI's vtkOutputWindow, as
    TestGUIPipeline.py does);
 4. leaves CondensedFEMDeform selected (its Properties panel shows the Lip Seal; FacialLandmarks
    selected would draw its plane and point widgets over the face) for the wrapper's screenshot.
"""
import os
import sys
import traceback

sys.path.insert(0, os.environ["FACEPLAN_GUI_TESTS"])  # Testing/GUI, set by run_gui_test.py
from gui_result import check, result, watch_messages, write_result  # noqa: E402


try:
    from paraview import simple

    said = watch_messages()

    sys.path.insert(0, os.environ["FACEPLAN_GUI_SCRIPTS"])
    import osteotomy_scenes

    simple.LoadPlugin(os.environ["FACEPLAN_GUI_PLUGIN"])
    tissue, mandible, osteotomy, skeleton, fem = osteotomy_scenes.build(os.environ["FACEPLAN_GUI_DATA"], "bsso")
    landmarks = simple.FacialLandmarks(registrationName="FacialLandmarks", Input=fem, Bone=skeleton)

    view = simple.GetActiveViewOrCreate("RenderView")
    check(view is not None, "the GUI has a render view")
    face = simple.Show(simple.OutputPort(fem, 0), view)
    face.ColorArrayName = ["POINTS", ""]
    face.DiffuseColor = face.AmbientColor = [0.93, 0.78, 0.68]
    face.Opacity = 0.45
    bone = simple.Show(simple.OutputPort(skeleton, 0), view)
    bone.ColorArrayName = ["POINTS", ""]
    bone.DiffuseColor = bone.AmbientColor = [0.95, 0.95, 0.88]
    points = simple.Show(simple.OutputPort(landmarks, 1), view)
    points.ColorArrayName = ["POINTS", ""]
    points.SetRepresentationType("Points")
    points.RenderPointsAsSpheres = 1
    points.PointSize = 14
    points.DiffuseColor = points.AmbientColor = [0.85, 0.1, 0.1]
    view.OrientationAxesVisibility = 1
    view.CameraFocalPoint = [62.0, 0.0, 92.0]
    view.CameraPosition = [-45.0, -215.0, 112.0]
    view.CameraViewUp = [0.0, 0.0, 1.0]
    view.CameraParallelScale = 70.0
    simple.Render(view)

    landmarks.UpdatePipeline()
    table = landmarks.GetClientSideObject().GetOutputDataObject(0)
    cloud = landmarks.GetClientSideObject().GetOutputDataObject(1)
    # (the GUI's Python shell has numpy's sum over the builtin one)
    found = len([r for r in range(table.GetNumberOfRows()) if table.GetColumnByName("Found").GetValue(r)])
    result["info"]["landmarks"] = table.GetNumberOfRows()
    result["info"]["points"] = cloud.GetNumberOfPoints()
    check(table.GetNumberOfRows() == 19 and found == 19, "all 19 landmarks found (%d of %d)" % (found, table.GetNumberOfRows()))
    check(cloud.GetNumberOfPoints() >= found, "every found landmark is a point of the output (%d)" % cloud.GetNumberOfPoints())
    checks = table.GetColumnByName("Check")
    banded = [table.GetColumnByName("Landmark").GetValue(r) for r in range(table.GetNumberOfRows())
              if checks.GetValue(r) in ("in", "out")]
    outside = [table.GetColumnByName("Landmark").GetValue(r) for r in range(table.GetNumberOfRows())
               if checks.GetValue(r) == "out"]
    check(len(banded) == 3 and not outside, "the BSSO's banded ratios are in band (%s; out: %s)" % (banded, outside))

    simple.SetActiveSource(fem)
    simple.Render(view)
    check(not said, "the session said no warning and no error (%d)" % len(said))
except Exception:
    result["error"] = traceback.format_exc()
finally:
    write_result()
