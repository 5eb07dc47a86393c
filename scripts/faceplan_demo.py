# SPDX-License-Identifier: BSD-3-Clause
"""FacePlan's main job (pvbatch): ROI on the chin, Bezier cut, soft-tissue deformation.
Writes before/after images of the bone and the face and the stage-timing table.

    pvbatch scripts/faceplan_demo.py <FacePlan.so> <Data dir> <output dir>
    mpiexec -n 2 pvbatch scripts/faceplan_demo.py <FacePlan.so> <Data dir> <output dir>
    pvpython scripts/faceplan_demo.py <FacePlan.so> <Data dir> <output dir> <host:port>

With <host:port> it runs against a pvserver (`pvserver --server-port=11111`, or under mpiexec)
that sees the same paths; results come back with Fetch, so the script is the same everywhere.
"""
import os
import sys
import time

from paraview import servermanager
from paraview.simple import *

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import faceplan_pipeline
from faceplan_views import screenshot, white_render_view

plugin, data_dir, out_dir = sys.argv[1], sys.argv[2], sys.argv[3]
os.makedirs(out_dir, exist_ok=True)
if len(sys.argv) > 4:
    host, port = sys.argv[4].rsplit(":", 1)
    Connect(host, int(port))
LoadPlugin(plugin, remote=True)  # on the server (this process unless connected), into paraview.simple
tissue, mandible, roi, cut, fem = faceplan_pipeline.build(data_dir)

start = time.time()
fem.UpdatePipeline()
first = time.time() - start

SIZE = [900, 700]
view = white_render_view(SIZE)


def camera(focal, position, up=(0, 0, 1)):
    view.CameraFocalPoint = focal
    view.CameraPosition = position
    view.CameraViewUp = list(up)


def shoot(name):
    return screenshot(view, out_dir, name, SIZE)


images = []
# Bone before: the ROI in orange on the mandible.
bone_display = Show(roi, view)
ColorBy(bone_display, ("POINTS", "ROIMask"))
lut = GetColorTransferFunction("ROIMask")
lut.ApplyPreset("Blue Orange (divergent)", True)
faceplan_pipeline.label_bar(lut, view, "ROI mask (1 = in the ROI)")
camera([75, 0, 75], [-120, -160, 20])
images.append(shoot("bone_before.png"))
Hide(roi, view)

# Bone after: the cut mandible coloured by displacement, with the operative surface.
GetScalarBar(lut, view).Visibility = 0
disp_lut = faceplan_pipeline.displacement_colors()
cut_display = Show(OutputPort(cut, 0), view)
ColorBy(cut_display, ("POINTS", "Displacement", "Magnitude"))
cut_display.LookupTable = disp_lut
surface_display = Show(OutputPort(cut, 1), view)
surface_display.Opacity = 0.35
surface_display.AmbientColor = surface_display.DiffuseColor = [0.2, 0.5, 0.9]
surface_display.ColorArrayName = ["POINTS", ""]
faceplan_pipeline.label_bar(disp_lut, view, "Bone displacement (mm)")
disp_lut.RescaleTransferFunction(*faceplan_pipeline.DISPLACEMENT_RANGE_MM)  # ColorBy rescales
images.append(shoot("bone_after.png"))
Hide(OutputPort(cut, 0), view)
Hide(OutputPort(cut, 1), view)

# Face before and after, coloured by the soft tissue's displacement magnitude.
face_before = Show(ExtractSurface(Input=tissue), view)
face_before.AmbientColor = face_before.DiffuseColor = [0.93, 0.78, 0.68]
face_before.ColorArrayName = ["POINTS", ""]
camera([90, 0, 110], [-260, -250, 60])
images.append(shoot("face_before.png"))
Hide(face_before.Input, view)
face_after = Show(ExtractSurface(Input=OutputPort(fem, 0)), view)
ColorBy(face_after, ("POINTS", "Displacement", "Magnitude"))
face_after.LookupTable = disp_lut
faceplan_pipeline.label_bar(disp_lut, view, "Soft-tissue displacement (mm)")
disp_lut.RescaleTransferFunction(*faceplan_pipeline.DISPLACEMENT_RANGE_MM)  # same map as the bone
images.append(shoot("face_after.png"))

# Stage timings (like the paper's Table 2) and an edit that only re-solves.
# Fetch, not GetClientSideObject(), which is None on a client; the table is the same on every rank.
table = servermanager.Fetch(fem, 0, None, 1)
rows = [(table.GetValue(r, 0).ToString(), table.GetValue(r, 1).ToDouble(), table.GetValue(r, 2).ToInt(),
         table.GetValue(r, 3).ToString()) for r in range(table.GetNumberOfRows())]
# The edit: the whole cut surface 0.5 mm lower (a deeper cut); bone, ROI and tissue unchanged.
faceplan_pipeline.place_cut(cut, -0.5)
start = time.time()
fem.UpdatePipeline()
edit = time.time() - start
edit_table = servermanager.Fetch(fem, 0, None, 1)
csv = os.path.join(out_dir, "stage_timings.csv")
with open(csv, "w") as f:
    f.write("Stage,FirstRunMs,FirstRunReused,EditMs,EditReused,Backend\n")
    for r, (stage, ms, reused, backend) in enumerate(rows):
        f.write("%s,%.3f,%d,%.3f,%d,%s\n" % (stage, ms, reused, edit_table.GetValue(r, 1).ToDouble(),
                                             edit_table.GetValue(r, 2).ToInt(), backend))
fd = servermanager.Fetch(fem, 0).GetFieldData()  # the same on every rank
print("FacePlan demo: first pipeline update %.2f s, edit of the cut %.3f s (%s, residual %.1e)"
      % (first, edit, fd.GetAbstractArray("Method").GetValue(0), fd.GetArray("RelativeResidual").GetValue(0)))
print("stage timings:", csv)
for path in images:
    print("image:", path)
