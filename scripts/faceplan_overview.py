# SPDX-License-Identifier: BSD-3-Clause
"""Renders the README's overview picture (docs/faceplan_overview.png): the main job's pipeline
(faceplan_pipeline.build) with the cut mandible and the operative surface on the left and the
deformed face on the right, both coloured by displacement magnitude on one colour scale.

    xvfb-run -a -s "-screen 0 1280x1024x24" pvbatch scripts/faceplan_overview.py \\
        <FacePlan.so> <Data dir> <output png>
"""
import os
import sys

from paraview.simple import *

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import faceplan_pipeline
from faceplan_views import white_render_view

plugin, data_dir, out_png = sys.argv[1], sys.argv[2], sys.argv[3]
LoadPlugin(plugin)
tissue, mandible, roi, cut, fem = faceplan_pipeline.build(data_dir)
fem.UpdatePipeline()

lut = faceplan_pipeline.displacement_colors()


layout = CreateLayout("FacePlan overview")
bone_view = white_render_view()
face_view = white_render_view()
AssignViewToLayout(view=bone_view, layout=layout, hint=0)
AssignViewToLayout(view=face_view, layout=layout, hint=0)
layout.SetSize(1600, 700)

# Left: the whole mandible, the chin's cut coloured by how far the bone moved, the cut surface.
bone = Show(OutputPort(cut, 0), bone_view)
ColorBy(bone, ("POINTS", "Displacement", "Magnitude"))
bone.LookupTable = lut
surface = Show(OutputPort(cut, 1), bone_view)
surface.ColorArrayName = ["POINTS", ""]
surface.AmbientColor = surface.DiffuseColor = [0.25, 0.55, 0.95]
surface.Opacity = 0.4
Render(bone_view)
bone_view.CameraFocalPoint = [98.0, 0.0, 92.0]
bone_view.CameraPosition = [-75.0, -170.0, 5.0]
bone_view.CameraViewUp = [0.0, 0.0, 1.0]
bone_view.CameraViewAngle = 30.0

# Right: the deformed face (its outer surface), same colour scale, with the scale bar.
face = Show(ExtractSurface(Input=OutputPort(fem, 0)), face_view)
ColorBy(face, ("POINTS", "Displacement", "Magnitude"))
face.LookupTable = lut
Render(face_view)
face_view.CameraFocalPoint = [80.0, 10.0, 112.0]
face_view.CameraPosition = [-255.0, -270.0, 10.0]
face_view.CameraViewUp = [0.0, 0.0, 1.0]
face_view.CameraViewAngle = 30.0
faceplan_pipeline.label_bar(lut, bone_view, "Bone displacement (mm)", position=(0.03, 0.42),
                            length=0.5)  # above the operative surface
faceplan_pipeline.label_bar(lut, face_view, "Soft-tissue displacement (mm)")
lut.RescaleTransferFunction(*faceplan_pipeline.DISPLACEMENT_RANGE_MM)  # ColorBy rescales to the data: back to the fixed scale
for v in (bone_view, face_view):
    Render(v)

os.makedirs(os.path.dirname(os.path.abspath(out_png)), exist_ok=True)
SaveScreenshot(out_png, layout, ImageResolution=[1600, 700], TransparentBackground=0,
               SeparatorWidth=0)
print("overview:", out_png)
sys.stdout.flush()
os._exit(0)
