# SPDX-License-Identifier: BSD-3-Clause
"""FacePlan's CT job (pvbatch): head CT -> tissue model -> ROI on the chin -> Bezier cut ->
soft-tissue deformation. Writes images of the CT model and of the face before and after.

    pvbatch scripts/faceplan_demo_ct.py <FacePlan.so> <Data dir> <output dir> [CellSize]
"""
import os
import sys
import time

from paraview.simple import *

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import faceplan_ct_pipeline
import faceplan_pipeline
from faceplan_views import screenshot, white_render_view

plugin, data_dir, out_dir = sys.argv[1], sys.argv[2], sys.argv[3]
cell_size = float(sys.argv[4]) if len(sys.argv) > 4 else 10.0
os.makedirs(out_dir, exist_ok=True)
LoadPlugin(plugin)
if "TissueModelFromCT" not in dir(sys.modules["paraview.simple"]):
    sys.exit("FacePlan was built without CGAL: TissueModelFromCT is absent (see README, TissueModelFromCT)")
# Timed from the pipeline's construction: setting up the downstream filters' properties may already
# update the model.
start = time.time()
ct, model, roi, cut, fem = faceplan_ct_pipeline.build(data_dir, cell_size)
model.UpdatePipeline()
meshed = time.time() - start
fem.UpdatePipeline()
first = time.time() - start
tissue = servermanager.Fetch(model)

SIZE = [900, 800]
view = white_render_view(SIZE)


def camera(position, focal=(102, 102, 75), up=(0, 0, -1)):
    view.CameraFocalPoint = list(focal)
    view.CameraPosition = list(position)
    view.CameraViewUp = list(up)


def shoot(name):
    return screenshot(view, out_dir, name, SIZE)


images = []
# The model: bone surface, translucent skin, and a clipped view of the tetrahedra.
bone_display = Show(OutputPort(model, 1), view)
bone_display.AmbientColor = bone_display.DiffuseColor = [0.95, 0.93, 0.85]
bone_display.ColorArrayName = ["CELLS", ""]
skin_display = Show(OutputPort(model, 2), view)
skin_display.AmbientColor = skin_display.DiffuseColor = [0.93, 0.78, 0.68]
skin_display.Opacity = 0.35
camera((-330, -300, 20))
images.append(shoot("ct_model.png"))
Hide(OutputPort(model, 2), view)
clip = Clip(Input=OutputPort(model, 0), ClipType="Plane", Crinkleclip=1)
clip.ClipType.Origin = [102, 102, 75]
clip.ClipType.Normal = [1, 0, 0]
clip_display = Show(clip, view)
clip_display.SetRepresentationType("Surface With Edges")
clip_display.AmbientColor = clip_display.DiffuseColor = [0.93, 0.78, 0.68]
clip_display.ColorArrayName = ["CELLS", ""]
camera((620, 60, 40))  # looking at the cut face
images.append(shoot("ct_tetrahedra.png"))
Hide(clip, view)
Hide(OutputPort(model, 1), view)

# The face before and after the cut, coloured by the displacement magnitude.
face_before = Show(OutputPort(model, 2), view)
face_before.AmbientColor = face_before.DiffuseColor = [0.93, 0.78, 0.68]
face_before.ColorArrayName = ["POINTS", ""]
face_before.Opacity = 1.0
camera((-250, -330, 120))
images.append(shoot("face_before.png"))
Hide(OutputPort(model, 2), view)
face_after = Show(ExtractSurface(Input=OutputPort(fem, 0)), view)
ColorBy(face_after, ("POINTS", "Displacement", "Magnitude"))
lut = faceplan_pipeline.displacement_colors()  # the demos' shared map and range
faceplan_pipeline.label_bar(lut, view, "Displacement (mm)")
images.append(shoot("face_after.png"))

fd = tissue.GetFieldData()
print("FacePlan CT demo: CellSize %.1f mm, %d tetrahedra; CT -> model %.1f s, CT -> first deformation %.1f s"
      % (cell_size, tissue.GetNumberOfCells(), meshed, first))
print("worst dihedral angle %.2f deg, smallest mean ratio %.3f, largest boundary distance %.2f mm"
      % (fd.GetArray("WorstDihedralAngle").GetValue(0), fd.GetArray("SmallestMeanRatio").GetValue(0),
         fd.GetArray("LargestBoundaryDistance").GetValue(0)))
for path in images:
    print("image:", path)
