# SPDX-License-Identifier: BSD-3-Clause
"""One run of the MPI deformation test (pvbatch, serial or under mpiexec): for each scene and split,
every process's piece of CondensedFEMDeform's output written to <work dir>/<label>/<scene>_<split>_
{before,after}.pvtu (before and after one edit of the bone; for the face BezierCut's output as
<scene>_<split>_<phase>_bone.pvtu or .pvtp too; for the sphere the Surface output as
<scene>_<split>_surface.pvtu), and the solving rank's precompute
count; then three runs with a real error (bad YoungsModulus, BezierCut without ROIExtract,
ContactModel ByArray on a bone without Sliding, whose output is written to
<work dir>/<label>/byarray/) whose messages the driver counts. servermanager.Fetch under pvbatch returns only the first process's piece, hence the files.

    pvbatch RunParallelDeform.py <FacePlan.so> <Data dir> <work dir> <label> <split>...
"""
import json
import os
import sys

from paraview.simple import LoadPlugin, SaveData, XMLPolyDataReader

plugin, data_dir, work_dir, label = sys.argv[1:5]
splits = sys.argv[5:]
here = os.path.dirname(os.path.abspath(__file__))
sys.path[:0] = [here, os.path.join(here, "..", "..", "scripts")]
LoadPlugin(plugin)  # into paraview.simple, where parallel_scenes finds the filters
import parallel_scenes
from paraview.simple import BezierCut

if label == "serial":
    parallel_scenes.write_scene_files(data_dir, work_dir)
out_dir = os.path.join(work_dir, label)
os.makedirs(out_dir, exist_ok=True)

precomputes = {}
runs = [(scene, split) for scene in parallel_scenes.SCENES for split in splits]
runs += [("osteotomy", split) for split in splits if split in ("none", parallel_scenes.OSTEOTOMY_SPLIT)]
for scene, split in runs:
    key = "%s_%s" % (scene, split)
    fem, bone, edit = parallel_scenes.build(scene, split, data_dir, work_dir)
    for phase in ("before", "after"):
        if phase == "after":
            edit()
        SaveData(os.path.join(out_dir, "%s_%s.pvtu" % (key, phase)), proxy=fem)
        if scene == "face":  # BezierCut's output, gathered and scattered back too
            bone_type = bone.GetDataInformation().GetDataClassName()
            extension = ".pvtp" if bone_type == "vtkPolyData" else ".pvtu"
            SaveData(os.path.join(out_dir, "%s_%s_bone%s" % (key, phase, extension)), proxy=bone)
    fem.UpdatePropertyInformation()  # from the solving rank
    precomputes[key] = fem.GetPropertyValue("PrecomputeCount")
    if scene == "sphere":  # the boundary surface only: each rank its own triangles
        fem.OutputMode = "Surface"
        SaveData(os.path.join(out_dir, "%s_surface.pvtu" % key), proxy=fem)
    print("%s %s: %d precompute(s)" % (label, key, precomputes[key]))

# Three real errors, each to be logged once however many processes run (the driver counts them).
fem, _, _ = parallel_scenes.build("sphere", splits[0], data_dir, work_dir)
fem.YoungsModulus = -1.0
fem.UpdatePipeline()
uncut = BezierCut(Input=XMLPolyDataReader(FileName=[os.path.join(data_dir, "face", "mandible.vtp")]))
uncut.UpdatePipeline()
# A failure found after the contact was built: every process must get an empty output.
fem, _, _ = parallel_scenes.build("sphere", splits[0], data_dir, work_dir)
fem.ContactModel = "ByArray"
SaveData(os.path.join(out_dir, "byarray.pvtu"), proxy=fem)

with open(os.path.join(out_dir, "precomputes.json"), "w") as f:
    json.dump(precomputes, f)
