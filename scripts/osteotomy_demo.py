# SPDX-License-Identifier: BSD-3-Clause
"""One osteotomy scene on the Badin face (pvbatch): the cut and move of the bone segment and the soft
tissue's deformation, solved for large deformations (osteotomy_scenes.configure_model). Writes
before/after images of the bone and the face (one displacement colour map and range for both, colour
bar in mm), the stage-timing table and the midline profile before and after with the facial
landmarks marked (profile.png); prints the largest strain and the landmark table (FacialLandmarks:
movements, soft:hard ratios and the published bands).

    pvbatch scripts/osteotomy_demo.py <FacePlan.so> <Data dir> <output dir> lefort1|bsso|genioplasty
"""
import math
import os
import sys
import time

import paraview.simple
from paraview.simple import *

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import landmark_profile
import osteotomy_scenes
from faceplan_views import screenshot, white_render_view

plugin, data_dir, out_root, scene = sys.argv[1:5]
if scene not in osteotomy_scenes.SCENES:
    sys.exit("unknown scene %r; choose one of %s" % (scene, ", ".join(osteotomy_scenes.SCENES)))
out_dir = os.path.join(out_root, scene)
os.makedirs(out_dir, exist_ok=True)
LoadPlugin(plugin)
tissue, bone, osteotomy, skeleton, fem = osteotomy_scenes.build(data_dir, scene)
contact = osteotomy_scenes.OPERATION_MODEL

start = time.time()
fem.UpdatePipeline()
seconds = time.time() - start
fd = fem.GetClientSideObject().GetOutputDataObject(0).GetFieldData()
move = math.sqrt(math.fsum(c * c for c in osteotomy_scenes.SCENES[scene][2]))  # the colour range, mm

SIZE = [900, 700]
view = white_render_view(SIZE)
# Lateral-oblique view from the front left: an advancement moves towards the viewer's left.
view.CameraFocalPoint = [85, 0, 100]
view.CameraPosition = [-150, -330, 130]
view.CameraViewUp = [0, 0, 1]

lut = GetColorTransferFunction("Displacement")
lut.ApplyPreset("Viridis (matplotlib)", True)
lut.AutomaticRescaleRangeMode = "Never"
lut.RescaleTransferFunction(0.0, move)
bar = GetScalarBar(lut, view)
bar.Title = "displacement (mm)"
bar.ComponentTitle = ""
bar.TitleColor = bar.LabelColor = [0, 0, 0]
bar.RangeLabelFormat = "%.1f"
bar.Visibility = 0  # shown with the "after" images only


def shoot(name):
    return screenshot(view, out_dir, name, SIZE)


def colour(display):
    ColorBy(display, ("POINTS", "Displacement", "Magnitude"))
    display.LookupTable = lut
    lut.RescaleTransferFunction(0.0, move)  # ColorBy rescales to the data: back to the shared range
    display.SetScalarBarVisibility(view, True)


images = []
# Bone before: all three bones, the cut plane(s) in blue; after: the skeleton by displacement.
before = [Show(proxy, view) for proxy in skeleton.Input[1:] + [bone]]
for display in before:
    display.AmbientColor = display.DiffuseColor = [0.9, 0.88, 0.8]
    display.ColorArrayName = ["POINTS", ""]
planes = Show(OutputPort(osteotomy, 1), view)
planes.ColorArrayName = ["POINTS", ""]
planes.AmbientColor = planes.DiffuseColor = [0.2, 0.5, 0.9]
planes.Opacity = 0.35
view.CameraFocalPoint = [90, 0, 110]
view.CameraPosition = [-90, -230, 140]
images.append(shoot("bone_before.png"))
for proxy in skeleton.Input[1:] + [bone, OutputPort(osteotomy, 1)]:
    Hide(proxy, view)
colour(Show(skeleton, view))
images.append(shoot("bone_after.png"))
Hide(skeleton, view)
HideScalarBarIfNotNeeded(lut, view)
view.CameraFocalPoint = [85, 0, 100]

face_before = Show(ExtractSurface(Input=tissue), view)
face_before.AmbientColor = face_before.DiffuseColor = [0.93, 0.78, 0.68]
face_before.ColorArrayName = ["POINTS", ""]
view.CameraPosition = [-200, -420, 140]
images.append(shoot("face_before.png"))
Hide(face_before.Input, view)
face_after = Show(ExtractSurface(Input=OutputPort(fem, 0)), view)
colour(face_after)
images.append(shoot("face_after.png"))

# The plan in one picture: the operated skeleton and the cut inside the translucent deformed face.
face_after.Opacity = 0.35
colour(Show(skeleton, view))
planes = Show(OutputPort(osteotomy, 1), view)
planes.ColorArrayName = ["POINTS", ""]
planes.AmbientColor = planes.DiffuseColor = [0.2, 0.5, 0.9]
planes.Opacity = 0.3
view.CameraFocalPoint = [90, 0, 105]
view.CameraPosition = [-130, -300, 150]
images.append(shoot("plan.png"))

table = fem.GetClientSideObject().GetOutputDataObject(1)
csv = os.path.join(out_dir, "stage_timings.csv")
with open(csv, "w") as f:
    f.write("Stage,TimeMs,Reused,Backend\n")
    for r in range(table.GetNumberOfRows()):
        f.write("%s,%.3f,%d,%s\n" % (table.GetValue(r, 0).ToString(), table.GetValue(r, 1).ToDouble(),
                                     table.GetValue(r, 2).ToInt(), table.GetValue(r, 3).ToString()))
print("FacePlan osteotomy demo, %s: %s" % (scene, osteotomy_scenes.SCENES[scene][3]))
print("contact: %s; pipeline update %.2f s (%s)" % (", ".join(contact), seconds,
                                                     fd.GetAbstractArray("Method").GetValue(0)))
print("stage timings (%s):" % csv)
for r in range(table.GetNumberOfRows()):
    print("  %-18s %10.3f ms  reused=%d" % (table.GetValue(r, 0).ToString(), table.GetValue(r, 1).ToDouble(),
                                           table.GetValue(r, 2).ToInt()))
strain = fd.GetArray("LargestStrain")
# The iterations the solver that ran reports: Newton's (LoadSteps, NewtonIterations) or the
# Precomputed solver's (QuasiNewtonIterations).
solver = fd.GetAbstractArray("LargeDeformationSolver")
iterations = ", ".join("%d %s" % (fd.GetArray(name).GetValue(0), label) for name, label in (
    ("LoadSteps", "load steps"), ("NewtonIterations", "Newton iterations"),
    ("QuasiNewtonIterations", "quasi-Newton iterations")) if fd.GetArray(name) is not None)
print("largest strain: %.1f %% (principal Green-Lagrange, %s model, %s solver; %s; smallest volume ratio %.2f, "
      "%d tissue nodes lifted off the teeth)" % (
          100.0 * strain.GetValue(0), fd.GetAbstractArray("Model").GetValue(0),
          solver.GetValue(0) if solver is not None else "linear", iterations,
          fd.GetArray("SmallestVolumeRatio").GetValue(0), fd.GetArray("LiftedNodes").GetValue(0)))
landmarks = paraview.simple.FacialLandmarks(Input=fem, Bone=skeleton)  # the bands of the preset's Operation
landmarks.UpdatePipeline()
print("facial landmarks (mm; horizontal + forward, vertical + up; ratio = soft / paired bone, horizontal):")
print(landmark_profile.table_text(landmarks))
images.append(landmark_profile.draw(landmarks, OutputPort(fem, 0), skeleton, os.path.join(out_dir, "profile.png"),
                                    "FacePlan, %s: midline profile before (grey) and after" % scene))
for path in images:
    print("image:", path)
